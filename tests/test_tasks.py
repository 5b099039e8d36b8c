"""Timed tasks (spacearm.motion.tasks): the quintic states, the peaks of the joint torques and
of the held wrench, the sweep metrics and the design objectives built on them.

References: the quintic's polynomial (numpy) and finite differences in time; a direct
evaluation of `sa.inverse_dynamics` at the same samples (for the planar arm at random bus
angles phi0, which at zero momentum change nothing; the UR5's at its default attitude), and
the held wrench as the rate of the system's momentum by central differences; the library kernels at the sweep's designs; central
differences of the design objectives."""

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import yaml

import spacearm as sa
from spacearm._core.errors import ConfigError
from spacearm.design.problem import load_problem
from spacearm.motion.tasks import TimedTask, peak_norm, task_from_mapping, task_peaks, task_states
from spacearm.studies import build_designs, load_sweep, run_sweep

UR5 = str(Path("configs/ur5-smallsat.yaml").resolve())
PAPER = str(Path("configs/umetani1990.yaml").resolve())
# Three waypoints of the UR5 (rad): two segments of 2 s.
UR5_WAYPOINTS = [[0.0, -1.0, 1.0, 0.0, 0.5, 0.0], [0.8, -0.5, 1.4, 0.3, 0.2, 0.4], [0.2, -1.2, 0.6, -0.2, 0.7, -0.3]]
UR5_TASK = {"waypoints": UR5_WAYPOINTS, "duration": 4.0}


@pytest.fixture(scope="module")
def ur5():
    return sa.load_robot(UR5)


@pytest.fixture(scope="module")
def ur5_task():
    return TimedTask(np.array(UR5_WAYPOINTS), 4.0)


def test_states_follow_the_quintic_and_stop_at_every_waypoint():
    rng = np.random.default_rng(0)
    waypoints, duration, samples = rng.uniform(-2, 2, (4, 3)), 3.0, 2001
    t, q, qd, qdd = (np.asarray(a) for a in task_states(waypoints, duration, samples))
    T = duration / 3
    assert t.shape == (3 * samples,) and q.shape == qd.shape == qdd.shape == (3 * samples, 3)
    q, qd, qdd = (a.reshape(3, samples, 3) for a in (q, qd, qdd))
    # the polynomial 6u^5 - 15u^4 + 10u^3 and its derivatives, per segment
    u = np.linspace(0, 1, samples)
    law = np.array([6.0, -15.0, 10.0, 0.0, 0.0, 0.0])
    s, ds, dds = np.polyval(law, u), np.polyval(np.polyder(law), u), np.polyval(np.polyder(law, 2), u)
    step = waypoints[1:] - waypoints[:-1]
    np.testing.assert_allclose(q, waypoints[:-1, None] + s[:, None] * step[:, None], atol=1e-14)
    np.testing.assert_allclose(qd, ds[:, None] / T * step[:, None], atol=1e-13)
    np.testing.assert_allclose(qdd, dds[:, None] / T**2 * step[:, None], atol=1e-12)
    np.testing.assert_allclose(t.reshape(3, samples), (np.arange(3)[:, None] + u) * T, atol=1e-15)
    # each segment starts and ends at its waypoints, at rest
    np.testing.assert_array_equal(q[:, 0], waypoints[:-1])
    np.testing.assert_allclose(q[:, -1], waypoints[1:], atol=1e-15)
    assert np.all(qd[:, [0, -1]] == 0) and np.all(qdd[:, [0, -1]] == 0)
    # rates and accelerations are the time derivatives: central differences inside each segment,
    # within their truncation error h^2 / 6 max|d3x/dt3| (|s'''| <= 60, |s''''| <= 360 in u)
    h, size = T / (samples - 1), np.abs(step).max()
    np.testing.assert_allclose((q[:, 2:] - q[:, :-2]) / (2 * h), qd[:, 1:-1], rtol=0, atol=h**2 * 10 * size / T**3)
    np.testing.assert_allclose((qd[:, 2:] - qd[:, :-2]) / (2 * h), qdd[:, 1:-1], rtol=0, atol=h**2 * 60 * size / T**4)


def test_peak_norm_has_a_finite_gradient_at_rest_samples():
    vectors = jnp.array([[0.0, 0.0, 0.0], [3.0, 4.0, 0.0], [1.0, 0.0, 0.0]])
    np.testing.assert_allclose(peak_norm(vectors), 5.0, rtol=1e-15)
    np.testing.assert_allclose(jax.grad(peak_norm)(vectors), [[0, 0, 0], [0.6, 0.8, 0], [0, 0, 0]], atol=1e-15)
    assert peak_norm(jnp.zeros((4, 3))) == 0 and not np.any(jax.grad(peak_norm)(jnp.zeros((4, 3))))


