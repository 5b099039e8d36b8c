"""Tree kernels (several arms on one bus) against Pinocchio and MuJoCo.

Two UR5 (example-robot-data) on a 400 kg cube, as in a public dual-arm space-robot
model, and random branched trees whose tips share torso joints (revolute, continuous
and prismatic joints, random inertials), each written as one URDF for the references
(tests/tree_references.py) and built as a TreeRobot from the same numbers. Tips, J*
over all joints, w*, the relative Jacobian, C_w and the reaction null space agree to
1e-10; the bus attitude after a closed joint loop of both arms to 1e-8 rad.
"""

from __future__ import annotations

import functools
import itertools

import jax
import numpy as np
import pytest

import spacearm as sa
from spacearm import inertia
from spacearm.analysis import reaction
from spacearm.kinematics import generic_generalized_jacobian, generic_tip_position
from spacearm.models.spatial import locate_package_file, read_urdf
from spacearm.models.spatial.urdf import rpy_matrix
from spacearm.models.tree import TREE, stack_tree_robots, tree_from_chains
from spacearm.models.tree.primitives import POSTURE_QUANTITIES, segments

from .tree_references import PinocchioTree, random_tree, relative, system_urdf

pin = pytest.importorskip("pinocchio")

UR5 = "robots/ur_description/urdf/ur5_robot.urdf"
MOUNT_XYZ = [[0.3, 0.5526, 0.08], [0.3, -0.5526, 0.08]]
MOUNT_RPY = [[-np.pi / 2, 0.0, 0.0], [np.pi / 2, 0.0, 0.0]]
BUS_MASS = 400.0
BUS_COM = np.array([0.01, -0.02, 0.03])
BUS_INERTIA = BUS_MASS * (2 * 0.4726) ** 2 / 6 * np.eye(3) + np.array([[0, 1, 0], [1, 0, -2], [0, -2, 3.0]])
SEEDS = (0, 1, 2)


def _rotation(rng):
    return rpy_matrix(rng.uniform(-np.pi, np.pi, size=3) * np.array([1.0, 0.45, 1.0]))


@pytest.fixture(scope="session")
def dual():
    """(TreeRobot, system URDF text) of two UR5 on the cube."""
    path = locate_package_file("test", "example-robot-data", UR5)
    with open(path, encoding="utf-8") as handle:
        text = handle.read()
    chain = read_urdf(path, root_link="base_link", tip="tool0")
    robot = tree_from_chains(
        [chain, chain],
        arm_names=["left", "right"],
        mount_xyz=MOUNT_XYZ,
        mount_rpy=MOUNT_RPY,
        base_mass=BUS_MASS,
        base_com=BUS_COM,
        base_inertia=BUS_INERTIA,
        name="dual_ur5",
    )
    urdf = system_urdf(
        base_mass=BUS_MASS,
        base_com=BUS_COM,
        base_inertia=BUS_INERTIA,
        arms=[
            (f"{arm}/", text, "base_link", x, r)
            for arm, x, r in zip(("left", "right"), MOUNT_XYZ, MOUNT_RPY, strict=True)
        ],
    )
    return robot, urdf


@pytest.fixture(scope="session")
def dual_pin(dual):
    robot, urdf = dual
    return PinocchioTree(urdf, robot.joint_names, robot.tip_names)


@pytest.fixture(scope="session")
def dual_postures():
    rng = np.random.default_rng(7)
    return rng.uniform(-np.pi, np.pi, size=(6, 12)), np.stack([_rotation(rng) for _ in range(6)])


def _blkdiag(R, J):
    return np.concatenate([R @ J[..., :3, :], R @ J[..., 3:, :]], axis=-2)


def _pairs(robot) -> tuple[tuple[int, int], ...]:
    k = robot.n_tips
    return tuple((i, j) for i in range(k) for j in range(k) if i != j)[:3]


def _kernels(robot, q, R, pairs):
    """The public kernels `_check_against` compares: tips, J*, w*, C, fixed-base J, J_rel per pair."""
    return (
        sa.tip_position(robot, q, base_rotation=R),
        sa.generalized_jacobian(robot, q, base_rotation=R),
        sa.manipulability(robot, q),
        sa.base_rate_matrix(robot, q),
        sa.fixed_base_jacobian(robot, q),
        {pair: sa.relative_jacobian(robot, q, base_rotation=R, tips=pair) for pair in pairs},
    )


