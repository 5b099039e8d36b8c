"""A grasp (`sa.capture`, free and locked joints) and the reaction-wheel momentum
(`sa.wheel_momentum`) against Pinocchio, conservation of momentum and finite differences.

The four systems of tests/test_dynamics.py (the planar system of Umetani & Yoshida 1990, the
UR5 on its smallsat, two UR5 on one bus grasping with either tip, a random 7-joint arm), each
read by the references from its own URDF (tests/dynamics_references.py). Six states per system
at random attitudes (the last three at nonzero momentum), each with its own random target
(5-200 kg, a random full inertia, its centroid 0.05-0.5 m from the tip, a random twist; planar
targets in the plane), go through one jitted program.

- Capture: Pinocchio's impulse dynamics (restitution 0) of the robot plus the target as a
  second free-floating body welded to the tip frame by a 6D constraint; locked joints: the
  same on Pinocchio's reduced model with every arm joint locked (tests/capture_references.py).
  Our formula is Yoshida's (Yoshida & Nenchev, ICRA 1995; Yoshida, Kurazume & Umetani 1991):
  Pinocchio never sees it.
- Conservation: the momentum of robot and target about a fixed point, the robot's from
  Pinocchio's centroidal momentum at our velocities after the grasp, the target's by hand as a
  body moving with the tip frame, is the same before and after; the robot's change of momentum
  about the tip origin is our impulse.
- Wheel momentum: h = R^T (L - L_bodies), the bodies' angular momentum from Pinocchio's
  centroidal map with the bus held in attitude and translating with the linear momentum P;
  its rate along a motion (five-point central differences) is minus the torque rows of the
  ``"attitude"`` wrench of `sa.inverse_dynamics` (the reaction null space keeps h constant:
  Yoshida, Hashizume & Abiko 2001).

Agreement with Pinocchio is asked to 1e-12 relative to each state's largest reference entry.
"""

from __future__ import annotations

import functools
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import spacearm as sa
from spacearm.models.family import family_of

from .capture_references import PinocchioCapture, random_inertia
from .dynamics_references import BUILDERS, CONFIGS, PLANAR_KEEP, PinocchioSystem
from .spatial_references import random_rotation

ROBOTS = ("planar", "ur5", "dual_ur5", "random7")
STATES = 6  # the last half at nonzero momentum
TOLERANCE = 1e-12  # relative to each state's largest reference entry
STEP = 1e-3  # the time step of the five-point central differences of h along a motion
RATE_TOLERANCE = 1e-10  # -dh/dt against the attitude wrench, relative to the largest torque


