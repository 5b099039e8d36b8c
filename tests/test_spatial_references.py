"""The spatial kernels against three independent URDF readers and dynamics libraries.

Pinocchio (crba + frame Jacobian, LOCAL_WORLD_ALIGNED), iDynTree (MIXED representation)
and MuJoCo (its own URDF parser, mj_fullM + mj_jacBody) each read the same arm, bus and
mount, written into one URDF (tests/spatial_references.py). J* = J_m - J_b H_b^-1 H_bm
does not depend on each library's base coordinates (SPATIAL.md), so J*, the tip about
the system centroid, H_m and H* compare directly. Agreement to 1e-10 (observed ~1e-14).
"""

import os

import jax
import numpy as np
import pytest

import spacearm as sa
from spacearm.models import spatial
from spacearm.models.spatial import primitives
from spacearm.models.spatial.robot import robot_from_chain

from .spatial_references import (
    combined_urdf,
    idyntree_reference,
    mujoco_model,
    mujoco_reference,
    pinocchio_reference,
    random_chain_urdf,
)

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")
TOLERANCE = 1e-10

BUS = {
    "base_mass": 80.0,
    "base_com": [0.1, -0.2, 0.05],
    "base_inertia": np.array([[9.0, 0.3, -0.2], [0.3, 8.0, 0.1], [-0.2, 0.1, 7.5]]),
    "mount_xyz": [0.4, 0.1, 0.3],
    "mount_rpy": [0.3, -0.5, 1.1],
}


def _random_case(seed, n=6, kinds=None):
    rng = np.random.default_rng(seed)
    text, names, lock, tip = random_chain_urdf(rng, n, kinds)
    chain = spatial.parse_urdf(text, root_link="root", tip=tip, lock_joints=lock)
    robot = robot_from_chain(chain, **BUS)
    combined = combined_urdf(text, root_link="root", lock_joints=lock, **BUS)
    return robot, combined, names, tip, rng


@jax.jit
def _everything(robot, q):
    # One program per arm structure (nested jits inline): keeps the compile count low.
    return {
        "jstar": sa.generalized_jacobian(robot, q),
        "tip": sa.tip_position(robot, q),
        "fixed": sa.fixed_base_jacobian(robot, q),
        "mass_matrix": sa.joint_mass_matrix(robot, q),
        "arm_inertia": sa.arm_inertia(robot, q),
        "base_rate": sa.base_rate_matrix(robot, q),
    }


def _mine(robot, qs):
    """All kernels for a batch of postures ``(k, n)``: a list of k dicts of numpy arrays."""
    out = {key: np.asarray(value) for key, value in _everything(robot, np.asarray(qs)).items()}
    return [{key: value[i] for key, value in out.items()} for i in range(len(qs))]


def _compare(reference, mine, label):
    for key, value in reference.items():
        if key in mine:
            scale = max(1.0, float(np.max(np.abs(value))))
            np.testing.assert_allclose(mine[key], value, rtol=0, atol=TOLERANCE * scale, err_msg=f"{label}: {key}")


SEEDS_AND_KINDS = [
    (0, None),  # revolute, continuous, prismatic in turn
    (1, ["prismatic", "revolute", "continuous", "revolute", "prismatic", "continuous"]),
    (2, ["continuous"] * 7),
    (3, ["revolute", "prismatic", "prismatic"]),
]


@pytest.mark.parametrize("seed, kinds", SEEDS_AND_KINDS)
def test_random_chains_agree_with_pinocchio(seed, kinds):
    pytest.importorskip("pinocchio")
    n = len(kinds) if kinds else 6
    robot, combined, names, tip, rng = _random_case(seed, n, kinds)
    qs = rng.uniform(-2.0, 2.0, (3, n))
    for q, mine in zip(qs, _mine(robot, qs), strict=False):
        reference = pinocchio_reference(combined, names, tip, q)
        _compare(reference, mine, f"seed {seed}")
        # C(q): Pinocchio's free-flyer twist is the bus origin's [v; w] (bus pose = identity).
        C = mine["base_rate"]
        rate = reference["free_flyer_rate"]
        w = rate[3:]
        v_centroid = rate[:3] + np.cross(w.T, np.asarray(BUS["base_com"])).T
        np.testing.assert_allclose(C, np.vstack([v_centroid, w]), atol=TOLERANCE)


