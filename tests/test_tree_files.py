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
from spacearm.models.tree.urdf import parse_urdf_tree

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


# The system: form ------------------------------------------------------------------------


def pinocchio_check(robot, path, base_link, locks=None, seed=0, bus=True):
    """Compare a system robot with Pinocchio's free-flyer model of the same URDF, the joints
    off the tree locked (``locks``, else 0 or the nearest limit) by `buildReducedModel`:
    parents, every body's mass, centroid and inertia (the same frames: the child link's),
    the bus when ``base_link`` is the URDF's root, and the tip frames at random joints."""
    pin = pytest.importorskip("pinocchio")
    locks = dict(locks or {})
    model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())
    ours = set(robot.joint_names)
    q0 = pin.neutral(model)
    locked = []
    for j in range(2, model.njoints):
        name, joint = model.names[j], model.joints[j]
        if name in ours:
            continue
        locked.append(j)
        if joint.nq == 1:
            low, high = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
            q0[joint.idx_q] = locks.get(name, min(max(0.0, low), high))
        else:
            value = locks.get(name, 0.0)
            q0[joint.idx_q : joint.idx_q + 2] = math.cos(value), math.sin(value)
    reduced = pin.buildReducedModel(model, locked, q0)
    assert reduced.njoints == robot.n_joints + 2
    for j, name in enumerate(robot.joint_names):
        jid = reduced.getJointId(name)
        parent = reduced.names[reduced.parents[jid]]
        assert parent == ("root_joint" if robot.parents[j] < 0 else robot.joint_names[robot.parents[j]])
        inertia = reduced.inertias[jid]
        assert robot.link_mass[j] == pytest.approx(inertia.mass, abs=1e-12)
        np.testing.assert_allclose(robot.link_com[j], inertia.lever, atol=1e-12)
        np.testing.assert_allclose(robot.link_inertia[j], inertia.inertia, atol=1e-12)
    if bus:
        inertia = reduced.inertias[1]
        assert float(robot.base_mass) == pytest.approx(inertia.mass, rel=1e-13)
        np.testing.assert_allclose(robot.base_com, inertia.lever, atol=1e-12)
        np.testing.assert_allclose(robot.base_inertia, inertia.inertia, atol=1e-11)
    # tips at random joints, in the bus frame
    q = np.random.default_rng(seed).uniform(-1.0, 1.0, robot.n_joints)
    lower = np.where(np.isfinite(robot.joint_lower), robot.joint_lower, -1.0)
    upper = np.where(np.isfinite(robot.joint_upper), robot.joint_upper, 1.0)
    q = np.clip(q, lower, upper)
    data = reduced.createData()
    qr = pin.neutral(reduced)
    for j, name in enumerate(robot.joint_names):
        joint = reduced.joints[reduced.getJointId(name)]
        if joint.nq == 2:
            qr[joint.idx_q : joint.idx_q + 2] = math.cos(q[j]), math.sin(q[j])
        else:
            qr[joint.idx_q] = q[j]
    pin.forwardKinematics(reduced, data, qr)
    pin.updateFramePlacements(reduced, data)
    base = data.oMf[reduced.getFrameId(base_link)]
    for t, (rotation, origin) in enumerate(tip_poses(robot, q)):
        pose = base.actInv(data.oMf[reduced.getFrameId(robot.tip_names[t])])
        np.testing.assert_allclose(rotation, pose.rotation, atol=1e-12)
        np.testing.assert_allclose(origin, pose.translation, atol=1e-12)


def urdf_path_of(robot):
    with open(robot.labels.source, encoding="utf-8") as handle:
        config = yaml.safe_load(handle)
    urdf = config["system"]["urdf"]
    if isinstance(urdf, dict):
        return erd(urdf["path"])
    return os.path.join(os.path.dirname(robot.labels.source), urdf)