def _states(rng, n, planar):
    """STATES states: joints, rates, accelerations, attitudes, momenta (zero for the first half)."""
    q = rng.uniform(-2.5, 2.5, (STATES, n))
    qd, qdd = rng.normal(size=(STATES, n)), rng.normal(size=(STATES, n))
    if planar:
        phi0 = rng.uniform(-np.pi, np.pi, STATES)
        R = np.array([[[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]] for a in phi0])
        posture = np.c_[phi0, q]
    else:
        R = np.array([random_rotation(rng) for _ in range(STATES)])
        posture = q
    momentum = rng.normal(size=(STATES, 3 if planar else 6)) * 20.0
    momentum[: STATES // 2] = 0.0
    return {"q": q, "posture": posture, "qd": qd, "qdd": qdd, "R": R, "momentum": momentum}


def _targets(rng, planar):
    """STATES random targets: ours (a mapping of batched arrays; planar: velocity [vx, vy, w],
    offset (2,), inertia Izz) and the references' (one full spatial mapping per state)."""
    mass = rng.uniform(5.0, 200.0, STATES)
    inertia = np.array([random_inertia(rng, m) for m in mass])
    direction = rng.normal(size=(STATES, 3))
    velocity = np.c_[rng.normal(size=(STATES, 3)) * 0.5, rng.normal(size=(STATES, 3)) * 0.3]
    if planar:  # in the plane: no z offset, no out-of-plane motion, no product of inertia with z
        direction[:, 2], velocity[:, 2:5] = 0.0, 0.0
        inertia[:, 2, :2], inertia[:, :2, 2] = 0.0, 0.0
    offset = direction / np.linalg.norm(direction, axis=1)[:, None] * rng.uniform(0.05, 0.5, (STATES, 1))
    theirs = [
        {"mass": m, "inertia": i, "offset": o, "velocity": v}
        for m, i, o, v in zip(mass, inertia, offset, velocity, strict=True)
    ]
    if planar:
        ours = {
            "mass": mass,
            "inertia": inertia[:, 2, 2],
            "offset": offset[:, :2],
            "velocity": velocity[:, list(PLANAR_KEEP)],
        }
    else:
        ours = {"mass": mass, "inertia": inertia, "offset": offset, "velocity": velocity}
    return ours, theirs


def _motion(posture, qd, qdd, planar):
    """The postures and rates at t = -2, -1, 1, 2 steps along (q + t qd, qd + t qdd) ``(4, STATES, ...)``
    (a planar phi0 stays: the wheels hold the attitude)."""
    t = STEP * jnp.array([-2.0, -1.0, 1.0, 2.0])[:, None, None]
    step = jnp.concatenate([jnp.zeros_like(qd[..., :1]), qd], axis=-1) if planar else qd
    return posture + t * step, qd + t * qdd


def _five_point(values):
    """d/dt at t = 0 from the values at t = -2, -1, 1, 2 steps (axis 0)."""
    return (values[0] - 8.0 * values[1] + 8.0 * values[2] - values[3]) / (12.0 * STEP)


@functools.partial(jax.jit, static_argnames=("planar",))
def _kernels(robot, posture, R, qd, qdd, momentum, target, tip, planar):
    """Every kernel at a batch of states (one program per robot; ``tip`` is traced)."""
    R = None if planar else R
    out = {}
    for joints in ("free", "locked"):
        after = sa.capture(robot, posture, qd, target, base_rotation=R, momentum=momentum, tip=tip, joints=joints)
        out.update({f"{joints}_{key}": value for key, value in zip(("qd", "base", "impulse"), after, strict=True)})
    last = jax.tree.map(lambda x: x[-1], (posture, qd, target, momentum))
    single = sa.capture(robot, *last[:3], base_rotation=None if planar else R[-1], momentum=last[3], tip=tip)
    out.update({f"single_{key}": value for key, value in zip(("qd", "base", "impulse"), single, strict=True)})
    shared = jax.tree.map(lambda x: x[-1], target)  # the last target for every state
    after = sa.capture(robot, posture, qd, shared, base_rotation=R, momentum=momentum, tip=tip)
    out.update({f"shared_{key}": value for key, value in zip(("qd", "base", "impulse"), after, strict=True)})
    if planar:  # the same targets written in 3D: offset (3,), a 3x3 inertia about the centroid
        spatial = dict(target, offset=jnp.pad(target["offset"], ((0, 0), (0, 1))))
        spatial["inertia"] = target["inertia"][:, None, None] * jnp.eye(3) + jnp.diag(jnp.array([2.0, 3.0, 0.0]))
        after = sa.capture(robot, posture, qd, spatial, momentum=momentum, tip=tip)
        out.update({f"spatial_{key}": value for key, value in zip(("qd", "base", "impulse"), after, strict=True)})
    out["wheel_momentum"] = sa.wheel_momentum(robot, posture, qd, base_rotation=R, momentum=momentum)
    moved, rates = _motion(posture, qd, qdd, planar)
    out["wheel_momentum_moved"] = sa.wheel_momentum(robot, moved, rates, base_rotation=R, momentum=momentum)
    _, wrench = sa.inverse_dynamics(robot, posture, qd, qdd, base_rotation=R, momentum=momentum, base="attitude")
    out["attitude_wrench"] = wrench
    return out


def _tips(name):
    return (0, 1) if name == "dual_ur5" else (0,)


def _references(reference, states, targets, tip):
    """Pinocchio's capture, free and locked, at every state (our outputs' shapes and the full
    velocities nu_pin after)."""
    out = {}
    for joints in ("free", "locked"):
        rows = [
            reference.capture(*(states[k][i] for k in ("q", "qd", "R", "momentum")), targets[i], tip=tip, joints=joints)
            for i in range(STATES)
        ]
        for j, key in enumerate(("qd", "base", "impulse")):
            out[f"{joints}_{key}"] = np.array([row[j] for row in rows])
    return out


@pytest.fixture(scope="module", params=ROBOTS)
def system(request, tmp_path_factory):
    """One robot: our kernels at STATES states and targets, per tip, and the references."""
    name = request.param
    pytest.importorskip("pinocchio")
    robot, text, names = BUILDERS[name](tmp_path_factory.mktemp(name))
    planar = name == "planar"
    reference = PinocchioCapture(PinocchioSystem(text, **names))
    rng = np.random.default_rng(100 + ROBOTS.index(name))
    states = _states(rng, reference.n, planar)
    ours, theirs = _targets(rng, planar)
    arrays = [states[k] for k in ("posture", "R", "qd", "qdd", "momentum")]
    mine = {tip: _kernels(robot, *arrays, ours, tip, planar=planar) for tip in _tips(name)}
    mine = {tip: {key: np.asarray(value) for key, value in out.items()} for tip, out in mine.items()}
    pinocchio = {tip: _references(reference, states, theirs, tip) for tip in _tips(name)}
    return {
        "name": name,
        "planar": planar,
        "states": states,
        "targets": theirs,
        "reference": reference,
        "mine": mine,
        "pinocchio": pinocchio,
    }


def _relative_error(mine, reference):
    """The largest error of any state relative to that state's largest reference entry."""
    mine, reference = np.asarray(mine), np.asarray(reference)
    assert mine.shape == reference.shape, (mine.shape, reference.shape)
    axes = tuple(range(1, reference.ndim))
    scale = np.maximum(np.abs(reference).max(axis=axes, initial=0.0), 1e-300)
    return float(np.max(np.abs(mine - reference).max(axis=axes, initial=0.0) / scale))


# Capture ----------------------------------------------------------------------------------


@pytest.mark.parametrize("joints", ["free", "locked"])
@pytest.mark.parametrize("quantity", ["qd", "base", "impulse"])
def test_capture_matches_pinocchio_impulse_dynamics(system, joints, quantity):
    """Joint rates, bus twist and the impulse on the tip after the grasp, every tip of a tree."""
    for tip, mine in system["mine"].items():
        key = f"{joints}_{quantity}"
        error = _relative_error(mine[key], system["pinocchio"][tip][key])
        assert error < TOLERANCE, f"{system['name']} tip {tip} {key}: relative error {error:.2e}"


def test_locked_joints_keep_their_rates(system):
    for mine in system["mine"].values():
        np.testing.assert_array_equal(mine["locked_qd"], system["states"]["qd"])


def _target_momentum(target, centroid, twist_at_tip):
    """[P; L about the world origin] of the target moving with ``twist_at_tip`` [v of its point at
    the tip origin; w]: m v_c and I w + c x m v_c."""
    w = twist_at_tip[3:]
    v = twist_at_tip[:3] + np.cross(w, target["offset"])
    P = target["mass"] * v
    return np.concatenate([P, target["inertia"] @ w + np.cross(centroid, P)])


def _balance(system, tip, joints, i):
    """(total momentum before, after, its scale; the robot's change about the tip origin, our impulse)
    at state i, world axes."""
    reference, s, target = system["reference"], system["states"], system["targets"][i]
    mine = system["mine"][tip]
    q, R = s["q"][i], s["R"][i]
    before = reference.velocity(q, s["qd"][i], R, s["momentum"][i])
    after = reference.ours_to_pin(R, mine[f"{joints}_base"][i], mine[f"{joints}_qd"][i])
    origin, _ = reference.tip_motion(q, R, before, tip)
    _, tip_after = reference.tip_motion(q, R, after, tip)
    centroid = origin + target["offset"]
    v, w = target["velocity"][:3], target["velocity"][3:]
    target_before = _target_momentum(target, centroid, np.concatenate([v - np.cross(w, target["offset"]), w]))
    robot_before = reference.momentum_about_origin(q, R, before)
    robot_after = reference.momentum_about_origin(q, R, after)
    scale = max(np.abs(robot_before).max(), np.abs(target_before).max())
    change = robot_after - robot_before
    change = np.concatenate([change[:3], change[3:] - np.cross(origin, change[:3])])  # about the tip origin
    impulse = reference.system.embed(mine[f"{joints}_impulse"][i])
    total = (robot_before + target_before, robot_after + _target_momentum(target, centroid, tip_after))
    return (*total, scale, change, impulse)


@pytest.mark.parametrize("joints", ["free", "locked"])
def test_grasp_conserves_momentum_and_the_impulse_is_the_robots_change(system, joints):
    """Robot and target together keep their momentum about a fixed point through the grasp (the
    locked joints' impulsive torques are internal), the target moving with the tip frame after
    it; the robot's momentum change about the tip origin is the impulse the target applied."""
    for tip in system["mine"]:
        for i in range(STATES):
            before, after, scale, change, impulse = _balance(system, tip, joints, i)
            np.testing.assert_allclose(after, before, rtol=0, atol=1e-12 * scale)
            np.testing.assert_allclose(change, impulse, rtol=0, atol=1e-12 * np.abs(impulse).max())


def test_other_forms_of_the_same_grasp(system):
    """One state and one target without a batch axis give the batched call's last row, and so
    does one target shared by a batch of states; a planar robot's targets written in 3D (offset
    (3,), a 3x3 inertia whose moment about z is the planar one, the other moments arbitrary)
    grasp like the in-plane form."""
    for mine in system["mine"].values():
        for key in ("qd", "base", "impulse"):
            batched = mine[f"free_{key}"]
            scale = np.abs(batched[-1]).max()
            assert mine[f"single_{key}"].shape == batched.shape[1:]
            np.testing.assert_allclose(mine[f"single_{key}"], batched[-1], rtol=0, atol=1e-13 * scale)
            assert mine[f"shared_{key}"].shape == batched.shape
            np.testing.assert_allclose(mine[f"shared_{key}"][-1], batched[-1], rtol=0, atol=1e-13 * scale)
            if system["planar"]:
                error = _relative_error(mine[f"spatial_{key}"], batched)
                assert error < 1e-13, f"planar target in 3D, {key}: relative error {error:.2e}"
    assert system["planar"] == ("spatial_qd" in system["mine"][0])


# Wheel momentum ---------------------------------------------------------------------------


def _reference_wheels(system, moved=False):
    """Pinocchio's h at every state ``(STATES, ...)`` or along the motion ``(4, STATES, ...)``."""
    reference, s = system["reference"], system["states"]
    if not moved:
        return np.array(
            [reference.wheel_momentum(s["q"][i], s["qd"][i], s["R"][i], s["momentum"][i]) for i in range(STATES)]
        )
    t = STEP * np.array([-2.0, -1.0, 1.0, 2.0])
    return np.array(
        [
            [
                reference.wheel_momentum(
                    s["q"][i] + dt * s["qd"][i], s["qd"][i] + dt * s["qdd"][i], s["R"][i], s["momentum"][i]
                )
                for i in range(STATES)
            ]
            for dt in t
        ]
    )


def test_wheel_momentum_matches_pinocchio(system):
    """h = R^T L - L_bodies, bus axes (planar: about z), zero and nonzero momentum."""
    error = _relative_error(system["mine"][0]["wheel_momentum"], _reference_wheels(system))
    assert error < TOLERANCE, f"{system['name']} wheel momentum: relative error {error:.2e}"


def test_wheel_torque_is_minus_the_rate_of_wheel_momentum(system):
    """-dh/dt along (q + t qd, qd + t qdd) at fixed momentum (five-point central differences of
    ours and of Pinocchio's h) is the torque the attitude mode's wheels apply to the bus."""
    mine = system["mine"][0]
    torque = mine["attitude_wrench"][:, 2:] if system["planar"] else mine["attitude_wrench"][:, 3:]
    torque = torque[:, 0] if system["planar"] else torque
    scale = np.abs(torque).max()
    for h in (mine["wheel_momentum_moved"], _reference_wheels(system, moved=True)):
        np.testing.assert_allclose(-_five_point(h), torque, rtol=0, atol=RATE_TOLERANCE * scale)


# Bad input --------------------------------------------------------------------------------

GOOD_TARGET = {"mass": 40.0, "inertia": np.eye(3) * 2.0, "offset": [0.1, 0.0, 0.2], "velocity": np.full(6, 0.1)}


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"joints": "rigid"}, r"^joints: one of free, locked, got 'rigid'"),
        ({"qd": np.zeros(5)}, r"^qd: expected trailing axes \(6,\)"),
        ({"momentum": np.zeros(3)}, r"^momentum: expected trailing axes \(6,\)"),
        ({"base_rotation": np.eye(2)}, r"^base_rotation: expected trailing axes \(3, 3\)"),
    ],
)
def test_capture_refuses_bad_input_naming_the_argument(arguments, message):
    robot = sa.load_robot(os.path.join(CONFIGS, "ur5-smallsat.yaml"))
    call = {"q": np.zeros(6), "qd": np.zeros(6), "target": GOOD_TARGET, **arguments}
    with pytest.raises(ValueError, match=message):
        sa.capture(robot, **call)