@functools.partial(jax.jit, static_argnames=("pairs",))
def _kernels_in_one_program(robot, q, R, pairs):
    """`_kernels` and the mass matrices H_m and H* at q[0], as one program. The kernels are
    jitted functions, inlined here unchanged: a random tree's new structure then compiles
    once (~10 s CPU) instead of once per kernel (~17 s)."""
    return _kernels(robot, q, R, pairs), sa.joint_mass_matrix(robot, q[0]), sa.arm_inertia(robot, q[0])


def _check_against(robot, reference, q, R, values=None):
    """Every public kernel at postures q (b, n) and attitudes R (b, 3, 3) against the reference
    (``values``: `_kernels` already evaluated; None: each kernel called on its own)."""
    pairs = _pairs(robot)
    values = _kernels(robot, q, R, pairs) if values is None else values
    tips, J, w, C, fixed = (np.asarray(v) for v in values[:5])
    relatives = {pair: np.asarray(v) for pair, v in values[5].items()}
    k, n = robot.n_tips, robot.n_joints
    assert tips.shape == (len(q), k, 3) and J.shape == (len(q), k, 6, n)
    assert w.shape == (len(q), k) and C.shape == (len(q), 6, n) and fixed.shape == (len(q), k, 6, n)
    for b in range(len(q)):
        ref = reference.evaluate(q[b])
        np.testing.assert_allclose(tips[b], ref["tip"] @ R[b].T, atol=1e-10)
        np.testing.assert_allclose(J[b], _blkdiag(R[b], ref["jstar"]), atol=1e-10)
        np.testing.assert_allclose(fixed[b], ref["fixed"], atol=1e-10)
        Jv = ref["jstar"][:, :3]
        np.testing.assert_allclose(w[b], np.sqrt(np.linalg.det(Jv @ np.swapaxes(Jv, 1, 2))), rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(C[b, 3:], ref["base"][3:], atol=1e-10)
        # The reaction null space: rank C_w = 3, dimension n - 3, and the reference's C_w vanishes on it.
        _, sv, vt = np.linalg.svd(C[b, 3:])
        assert sv[-1] > 1e-6 * sv[0]
        null = vt[3:].T
        assert null.shape == (n, n - 3)
        np.testing.assert_allclose(ref["base"][3:] @ null, 0.0, atol=1e-10)
        for i, j in pairs:
            J_rel = relatives[i, j][b]
            expected = _blkdiag(R[b], relative(ref["jstar"], ref["tip"], i, j))
            np.testing.assert_allclose(J_rel, expected, atol=1e-10)
            # The bus drops out: the same from the fixed-base Jacobians.
            np.testing.assert_allclose(J_rel, _blkdiag(R[b], relative(ref["fixed"], ref["tip"], i, j)), atol=1e-10)


def test_dual_ur5_against_pinocchio(dual, dual_pin, dual_postures):
    """Tips, J*, w*, J_rel, C_w and the reaction null space of two UR5 on a cube (Pinocchio free-flyer)."""
    robot, _ = dual
    q, R = dual_postures
    _check_against(robot, dual_pin, q, R)
    by_name = sa.relative_jacobian(robot, q[0], tips=("right/tool0", "left/tool0"))
    np.testing.assert_allclose(by_name, sa.relative_jacobian(robot, q[0], tips=(1, 0)), atol=0)


def test_other_arm_columns_are_not_zero(dual, dual_pin, dual_postures, capsys):
    """Tip 1's J* has non-zero columns for arm 2 (a few % of its own: moving arm 2 moves the bus)."""
    robot, _ = dual
    q, _ = dual_postures
    J = np.asarray(sa.generalized_jacobian(robot, q))
    ratio = np.linalg.norm(J[:, 0, :, 6:], axis=(1, 2)) / np.linalg.norm(J[:, 0, :, :6], axis=(1, 2))
    reference = [dual_pin.evaluate(x)["jstar"][0] for x in q]
    expected = [np.linalg.norm(j[:, 6:]) / np.linalg.norm(j[:, :6]) for j in reference]
    np.testing.assert_allclose(ratio, expected, rtol=1e-9)
    assert np.all(ratio > 1e-3) and np.all(ratio < 0.2)
    fixed = np.asarray(sa.fixed_base_jacobian(robot, q))
    assert np.all(fixed[:, 0, :, 6:] == 0) and np.all(fixed[:, 1, :, :6] == 0)
    with capsys.disabled():
        print(f"\n  dual UR5: arm 2 columns / arm 1 columns of tip 1's J*: median {np.median(ratio):.2%}")


@pytest.mark.parametrize("seed", SEEDS)
def test_random_tree_against_pinocchio(seed):
    """A random tree (shared torso, revolute/continuous/prismatic joints, three tips) against Pinocchio.

    Each seed draws other joint kinds, a new static structure: its kernels compile anew, as
    one program (~10 s CPU)."""
    urdf, robot = random_tree(seed)
    assert min(robot.support[:, 0]) and len(set(robot.labels.urdf_types)) >= 2
    reference = PinocchioTree(urdf, robot.joint_names, robot.tip_names)
    rng = np.random.default_rng(100 + seed)
    q = rng.uniform(-1.5, 1.5, size=(2, robot.n_joints))
    R = np.stack([_rotation(rng) for _ in range(2)])
    values, mass_matrix, arm_inertia = _kernels_in_one_program(robot, q, R, _pairs(robot))
    _check_against(robot, reference, q, R, values)
    # H_m and H* over the tree (Pinocchio's joint-space block and its Schur complement).
    model, data = reference.model, reference.data
    M = pin.crba(model, data, reference.config(q[0]))
    M = np.triu(M) + np.triu(M, 1).T
    cols = np.array([j.idx_v for j in reference.joints])
    H_m = M[np.ix_(cols, cols)]
    H_star = H_m - M[cols, :6] @ np.linalg.solve(M[:6, :6], M[:6, cols])
    np.testing.assert_allclose(mass_matrix, H_m, atol=1e-10)
    np.testing.assert_allclose(arm_inertia, H_star, atol=1e-10)


def test_tree_metrics_against_pinocchio(dual, dual_pin, dual_postures):
    """C in inertial axes, the reaction null space, w*_w and w_d per tip from Pinocchio's M and J*."""
    robot, _ = dual
    q, R = dual_postures
    C = np.asarray(inertia.base_twist_map(robot, q, base_rotation=R))
    N = np.asarray(reaction.reaction_null_space(robot, q))
    w_rot = np.asarray(inertia.rotational_manipulability(robot, q))
    w_d = np.asarray(inertia.dynamic_manipulability(robot, q))
    assert N.shape == (len(q), 12, 9) and w_d.shape == (len(q), 2)
    model, data = dual_pin.model, dual_pin.data
    cols = np.array([j.idx_v for j in dual_pin.joints])
    for b in range(len(q)):
        ref = dual_pin.evaluate(q[b])
        np.testing.assert_allclose(C[b, 3:], R[b] @ ref["base"][3:], atol=1e-10)
        np.testing.assert_allclose(N[b].T @ N[b], np.eye(9), atol=1e-12)
        np.testing.assert_allclose(ref["base"][3:] @ N[b], 0.0, atol=1e-10)
        Jw = ref["jstar"][:, 3:]
        np.testing.assert_allclose(w_rot[b], np.sqrt(np.linalg.det(Jw @ np.swapaxes(Jw, 1, 2))), rtol=1e-9)
        M = pin.crba(model, data, dual_pin.config(q[b]))
        M = np.triu(M) + np.triu(M, 1).T
        H = M[np.ix_(cols, cols)] - M[cols, :6] @ np.linalg.solve(M[:6, :6], M[:6, cols])
        K = ref["jstar"][:, :3] @ np.linalg.inv(H)
        np.testing.assert_allclose(w_d[b], np.sqrt(np.linalg.det(K @ np.swapaxes(K, 1, 2))), rtol=1e-9)
    with pytest.raises(TypeError, match="no rotational rows for a planar robot"):
        inertia.rotational_manipulability(sa.umetani1990(), np.zeros(3))


def test_posture_quantities_in_one_pass(dual):
    """J*, C and H* from one pass over the tree equal their own kernels."""
    robot, _ = dual
    q = np.random.default_rng(9).uniform(-2, 2, size=(2, 3, 12))
    got = jax.jit(lambda r, x: TREE.fast_paths.posture_quantities(r, x, POSTURE_QUANTITIES))(robot, q)
    assert got["jacobian"].shape == (2, 3, 2, 6, 12) and got["arm_inertia"].shape == (2, 3, 12, 12)
    np.testing.assert_allclose(got["jacobian"], sa.generalized_jacobian(robot, q), atol=1e-13)
    np.testing.assert_allclose(got["base_rate"], sa.base_rate_matrix(robot, q), atol=1e-13)
    np.testing.assert_allclose(got["arm_inertia"], sa.arm_inertia(robot, q), atol=1e-12)


def test_second_mount_moves_first_w_star(dual):
    """d w*_1 / d mount_xyz of arm 2 is not zero and matches central differences.

    Compiles the reverse-mode program of the tree pass (~10 s CPU), and a design vmap."""
    robot, _ = dual
    q = np.random.default_rng(4).uniform(-2, 2, size=12)
    w_first = lambda r: sa.manipulability(r, q)[0]
    grad = np.asarray(jax.grad(w_first)(robot).mount_xyz)
    h, moved = 1e-6, []
    for sign in (1.0, -1.0):
        xyz = np.array(robot.mount_xyz)
        xyz[1, 1] += sign * h
        moved.append(float(w_first(robot.replace(mount_xyz=xyz))))
    assert abs(grad[1, 1]) > 1e-5
    np.testing.assert_allclose(grad[1, 1], (moved[0] - moved[1]) / (2 * h), rtol=1e-5)
    designs = stack_tree_robots([robot, robot.replace(mount_xyz=np.array(robot.mount_xyz) + 0.1)])
    J = jax.vmap(sa.generalized_jacobian, in_axes=(0, None))(designs, q)
    np.testing.assert_allclose(J[1], sa.generalized_jacobian(jax.tree.map(lambda x: x[1], designs), q), atol=1e-14)


def test_segments_of_a_tree():
    _, robot = random_tree(0, torso=2, branches=(3, 1, 2))
    assert segments(robot.parents) == ((0, 5, -1), (5, 6, 1), (6, 8, 1))


def test_generic_path_equals_fast_path(dual):
    """J_M - J_S I_S^-1 I_M from the stacked primitives equals the closed form, per tip."""
    robot, _ = dual
    q = np.random.default_rng(3).uniform(-2, 2, size=(3, 12))
    generic = jax.jit(lambda r, x: (generic_generalized_jacobian(r, x), generic_tip_position(r, x)))(robot, q)
    np.testing.assert_allclose(generic[0], sa.generalized_jacobian(robot, q), atol=1e-12)
    np.testing.assert_allclose(generic[1], sa.tip_position(robot, q), atol=1e-14)
    Jv = np.asarray(generic[0])[..., :3, :]
    w = np.sqrt(np.linalg.det(Jv @ np.swapaxes(Jv, -1, -2)))
    np.testing.assert_allclose(w, sa.manipulability(robot, q), rtol=1e-10)
    I_S, I_M = jax.jit(TREE.momentum_map)(robot, q[0])
    np.testing.assert_allclose(-np.linalg.solve(I_S, I_M), sa.base_rate_matrix(robot, q[0]), atol=1e-12)


def test_batch_shapes_and_blocks(dual):
    """Leading batch axes, an attitude per posture, and the blocked path for big batches."""
    robot, _ = dual
    rng = np.random.default_rng(5)
    q = rng.uniform(-2, 2, size=(2, 3, 12))
    R = np.stack([np.stack([_rotation(rng) for _ in range(3)]) for _ in range(2)])
    J = sa.generalized_jacobian(robot, q, base_rotation=R)
    assert J.shape == (2, 3, 2, 6, 12) and sa.tip_position(robot, q, base_rotation=R).shape == (2, 3, 2, 3)
    np.testing.assert_allclose(J[1, 2], _blkdiag(R[1, 2], np.asarray(sa.generalized_jacobian(robot, q[1, 2]))))
    assert sa.relative_jacobian(robot, q, base_rotation=R, tips=(0, 1)).shape == (2, 3, 6, 12)
    many = rng.uniform(-2, 2, size=(2100, 12))
    w = np.asarray(sa.manipulability(robot, many))
    np.testing.assert_allclose(w[[0, 2099]], np.asarray(sa.manipulability(robot, many[[0, 2099]])), rtol=1e-12)


def test_relative_jacobian_refuses():
    _, robot = random_tree(1)
    with pytest.raises(ValueError, match="unknown tip 'nope'"):
        sa.relative_jacobian(robot, np.zeros(robot.n_joints), tips=("tip0", "nope"))
    with pytest.raises(ValueError, match="out of range"):
        sa.relative_jacobian(robot, np.zeros(robot.n_joints), tips=(0, 5))
    with pytest.raises(TypeError, match="several tips, got a PlanarRobot"):
        sa.relative_jacobian(sa.umetani1990(), np.zeros(3))
    with pytest.raises(TypeError, match=r"straight tip paths: a tree robot with \d+ tips; choose one with robot.focus"):
        TREE.straight_maps(robot, np.zeros(robot.n_joints))


def _pinocchio_loop(reference, waypoints, steps):
    """Bus attitude after a joint polyline: RK4 on R' = R [C_w(q) q']x, C_w from Pinocchio."""

    def omega(q, rate):
        return reference.evaluate(q)["base"][3:] @ rate

    def hat(w):
        return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])

    R = np.eye(3)
    for a, b in itertools.pairwise(waypoints):
        rate, h = b - a, 1.0 / steps
        for i in range(steps):
            t = i * h
            w0, wm, w1 = omega(a + t * rate, rate), omega(a + (t + h / 2) * rate, rate), omega(a + (t + h) * rate, rate)
            k1 = R @ hat(w0)
            k2 = (R + h / 2 * k1) @ hat(wm)
            k3 = (R + h / 2 * k2) @ hat(wm)
            k4 = (R + h * k3) @ hat(w1)
            R = R + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return R


