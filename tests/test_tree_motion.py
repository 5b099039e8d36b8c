"""Motion and planning for several arms on one bus, through the one generic stack.

A tree focused on one tip and some moving joints (`TreeRobot.focus`) is a single-tip
robot: the straight-path, reach, reorientation and reaction-free planners serve it
unchanged. Checked against independent references: the focused kernels against the
whole tree's, the bus attitude along joint paths against RK4 on the generic momentum
map (I_S, I_M by a solve, not the closed form the Magnus integrator uses), straight and
reaction-free paths against their line and an independent integration of the bus
attitude, reorientation against the integrator on the whole (unfocused) robot, and the
tip shell against sampled tips and the spatial arm's shell.

The two UR5 on a 400 kg servicer (configs/dual-ur5-servicer.yaml) need the test extra
(example-robot-data).
"""

from __future__ import annotations

import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import spacearm as sa
from spacearm._core.groups import expm, geodesic_distance
from spacearm.analysis import reaction
from spacearm.cli import main
from spacearm.kinematics import generic_generalized_jacobian, generic_tip_position
from spacearm.models.family import family_of
from spacearm.models.spatial import locate_package_file, read_urdf
from spacearm.models.tree import tree_from_chains
from spacearm.models.tree.primitives import tip_pose
from spacearm.models.tree.shell import tip_shell

from .conftest import count_compiles

ROOT = os.path.join(os.path.dirname(__file__), "..")
DUAL = os.path.join(ROOT, "configs", "dual-ur5-servicer.yaml")
TREES = ("dual-ur5-servicer", "baxter-system", "tiago-dual-system", "three-arm-servicer")
Q_DEG = [20.0, -70.0, 90.0, -50.0, 70.0, 20.0] * 2
Q0 = np.radians(Q_DEG)
D = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint")


@pytest.fixture(scope="session")
def dual():
    return sa.load_robot(DUAL)


@pytest.fixture(scope="session")
def right_alone(dual):
    """The right tip, the left arm held."""
    return dual.focus(tip="right/tool0", moving=("right",))


@jax.jit
def _generic_bus_rate(robot, q):
    """C_w from the generic momentum map: -(I_S^-1 I_M) by a solve, angular rows (bus axes)."""
    family = family_of(robot)
    I_S, I_M = family.momentum_map(robot, q)
    return -jnp.linalg.solve(I_S, I_M)[3:]


@jax.jit
def _rk4_polyline(robot, waypoints, steps_per_segment):
    """Bus attitude after a joint polyline: classical RK4 on R' = R [C_w(q) q']x, fixed steps."""

    def hat(w):
        return jnp.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])

    steps = steps_per_segment.shape[0]
    h = 1.0 / steps

    def segment(R, ab):
        a, b = ab
        rate = b - a

        def step(R, i):
            t = i * h
            w0, wm, w1 = (hat(_generic_bus_rate(robot, a + s * rate) @ rate) for s in (t, t + h / 2, t + h))
            k1 = R @ w0
            k2 = (R + h / 2 * k1) @ wm
            k3 = (R + h / 2 * k2) @ wm
            k4 = (R + h * k3) @ w1
            return R + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), None

        return jax.lax.scan(step, R, jnp.arange(steps, dtype=waypoints.dtype))[0], None

    return jax.lax.scan(segment, jnp.eye(3, dtype=waypoints.dtype), (waypoints[:-1], waypoints[1:]))[0]


def _turn(R):
    return float(np.asarray(geodesic_distance(np.eye(3), np.asarray(R))))


# The focus ----------------------------------------------------------------------------------


@jax.jit
def _focus_kernels(robot, q, R):
    """The public kernels the focus test reads, as one program per robot (the jitted kernels
    inlined unchanged): each focus is a new tree structure, compiled once instead of once per
    kernel. Tips and J* in inertial axes (R) and in bus axes, C, w*."""
    return (
        sa.tip_position(robot, q, R),
        sa.generalized_jacobian(robot, q, R),
        sa.base_rate_matrix(robot, q),
        sa.manipulability(robot, q),
        sa.tip_position(robot, q),
        sa.generalized_jacobian(robot, q),
    )


