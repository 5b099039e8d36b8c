"""Impact and wheel design quantities: the virtual mass and the bus-rate jump at a posture,
their joint-box averages and that of the bus rate after a reference capture, the peak wheel
momentum and torque of a task, as sweep columns and design objectives.

References: Pinocchio's mass matrix and frame Jacobians (G = J M^-1 J^T and the response to
a tip impulse, tests/dynamics_references.py), Pinocchio's centroidal momentum and inverse
dynamics for the wheels at every sample of a task (numpy's quintic), plain Monte Carlo means
of the kernels over the joint box, the library kernels at a sweep's designs, and central
differences of the design objectives."""

import csv
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import yaml

import spacearm as sa
from spacearm._core.errors import ConfigError
from spacearm.analysis.averages import joint_averages
from spacearm.analysis.impacts import impact_setup
from spacearm.analysis.joint_box import joint_box
from spacearm.cli import main as cli_main
from spacearm.design.fronts import nondominated_mask
from spacearm.design.problem import load_problem
from spacearm.studies import build_designs, load_sweep, run_sweep

from .dynamics_references import BUILDERS, PinocchioSystem
from .spatial_references import config_urdf, random_rotation

UR5 = str(Path("configs/ur5-smallsat.yaml").resolve())
DUAL = str(Path("configs/dual-ur5-servicer.yaml").resolve())
TARGET = {
    "mass": 50.0,
    "inertia": [[4.0, 0.2, 0.0], [0.2, 5.0, 0.1], [0.0, 0.1, 6.0]],
    "offset": [0.05, -0.1, 0.3],
    "velocity": [0.05, -0.02, 0.01, 0.02, -0.03, 0.1],
}
UR5_WAYPOINTS = [[0.0, -1.0, 1.0, 0.0, 0.5, 0.0], [0.8, -0.5, 1.4, 0.3, 0.2, 0.4], [0.2, -1.2, 0.6, -0.2, 0.7, -0.3]]
UR5_TASK = {"waypoints": UR5_WAYPOINTS, "duration": 4.0}
POSTURES = 4
TARGET_FILE_MASS = 50.0  # the reference client of sweeps/pareto-capture-ur5.yaml, kg


@pytest.fixture(scope="module", params=["planar", "ur5", "dual_ur5"])
def impact_system(request, tmp_path_factory):
    """A robot, its Pinocchio reference, and our virtual mass and bus-rate jump at random
    postures, attitudes and directions, free and locked."""
    pytest.importorskip("pinocchio")
    name = request.param
    robot, text, names = BUILDERS[name](tmp_path_factory.mktemp(name))
    reference = PinocchioSystem(text, **names)
    rng = np.random.default_rng(11)
    planar = name == "planar"
    q = rng.uniform(-2.5, 2.5, (POSTURES, reference.n))
    if planar:
        phi0 = rng.uniform(-np.pi, np.pi, POSTURES)
        c, s = np.cos(phi0), np.sin(phi0)
        R = np.array([[[ci, -si, 0.0], [si, ci, 0.0], [0.0, 0.0, 1.0]] for ci, si in zip(c, s, strict=True)])
        posture, attitude = np.c_[phi0, q], None
    else:
        R = np.array([random_rotation(rng) for _ in range(POSTURES)])
        posture, attitude = q, R
    linear = 2 if planar else 3
    u = rng.normal(size=(POSTURES, linear))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    tip = 1 if name == "dual_ur5" else 0
    mine = {
        joints: (
            np.asarray(sa.virtual_mass(robot, posture, u, base_rotation=attitude, tip=tip, joints=joints)),
            np.asarray(sa.bus_rate_jump(robot, posture, u, base_rotation=attitude, tip=tip, joints=joints)),
        )
        for joints in sa.dynamics.JOINT_MODES
    }
    impulse = np.c_[u, np.zeros((POSTURES, len(reference.keep) - linear))]
    zero = np.zeros(reference.n)
    refs = [
        reference.state(q[i], zero, zero, R[i], np.zeros(len(reference.keep)), impulse[i], tip=tip)
        for i in range(POSTURES)
    ]
    return {"mine": mine, "refs": refs, "u": u, "tip": tip, "linear": linear}