@pytest.mark.parametrize("seed, kinds", SEEDS_AND_KINDS[:2])
def test_random_chains_agree_with_idyntree_mixed(seed, kinds):
    pytest.importorskip("idyntree")
    n = len(kinds) if kinds else 6
    robot, combined, names, tip, rng = _random_case(seed, n, kinds)
    qs = rng.uniform(-2.0, 2.0, (3, n))
    for q, mine in zip(qs, _mine(robot, qs), strict=False):
        _compare(idyntree_reference(combined, names, tip, q), mine, f"seed {seed}")


@pytest.mark.parametrize("seed, kinds", SEEDS_AND_KINDS[:2])
def test_random_chains_agree_with_mujoco(seed, kinds):
    pytest.importorskip("mujoco")
    n = len(kinds) if kinds else 6
    robot, combined, names, tip, rng = _random_case(seed, n, kinds)
    model = mujoco_model(combined)
    qs = rng.uniform(-2.0, 2.0, (3, n))
    for q, mine in zip(qs, _mine(robot, qs), strict=False):
        _compare(mujoco_reference(model, names, tip, q), mine, f"seed {seed}")


# Real arms ------------------------------------------------------------------------------

REAL_ARMS = {
    "ur5": ("robots/ur_description/urdf/ur5_robot.urdf", "base_link", "tool0", {}),
    "panda": (
        "robots/panda_description/urdf/panda.urdf",
        "panda_link0",
        "panda_hand_tcp",
        {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.03},
    ),
    "kinova": ("robots/kinova_description/robots/kinova.urdf", "base", "j2s6s200_end_effector", {}),
    "z1": ("robots/z1_description/urdf/z1.urdf", "link00", "gripperStator", {"jointGripper": -0.5}),
    "xarm7": ("robots/xarm_description/urdf/xarm7.urdf", "link_base", "link_eef", {}),
}


def _real_case(name):
    path, root, tip, lock = REAL_ARMS[name]
    try:
        urdf = spatial.locate_package_file("test", "example-robot-data", path)
    except sa.ConfigError:
        pytest.skip("example-robot-data is not installed")
    robot = sa.load_robot(
        {
            "name": name,
            "base": {"mass": 500.0, "com": [-0.2, 0.05, -0.1], "inertia": [[80, 1, 0], [1, 95, 2], [0, 2, 120]]},
            "mount": {"xyz": [0.6, 0.1, 0.5], "rpy": [0.1, -0.2, 0.3]},
            "arm": {"urdf": urdf, "root_link": root, "tip": tip, "lock_joints": lock, "inertia_as_written": True},
        }
    )
    with open(urdf, encoding="utf-8") as handle:
        text = handle.read()
    combined = combined_urdf(
        text,
        root_link=root,
        lock_joints=lock,
        base_mass=500.0,
        base_com=[-0.2, 0.05, -0.1],
        base_inertia=[[80, 1, 0], [1, 95, 2], [0, 2, 120]],
        mount_xyz=[0.6, 0.1, 0.5],
        mount_rpy=[0.1, -0.2, 0.3],
    )
    return robot, combined, tip


@pytest.mark.parametrize("name", sorted(REAL_ARMS))
def test_real_arms_agree_with_pinocchio(name):
    pytest.importorskip("pinocchio")
    robot, combined, tip = _real_case(name)
    qs = np.random.default_rng(len(name)).uniform(-2.5, 2.5, (3, robot.n_joints))
    for q, mine in zip(qs, _mine(robot, qs), strict=False):
        _compare(pinocchio_reference(combined, robot.joint_names, tip, q), mine, name)


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_real_arms_agree_with_idyntree_and_mujoco(name):
    pytest.importorskip("idyntree")
    pytest.importorskip("mujoco")
    robot, combined, tip = _real_case(name)
    model = mujoco_model(combined)
    qs = np.random.default_rng(5).uniform(-2.5, 2.5, (3, robot.n_joints))
    for q, mine in zip(qs, _mine(robot, qs), strict=False):
        _compare(idyntree_reference(combined, robot.joint_names, tip, q), mine, f"{name} iDynTree")
        _compare(mujoco_reference(model, robot.joint_names, tip, q), mine, f"{name} MuJoCo")