def test_a_task_is_validated_and_passes_through_jit_as_data():
    with pytest.raises(ConfigError, match=r"task.waypoints: must be a \(k, n\) array"):
        TimedTask(np.zeros((1, 3)), 1.0)
    with pytest.raises(ConfigError, match=r"task\.duration: must be a positive number"):
        TimedTask(np.zeros((2, 3)), -1.0)
    task = TimedTask([[0, 0], [1, 2]], 2)
    assert task.waypoints.dtype == np.float64 and task.segment_duration == 2.0
    through = jax.jit(lambda task: task)(task)  # leaves traced, rebuilt without validation
    assert isinstance(through, TimedTask) and float(through.duration) == 2.0
    np.testing.assert_array_equal(through.waypoints, task.waypoints)


def test_peaks_are_the_largest_inverse_dynamics_over_the_samples(ur5, ur5_task):
    peaks = task_peaks(ur5, ur5_task)
    _, q, qd, qdd = task_states(ur5_task.waypoints, ur5_task.duration)
    assert q.shape == (2 * 101, 6)
    tau_free, _ = sa.inverse_dynamics(ur5, q, qd, qdd)
    tau_held, wrench = sa.inverse_dynamics(ur5, q, qd, qdd, base="held")
    tau_free, tau_held, wrench = (np.asarray(a) for a in (tau_free, tau_held, wrench))
    np.testing.assert_allclose(peaks.joint_torque, np.abs(tau_free).max(axis=0), rtol=1e-12)
    np.testing.assert_allclose(peaks.max_joint_torque, np.abs(tau_free).max(), rtol=1e-12)
    np.testing.assert_allclose(peaks.held_force, np.linalg.norm(wrench[:, :3], axis=1).max(), rtol=1e-12)
    np.testing.assert_allclose(peaks.held_torque, np.linalg.norm(wrench[:, 3:], axis=1).max(), rtol=1e-12)
    # the held wrench is the rate of the system's momentum with the bus at rest: [P; L about the
    # bus centroid] = H[:6, 6:] qd (bus axes, fixed in space), by central differences in time
    dense = 2001  # every 20th dense sample is one of the 101
    _, q_dense, qd_dense, _ = task_states(ur5_task.waypoints, ur5_task.duration, dense)
    H = np.asarray(sa.mass_matrix(ur5, q_dense))
    momentum = np.einsum("sij,sj->si", H[:, :6, 6:], np.asarray(qd_dense)).reshape(2, dense, 6)
    rate = (momentum[:, 2:] - momentum[:, :-2]) / (2 * 2.0 / (dense - 1))  # at dense samples 1 .. dense - 2
    np.testing.assert_allclose(
        rate[:, 20 * np.arange(1, 100) - 1], wrench.reshape(2, 101, 6)[:, 1:100], rtol=0, atol=1e-5 * wrench.max()
    )
    # the bus at rest at every waypoint (both ends of each segment): no effort there
    ends = np.r_[0, 100, 101, 201]
    assert np.abs(tau_free[ends]).max() < 1e-12 and np.abs(wrench[ends]).max() < 1e-12
    assert peaks.max_joint_torque > 1.0 and not np.allclose(np.abs(tau_held).max(0), peaks.joint_torque)


def test_planar_peaks_read_the_in_plane_wrench():
    """The paper's arm: the wrench is [fx, fy, m]; the reference's postures carry random bus
    angles phi0, which at zero momentum change nothing."""
    robot = sa.load_robot(PAPER)
    task = TimedTask(np.array([[0.3, 1.0], [1.2, 0.2], [0.5, 1.5]]), 3.0)
    peaks = task_peaks(robot, task)
    _, q, qd, qdd = task_states(task.waypoints, task.duration)
    phi = jnp.concatenate([jnp.asarray(np.random.default_rng(2).uniform(-3, 3, (q.shape[0], 1))), q], axis=-1)
    tau, _ = sa.inverse_dynamics(robot, phi, qd, qdd)
    _, wrench = sa.inverse_dynamics(robot, phi, qd, qdd, base="held")
    assert wrench.shape == (q.shape[0], 3)
    np.testing.assert_allclose(peaks.joint_torque, np.abs(tau).max(axis=0), rtol=1e-12)
    np.testing.assert_allclose(peaks.held_force, np.linalg.norm(wrench[:, :2], axis=1).max(), rtol=1e-12)
    np.testing.assert_allclose(peaks.held_torque, np.abs(wrench[:, 2]).max(), rtol=1e-12)