@pytest.mark.parametrize("joints", ["free", "locked"])
def test_virtual_mass_and_bus_rate_jump_match_pinocchio(impact_system, joints):
    """1 / (u^T G_v u) from Pinocchio's G = J M^-1 J^T (locked: J_S M_b^-1 J_S^T), and the norm
    of the bus angular-velocity jump M^-1 J^T [u; 0], at random postures and attitudes."""
    mass, jump = impact_system["mine"][joints]
    linear, tip = impact_system["linear"], impact_system["tip"]
    for i, ref in enumerate(impact_system["refs"]):
        u = impact_system["u"][i]
        G = ref["G_free" if joints == "free" else "G_locked"][tip][:linear, :linear]
        dbase = ref["impulse_dbase" if joints == "free" else "impulse_locked_dbase"]
        np.testing.assert_allclose(mass[i], 1.0 / (u @ G @ u), rtol=1e-11)
        np.testing.assert_allclose(jump[i], np.linalg.norm(dbase[linear:]), rtol=1e-11)
    # locking the joints makes the hand meet the whole robot: a larger virtual mass
    if joints == "locked":
        assert np.all(mass > impact_system["mine"]["free"][0])


def test_joint_box_averages_are_the_means_of_the_kernels():
    """Each impact average agrees with a plain Monte Carlo mean of its kernel at 4096
    independent uniform postures of the joint box, within 5 combined standard errors (the
    capture's reference target held the same way by the hand: offset and inertia in tip axes)."""
    robot = sa.load_robot(UR5)
    setup = impact_setup("test", {"target": TARGET, "direction": [0.0, 1.0, 1.0]}, robot, need_target=True)
    metrics = ("virtual_mass", "bus_rate_jump", "capture_bus_rate")
    averages = joint_averages(robot, metrics, impact=setup, rtol=2e-3)
    lower, upper = (np.asarray(bound) for bound in joint_box(robot))
    q = np.random.default_rng(3).uniform(lower, upper, (4096, len(lower)))
    u = np.array([0.0, 1.0, 1.0]) / np.sqrt(2.0)
    held = sa.dynamics.payload.target_from_tip_frame(robot, q, setup.target)  # held the same way by the hand
    _, base, _ = sa.capture(robot, q, np.zeros_like(q), held)
    values = {
        "virtual_mass": np.asarray(sa.virtual_mass(robot, q, u)),
        "bus_rate_jump": np.asarray(sa.bus_rate_jump(robot, q, u)),
        "capture_bus_rate": np.linalg.norm(np.asarray(base)[:, 3:], axis=1),
    }
    for name in metrics:
        sample = values[name]
        error = np.hypot(float(averages[name].error), sample.std() / np.sqrt(sample.size))
        assert abs(float(averages[name].value) - sample.mean()) < 5 * error, name


def _sweep(tmp_path, robot, axis, metrics):
    spec = load_sweep(
        {"name": "impact-sweep", "robot": robot, "axes": axis, "metrics": metrics, "task": UR5_TASK}
        if any(m == "peak_wheel" for m in metrics)
        else {"name": "impact-sweep", "robot": robot, "axes": axis, "metrics": metrics}
    )
    table = run_sweep(spec, tmp_path / "out", progress=False).table
    designs, _ = build_designs(spec)
    count = len(table["design"])
    return table, [jax.tree_util.tree_map(lambda leaf, i=i: leaf[i], designs) for i in range(count)]


def test_sweep_columns_are_the_library_kernels(tmp_path):
    """The sweep's columns equal `joint_averages` with the same settings and `sa.wheel_peaks`
    at the same designs (two mounts of the UR5)."""
    rule = {"min_samples": 1024, "max_samples": 1024}
    metrics = [
        {"name": "virtual_mass", **rule},
        {"name": "bus_rate_jump", "direction": [0.0, 0.0, 1.0], "joints": "locked", **rule},
        {"name": "capture_bus_rate", "target": TARGET, **rule},
        "peak_wheel",
    ]
    axis = {"x": {"field": "mount.xyz[0]", "values": [0.0, 0.4]}}
    table, designs = _sweep(tmp_path, UR5, axis, metrics)
    task = sa.TimedTask(np.array(UR5_WAYPOINTS), 4.0)
    for i, design in enumerate(designs):
        free = impact_setup("t", {"target": TARGET}, design, need_target=True)
        locked = impact_setup("t", {"direction": [0.0, 0.0, 1.0], "joints": "locked"}, design, need_target=False)
        expect = {
            "virtual_mass_kg": joint_averages(design, ["virtual_mass"], impact=free, **rule)["virtual_mass"],
            "bus_rate_jump_radps_per_Ns": joint_averages(design, ["bus_rate_jump"], impact=locked, **rule)[
                "bus_rate_jump"
            ],
            "capture_bus_rate_radps": joint_averages(design, ["capture_bus_rate"], impact=free, **rule)[
                "capture_bus_rate"
            ],
        }
        for column, average in expect.items():
            np.testing.assert_allclose(table[column][i], average.value, rtol=1e-12)
            np.testing.assert_allclose(table[f"{column}_error"][i], average.error, rtol=1e-9)
        peaks = sa.wheel_peaks(design, task)
        np.testing.assert_allclose(table["peak_wheel_momentum_Nms"][i], peaks.momentum, rtol=1e-12)
        np.testing.assert_allclose(table["peak_wheel_torque_Nm"][i], peaks.torque, rtol=1e-12)
    assert abs(table["peak_wheel_momentum_Nms"][0] - table["peak_wheel_momentum_Nms"][1]) > 1e-3  # the mount matters