@pytest.mark.parametrize("config", ["ur5-smallsat", "ets7", "arm3dof-100kg"])
def test_example_robot_files_agree_with_pinocchio(config):
    pytest.importorskip("pinocchio")
    import yaml

    path = os.path.join(CONFIGS, f"{config}.yaml")
    robot = sa.load_robot(path)
    with open(path, encoding="utf-8") as handle:
        spec = yaml.safe_load(handle)
    arm = spec["arm"]
    urdf = arm["urdf"]
    urdf = (
        spatial.locate_package_file(path, urdf["package"], urdf["path"])
        if isinstance(urdf, dict)
        else os.path.join(CONFIGS, urdf)
    )
    with open(urdf, encoding="utf-8") as handle:
        text = handle.read()
    combined = combined_urdf(
        text,
        root_link=arm["root_link"],
        lock_joints=arm.get("lock_joints") or {},
        base_mass=spec["base"]["mass"],
        base_com=spec["base"].get("com", [0, 0, 0]),
        base_inertia=spec["base"]["inertia"],
        mount_xyz=spec["mount"]["xyz"],
        mount_rpy=spec["mount"]["rpy"],
    )
    qs = np.random.default_rng(11).uniform(-2.5, 2.5, (3, robot.n_joints))
    for q, mine in zip(qs, _mine(robot, qs), strict=False):
        _compare(pinocchio_reference(combined, robot.joint_names, arm["tip"], q), mine, config)


def test_spatial_md_recipe_for_the_ur5_smallsat():
    """The recipe of SPATIAL.md verbatim: free-flyer on the URDF root, bus appended in code."""
    pin = pytest.importorskip("pinocchio")
    robot = sa.load_robot(os.path.join(CONFIGS, "ur5-smallsat.yaml"))
    urdf = spatial.locate_package_file("test", "example-robot-data", "robots/ur_description/urdf/ur5_robot.urdf")
    model = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
    R_mount = pin.rpy.rpyToMatrix(0.1, -0.2, 0.3)
    X_mount = pin.SE3(R_mount, np.array([0.6, 0.1, 0.5]))
    # The free-flyer carries the URDF root `world`; world -> base_link is the identity here.
    model.appendBodyToJoint(
        1,
        pin.Inertia(500.0, np.array([-0.2, 0.05, -0.1]), np.array([[80.0, 1, 0], [1, 95, 2], [0, 2, 120]])),
        X_mount.inverse(),
    )
    data = model.createData()
    tip = model.getFrameId("tool0")
    qs = np.random.default_rng(3).uniform(-3, 3, (3, 6))
    for joint_q, mine in zip(qs, _mine(robot, qs), strict=False):
        q = pin.neutral(model)
        q[:3] = X_mount.translation
        q[3:7] = pin.Quaternion(X_mount.rotation).coeffs()
        q[7:] = joint_q
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        J = pin.computeFrameJacobian(model, data, q, tip, pin.LOCAL_WORLD_ALIGNED)
        jstar = J[:, 6:] - J[:, :6] @ np.linalg.solve(M[:6, :6], M[:6, 6:])
        np.testing.assert_allclose(mine["jstar"], jstar, atol=TOLERANCE)


def test_one_pass_primitives_are_consistent():
    """The closed-form J* equals J_M - J_S I_S^-1 I_M of the seam primitives."""
    robot, _, _, _, rng = _random_case(4)
    for q in rng.uniform(-2, 2, (4, robot.n_joints)):
        J_S, J_M = primitives.jacobians(robot, q)
        I_S, I_M = primitives.momentum_map(robot, q)
        generic = np.asarray(J_M) - np.asarray(J_S) @ np.linalg.solve(np.asarray(I_S), np.asarray(I_M))
        np.testing.assert_allclose(primitives.generalized_jacobian(robot, q), generic, atol=1e-13)