def test_focus_is_the_chosen_tip_with_held_columns_zero(dual, right_alone):
    q = np.random.default_rng(0).uniform(-2.0, 2.0, (3, 12))
    R = np.asarray(expm(np.array([0.3, -0.2, 0.5])))
    tips, J, C, _, _, J_bus = (np.asarray(x) for x in _focus_kernels(dual, q, R))
    tips_f, Jf, Cf, wf, tips_f_bus, Jf_bus = (np.asarray(x) for x in _focus_kernels(right_alone, q, R))
    np.testing.assert_array_equal(tips_f, tips[:, 1])
    assert Jf.shape == (3, 6, 12)
    np.testing.assert_array_equal(Jf[..., :6], 0.0)  # the held arm's columns
    np.testing.assert_allclose(Jf[..., 6:], J[:, 1, :, 6:], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(Cf[..., :6], 0.0)
    np.testing.assert_allclose(Cf[..., 6:], C[..., 6:], atol=1e-15)
    Jv = J[:, 1, :3, 6:]
    np.testing.assert_allclose(wf, np.sqrt(np.linalg.det(Jv @ np.swapaxes(Jv, -1, -2))), rtol=1e-12)
    # the generic path over the focused primitives (J_S, J_M, I_S, I_M) equals the fast path
    generic_J, generic_tip = jax.jit(lambda r, q: (generic_generalized_jacobian(r, q), generic_tip_position(r, q)))(
        right_alone, q
    )
    np.testing.assert_allclose(generic_J, Jf_bus, atol=1e-14)
    np.testing.assert_allclose(generic_tip, tips_f_bus, atol=1e-15)
    # a focus on one tip with every joint moving: the tip's J* over all joints (the other arm's columns are not zero)
    left = dual.focus(tip="left/tool0")
    np.testing.assert_array_equal(sa.generalized_jacobian(left, q), J_bus[:, 0])
    assert family_of(left).tip_count(left) is None and family_of(dual).tip_count(dual) == 2


def test_focus_locks_the_held_joints_in_the_inertias(dual, right_alone):
    """H* of the focused tree: the moving block, identity on the held joints (their rates are
    zero); the metrics' posture quantities are the focused kernels'."""
    q = np.random.default_rng(4).uniform(-2.0, 2.0, 12)
    family = family_of(right_alone)
    full = np.asarray(jax.jit(sa.arm_inertia)(dual, q))
    # the focused robot's inertia, posture quantities and public kernels: one program
    held, quantities, J, C = jax.jit(
        lambda r, q: (
            sa.arm_inertia(r, q),
            family.fast_paths.posture_quantities(r, q, ("jacobian", "base_rate")),
            sa.generalized_jacobian(r, q),
            sa.base_rate_matrix(r, q),
        )
    )(right_alone, q)
    held = np.asarray(held)
    np.testing.assert_allclose(held[6:, 6:], full[6:, 6:], rtol=1e-14)
    np.testing.assert_array_equal(held[:6, :6], np.eye(6))
    np.testing.assert_array_equal(held[:6, 6:], 0.0)
    np.testing.assert_allclose(quantities["jacobian"], J, atol=1e-15)
    np.testing.assert_allclose(quantities["base_rate"], C, atol=1e-15)


def test_focus_names_arms_tips_and_joints(dual):
    by_arm = dual.focus(moving=("right",)).moving_mask
    np.testing.assert_array_equal(by_arm, [False] * 6 + [True] * 6)
    np.testing.assert_array_equal(dual.focus(moving="right/tool0").moving_mask, by_arm)  # a tip: its path
    np.testing.assert_array_equal(
        dual.focus(moving=[f"right/{n}" for n in ("shoulder_pan_joint",)]).moving_mask,
        [False] * 6 + [True] + [False] * 5,
    )
    np.testing.assert_array_equal(dual.focus(moving=[True] * 6 + [False] * 6).moving_mask, [True] * 6 + [False] * 6)
    assert dual.focus(moving=("left", "right")).moving_mask.all()
    # which tip and which joints are data: one structure for every tip and held set, leaves shared
    focused = dual.focus(tip=1, moving=("right",))
    structure = jax.tree_util.tree_structure
    assert structure(focused) != structure(dual)
    assert structure(focused) == structure(dual.focus(tip=0)) == structure(dual.focus(tip=0, moving="left"))
    assert structure(focused.focus()) == structure(dual)
    assert focused.link_mass is dual.link_mass and focused.active_tip_name == "right/tool0"
    with pytest.raises(sa.ConfigError, match=r"tip: unknown tip 'rigth/tool0' \(did you mean 'right/tool0'\?\)"):
        dual.focus(tip="rigth/tool0")
    with pytest.raises(sa.ConfigError, match=r"moving: unknown arm, tip or joint 'rigth' \(did you mean 'right'\?\)"):
        dual.focus(moving=("rigth",))
    with pytest.raises(sa.ConfigError, match="moving: no joint moves"):
        dual.focus(moving=[False] * 12)
    with pytest.raises(TypeError, match=r"choose one with robot.focus\(tip=...\)"):
        family_of(dual).straight_maps(dual, Q0)


def test_reaction_null_space_over_the_moving_joints(dual, right_alone):
    q = np.random.default_rng(3).uniform(-2.0, 2.0, (4, 12))
    C = np.asarray(sa.base_rate_matrix(dual, q))[..., 3:, :]
    N = np.asarray(reaction.reaction_null_space(dual, q))
    assert N.shape == (4, 12, 9)  # n - 3 over all joints of both arms
    np.testing.assert_allclose(C @ N, 0.0, atol=1e-15)
    held = np.asarray(reaction.reaction_null_space(right_alone, q))
    assert held.shape == (4, 12, 3)  # 6 moving joints - 3
    np.testing.assert_array_equal(held[:, :6], 0.0)
    np.testing.assert_allclose(C @ held, 0.0, atol=1e-15)
    np.testing.assert_allclose(np.swapaxes(held, -1, -2) @ held, np.broadcast_to(np.eye(3), (4, 3, 3)), atol=1e-13)


# The tip shell --------------------------------------------------------------------------------


@pytest.mark.parametrize("name", TREES)
def test_tip_shell_holds_every_sampled_tip(name):
    robot = sa.load_robot(os.path.join(ROOT, "configs", f"{name}.yaml"))
    lower, upper = np.asarray(robot.joint_lower), np.asarray(robot.joint_upper)
    lower, upper = np.where(np.isfinite(lower), lower, -np.pi), np.where(np.isfinite(upper), upper, np.pi)
    q = np.random.default_rng(5).uniform(lower, upper, (4096, robot.n_joints))
    distance = np.linalg.norm(np.asarray(sa.tip_position(robot, q)), axis=-1)  # (4096, k)
    for t in range(robot.n_tips):
        inner, outer = family_of(robot).tip_shell(robot.focus(tip=t))
        assert (inner, outer) == tip_shell(robot, t)
        assert inner <= distance[:, t].min() and distance[:, t].max() <= outer
        assert distance[:, t].max() > 0.75 * outer  # not a loose bound


def test_a_one_arm_tree_is_the_spatial_arm():
    """The UR5 smallsat written as an arms: tree of one arm: tips and the shell of the serial arm."""
    arm = sa.load_robot(os.path.join(ROOT, "configs", "ur5-smallsat.yaml"))
    path = locate_package_file("test", "example-robot-data", "robots/ur_description/urdf/ur5_robot.urdf")
    chain = read_urdf(path, root_link="base_link", tip="tool0")
    tree = tree_from_chains(
        [chain],
        arm_names=["arm"],
        mount_xyz=[np.asarray(arm.mount_xyz)],
        mount_rpy=[np.asarray(arm.mount_rpy)],
        base_mass=arm.base_mass,
        base_com=arm.base_com,
        base_inertia=arm.base_inertia,
    )
    q = np.random.default_rng(2).uniform(-3, 3, (8, 6))
    np.testing.assert_allclose(sa.tip_position(tree, q)[:, 0], sa.tip_position(arm, q), atol=1e-14)
    np.testing.assert_allclose(tip_shell(tree, 0), family_of(arm).tip_shell(arm), rtol=1e-14)


# Joint paths, straight paths, the balance arm ---------------------------------------------------


def test_joint_loop_of_all_arms_against_rk4(dual, right_alone):
    """Magnus over the tree's closed form = RK4 over the generic momentum map, 1e-8 rad; a loop
    run backwards undoes the turn."""
    rng = np.random.default_rng(11)
    waypoints = np.stack([Q0, Q0 + rng.uniform(-1, 1, 12), Q0 + rng.uniform(-1, 1, 12), Q0])
    R_end, q_end = sa.integrate_joint_path(dual, Q0, waypoints, base_rotation=np.eye(3))
    np.testing.assert_array_equal(q_end, Q0)
    reference = np.asarray(_rk4_polyline(dual, jnp.asarray(waypoints), jnp.zeros(200)))
    assert _turn(reference) > 1e-3
    assert _turn(np.asarray(R_end).T @ reference) < 1e-8
    back, _ = sa.integrate_joint_path(dual, Q0, waypoints[::-1], base_rotation=R_end)
    assert _turn(back) < 1e-12
    # a focused robot holds its other arm: a path that moves it is refused
    with pytest.raises(sa.ConfigError, match="moves joints this robot holds"):
        sa.integrate_joint_path(right_alone, Q0, waypoints)


@pytest.fixture(scope="session")
def straight_paths(dual, right_alone):
    """The right tip 5 cm along D with the left arm held, and with every joint moving (one batch each)."""
    held = sa.straight_tip_path(right_alone, Q0, D, max_length=0.05)
    both = sa.straight_tip_path(dual.focus(tip="right/tool0"), Q0, D, max_length=0.05)
    return held, both


@pytest.mark.slow  # compiles the DOP853 lanes for two focuses of the 12-joint tree
def test_straight_path_of_one_tip_with_the_other_arm_held(dual, straight_paths):
    held, both = straight_paths
    start = np.asarray(sa.tip_position(dual, Q0))[1]
    for path in (held, both):
        assert int(path.reason) == sa.motion.REASON_MAX_LENGTH
        # on the line in inertial axes: the bus attitude and the joints are right together
        np.testing.assert_allclose(np.asarray(path.end_tip) - start, 0.05 * D, atol=1e-9)
        R_end = np.asarray(path.end_rotation)
        np.testing.assert_allclose(
            R_end @ np.asarray(sa.tip_position(dual, path.end_joints))[1], path.end_tip, atol=1e-12
        )
        assert _turn(R_end) > 1e-4  # the arm's reaction turns the bus
    np.testing.assert_array_equal(np.asarray(held.end_joints)[:6], Q0[:6])  # held: exactly
    assert np.max(np.abs(np.asarray(both.end_joints)[:6] - Q0[:6])) > 1e-4  # free: the left arm helps


@pytest.mark.slow  # runs the straight-path programs of the fixture for two more focuses
def test_another_focus_compiles_no_program(dual, straight_paths):
    """The chosen tip and the held joints are data: after one focus has compiled its programs,
    another tip or other held joints run them again (the left tip with the right arm held)."""
    sa.manipulability(dual.focus(tip="right/tool0"), Q0)
    sa.generalized_jacobian(dual.focus(tip="right/tool0"), Q0)
    with count_compiles() as compiles:
        left_alone = dual.focus(tip="left/tool0", moving=("left",))
        path = sa.straight_tip_path(left_alone, Q0, -D, max_length=0.05)
        w = sa.manipulability(left_alone, Q0)
        J = sa.generalized_jacobian(dual.focus(tip="left/tool0"), Q0)
    assert not compiles, dict(compiles)
    assert int(path.reason) == sa.motion.REASON_MAX_LENGTH
    np.testing.assert_array_equal(np.asarray(path.end_joints)[6:], Q0[6:])  # the right arm held exactly
    start = np.asarray(sa.tip_position(dual, Q0))[0]
    np.testing.assert_allclose(np.asarray(path.end_tip) - start, -0.05 * D, atol=1e-9)
    J_all = np.asarray(sa.generalized_jacobian(dual, Q0))
    np.testing.assert_array_equal(np.asarray(J), J_all[0])
    Jv = J_all[0][:3, :6]  # held joints have zero columns: w* over the left arm's own
    np.testing.assert_allclose(w, np.sqrt(np.linalg.det(Jv @ Jv.T)), rtol=1e-12)


@pytest.mark.slow  # compiles the reaction-free integrator for the 12-joint tree
def test_balance_arm_keeps_the_bus_still(dual, straight_paths):
    """The left tip moves straight; minimum-norm rates of [C_w; J*_v] over both arms: the right
    arm cancels the bus rotation."""
    path = reaction.reaction_free_tip_path(dual.focus(tip="left/tool0"), Q0, D, 0.02, steps=100)
    assert float(path.smallest_singular_value) > 1e-4
    start = np.asarray(sa.tip_position(dual, Q0))[0]
    np.testing.assert_allclose(np.asarray(path.tip[-1]) - start, 0.02 * D, atol=1e-12)
    assert float(path.tip_residual) < 1e-10 and float(path.bus_rate) < 1e-10
    joints = np.asarray(path.joints)
    assert np.max(np.abs(joints[-1, 6:] - Q0[6:])) > 1e-4  # the right arm balances
    # independently: the sampled joint path through the SO(3) integrator of the whole tree
    fine, _ = sa.integrate_joint_path(dual, joints[0], joints)
    coarse, _ = sa.integrate_joint_path(dual, joints[0], joints[::4])
    assert _turn(fine) < 1e-9 < 10 * _turn(fine) < _turn(coarse)  # O(chord^2), converging
    # the same tip motion by plain minimum-norm rates turns the bus
    _, both = straight_paths
    assert _turn(both.end_rotation) > 1e-4


# Planning ---------------------------------------------------------------------------------------


@pytest.mark.slow  # runs the SO(3) loop optimizer for the 12-joint tree
def test_reorientation_with_one_arm(dual):
    target = np.asarray(expm(np.array([0.04, -0.03, 0.05])))
    waypoints = sa.plan_reorientation(dual.focus(moving=("left",)), Q0, target)
    np.testing.assert_array_equal(waypoints[:, 6:], np.broadcast_to(Q0[6:], (len(waypoints), 6)))  # right held
    np.testing.assert_array_equal(waypoints[0], Q0)
    np.testing.assert_array_equal(waypoints[-1], Q0)
    R0 = np.asarray(expm(np.array([0.1, 0.2, -0.3])))
    R_end, _ = sa.integrate_joint_path(dual, Q0, waypoints, base_rotation=R0, steps=16)  # the whole robot
    assert _turn(np.asarray(R_end).T @ (R0 @ target)) < 1e-9


@pytest.mark.slow  # compiles the pose path for two focuses of the 12-joint tree
def test_pose_target_for_a_tree_tip(dual):
    """A straight pose path of the right tip, the left arm held and free: the end pose read
    from the whole tree's kernels; the bus attitude against the integrator on the whole tree."""
    for moving in (("right",), None):
        robot = dual.focus(tip="right/tool0", moving=moving)
        p0, T0 = (np.asarray(x) for x in family_of(robot).tip_frame(robot, Q0))
        target = p0 + np.array([0.03, -0.02, 0.04])
        T1 = np.asarray(expm(np.array([0.1, -0.05, 0.08]))) @ T0
        plan = sa.plan_pose_reach(robot, Q0, target, T1)
        q, R = np.asarray(plan.end_joints), np.asarray(plan.end_rotation)
        axes = np.asarray(tip_pose(dual, q)[0])[1]
        np.testing.assert_allclose(R @ axes, T1, atol=1e-12)
        np.testing.assert_allclose(R @ np.asarray(sa.tip_position(dual, q))[1], target, atol=1e-12)
        chords, _ = sa.integrate_joint_path(dual, Q0, np.asarray(plan.joints))  # O(chord^2) from the path
        assert _turn(np.asarray(chords).T @ R) < 1e-8 < 1e-4 < _turn(R)
        moved = np.max(np.abs(np.asarray(plan.joints)[:, :6] - Q0[:6]))
        assert moved == 0.0 if moving else moved > 1e-3
    with pytest.raises(sa.ConfigError, match=r"choose the tip to aim with robot.focus\(tip=...\)"):
        sa.plan_pose_reach(dual, Q0, target, T1)
    with pytest.raises(sa.ConfigError, match=r"at least 6 joints .* the arm has 3 moving"):
        sa.plan_pose_reach(dual.focus(tip=1, moving=[f"right/{j}" for j in JOINTS[:3]]), Q0, target, T1)


# The documented starts of `spacearm reach` for the whole-system files (the first tip, every joint moving).
SYSTEM_STARTS = {
    "baxter-system": ([0, -30, 0, 45, 0, 70, 0] * 2, [0.60, 0.88, -0.05]),
    "tiago-dual-system": ([0.15] + [30, 30, 60, 90, 0, 30, 0] * 2, [0.53, 0.56, 0.30]),
    "three-arm-servicer": ([20, 40, -60, 10, 30, 0.2, 20, 0.5, 40, 10], [0.72, 0.09, 0.96]),
}


@pytest.mark.slow  # compiles the straight-path lanes of each system (about 15 s of CPU each)
@pytest.mark.parametrize("name", sorted(SYSTEM_STARTS))
def test_reach_runs_on_the_shipped_systems(name):
    robot = sa.load_robot(os.path.join(ROOT, "configs", f"{name}.yaml"))
    start, target = SYSTEM_STARTS[name]
    prismatic = np.array([kind == "prismatic" for kind in robot.joint_kinds])
    q0 = np.where(prismatic, start, np.radians(start))
    plan = sa.plan_reach(robot.focus(tip=0), q0, np.asarray(target))
    assert plan.mode == "straight" and plan.error < 1e-9
    end = np.asarray(sa.tip_position(robot, plan.end_joints, plan.end_rotation))[0]
    np.testing.assert_allclose(end, target, atol=1e-9)  # read back from the whole tree


def test_reach_refuses_an_unknown_tip_or_arm(tmp_path, capsys):
    """Refused before any work, naming the option (exit 2)."""
    args = ["reach", DUAL, "--from=" + ",".join(map(str, Q_DEG)), "--to=0.8,-0.8,0.4", "--out", str(tmp_path)]
    assert main([*args, "--tip", "rigth/tool0"]) == 2
    assert "--tip: unknown tip 'rigth/tool0' (did you mean 'right/tool0'?)" in capsys.readouterr().err
    assert main([*args, "--moving", "right,lfet"]) == 2
    assert "--moving: unknown arm, tip or joint 'lfet' (did you mean 'left'?)" in capsys.readouterr().err
    arm = os.path.join(ROOT, "configs", "arm3dof-100kg.yaml")
    assert main(["reach", arm, "--from=0,40,-70", "--to=0.1,0.1,0.1", "--tip", "tool0", "--out", str(tmp_path)]) == 2
    assert "--tip: applies to robots with several arms" in capsys.readouterr().err


@pytest.mark.slow  # loads and plans the 12-joint tree
def test_reach_command_with_a_chosen_tip(dual, tmp_path, capsys):
    target = np.asarray(sa.tip_position(dual, Q0))[1] + np.array([0.05, 0.05, -0.05])
    to = ",".join(f"{v:.12f}" for v in target)
    command = ["reach", DUAL, "--tip", "right/tool0", "--moving", "right"]
    command += ["--from=" + ",".join(map(str, Q_DEG)), f"--to={to}", "--out", str(tmp_path)]
    code = main(command)
    done = capsys.readouterr()
    assert code == 0, done.err
    assert "tip            right/tool0" in done.out and "held joints    6 of 12" in done.out
    saved = np.load(tmp_path / "reach.npz")
    joints, R, tip = saved["joints"], saved["base_rotation"], saved["tip"]
    assert joints.shape[1] == 12 and R.shape == (len(joints), 3, 3) and tip.shape == (len(joints), 3)
    np.testing.assert_allclose(joints[0], Q0, atol=1e-15)
    np.testing.assert_array_equal(joints[:, :6], np.broadcast_to(Q0[:6], (len(joints), 6)))  # the left arm held
    np.testing.assert_allclose(tip, np.asarray(sa.tip_position(dual, joints, R))[:, 1], atol=1e-12)
    assert np.linalg.norm(tip[-1] - target) < 1e-9
    assert int(saved["tip_index"]) == 1 and saved["moving"].tolist() == [False] * 6 + [True] * 6