def test_a_tree_names_the_tip_of_each_impact_column(tmp_path):
    """On two UR5 the per-tip columns carry the tip's name and are that tip's kernel averages."""
    robot = sa.load_robot(DUAL)
    left, right = robot.tip_names
    rule = {"min_samples": 512, "max_samples": 512}
    metrics = [{"name": "virtual_mass", "tip": left, **rule}, {"name": "virtual_mass", "tip": 1, **rule}]
    table, designs = _sweep(tmp_path, DUAL, {"m": {"field": "base.mass", "values": [300.0]}}, metrics)
    setup = impact_setup("t", {}, designs[0], need_target=False)
    expect = joint_averages(designs[0], ["virtual_mass[0]", "virtual_mass[1]"], impact=setup, **rule)
    np.testing.assert_allclose(table[f"virtual_mass_kg[{left}]"][0], expect["virtual_mass[0]"].value, rtol=1e-12)
    np.testing.assert_allclose(table[f"virtual_mass_kg[{right}]"][0], expect["virtual_mass[1]"].value, rtol=1e-12)


def test_impact_and_wheel_objective_gradients_match_central_differences():
    """Every impact and wheel objective's gradient in the mount and the bus mass against
    central differences (the QMC rule is fixed, so each average is smooth in the design)."""
    problem = load_problem(
        {
            "name": "impact-problem",
            "robot": UR5,
            "variables": {"mount.xyz[0]": [-0.4, 0.6], "mount.rpy[1]": [-0.8, 0.8], "base.mass": [200.0, 800.0]},
            "objectives": [
                "low_virtual_mass",
                "low_bus_rate_jump",
                "low_capture_bus_rate",
                "low_peak_wheel_momentum",
                "low_peak_wheel_torque",
            ],
            "impact": {"target": TARGET, "direction": [1.0, 0.5, 0.0]},
            "task": UR5_TASK,
            "average": {"samples": 64, "randomizations": 4, "seed": 0},
        }
    )
    f = problem.objective_function()
    x = np.array([0.1, 0.3, 450.0])
    jacobian = np.asarray(jax.jit(jax.jacfwd(f))(jnp.asarray(x)))
    steps = np.array([1e-5, 1e-5, 1e-3])
    differences = np.stack([(f(x + e) - f(x - e)) / (2 * h) for e, h in zip(np.diag(steps), steps, strict=True)], -1)
    scale = np.abs(jacobian).max(axis=1, keepdims=True)
    np.testing.assert_allclose(jacobian / scale, differences / scale, rtol=0, atol=1e-6)
    assert np.all(np.abs(jacobian[:, :2]).max(axis=1) > 0)  # the mount moves every objective
    assert np.all(np.asarray(f(x)) < 0)  # minus positive quantities


@pytest.fixture(scope="module")
def mounts(tmp_path_factory):
    """Four UR5 smallsats that differ in their mount (position on the bus and tilt)."""
    folder = tmp_path_factory.mktemp("mounts")
    config = yaml.safe_load(Path(UR5).read_text(encoding="utf-8"))
    poses = [
        ([0.6, 0.1, 0.5], [0.1, -0.2, 0.3]),
        ([0.0, 0.0, 0.5], [0.0, 0.0, 0.0]),
        ([-0.3, 0.35, 0.5], [0.0, 0.6, -0.4]),
        ([0.4, -0.3, 0.2], [1.2, -0.5, 0.9]),
    ]
    paths = []
    for i, (xyz, rpy) in enumerate(poses):
        path = folder / f"mount{i}.yaml"
        path.write_text(yaml.safe_dump({**config, "name": f"mount{i}", "mount": {"xyz": xyz, "rpy": rpy}}))
        paths.append(path)
    return paths