SYSTEMS = {
    "three-arm-servicer": dict(
        joints=(
            "Left_Joint_1",
            "Left_Joint_2",
            "Left_Joint_3",
            "Turret_Joint",
            "Right_Shoulder",
            "Right_Telescope",
            "Right_Wrist",
            "Boom_Deploy",
            "Boom_Elbow",
            "Boom_Roll",
        ),
        parents=(-1, 0, 1, -1, 3, 4, 5, 3, 7, 8),
        tips=("Left_EE", "Right_EE", "Boom_EE"),
        tip_bodies=(2, 6, 9),
        kinds="RRRRRPRPRR",
        base_link="Servicer_Bus",
        locks={"Right_Finger_L_Joint": 0.02, "Right_Finger_R_Joint": 0.02},
        bus=True,
    ),
    "baxter-system": dict(
        joints=tuple(f"{side}_{j}" for side in ("left", "right") for j in ("s0", "s1", "e0", "e1", "w0", "w1", "w2")),
        parents=(-1, 0, 1, 2, 3, 4, 5, -1, 7, 8, 9, 10, 11, 12),
        tips=("left_gripper", "right_gripper"),
        tip_bodies=(6, 13),
        kinds="R" * 14,
        base_link="base",
        locks={},
        bus=True,
    ),
    "tiago-dual-system": dict(
        joints=("torso_lift_joint",)
        + tuple(f"arm_{side}_{i}_joint" for side in ("left", "right") for i in range(1, 8)),
        parents=(-1, 0, 1, 2, 3, 4, 5, 6, 0, 8, 9, 10, 11, 12, 13),
        tips=("hand_left_grasping_frame", "hand_right_grasping_frame"),
        tip_bodies=(7, 14),
        kinds="P" + "R" * 14,
        base_link="torso_fixed_link",
        locks={},
        bus=False,  # Pinocchio's free flyer sits on base_footprint, above this bus
    ),
}


@pytest.fixture(scope="module", params=sorted(SYSTEMS))
def system(request):
    robot = sa.load_robot(os.path.join(CONFIGS, f"{request.param}.yaml"))
    return request.param, robot


def test_system_structure_and_mass(system):
    name, robot = system
    expected = SYSTEMS[name]
    assert isinstance(robot, TreeRobot) and robot.name == name
    assert robot.joint_names == expected["joints"]
    assert robot.parents == expected["parents"]
    assert robot.tip_names == expected["tips"] and robot.tip_bodies == expected["tip_bodies"]
    assert "".join(k[0].upper() for k in robot.joint_kinds) == expected["kinds"]
    assert robot.n_roots == 1 and float(robot.root_mass[0]) == 0.0
    np.testing.assert_array_equal(robot.mount_xyz, np.zeros((1, 3)))
    # every link at or below base_link is kept (merged or a body); the rest are dropped
    path = urdf_path_of(robot)
    assert total_mass(robot) == pytest.approx(xml_subtree_mass(path, expected["base_link"]), rel=1e-13)


def test_system_against_pinocchio(system):
    name, robot = system
    expected = SYSTEMS[name]
    pinocchio_check(robot, urdf_path_of(robot), expected["base_link"], expected["locks"], bus=expected["bus"])


def test_three_arm_details():
    robot = sa.load_robot(os.path.join(CONFIGS, "three-arm-servicer.yaml"))
    assert robot.labels.urdf_types[:3] == ("continuous",) * 3 and robot.labels.urdf_types[-1] == "continuous"
    assert np.all(np.isinf(robot.joint_lower[:3]))
    assert (robot.joint_lower[5], robot.joint_upper[5]) == (0.0, 0.4)  # the telescope, m
    # the bus: 800 kg + two 25 kg panels + the 3 kg camera held by lock_others
    assert float(robot.base_mass) == pytest.approx(853.0)
    assert set(robot.labels.body_links[6]) == {"Right_Hand", "Right_Finger_L", "Right_Finger_R", "Right_EE"}
    # the locked fingers, 2 cm out along +-y, move the hand's centroid by nothing in y
    assert robot.link_com[6][1] == pytest.approx(0.0, abs=1e-15)
    assert robot.link_com[6][0] == pytest.approx((2.0 * 0.05 + 2 * 0.2 * 0.13) / 2.4)


def tiago_config(**system):
    config = {
        "urdf": {"package": ERD, "path": TIAGO},
        "base_link": "torso_fixed_link",
        "tips": ["hand_left_grasping_frame", "hand_right_grasping_frame"],
        "lock_others": True,
        "inertia_as_written": True,
    }
    config.update(system)
    return {"name": "t", "system": {k: v for k, v in config.items() if v is not None}}


def _write(tmp_path, config):
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(config))
    return str(path)


