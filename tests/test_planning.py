"""Reorientation loops and reach plans against independent references: SciPy quadrature
of eq. (5) over the naive model of tests/reference.py, a MuJoCo zero-gravity simulation
of a planned loop, and the reached targets themselves."""

import itertools

import numpy as np
import pytest
from scipy.integrate import quad

import spacearm as sa
from spacearm import motion, planning
from spacearm.planning import reorientation

from . import reference as ref
from .conftest import count_compiles, random_robot

DEG = np.pi / 180.0
PHI_START = np.array([0.0, -60.0, 120.0]) * DEG  # the initial posture of Fig. 3 and Fig. 5


def _posture(end):
    """[phi0, joints] from `integrate_joint_path`'s (attitude, joints) of a planar robot."""
    phi0, joints = end
    return np.concatenate([np.asarray(phi0)[..., None], np.asarray(joints)], axis=-1)


def reference_loop_rotation(d, waypoints):
    """Line integral of eq. (5) along the polygon, scipy.integrate.quad over the naive model."""
    total = 0.0
    for start, end in itertools.pairwise(waypoints):
        step = end - start
        if not np.any(step):
            continue

        def integrand(t, start=start, step=step):
            return ref.base_rate(d, np.r_[0.0, start + t * step], step)

        value, _ = quad(integrand, 0.0, 1.0, epsabs=1e-15, epsrel=1e-13, limit=200)
        total += value
    return total


def split_loops(details):
    """The waypoints are the loop repeated: return the loop, checking the repetition."""
    loop = details.loop
    k = loop.shape[0] - 1
    assert details.waypoints.shape[0] == details.loops * k + 1
    for i in range(details.loops):
        np.testing.assert_array_equal(details.waypoints[i * k : (i + 1) * k + 1], loop)
    return loop


@pytest.fixture(scope="module")
def loop30():
    robot = sa.umetani1990()
    return robot, planning.plan_reorientation_details(robot, PHI_START, 30.0 * DEG)


def test_loop_turns_the_base_by_the_request_independently_integrated(loop30):
    robot, details = loop30
    waypoints = details.waypoints
    q0 = PHI_START[1:]
    # closed, starting and ending exactly at the start joints
    np.testing.assert_array_equal(waypoints[0], q0)
    np.testing.assert_array_equal(waypoints[-1], q0)
    loop = split_loops(details)
    per_loop = reference_loop_rotation(ref.design(robot), loop)
    assert abs(details.loops * per_loop - 30.0 * DEG) < 1e-9
    phi_end = _posture(sa.integrate_joint_path(robot, PHI_START, waypoints))
    assert abs(phi_end[0] - PHI_START[0] - 30.0 * DEG) < 1e-10
    np.testing.assert_array_equal(phi_end[1:], q0)
    # the public function returns the same waypoints
    np.testing.assert_array_equal(sa.plan_reorientation(robot, PHI_START, 30.0 * DEG), waypoints)
    # the loop stays within the excursion bound and its travel is what it says
    assert details.excursion <= planning.LoopSettings().max_excursion
    assert np.max(np.abs(waypoints - q0)) == pytest.approx(details.excursion, abs=1e-12)
    travel = np.sum(np.linalg.norm(np.diff(waypoints, axis=0), axis=-1))
    assert travel == pytest.approx(details.travel, rel=1e-12)


def test_small_loop_rotation_matches_the_curl_times_the_area():
    """Stokes: a small loop turns the base by Omega_12 times the enclosed signed area."""
    robot = sa.umetani1990()
    q0 = PHI_START[1:]
    omega = np.asarray(planning.rotation_curl(robot, q0))
    np.testing.assert_allclose(omega, -omega.T, atol=0)
    radius = 1e-4
    t = np.linspace(0.0, 2.0 * np.pi, 61)
    circle = q0 + radius * np.stack([1.0 - np.cos(t), -np.sin(t)], axis=-1)  # counter-clockwise
    circle[-1] = q0
    rotation = reference_loop_rotation(ref.design(robot), circle)
    area = 0.5 * 60 * radius**2 * np.sin(2 * np.pi / 60)  # area of the inscribed 60-gon
    assert rotation == pytest.approx(omega[0, 1] * area, rel=1e-3)