def _quintic_states(waypoints, duration, samples=101):
    """The task's samples from the polynomial 10u^3 - 15u^4 + 6u^5 (numpy)."""
    waypoints = np.asarray(waypoints)
    T = duration / (len(waypoints) - 1)
    u = np.linspace(0.0, 1.0, samples)
    law = np.array([6.0, -15.0, 10.0, 0.0, 0.0, 0.0])
    s, ds, dds = (np.polyval(np.polyder(law, k), u) for k in range(3))
    step = np.diff(waypoints, axis=0)[:, None, :]
    q = waypoints[:-1, None, :] + s[:, None] * step
    return (a.reshape(-1, waypoints.shape[1]) for a in (q, ds[:, None] / T * step, dds[:, None] / T**2 * step))


def _pinocchio_wheels(reference: PinocchioSystem, q, qd, qdd):
    """The wheel momentum and torque at one state at zero momentum, bus attitude the identity:
    with w = 0 and P = 0 the bus's linear velocity cancels the arm's momentum, and the wheels
    hold minus the bodies' angular momentum about the system centroid (Pinocchio's centroidal
    momentum); their torque is the bus torque of Pinocchio's rnea with w = w' = 0."""
    pin, model, data = reference.pin, reference.model, reference.data
    config = reference.config(q, np.eye(3))
    M = pin.crba(model, data, config)
    Mo = (np.triu(M) + np.triu(M, 1).T)[np.ix_(reference.order, reference.order)]
    v = np.linalg.solve(Mo[:3, :3], -Mo[:3, 6:] @ qd)  # P = 0 with the bus not turning
    momentum = pin.computeCentroidalMomentum(model, data, config, reference._pin(np.r_[v, np.zeros(3), qd]))
    _, wrench = reference._attitude(config, Mo, qd, qdd, np.eye(3), np.zeros(6))
    return -np.asarray(momentum.angular), wrench[3:]


def test_peak_wheel_momentum_and_torque_on_four_mounts_match_pinocchio(mounts):
    """The peaks of a three-waypoint task on four UR5 mounts equal the largest norms of
    Pinocchio's wheel momentum and torque over the same 2 x 101 samples, to 1e-10."""
    pytest.importorskip("pinocchio")
    task = sa.TimedTask(np.array(UR5_WAYPOINTS), 4.0)
    q, qd, qdd = _quintic_states(UR5_WAYPOINTS, 4.0)
    for path in mounts:
        robot = sa.load_robot(path)
        text, com = config_urdf(path)
        reference = PinocchioSystem(text, bus_com=com, joint_names=list(robot.joint_names), tips=["tool0"])
        wheels = [_pinocchio_wheels(reference, *state) for state in zip(q, qd, qdd, strict=True)]
        h, torque = (np.array(a) for a in zip(*wheels, strict=True))
        peaks = sa.wheel_peaks(robot, task)
        np.testing.assert_allclose(peaks.momentum, np.linalg.norm(h, axis=1).max(), rtol=1e-10)
        np.testing.assert_allclose(peaks.torque, np.linalg.norm(torque, axis=1).max(), rtol=1e-10)
        np.testing.assert_allclose(np.asarray(sa.wheel_momentum(robot, q, qd)), h, rtol=0, atol=1e-10 * np.abs(h).max())


def test_planar_wheel_peaks_are_about_the_plane_normal():
    """The paper's arm: the wheel momentum is the z component alone, the peak its largest |h|."""
    robot = sa.umetani1990()
    waypoints = [[0.0, 0.5], [1.0, 1.5], [2.0, 0.3]]
    task = sa.TimedTask(np.array(waypoints), 6.0)
    q, qd, _ = _quintic_states(waypoints, 6.0)
    h = np.asarray(sa.wheel_momentum(robot, np.c_[np.zeros(len(q)), q], qd))
    assert h.shape == (len(q),)
    np.testing.assert_allclose(sa.wheel_peaks(robot, task).momentum, np.abs(h).max(), rtol=1e-12)


