"""Robot files with several arms (``arms:`` and ``system:``): structure against independent readings.

The tree kernels are tested elsewhere; here each loaded `TreeRobot` is checked for its
joint order, names, parents, tip bodies and masses against the URDF read independently
(the XML summed by hand, and Pinocchio's model of the same file: joint names, and tip
poses from its forward kinematics against a numpy walk over the tree's leaves).
"""

import math
import os
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import yaml

import spacearm as sa
from spacearm.cli import main
from spacearm.models.spatial import locate_package_file
from spacearm.models.tree import TreeRobot

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")
ERD = "example-robot-data"


def erd(path):
    try:
        return locate_package_file("test", ERD, path)
    except sa.ConfigError:
        pytest.skip("example-robot-data is not installed")


UR5 = "robots/ur_description/urdf/ur5_robot.urdf"
BAXTER = "robots/baxter_description/urdf/baxter.urdf"
TIAGO = "robots/tiago_description/robots/tiago_dual.urdf"


# Independent references ------------------------------------------------------------------


def xml_subtree_mass(path, top):
    """The sum of ``<mass>`` over ``top`` and every link below it, read from the XML."""
    root = ET.parse(path).getroot()
    below = {top}
    changed = True
    joints = [(j.find("parent").get("link"), j.find("child").get("link")) for j in root.findall("joint")]
    while changed:
        changed = False
        for parent, child in joints:
            if parent in below and child not in below:
                below.add(child)
                changed = True
    total = 0.0
    for link in root.findall("link"):
        mass = link.find("inertial/mass")
        if link.get("name") in below and mass is not None:
            total += float(mass.get("value"))
    return total


def total_mass(robot):
    return float(robot.base_mass + np.sum(robot.root_mass) + np.sum(robot.link_mass))


def _rot(axis, angle):
    axis = np.asarray(axis) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def _rpy(rpy):
    r, p, y = rpy
    return _rot([0, 0, 1], y) @ _rot([0, 1, 0], p) @ _rot([1, 0, 0], r)


def tip_poses(robot, q):
    """Tip frames in the bus frame at joints q: a numpy walk over parents and the leaves."""
    roots = [(_rpy(robot.mount_rpy[r]), np.asarray(robot.mount_xyz[r])) for r in range(robot.n_roots)]
    bodies = []
    for j, parent in enumerate(robot.parents):
        rotation, origin = roots[-1 - parent] if parent < 0 else bodies[parent]
        r = rotation @ robot.joint_rotation[j]
        p = origin + rotation @ robot.joint_translation[j]
        if robot.joint_kinds[j] == "revolute":
            r = r @ _rot(robot.joint_axis[j], q[j])
        else:
            p = p + r @ robot.joint_axis[j] * q[j]
        bodies.append((r, p))
    out = []
    for t, body in enumerate(robot.tip_bodies):
        r, p = bodies[body]
        out.append((r @ robot.tip_rotation[t], p + r @ robot.tip_translation[t]))
    return out


def pinocchio_tip_poses(path, base_link, tips, values):
    """Tip frames in the ``base_link`` frame from Pinocchio's kinematics of the URDF.

    ``values``: joint name -> position (every other joint at 0, or its nearest limit)."""
    pin = pytest.importorskip("pinocchio")
    model = pin.buildModelFromUrdf(path)
    data = model.createData()
    q = pin.neutral(model)
    for j in range(1, model.njoints):
        name, joint = model.names[j], model.joints[j]
        if joint.nq == 2:  # continuous: (cos, sin)
            value = values.get(name, 0.0)
            q[joint.idx_q : joint.idx_q + 2] = math.cos(value), math.sin(value)
        elif joint.nq == 1:
            low, high = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
            q[joint.idx_q] = values.get(name, min(max(0.0, low), high))
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    base = data.oMf[model.getFrameId(base_link)]
    out = []
    for tip in tips:
        pose = base.actInv(data.oMf[model.getFrameId(tip)])
        out.append((pose.rotation, pose.translation))
    return out, model


def assert_tips_agree(robot, path, base_link, tips, names, seed=0, mounts=None):
    rng = np.random.default_rng(seed)
    q = rng.uniform(-1.0, 1.0, robot.n_joints)
    ours = tip_poses(robot, q)
    for t, tip in enumerate(tips):
        values = {name.split("/")[-1]: q[j] for j, name in enumerate(names) if robot.support[t, j]}
        [(rotation, origin)], _ = pinocchio_tip_poses(path, base_link, [tip], values)
        if mounts is not None:
            rm, pm = mounts[t]
            rotation, origin = rm @ rotation, pm + rm @ origin
        np.testing.assert_allclose(ours[t][0], rotation, atol=1e-12)
        np.testing.assert_allclose(ours[t][1], origin, atol=1e-12)


# The arms: form ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def dual_ur5():
    erd(UR5)
    return sa.load_robot(os.path.join(CONFIGS, "dual-ur5-servicer.yaml"))


UR5_JOINTS = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)