def test_large_rotations_repeat_a_loop_and_stay_exact():
    robot = sa.umetani1990()
    d = ref.design(robot)
    for degrees in (90.0, -180.0):
        details = planning.plan_reorientation_details(robot, PHI_START, degrees * DEG)
        assert details.loops > 1  # one loop within 1.5 rad of the start cannot turn the base this far
        loop = split_loops(details)
        assert abs(details.loops * reference_loop_rotation(d, loop) - degrees * DEG) < 1e-8
        phi_end = _posture(sa.integrate_joint_path(robot, PHI_START, details.waypoints))
        assert abs(phi_end[0] - degrees * DEG) < 1e-6
        assert details.excursion <= planning.LoopSettings().max_excursion


def test_joint_limits_are_respected_and_the_cache_is_reused():
    lower = np.array([-80.0, 100.0]) * DEG
    upper = np.array([-20.0, 135.0]) * DEG
    robot = sa.umetani1990().replace(joint_lower=lower, joint_upper=upper)
    details = planning.plan_reorientation_details(robot, PHI_START, -20.0 * DEG)
    assert np.all(details.waypoints >= lower) and np.all(details.waypoints <= upper)
    assert abs(details.loops * reference_loop_rotation(ref.design(robot), split_loops(details)) + 20.0 * DEG) < 1e-9
    # new limits, start and angle are new values of the same shapes: no new compilation
    cache_size = reorientation._optimize_loops._cache_size()
    other = robot.replace(joint_lower=lower - 0.1, joint_upper=upper + 0.1)
    again = planning.plan_reorientation_details(other, PHI_START + np.array([0.3, 0.1, -0.1]), -12.0 * DEG)
    assert reorientation._optimize_loops._cache_size() == cache_size
    assert abs(again.rotation + 12.0 * DEG) < 1e-9
    # so are new step counts, rates, bounds and weights (traced, not compiled in)
    settings = planning.LoopSettings(
        steps=200, learning_rate=0.04, newton_steps=10, travel_weight=0.01, room_fraction=0.9
    )
    tuned = planning.plan_reorientation_details(
        other, PHI_START + np.array([0.3, 0.1, -0.1]), -12.0 * DEG, settings=settings
    )
    assert reorientation._optimize_loops._cache_size() == cache_size
    assert abs(tuned.rotation + 12.0 * DEG) < 1e-9 and not np.array_equal(tuned.loop, again.loop)


def test_redundant_arm():
    robot = random_robot(np.random.default_rng(7), 3)
    phi = np.array([0.3, 0.4, -0.9, 1.1])
    settings = planning.LoopSettings(loop_counts=(1, 2, 4), directions=2, steps=200)  # a lighter search
    details = planning.plan_reorientation_details(robot, phi, 15.0 * DEG, settings=settings)
    loop = split_loops(details)
    assert abs(details.loops * reference_loop_rotation(ref.design(robot), loop) - 15.0 * DEG) < 1e-9


def test_reorientation_errors():
    robot = sa.umetani1990()
    with pytest.raises(sa.ConfigError, match="phi_start"):
        planning.plan_reorientation(robot, [0.0, 1.0], 0.1)
    limited = robot.replace(joint_lower=np.array([-1.0, -1.0]), joint_upper=np.array([1.0, 1.0]))
    with pytest.raises(sa.ConfigError, match="outside its limits"):
        planning.plan_reorientation(limited, PHI_START, 0.1)
    with pytest.raises(sa.ConfigError, match="delta_phi0"):
        planning.plan_reorientation(robot, PHI_START, float("nan"))
    boxed = robot.replace(joint_lower=PHI_START[1:] - 0.01, joint_upper=PHI_START[1:] + 0.01)
    with pytest.raises(sa.ConfigError, match="no loop turns the base"):
        planning.plan_reorientation(boxed, PHI_START, 90.0 * DEG)
    still = planning.plan_reorientation(robot, PHI_START, 0.0)
    np.testing.assert_array_equal(still, [PHI_START[1:], PHI_START[1:]])


# MuJoCo -----------------------------------------------------------------------------------