@pytest.mark.parametrize(
    ("metric", "message"),
    [
        ({"name": "capture_bus_rate"}, "metrics[0].target: missing"),
        ({"name": "capture_bus_rate", "target": {**TARGET, "mass": -1.0}}, "metrics[0].target.mass: must be positive"),
        (
            {"name": "capture_bus_rate", "target": {**TARGET, "inertia": [[1, 0, 0], [0, 1, 0], [0, 0, -1]]}},
            "metrics[0].target.inertia: must be positive definite",
        ),
        ({"name": "capture_bus_rate", "target": {**TARGET, "spin": 1}}, "metrics[0].target: unknown key 'spin'"),
        ({"name": "virtual_mass", "direction": [0, 0, 0]}, "metrics[0].direction: must not be zero"),
        ({"name": "virtual_mass", "direction": [1, 0]}, "metrics[0].direction: must be a list of 3 numbers"),
        ({"name": "virtual_mass", "joints": "stiff"}, "metrics[0].joints: must be one of"),
        ({"name": "virtual_mass", "target": TARGET}, "metrics[0]: unknown key 'target'"),
        ({"name": "capture_bus_rate", "target": TARGET, "direction": [1, 0, 0]}, "metrics[0]: unknown key 'direction'"),
        ({"name": "virtual_mass", "tip": "left/tool0"}, "metrics[0].tip: the robot has one tip"),
    ],
)
def test_bad_impact_settings_are_refused_naming_the_file_and_field(tmp_path, metric, message):
    path = tmp_path / "bad.yaml"
    axes = {"x": {"field": "mount.xyz[0]", "values": [0.0]}}
    path.write_text(yaml.safe_dump({"name": "bad", "robot": UR5, "axes": axes, "metrics": [metric]}))
    with pytest.raises(ConfigError) as error:
        load_sweep(path)
    assert message in str(error.value) and "bad.yaml" in str(error.value)


def test_problem_impact_section_needs_an_impact_objective_and_the_capture_its_target():
    base = {"name": "p", "robot": UR5, "variables": {"mount.xyz[0]": [-0.4, 0.6]}, "reference_point": [0.0, -1.0]}
    with pytest.raises(ConfigError, match=r"impact\.target: missing"):
        load_problem({**base, "objectives": ["w_avg", "low_capture_bus_rate"]})
    with pytest.raises(ConfigError, match="impact: the settings of the impact objectives"):
        load_problem({**base, "objectives": ["w_avg", "gci"], "impact": {"joints": "locked"}})
    planar = load_problem(
        {
            "name": "p",
            "fixed": {"base_mass": 1000.0, "base_inertia": 635.3, "arm_mass": 200.0, "reach": 2.0},
            "variables": {"b0": [0.5, 2.0]},
            "objectives": ["wbar", "low_bus_rate_jump"],
            "impact": {"direction": [0.0, 1.0]},
            "reference_point": [0.0, -1.0],
        }
    )
    np.testing.assert_allclose(planar.impact.direction, [0.0, 1.0])


@pytest.mark.slow
def test_pareto_run_with_a_capture_objective_reproduces_its_front(tmp_path):
    """The shipped capture problem (w-bar against the bus rate after the reference capture), at
    a cheap rule and a small budget: it finishes, and the objectives of pareto.csv are
    ``sa.load_problem(file).batch_function()`` at its designs to 1e-9."""
    config = yaml.safe_load(Path("sweeps/pareto-capture-ur5.yaml").read_text(encoding="utf-8"))
    config.update(
        robot=UR5,
        average={"samples": 64, "randomizations": 4, "seed": 0},
        hybrid={"population": 8, "generations": 3},
    )
    path = tmp_path / "capture.yaml"
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    out = tmp_path / "out"
    assert cli_main(["optimize", str(path), "--out", str(out), "--no-baselines"]) == 0
    with open(out / "pareto.csv") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == [*config["variables"], "w_avg", "low_capture_bus_rate"]
    table = np.array(rows[1:], dtype=float)
    again = np.asarray(sa.load_problem(str(path)).batch_function()(jnp.asarray(table[:, :3])))
    np.testing.assert_allclose(table[:, 3:], again, rtol=1e-9, atol=0)
    assert table.shape[0] >= 2 and np.all(nondominated_mask(table[:, 3:]))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["fixed"]["impact"]["target"]["mass"] == TARGET_FILE_MASS