def test_tiago_antenna_above_the_bus_is_not_checked(tmp_path):
    """The 1 ug antenna on TIAGo's mobile base has a negative principal moment; it is above
    torso_fixed_link (dropped, not checked) but kept when the mobile base is the bus."""
    path = erd(TIAGO)
    root = ET.parse(path).getroot()
    antenna = next(link for link in root.findall("link") if link.get("name") == "base_antenna_left_link")
    assert float(antenna.find("inertial/mass").get("value")) == 1e-6
    assert sa.load_robot(_write(tmp_path, tiago_config())).n_joints == 15
    with pytest.raises(
        sa.ConfigError,
        match=r"robot.yaml: system.urdf: .*tiago_dual.urdf: link 'base_antenna_left_link': inertial inertia: "
        r"must be positive semidefinite; principal moments -3.53486e-08",
    ):
        sa.load_robot(_write(tmp_path, tiago_config(base_link="base_link")))
    # the single-arm file from the torso: the antenna above root_link no longer refuses it
    arm = {
        "name": "t",
        "base": {"mass": 100.0, "inertia": [[10, 0, 0], [0, 10, 0], [0, 0, 10]]},
        "arm": {
            "urdf": {"package": ERD, "path": TIAGO},
            "root_link": "torso_lift_link",
            "tip": "hand_left_grasping_frame",
            "lock_others": True,
            "inertia_as_written": True,
        },
    }
    assert sa.load_robot(_write(tmp_path, arm)).n_joints == 7


def test_lock_others_message_lists_every_joint_at_once(tmp_path):
    path = erd(TIAGO)
    root = ET.parse(path).getroot()
    # independently: movable joints below torso_fixed_link, less those on the two tip paths
    joints = {j.get("name"): j for j in root.findall("joint")}
    by_child = {j.find("child").get("link"): j for j in joints.values()}
    below, frontier = set(), {"torso_fixed_link"}
    while frontier:
        link = frontier.pop()
        for j in joints.values():
            if j.find("parent").get("link") == link:
                below.add(j.get("name"))
                frontier.add(j.find("child").get("link"))
    on_paths = set()
    for tip in ("hand_left_grasping_frame", "hand_right_grasping_frame"):
        link = tip
        while link != "torso_fixed_link":
            on_paths.add(by_child[link].get("name"))
            link = by_child[link].find("parent").get("link")
    movable = {"revolute", "continuous", "prismatic"}
    off = sorted(n for n in below - on_paths if joints[n].get("type") in movable)
    assert len(off) == 2 + 2 * 36  # the head and every finger joint of both hands
    with pytest.raises(sa.ConfigError) as error:
        sa.load_robot(_write(tmp_path, tiago_config(lock_others=None)))
    message = str(error.value)
    assert f"{len(off)} joints are off the paths from base_link 'torso_fixed_link'" in message
    assert all(f"'{name}' (revolute)" in message for name in off)
    assert "system.lock_joints" in message and "system.lock_others: true" in message
    assert "wheel" not in message and "\n" not in message  # joints above the bus are not named
    # explicit locks for all of them load the same robot as lock_others
    robot = sa.load_robot(_write(tmp_path, tiago_config(lock_others=None, lock_joints=dict.fromkeys(off, 0.0))))
    reference = sa.load_robot(_write(tmp_path, tiago_config()))
    np.testing.assert_array_equal(robot.link_inertia, reference.link_inertia)


@pytest.mark.parametrize(
    "change, message",
    [
        (
            dict(lock_joints={"head_1_joint": 3.0}),
            r"robot.yaml: system.lock_joints: \(in .*tiago_dual.urdf\) joint 'head_1_joint': the value 3 is "
            r"outside its limits \[-1.309, 1.309\] rad",
        ),
        (
            dict(lock_joints={"torso_lift_joint": 0.5}),
            r"joint 'torso_lift_joint': the value 0.5 is outside its limits \[0, 0.35\] m",
        ),
        (dict(inertia_as_written=None), r"link 'arm_left_tool_link': .*\(system.inertia_as_written: true takes it"),
        (
            dict(tips=["hand_left_grasping_frame", "hand_right_grasping_fram"]),
            r"robot.yaml: system.tips\[1\]: \(in .*\) link 'hand_right_grasping_fram' is not in the URDF "
            r"\(did you mean 'hand_right_grasping_frame'\?\)",
        ),
        (dict(tips=["base_link"]), r"system.tips\[0\]: .*link 'base_link' is not below base_link 'torso_fixed_link'"),
        (dict(tips="hand_left_grasping_frame"), r"system.tips: must be a list of link names"),
        (dict(base_link="torso_fixd_link"), r"system.base_link: .* \(did you mean 'torso_fixed_link'\?\)"),
        (dict(tip=["x"]), r"robot.yaml: system: unknown key 'tip' \(did you mean 'tips'\?\)"),
        (dict(lock_others="yes"), r"system.lock_others: must be true or false"),
    ],
)
def test_system_errors_name_the_file_and_field(tmp_path, change, message):
    erd(TIAGO)
    with pytest.raises(sa.ConfigError, match=message):
        sa.load_robot(_write(tmp_path, tiago_config(**change)))