def test_dual_ur5_structure(dual_ur5):
    robot = dual_ur5
    assert isinstance(robot, TreeRobot) and robot.name == "dual-ur5-servicer"
    assert robot.joint_names == tuple(f"{arm}/{j}" for arm in ("left", "right") for j in UR5_JOINTS)
    assert robot.tip_names == ("left/tool0", "right/tool0")
    assert robot.parents == (-1, 0, 1, 2, 3, 4, -2, 6, 7, 8, 9, 10)
    assert robot.tip_bodies == (5, 11)
    assert robot.labels.root_names == ("left", "right")
    np.testing.assert_allclose(robot.mount_xyz, [[0.3, 0.5526, 0.08], [0.3, -0.5526, 0.08]])
    np.testing.assert_allclose(robot.mount_rpy, [[-np.pi / 2, 0, 0], [np.pi / 2, 0, 0]])
    # a uniform 400 kg cube of 0.4726 m half-size
    np.testing.assert_allclose(robot.base_inertia, np.eye(3) * 400.0 * 0.9452**2 / 6, rtol=1e-10)
    # the bus plus two copies of every link below base_link (the `world` link has no mass)
    arm_mass = xml_subtree_mass(erd(UR5), "base_link")
    assert arm_mass == pytest.approx(20.9939)  # the 21.0 kg of example-robot-data's UR5
    assert total_mass(robot) == pytest.approx(400.0 + 2 * arm_mass, rel=1e-14)


def test_dual_ur5_tips_agree_with_pinocchio(dual_ur5):
    robot = dual_ur5
    mounts = [(_rpy(robot.mount_rpy[r]), robot.mount_xyz[r]) for r in range(2)]
    assert_tips_agree(robot, erd(UR5), "base_link", ["tool0", "tool0"], robot.joint_names, mounts=mounts)


def _arms_file(tmp_path, arms, **top):
    config = {
        "name": "t",
        "base": {"mass": 100.0, "inertia": [[10, 0, 0], [0, 10, 0], [0, 0, 10]]},
        "arms": arms,
        **top,
    }
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(config))
    return str(path)


def _ur5_arm(name, **changes):
    arm = {
        "name": name,
        "urdf": {"package": ERD, "path": UR5},
        "root_link": "base_link",
        "tip": "tool0",
        "mount": {"xyz": [0.0, 0.0, 0.0], "rpy_deg": [0.0, 0.0, 90.0]},
    }
    arm.update(changes)
    return arm


def test_mount_rpy_deg_and_a_locked_joint(tmp_path):
    erd(UR5)
    robot = sa.load_robot(_arms_file(tmp_path, [_ur5_arm("a"), _ur5_arm("b", lock_joints={"wrist_3_joint": 0.5})]))
    np.testing.assert_allclose(robot.mount_rpy[0], [0, 0, np.pi / 2])
    assert robot.joint_names[-1] == "b/wrist_2_joint" and robot.n_joints == 11
    assert robot.tip_bodies == (5, 10)


@pytest.mark.parametrize(
    "arms, message",
    [
        (
            [_ur5_arm("a"), _ur5_arm("b", tipp="tool0")],
            r"robot.yaml: arms\[1\]: unknown key 'tipp' \(did you mean 'tip'\?\)",
        ),
        (
            [_ur5_arm("a"), _ur5_arm("b", tip="tool9")],
            r"robot.yaml: arms\[1\].tip: \(in .*ur5_robot.urdf\) link 'tool9' is not in the URDF \(did you mean 'tool0'\?\)",
        ),
        ([_ur5_arm("a"), _ur5_arm("a")], r"robot.yaml: arms\[1\].name: 'a' is already arms\[0\]"),
        (
            [_ur5_arm("a", mount={"xyz": [0, 0], "rpy": [0, 0, 0]})],
            r"robot.yaml: arms\[0\].mount.xyz: must be numbers of shape \[3\]",
        ),
        (
            [_ur5_arm("a", mount={"xyz": [0, 0, 0], "rpyy": [0, 0, 0]})],
            r"robot.yaml: arms\[0\].mount: unknown key 'rpyy' \(did you mean 'rpy'\?\)",
        ),
        (
            [_ur5_arm("a", lock_joints={"elbow_joint": 4.0})],
            r"robot.yaml: arms\[0\].lock_joints: \(in .*\) joint 'elbow_joint': the value 4 is outside its limits \[-3.14159, 3.14159\] rad",
        ),
        (
            [_ur5_arm("a", urdf={"package": ERD, "path": "robots/none.urdf"})],
            r"robot.yaml: arms\[0\].urdf.path: package 'example-robot-data' has no file",
        ),
        ([], r"robot.yaml: arms: must be a list of one or more arms"),
        ([_ur5_arm("a", inertia_as_written="yes")], r"robot.yaml: arms\[0\].inertia_as_written: must be true or false"),
    ],
)
def test_arms_errors_name_the_file_and_field(tmp_path, arms, message):
    erd(UR5)
    with pytest.raises(sa.ConfigError, match=message):
        sa.load_robot(_arms_file(tmp_path, arms))


def test_top_level_typo_and_both_forms(tmp_path):
    erd(UR5)
    with pytest.raises(sa.ConfigError, match=r"robot.yaml: unknown key 'arm' \(did you mean 'arms'\?\)"):
        sa.load_robot(_arms_file(tmp_path, [_ur5_arm("a")], arm={}))
    with pytest.raises(sa.ConfigError, match=r"give either 'arms' .* or 'system' .*, not both"):
        sa.load_robot(_arms_file(tmp_path, [_ur5_arm("a")], system={}))


def test_cli_validate_exit_2_names_file_and_field(tmp_path, capsys):
    erd(UR5)
    path = _arms_file(tmp_path, [_ur5_arm("a"), _ur5_arm("b", tipp="tool0")])
    assert main(["validate", path]) == 2
    err = capsys.readouterr().err
    assert f"{path}: arms[1]: unknown key 'tipp' (did you mean 'tip'?)" in err
    assert len(err.strip().splitlines()) == 1
    assert main(["validate", os.path.join(CONFIGS, "dual-ur5-servicer.yaml")]) == 0
    assert "valid robot (dual-ur5-servicer, 12 joints, tips left/tool0, right/tool0)" in capsys.readouterr().out