def test_a_target_no_rigid_body_could_be_is_refused():
    """Principal moments (1, 1, 3): the largest exceeds the sum of the other two."""
    robot = sa.load_robot(UR5)
    with pytest.raises(ConfigError, match=r"t\.inertia: no rigid body has these principal moments"):
        impact_setup("t", {"target": {**TARGET, "inertia": [[1, 0, 0], [0, 1, 0], [0, 0, 3]]}}, robot, need_target=True)


def test_a_target_at_rest_keeps_every_gradient_finite():
    """A target at rest leaves the resting bus at rest (a rate of exactly 0 at every posture);
    the reverse-mode gradient of every objective stays finite (the rate's norm is taken with
    a finite derivative at 0), so the other objectives still steer the search."""
    problem = load_problem(
        {
            "name": "rest",
            "robot": UR5,
            "variables": {"mount.xyz[0]": [-0.4, 0.6], "base.mass": [200.0, 800.0]},
            "objectives": ["low_capture_bus_rate", "low_virtual_mass"],
            "impact": {"target": {"mass": 50.0, "inertia": [[4, 0, 0], [0, 5, 0], [0, 0, 6]]}},
            "average": {"samples": 64, "randomizations": 4, "seed": 0},
            "reference_point": [-1.0, -100.0],
        }
    )
    x = jnp.array([0.1, 450.0])
    f = problem.objective_function()
    np.testing.assert_array_equal(f(x)[0], 0.0)
    jacobian = np.asarray(jax.jacrev(f)(x))
    assert np.all(np.isfinite(jacobian)) and np.all(jacobian[0] == 0) and np.all(jacobian[1] != 0)


def test_a_planar_target_lies_in_the_plane():
    robot = sa.umetani1990()
    target = {"mass": 10.0, "inertia": 2.0, "offset": [0.1, 0.2, 0.3], "velocity": [0.1, 0.0, 0.2]}
    posture, rates = np.radians([10.0, 30.0, 60.0]), np.array([0.1, -0.2])
    with pytest.raises(ValueError, match=r"^target\.offset: a planar robot's target lies in the plane"):
        sa.capture(robot, posture, rates, target)
    tilted = {**target, "offset": [0.1, 0.2], "inertia": [[1.0, 0.0, 0.5], [0.0, 1.0, 0.0], [0.5, 0.0, 2.0]]}
    with pytest.raises(ValueError, match=r"^target\.inertia: a planar robot's target turns about z alone"):
        sa.capture(robot, posture, rates, tilted)
    # Ixx and Iyy do not enter the in-plane grasp: only Izz does
    flat = {**target, "offset": [0.1, 0.2]}
    full = {**flat, "inertia": [[7.0, 0.3, 0.0], [0.3, 5.0, 0.0], [0.0, 0.0, 2.0]]}
    for mine, same in zip(
        sa.capture(robot, posture, rates, flat), sa.capture(robot, posture, rates, full), strict=True
    ):
        np.testing.assert_allclose(mine, same, rtol=1e-13, atol=1e-15)
    with pytest.raises(ConfigError, match=r"t\.offset: a planar robot's target lies in the plane"):
        impact_setup("t", {"target": target}, robot, need_target=True)