SPART_STYLE = """<?xml version="1.0" ?>
<robot name="Chaser">
  <material name="Grey"><color rgba="0.2 0.2 0.2 1.0"/></material>
  <link name="Spacecraft"><inertial><origin rpy="0 0 0" xyz="0 0 0"/><mass value="100"/>
    <inertia ixx="10" ixy="0" ixz="0" iyy="12" iyz="0" izz="14"/></inertial></link>
  <joint name="Spacecraft_Panel" type="fixed"><parent link="Spacecraft"/><child link="Panel"/>
    <origin rpy="0 0 0" xyz="0 -0.75 0"/><axis xyz="0 0 1"/></joint>
  <link name="Panel"><inertial><origin rpy="0 0 0" xyz="0 -1.5 0"/><mass value="20"/>
    <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <joint name="J1" type="continuous"><parent link="Spacecraft"/><child link="L1"/>
    <origin rpy="3.1416 -1.570796 0" xyz="1.5 0 0"/><axis xyz="0 0 1"/></joint>
  <link name="L1"><inertial><origin rpy="0 0 0" xyz="0 0.042 0.128"/><mass value="10"/>
    <inertia ixx="0.07" ixy="0" ixz="0" iyy="0.07" iyz="0" izz="0.04"/></inertial></link>
  <joint name="J2" type="continuous"><parent link="Spacecraft"/><child link="L2"/>
    <origin rpy="0 0 0" xyz="-1.5 0 0"/><axis xyz="0 0 1"/></joint>
  <link name="L2"/>
</robot>"""


def test_spart_style_point_masses_need_the_opt_in():
    """SPART's models write point masses (zero inertia) for panels: refused by default, with
    the key that takes them as written; then the panel is merged into the bus."""
    options = dict(source="sc.urdf", base_link="Spacecraft", tips=["L1", "L2"])
    with pytest.raises(sa.ConfigError, match=r"link 'Panel'.*\(system.inertia_as_written: true takes it as written\)"):
        parse_urdf_tree(SPART_STYLE, **options)
    tree = parse_urdf_tree(SPART_STYLE, inertia_as_written=True, **options)
    assert tree.joint_names == ("J1", "J2") and tree.parents == (-1, -1) and tree.tip_bodies == (0, 1)
    assert tree.body_mass[0] == 120.0 and tree.body_links[0] == ("Spacecraft", "Panel")
    np.testing.assert_allclose(tree.body_com[0], [0, -2.25 * 20 / 120, 0])
    assert tree.urdf_types == ("continuous", "continuous")


# Both forms -------------------------------------------------------------------------------


def _baxter_arm(side, **changes):
    arm = {
        "name": side,
        "urdf": {"package": ERD, "path": BAXTER},
        "root_link": f"{side}_arm_mount",
        "tip": f"{side}_gripper",
        "inertia_as_written": True,
        "lock_others": True,
        "mount": {"xyz": [0.0, 0.3 if side == "left" else -0.3, 0.0]},
    }
    arm.update(changes)
    return {k: v for k, v in arm.items() if v is not None}