def test_mujoco_simulation_of_a_planned_loop_agrees():
    """The motion helper's zero-gravity simulation (tests/test_mujoco.py: base floating on
    slide x, slide y, hinge z; only the arm driven) of a planned loop."""
    pytest.importorskip("mujoco")
    from .test_mujoco import simulate_loop

    robot = sa.umetani1990()
    details = planning.plan_reorientation_details(robot, PHI_START, 8.0 * DEG)
    assert details.loops == 1
    z, worst_momentum, data = simulate_loop(robot, details.waypoints, segment_time=0.25, dt=2.5e-3)
    assert abs(z[2] - 8.0 * DEG) < 1e-6  # the base turned by the planned 8 deg (measured 7.5e-9)
    # RK4 at 2.5 ms keeps |L| below 1e-5 kg m^2/s while the arm alone carries ~1e2
    assert worst_momentum < 1e-5
    np.testing.assert_allclose(data.qpos[3:], PHI_START[1:], atol=1e-12)  # the joints came back
    end = np.r_[8.0 * DEG, PHI_START[1:]]
    tip = data.site("tip").xpos[:2] - data.subtree_com[0][:2]
    np.testing.assert_allclose(tip, np.asarray(sa.tip_position(robot, end)), atol=1e-6)


# Reach plans -----------------------------------------------------------------------------


def test_a_program_compiled_ahead_is_not_compiled_again(table1):
    """plan_reach compiles the history sampler ahead in a thread; the later call must find
    that program (7 samples: a program no other test builds)."""
    with count_compiles() as compiles:
        motion.compile_straight_tip_path_history(table1, 1, 7)
        motion.straight_tip_path_history(table1, PHI_START, np.array([-1.0, 0.2]), 7, max_length=0.5)
    assert [count for name, count in compiles.items() if "_history_flat" in name] == [1], dict(compiles)


def test_point_b_is_reached_by_a_straight_path():
    robot = sa.umetani1990()
    target = np.array([2.0, 1.0])
    plan = sa.plan_reach(robot, PHI_START, target)
    assert plan.mode == "straight" and plan.loops == 0
    assert plan.error < 1e-6
    assert np.linalg.norm(plan.tips[-1] - target) < 1e-6
    np.testing.assert_allclose(plan.tips[0], np.asarray(sa.tip_position(robot, PHI_START)), atol=1e-12)
    # every tip of the history lies on the straight line from the start to the target
    start = plan.tips[0]
    direction = (target - start) / np.linalg.norm(target - start)
    offsets = plan.tips - start
    assert np.max(np.abs(offsets[:, 0] * direction[1] - offsets[:, 1] * direction[0])) < 1e-8


def test_point_c_needs_a_reorientation_loop_then_a_straight_path():
    robot = sa.umetani1990()
    target = np.array([0.0, -3.0])
    # point C: the straight path towards it from the start stops at a singularity first
    start_tip = np.asarray(sa.tip_position(robot, PHI_START))
    offset = target - start_tip
    direct = sa.straight_tip_path(robot, PHI_START, offset, max_length=float(np.linalg.norm(offset)))
    assert int(direct.reason) != 1
    plan = sa.plan_reach(robot, PHI_START, target)
    assert plan.mode == "reorient" and plan.loops >= 1
    assert plan.error < 1e-6
    assert np.linalg.norm(plan.tips[-1] - target) < 1e-6
    # the loop part turns the base by the planned angle (independent quadrature), joints back
    k = np.flatnonzero(plan.phase == planning.PHASE_LOOP)[-1]
    np.testing.assert_allclose(plan.postures[k, 1:], PHI_START[1:], atol=1e-12)
    rotation = reference_loop_rotation(ref.design(robot), plan.joint_waypoints)
    assert abs(rotation - plan.delta_phi0) < 1e-9
    assert abs(plan.postures[k, 0] - PHI_START[0] - plan.delta_phi0) < 1e-9
    # zero angular momentum along the whole history (finite differences of the samples)
    np.testing.assert_allclose(plan.end_tip, np.asarray(sa.tip_position(robot, plan.end_posture)), atol=1e-12)