def test_sweep_columns_are_the_library_peaks(tmp_path, ur5, ur5_task):
    spec = load_sweep(
        {
            "name": "task-sweep",
            "robot": UR5,
            "axes": {"x": {"field": "mount.xyz[0]", "values": [0.0, 0.4]}},
            "metrics": ["peak_joint_torque", "peak_held_wrench"],
            "task": {"waypoints_deg": np.degrees(UR5_WAYPOINTS).tolist(), "duration": 4.0},
        }
    )
    np.testing.assert_allclose(spec.config["task"]["waypoints"], UR5_WAYPOINTS, atol=1e-15)  # written in rad
    table = run_sweep(spec, tmp_path / "out", progress=False).table
    designs, _ = build_designs(spec)
    for i in range(2):
        design = jax.tree_util.tree_map(lambda leaf, i=i: leaf[i], designs)
        peaks = task_peaks(design, ur5_task)
        np.testing.assert_allclose(table["peak_joint_torque_Nm"][i], peaks.max_joint_torque, rtol=1e-12)
        np.testing.assert_allclose(table["peak_held_force_N"][i], peaks.held_force, rtol=1e-12)
        np.testing.assert_allclose(table["peak_held_torque_Nm"][i], peaks.held_torque, rtol=1e-12)
    # moving the mount changes the torques, not the force (the arm's momentum is the same)
    assert abs(table["peak_held_torque_Nm"][0] - table["peak_held_torque_Nm"][1]) > 0.1
    np.testing.assert_allclose(table["peak_held_force_N"][0], table["peak_held_force_N"][1], rtol=1e-12)


def test_task_objective_gradients_match_central_differences(ur5_task):
    problem = load_problem(
        {
            "name": "task-problem",
            "robot": UR5,
            "variables": {"mount.xyz[0]": [-0.4, 0.6], "mount.rpy[1]": [-0.8, 0.8], "base.mass": [200.0, 800.0]},
            "objectives": ["low_peak_joint_torque", "low_peak_held_torque"],
            "task": UR5_TASK,
        }
    )
    f = problem.objective_function()
    x = np.array([0.1, 0.3, 450.0])
    jacobian = np.asarray(jax.jit(jax.jacfwd(f))(jnp.asarray(x)))  # one program: compiles faster
    steps = np.array([1e-5, 1e-5, 1e-3])
    differences = np.stack([(f(x + e) - f(x - e)) / (2 * h) for e, h in zip(np.diag(steps), steps, strict=True)], -1)
    np.testing.assert_allclose(jacobian, differences, rtol=1e-6, atol=1e-9)
    assert np.all(np.abs(jacobian[:, :2]) > 1e-3)  # the mount moves both peaks


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"task": None}, "metrics[0]: peak_joint_torque is taken along a timed task"),
        ({"task": {"waypoints": [[0.0] * 6], "duration": 1.0}}, "task.waypoints: must be a list of 2 to"),
        ({"task": {"waypoints": [[0.0] * 6, [0.0] * 5], "duration": 1.0}}, "task.waypoints[1]: needs 6 joint"),
        ({"task": {"waypoints": UR5_WAYPOINTS, "duration": 0}}, "task.duration: must be positive"),
        ({"task": {"waypoints": UR5_WAYPOINTS}}, "task.duration: missing required key"),
        ({"task": {**UR5_TASK, "waypoints_deg": UR5_WAYPOINTS}}, "give exactly one of waypoints"),
        ({"task": {**UR5_TASK, "time": 2}}, "task: unknown key 'time'"),
        ({"metrics": ["posture"]}, "task: no metric listed uses it"),
        ({"metrics": [{"name": "peak_joint_torque", "base": "fixed"}]}, "metrics[0].base: must be one of"),
        ({"metrics": [{"name": "peak_held_wrench", "tip": 0}]}, "metrics[0]: unknown key 'tip'"),
    ],
)
def test_bad_tasks_are_refused_naming_the_file_and_field(tmp_path, changes, message):
    config = {
        "name": "bad",
        "robot": UR5,
        "axes": {"x": {"field": "mount.xyz[0]", "values": [0.0]}},
        "metrics": ["peak_joint_torque"],
        "task": UR5_TASK,
    }
    config.update(changes)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump({k: v for k, v in config.items() if v is not None}))
    with pytest.raises(ConfigError) as error:
        load_sweep(path)
    assert str(error.value).startswith(str(path)) and message in str(error.value), str(error.value)


def test_problem_needs_its_task_and_a_task_its_objective():
    base = {"name": "p", "robot": UR5, "variables": {"mount.xyz[0]": [-0.4, 0.6]}}
    with pytest.raises(ConfigError, match="task: missing; low_peak_held_force is taken along a timed task"):
        load_problem({**base, "objectives": ["w_avg", "low_peak_held_force"]})
    with pytest.raises(ConfigError, match="which objectives does not list"):
        load_problem({**base, "objectives": ["w_avg", "gci"], "task": UR5_TASK})
    with pytest.raises(ConfigError, match=r"task\.waypoints\[0\]: needs 6 joint positions"):
        task_from_mapping("problem", {"waypoints": [[0.0], [1.0]], "duration": 1.0}, ("revolute",) * 6)
    problem = load_problem({**base, "objectives": ["w_avg", "low_peak_held_force"], "task": UR5_TASK})
    assert problem.reference_point is None and problem.fixed["task"] == UR5_TASK