def test_arms_take_lock_others(tmp_path):
    erd(BAXTER)
    robot = sa.load_robot(_arms_file(tmp_path, [_baxter_arm("left"), _baxter_arm("right")]))
    assert robot.n_joints == 14 and robot.tip_names == ("left/left_gripper", "right/right_gripper")
    assert {"l_gripper_l_finger", "l_gripper_r_finger"} <= set(robot.labels.body_links[6])
    with pytest.raises(sa.ConfigError) as error:
        sa.load_robot(_arms_file(tmp_path, [_baxter_arm("left"), _baxter_arm("right", lock_others=None)]))
    message = str(error.value)
    assert message.startswith(f"{tmp_path / 'robot.yaml'}: arms[1].urdf: ")
    assert "2 joints are off the path from 'right_arm_mount' to 'right_gripper' and not locked" in message
    assert "'r_gripper_l_finger_joint' (prismatic), 'r_gripper_r_finger_joint' (prismatic)" in message
    assert "arms[1].lock_others: true" in message
    with pytest.raises(sa.ConfigError, match=r"link 'left_gripper': .*\(arms\[0\].inertia_as_written: true takes it"):
        sa.load_robot(_arms_file(tmp_path, [_baxter_arm("left", inertia_as_written=None)]))


def test_arms_from_different_urdfs_with_the_same_joint_names(tmp_path):
    erd(UR5)
    ur10 = _ur5_arm("big", urdf={"package": ERD, "path": "robots/ur_description/urdf/ur10_robot.urdf"})
    robot = sa.load_robot(_arms_file(tmp_path, [_ur5_arm("small"), ur10]))
    assert robot.joint_names == tuple(f"{arm}/{j}" for arm in ("small", "big") for j in UR5_JOINTS)
    assert robot.tip_names == ("small/tool0", "big/tool0")
    ur10_mass = xml_subtree_mass(erd("robots/ur_description/urdf/ur10_robot.urdf"), "base_link")
    assert total_mass(robot) == pytest.approx(100.0 + 20.9939 + ur10_mass, rel=1e-13)


@pytest.mark.parametrize("name", ["dual-ur5-servicer", "baxter-system", "tiago-dual-system", "three-arm-servicer"])
def test_shipped_tree_files_validate(name, capsys):
    erd(UR5)
    assert main(["validate", os.path.join(CONFIGS, f"{name}.yaml")]) == 0
    assert f"valid robot ({name}, " in capsys.readouterr().out


def test_single_arm_files_are_unchanged():
    """An ``arm:`` file is still a spatial robot with its shapes (no tip axis)."""
    robot = sa.load_robot(os.path.join(CONFIGS, "ur5-smallsat.yaml"))
    assert type(robot).__name__ == "SpatialRobot" and robot.tip_translation.shape == (3,)


@pytest.mark.parametrize(
    "options, message",
    [
        (dict(tips=["L1", "L1"]), r"sc.urdf: tips\[1\]: link 'L1' is already tips\[0\]"),
        (dict(tips=["Panel"]), r"sc.urdf: tips\[0\]: no movable joint between base_link 'Spacecraft' and 'Panel'"),
        (dict(tips=["L1"], lock_joints={"J1": 0.3}), r"tips\[0\]: no movable joint .* \(all fixed or locked\)"),
        (dict(tips=[]), r"sc.urdf: tips: give one or more tip links"),
        (dict(tips=["L1"]), r"sc.urdf: joint 'J2' \(continuous\) is off the paths from base_link 'Spacecraft'"),
        (
            dict(tips=["L1"], lock_joints={"J11": 0.0}),
            r"sc.urdf: lock_joints: unknown joint 'J11' \(did you mean 'J1'\?\)",
        ),
        (dict(tips=["L1"], base_link="L1"), r"sc.urdf: tips\[0\]: no movable joint between base_link 'L1' and 'L1'"),
    ],
)
def test_system_urdf_errors(options, message):
    options = {"source": "sc.urdf", "base_link": "Spacecraft", "inertia_as_written": True, **options}
    with pytest.raises(sa.ConfigError, match=message):
        parse_urdf_tree(SPART_STYLE, **options)


def test_a_bus_without_mass_is_refused(tmp_path):
    text = SPART_STYLE.replace('<mass value="100"/>', '<mass value="0"/>').replace(
        '<mass value="20"/>', '<mass value="0"/>'
    )
    (tmp_path / "sc.urdf").write_text(text)
    config = {"name": "t", "system": {"urdf": "sc.urdf", "base_link": "Spacecraft", "tips": ["L1", "L2"]}}
    with pytest.raises(
        sa.ConfigError,
        match=r"robot.yaml: system.base_link: the bus 'Spacecraft' and the links rigidly attached to it "
        r"\(Spacecraft, Panel\) have no mass",
    ):
        sa.load_robot(_write(tmp_path, config))