def test_repositioning_mode_reaches_the_target():
    """Forced third strategy: a straight joint move to the target's radius, then a loop."""
    robot = sa.umetani1990()
    target = np.array([0.0, -3.0])
    plan = sa.plan_reach(robot, PHI_START, target, modes=("reposition",))
    assert plan.mode == "reposition"
    assert plan.error < 1e-6
    assert np.any(plan.phase == planning.PHASE_REPOSITION) and np.any(plan.phase == planning.PHASE_LOOP)
    # the base attitude at the end is what the independent quadrature of the whole joint path gives
    rotation = reference_loop_rotation(ref.design(robot), plan.joint_waypoints)
    assert abs(plan.end_posture[0] - PHI_START[0] - rotation) < 1e-9
    np.testing.assert_allclose(plan.end_tip, target, atol=1e-6)


def test_target_outside_the_maximum_reachable_space_is_refused():
    robot = sa.umetani1990()
    radius = float(np.sum(np.abs(np.asarray(sa.tip_coefficients(robot)))))
    with pytest.raises(sa.ConfigError, match="Maximum Reachable"):
        sa.plan_reach(robot, PHI_START, [0.0, radius * 1.01])
    with pytest.raises(sa.ConfigError, match="target"):
        sa.plan_reach(robot, PHI_START, [1.0, np.inf])
    with pytest.raises(sa.ConfigError, match="modes"):
        sa.plan_reach(robot, PHI_START, [1.0, 1.0], modes=("teleport",))


def test_plan_reach_honours_every_argument_for_planar_robots():
    """Each argument of `sa.plan_reach` changes the plan or is refused by name."""
    robot = sa.umetani1990()
    point_b, point_c = np.array([2.0, 1.0]), np.array([0.0, -3.0])
    # history_samples: the straight leg's samples (plus the start)
    assert sa.plan_reach(robot, PHI_START, point_b, history_samples=11).postures.shape == (11, 3)
    # tolerance: the straight path ends ~1e-12 m from B; a tolerance below that refuses it
    with pytest.raises(sa.ConfigError, match="tolerance"):
        sa.plan_reach(robot, PHI_START, point_b, tolerance=1e-300)
    # modes and rotation_grid: with one grid rotation (zero) C is not reachable by turning
    with pytest.raises(sa.ConfigError, match="not reachable"):
        sa.plan_reach(robot, PHI_START, point_c, rotation_grid=1, modes=("straight", "reorient"))
    # settings: the loop of the plan has the settings' samples per pass
    settings = planning.LoopSettings(samples_per_loop=40)
    plan = sa.plan_reach(robot, PHI_START, point_c, settings=settings)
    assert plan.mode == "reorient" and len(plan.joint_waypoints) == 40 * plan.loops + 1
    for options, message in [
        ({"settings": planning.SpatialLoopSettings()}, "settings: expected LoopSettings"),
        ({"base_rotation": np.eye(3)}, "base_rotation"),
        ({"rotations": np.zeros((1, 3))}, "rotations"),
        ({"rotation_grid": 0}, "rotation_grid"),
        ({"history_samples": 1}, "history_samples"),
        ({"tolerance": 0.0}, "tolerance"),
    ]:
        with pytest.raises(sa.ConfigError, match=message):
            sa.plan_reach(robot, PHI_START, point_b, **options)


def test_reach_command_line(tmp_path):
    from spacearm.cli import main

    robot_file = tmp_path / "robot.yaml"
    import yaml

    from spacearm.models.planar import robot_to_mapping

    robot_file.write_text(yaml.safe_dump(robot_to_mapping(sa.umetani1990())))
    out = tmp_path / "reach"
    assert main(["reach", str(robot_file), "--from", "0,-60,120", "--to", "2,1", "--out", str(out)]) == 0
    assert (out / "reach.png").stat().st_size > 0
    saved = np.load(out / "reach.npz")
    np.testing.assert_allclose(saved["tip"][-1], [2.0, 1.0], atol=1e-6)
    np.testing.assert_allclose(saved["phi"][0], PHI_START, atol=1e-15)  # --from is in degrees
    k = saved["phi"].shape[0]
    assert k > 2 and saved["phi"].shape == (k, 3) and saved["tip"].shape == (k, 2) and saved["joints"].shape == (k, 2)
    np.testing.assert_array_equal(saved["joints"], saved["phi"][:, 1:])
    assert main(["reach", str(robot_file), "--from", "0,-60,120", "--to", "9,0", "--out", str(out)]) == 2
    assert main(["reach", str(robot_file), "--from", "0,-60", "--to", "2,1", "--out", str(out)]) == 2