def test_bus_attitude_after_a_loop_of_both_arms(dual, dual_pin, capsys):
    """A closed joint loop of both arms turns the bus; Magnus over the tree = RK4 over Pinocchio (1e-8 rad)."""
    robot, _ = dual
    rng = np.random.default_rng(11)
    start = rng.uniform(-1, 1, size=12)
    waypoints = np.stack([start, start + rng.uniform(-1, 1, 12), start + rng.uniform(-1, 1, 12), start])
    R_end, q_end = sa.integrate_joint_path(robot, start, waypoints)
    np.testing.assert_allclose(q_end, start)
    reference = _pinocchio_loop(dual_pin, waypoints, 150)
    angle = np.linalg.norm(_log(np.asarray(R_end).T @ reference))
    turned = np.linalg.norm(_log(reference))
    assert turned > 1e-3, turned
    assert angle < 1e-8, angle
    with capsys.disabled():
        print(f"\n  dual UR5 loop: bus turned {turned:.4f} rad, Magnus vs Pinocchio RK4 {angle:.1e} rad")


def _log(R):
    angle = np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / 2
    return w if angle < 1e-12 else w * angle / np.sin(angle)


def test_dual_ur5_against_mujoco(dual, dual_postures):
    """MuJoCo's own URDF import with a free joint on the bus: mj_jac + momentum conservation."""
    mujoco = pytest.importorskip("mujoco")
    robot, urdf = dual
    urdf = urdf.replace(
        '<robot name="system">', '<robot name="system"><mujoco><compiler fusestatic="false"/></mujoco>', 1
    )
    spec = mujoco.MjSpec.from_string(urdf)
    spec.option.gravity = [0, 0, 0]
    spec.worldbody.first_body().add_freejoint()
    model = spec.compile()
    model.dof_damping[:] = model.dof_armature[:] = model.dof_frictionloss[:] = 0
    data = mujoco.MjData(model)
    joints = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name) for name in robot.joint_names]
    cols = np.array([model.jnt_dofadr[j] for j in joints])
    bodies = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name) for name in robot.tip_names]
    q, _ = dual_postures
    J = np.asarray(sa.generalized_jacobian(robot, q))
    for b in range(len(q)):
        data.qpos[:7] = [0, 0, 0, 1, 0, 0, 0]
        data.qpos[[model.jnt_qposadr[j] for j in joints]] = q[b]
        mujoco.mj_forward(model, data)
        M = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, M)
        solve = np.linalg.solve(M[:6, :6], M[:6][:, cols])
        for t, body in enumerate(bodies):
            jp, jr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
            mujoco.mj_jac(model, data, jp, jr, data.xpos[body], body)
            full = np.vstack([jp, jr])
            np.testing.assert_allclose(J[b, t], full[:, cols] - full[:, :6] @ solve, atol=1e-10)