def test_a_floating_joint_above_the_bus_is_dropped():
    """Simulator-style files hang the spacecraft from ``world`` by a floating joint: above the
    bus it is dropped with its link; below the bus it is refused."""
    above = SPART_STYLE.replace(
        "</robot>",
        '<link name="world"/><joint name="float" type="floating"><parent link="world"/>'
        '<child link="Spacecraft"/></joint></robot>',
    )
    tree = parse_urdf_tree(above, source="sc.urdf", base_link="Spacecraft", tips=["L1", "L2"], inertia_as_written=True)
    assert tree.joint_names == ("J1", "J2") and "world" not in tree.body_links[0]
    below = SPART_STYLE.replace('name="J2" type="continuous"', 'name="J2" type="floating"')
    with pytest.raises(sa.ConfigError, match=r"sc.urdf: joint 'J2': type 'floating' is not supported"):
        parse_urdf_tree(below, source="sc.urdf", base_link="Spacecraft", tips=["L1"], inertia_as_written=True)
    with pytest.raises(sa.ConfigError, match=r"lock_joints: joint 'float' is floating; only movable joints"):
        parse_urdf_tree(above, source="sc.urdf", base_link="Spacecraft", tips=["L1", "L2"], lock_joints={"float": 0.0})


def test_three_arm_moving_bodies_agree_with_mujoco():
    """MuJoCo's own URDF reader (it fuses the bus into its world body): the moving bodies'
    mass, centroid and inertia about it, in the bus frame, at random joints."""
    mujoco = pytest.importorskip("mujoco")
    robot = sa.load_robot(os.path.join(CONFIGS, "three-arm-servicer.yaml"))
    model = mujoco.MjModel.from_xml_path(os.path.join(CONFIGS, "urdf", "three_arm_servicer.urdf"))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(1)
    lower = np.where(np.isfinite(robot.joint_lower), robot.joint_lower, -3.0)
    upper = np.where(np.isfinite(robot.joint_upper), robot.joint_upper, 3.0)
    for _ in range(3):
        q = rng.uniform(lower, upper)
        values = dict(zip(robot.joint_names, q, strict=True))
        values.update(Right_Finger_L_Joint=0.02, Right_Finger_R_Joint=0.02)
        for j in range(model.njnt):
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
            data.qpos[model.jnt_qposadr[j]] = values.get(name, 0.0)
        mujoco.mj_kinematics(model, data)
        # MuJoCo's moving bodies, less the camera (merged into our bus by lock_others)
        camera = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "Camera_Head")
        bodies = [b for b in range(1, model.nbody) if b != camera]
        mass = model.body_mass[bodies]
        centroid = mass @ data.xipos[bodies] / mass.sum()
        theirs = np.zeros((3, 3))
        for b in bodies:
            rotation = data.ximat[b].reshape(3, 3)
            d = data.xipos[b] - centroid
            theirs += rotation @ np.diag(model.body_inertia[b]) @ rotation.T
            theirs += model.body_mass[b] * (d @ d * np.eye(3) - np.outer(d, d))
        # ours: walk the tree for every body's pose, then the same sums
        frames, poses = [], []
        for j, parent in enumerate(robot.parents):
            rotation, origin = (np.eye(3), np.zeros(3)) if parent < 0 else poses[parent]
            r = rotation @ robot.joint_rotation[j]
            p = origin + rotation @ robot.joint_translation[j]
            if robot.joint_kinds[j] == "revolute":
                r = r @ _rot(robot.joint_axis[j], q[j])
            else:
                p = p + r @ robot.joint_axis[j] * q[j]
            poses.append((r, p))
            frames.append((r, p + r @ robot.link_com[j]))
        ours_mass = robot.link_mass.sum()
        ours_centroid = sum(m * c for m, (_, c) in zip(robot.link_mass, frames, strict=True)) / ours_mass
        ours = np.zeros((3, 3))
        for m, inertia, (r, c) in zip(robot.link_mass, robot.link_inertia, frames, strict=True):
            d = c - ours_centroid
            ours += r @ inertia @ r.T + m * (d @ d * np.eye(3) - np.outer(d, d))
        assert ours_mass == pytest.approx(mass.sum(), rel=1e-12)
        np.testing.assert_allclose(ours_centroid, centroid, atol=1e-9)
        np.testing.assert_allclose(ours, theirs, atol=1e-8)