PLANAR_TARGET = {"mass": 40.0, "inertia": 2.0, "offset": [0.1, 0.2], "velocity": [0.1, 0.0, 0.2]}


@pytest.mark.parametrize(
    ("robot", "change", "message"),
    [
        ("ur5-smallsat", {"tip": 1}, r"^tip: 1 is not one of the robot's 1 tip"),
        ("ur5-smallsat", {"tip": -1}, r"^tip: -1 is not one of the robot's 1 tip"),
        ("dual-ur5-servicer", {"tip": 2}, r"^tip: 2 is not one of the robot's 2 tip"),
        ("umetani1990", {"tip": 1}, r"^tip: 1 is not one of the robot's 1 tip"),
        ("ur5-smallsat", {"target": {k: v for k, v in GOOD_TARGET.items() if k != "velocity"}}, r"target.*velocity"),
        ("ur5-smallsat", {"target": dict(GOOD_TARGET, speed=1.0)}, r"target.*speed"),
        ("ur5-smallsat", {"target": 3.0}, r"target"),
        ("ur5-smallsat", {"target": dict(GOOD_TARGET, offset=np.ones(4))}, r"target.*offset"),
        ("ur5-smallsat", {"target": dict(GOOD_TARGET, velocity=np.ones(5))}, r"target.*velocity"),
        ("ur5-smallsat", {"target": dict(GOOD_TARGET, inertia=np.eye(2))}, r"target.*inertia"),
        ("umetani1990", {"target": dict(PLANAR_TARGET, velocity=np.ones(6))}, r"target.*velocity"),
        ("umetani1990", {"target": dict(PLANAR_TARGET, offset=np.ones(4))}, r"target.*offset"),
        ("ur5-smallsat", {"target": dict(GOOD_TARGET, mass=-5.0)}, r"^target\.mass: must be positive"),
    ],
)
def test_capture_refuses_a_bad_target_or_tip(robot, change, message):
    """A wrong target (a missing or unknown key, a wrong trailing shape) or a tip the robot does
    not have is refused with a message naming it, not read as something else (a tip of a
    one-tip robot as tip 0, a tree's third tip as NaN, an unknown key ignored)."""
    robot = sa.umetani1990() if robot == "umetani1990" else sa.load_robot(os.path.join(CONFIGS, f"{robot}.yaml"))
    family = family_of(robot)
    n = family.joint_count(robot)
    target = PLANAR_TARGET if family.posture_offset else GOOD_TARGET
    call = {"q": np.zeros(family.posture_offset + n), "qd": np.zeros(n), "target": target, **change}
    with pytest.raises(ValueError, match=message):
        sa.capture(robot, **call)