def test_kernel_arguments_are_named_when_wrong():
    robot = sa.load_robot(DUAL)
    q = np.zeros(12)
    with pytest.raises(ValueError, match=r"^direction: must not be zero"):
        sa.virtual_mass(robot, q, [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"^tip: the index of a tip \(0\.\.1\), got the name 'right/tool0'"):
        sa.capture(robot, q, q, {**TARGET}, tip="right/tool0")
    with pytest.raises(ValueError, match=r"^target: missing offset"):
        sa.target_in_tip_frame(robot, q, {"mass": 5.0, "inertia": np.eye(3)}, tip=1)
    with pytest.raises(ConfigError, match=r"impact\.target: only the bus rate after a capture"):
        load_problem(
            {
                "name": "p",
                "robot": UR5,
                "variables": {"mount.xyz[0]": [-0.4, 0.6]},
                "objectives": ["w_avg", "low_virtual_mass"],
                "impact": {"target": TARGET},
                "reference_point": [0.0, -100.0],
            }
        )


def test_planar_impact_and_wheel_objective_gradients_match_central_differences():
    """The paper's arm: the impact averages (direction, target in the plane) and the wheel
    peaks along a task, against central differences in the attachment and the link split."""
    problem = load_problem(
        {
            "name": "planar-impact",
            "fixed": {"base_mass": 1000.0, "base_inertia": 635.3, "arm_mass": 200.0, "reach": 2.0},
            "variables": {"b0": [0.5, 2.0], "l1_over_L": [0.3, 0.7]},
            "objectives": ["low_virtual_mass", "low_bus_rate_jump", "low_capture_bus_rate", "low_peak_wheel_torque"],
            "impact": {
                "direction": [1.0, 1.0],
                "target": {"mass": 40.0, "inertia": 2.0, "offset": [0.2, 0.0], "velocity": [0.05, -0.02, 0.1]},
            },
            "task": {"waypoints": [[0.0, 0.5], [1.0, 1.5], [2.0, 0.3]], "duration": 6.0},
            "average": {"samples": 64, "randomizations": 4, "seed": 0},
            "reference_point": [-1000.0, -1.0, -1.0, -1e4],
        }
    )
    f = problem.objective_function()
    x = np.array([1.2, 0.45])
    jacobian = np.asarray(jax.jit(jax.jacfwd(f))(jnp.asarray(x)))
    h = 1e-6
    differences = np.stack([(f(x + e) - f(x - e)) / (2 * h) for e in np.eye(2) * h], -1)
    scale = np.abs(jacobian).max(axis=1, keepdims=True)
    np.testing.assert_allclose(jacobian / scale, differences / scale, rtol=0, atol=1e-6)
    assert np.all(scale > 0)


def test_a_point_target_grasp_is_the_rigid_grasp_formula():
    """A target of negligible inertia grasped at its centroid: the linear impulse is
    (G_v + I / m_t)^-1 (v_t - v_hand), the two-body plastic impact with G_v the hand's inverse
    inertia (docs/explanation/capture.md), at random postures and masses; and the numbers the
    page quotes at the zero posture (a regression pin of this kernel: m_v along x)."""
    robot = sa.load_robot(UR5)
    rng = np.random.default_rng(8)
    q = rng.uniform(-2.5, 2.5, (6, 6))
    G = np.asarray(sa.tip_inverse_inertia(robot, q))[:, :3, :3]
    for mass in (1.0, 10.0, 50.0):
        velocity = rng.normal(size=(6, 3)) * 0.1
        target = {"mass": mass, "inertia": np.eye(3) * 1e-12, "offset": np.zeros(3)}
        target["velocity"] = np.c_[velocity, np.zeros((6, 3))]
        _, _, impulse = sa.capture(robot, q, np.zeros_like(q), target)
        expect = np.linalg.solve(G + np.eye(3) / mass, velocity[..., None])[..., 0]
        np.testing.assert_allclose(np.asarray(impulse)[:, :3], expect, rtol=0, atol=1e-9 * np.abs(expect).max())
    np.testing.assert_allclose(sa.virtual_mass(robot, np.zeros(6), [1.0, 0.0, 0.0]), 10.00, atol=0.005)


def test_a_focused_tree_grasps_and_carries_with_its_focused_hand():
    """On two UR5 focused on the right arm, tip 0 is the right hand everywhere: the capture,
    the target in tip axes and the robot carrying it equal the whole tree's tip 1."""
    dual = sa.load_robot(DUAL)
    focused = dual.focus(tip=dual.tip_names[1])
    rng = np.random.default_rng(4)
    q, qd = rng.uniform(-2.0, 2.0, 12), rng.normal(size=12) * 0.3
    for mine, tree in zip(sa.capture(focused, q, qd, TARGET), sa.capture(dual, q, qd, TARGET, tip=1), strict=True):
        np.testing.assert_allclose(mine, tree, rtol=1e-13, atol=1e-15)
    held, whole = sa.target_in_tip_frame(focused, q, TARGET), sa.target_in_tip_frame(dual, q, TARGET, tip=1)
    np.testing.assert_allclose(held["com"], whole["com"], rtol=1e-13)
    carried, carried_tree = sa.grasped_robot(focused, q, TARGET), sa.grasped_robot(dual, q, TARGET, tip=1)
    np.testing.assert_allclose(carried.link_mass, carried_tree.link_mass, rtol=1e-15)
    with pytest.raises(ValueError, match=r"^tip: 1 is not one of the robot's 1 tip"):
        sa.target_in_tip_frame(focused, q, TARGET, tip=1)
