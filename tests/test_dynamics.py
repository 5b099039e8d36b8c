"""The free-floating dynamics (`spacearm.dynamics`) against Pinocchio, MuJoCo, finite
differences and the energy balance.

Four systems, each read by the references from its own URDF (tests/dynamics_references.py):

- the planar system of Umetani & Yoshida 1990 (Table 1), written as a URDF of z-axis
  revolute joints from the paper's numbers (configs/umetani1990.yaml read as plain YAML);
- the UR5 on its smallsat (configs/ur5-smallsat.yaml);
- two UR5 on one bus (configs/dual-ur5-servicer.yaml), a tree with two tips;
- a random 7-joint arm (revolute, continuous and prismatic joints, a fixed joint on the
  path, side branches, a locked finger) on a bus with a rotated full inertia, an
  off-centre centroid and a tilted mount, loaded from a robot file written here.

Eight states per system at random attitudes, the last four at nonzero momentum, go
through one jitted program of every kernel; Pinocchio (crba, computeCentroidalMap, aba,
rnea, nonLinearEffects, frame Jacobians) and MuJoCo (mj_fullM, mj_subtreeVel, mj_forward,
mj_inverse) give the references state by state. Agreement is asked to 1e-10 relative to
each quantity's largest reference entry (observed: a few 1e-14 at worst).
"""

from __future__ import annotations

import dataclasses
import functools
import importlib.util
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import spacearm as sa
from spacearm.models.family import family_of

from .dynamics_references import BUILDERS, CONFIGS, PLANAR_KEEP, MujocoSystem, PinocchioSystem
from .spatial_references import mujoco_model, random_rotation
from .tree_references import random_tree

TOLERANCE = 1e-10  # relative to each quantity's largest reference entry
STATES = 8  # the last half at nonzero momentum
ROBOTS = ("planar", "ur5", "dual_ur5", "random7")


# The states and our kernels in one program --------------------------------------------------


def _states(rng, n, planar):
    """STATES states: joints, rates, torques, attitudes, momenta (zero for the first half), impulses."""
    keep = len(PLANAR_KEEP) if planar else 6
    q = rng.uniform(-2.5, 2.5, (STATES, n))
    qd = rng.normal(size=(STATES, n))
    tau = rng.normal(size=(STATES, n)) * 5.0
    if planar:
        phi0 = rng.uniform(-np.pi, np.pi, STATES)
        c, s = np.cos(phi0), np.sin(phi0)
        R = np.stack(
            [np.stack([c, -s, 0 * c], -1), np.stack([s, c, 0 * c], -1), np.tile([0.0, 0.0, 1.0], (STATES, 1))], 1
        )
        posture = np.c_[phi0, q]
    else:
        R = np.array([random_rotation(rng) for _ in range(STATES)])
        posture = q
    momentum = rng.normal(size=(STATES, keep)) * 20.0
    momentum[: STATES // 2] = 0.0
    impulse = rng.normal(size=(STATES, keep))
    return {"q": q, "posture": posture, "qd": qd, "tau": tau, "R": R, "momentum": momentum, "impulse": impulse}


ENERGY_STEP = 1e-4  # joint step along qd for dH/dt by central differences


@functools.partial(jax.jit, static_argnames=("tip", "planar"))
def _kernels(robot, posture, R, qd, tau, qdd, momentum, impulse, tip, planar):
    """Every kernel at a batch of states (one program per robot structure; nested jits inline)."""
    R = None if planar else R
    state = {"base_rotation": R, "momentum": momentum}
    out = {
        "mass_matrix": sa.mass_matrix(robot, posture, base_rotation=R),
        "bias_forces": sa.bias_forces(robot, posture, qd, **state),
        "arm_inertia": sa.arm_inertia(robot, posture),
        "reduced_bias": sa.reduced_bias(robot, posture, qd, **state),
        "base_velocity": sa.base_velocity(robot, posture, qd, **state),
        "tip_velocity": sa.tip_velocity(robot, posture, qd, **state),
        "forward_dynamics": sa.forward_dynamics(robot, posture, qd, tau, **state),
        "G_free": sa.tip_inverse_inertia(robot, posture, base_rotation=R),
        "G_locked": sa.tip_inverse_inertia(robot, posture, base_rotation=R, joints="locked"),
    }
    for base in sa.dynamics.BASE_MODES:
        out[f"{base}_tau"], out[f"{base}_wrench"] = sa.inverse_dynamics(robot, posture, qd, qdd, **state, base=base)
    last = jax.tree.map(lambda x: None if x is None else x[-1], state)  # one state, no batch axis
    out["single_forward_dynamics"] = sa.forward_dynamics(robot, posture[-1], qd[-1], tau[-1], **last)
    out["impulse_dqd"], out["impulse_dbase"] = sa.impulse_response(robot, posture, impulse, base_rotation=R, tip=tip)
    locked = sa.impulse_response(robot, posture, impulse, base_rotation=R, tip=tip, joints="locked")
    out["impulse_locked_dqd"], out["impulse_locked_dbase"] = locked
    # H along the motion, for the energy balance: q -/+ h qd (a planar phi0 stays).
    step = jnp.concatenate([jnp.zeros_like(qd[..., :1]), qd], axis=-1) if planar else qd
    out["mass_matrix_ahead"] = sa.mass_matrix(robot, posture + ENERGY_STEP * step, base_rotation=R)
    out["mass_matrix_behind"] = sa.mass_matrix(robot, posture - ENERGY_STEP * step, base_rotation=R)
    return out


@pytest.fixture(scope="module")
def system(request, tmp_path_factory):
    """One robot: its kernels at STATES states and the references there (built once)."""
    name = request.param
    pytest.importorskip("pinocchio")
    robot, text, names = BUILDERS[name](tmp_path_factory.mktemp(name))
    planar = name == "planar"
    reference = PinocchioSystem(text, **names)
    rng = np.random.default_rng(ROBOTS.index(name))
    states = _states(rng, reference.n, planar)
    tip = 1 if name == "dual_ur5" else 0
    refs = [
        reference.state(*(states[k][i] for k in ("q", "qd", "tau", "R", "momentum", "impulse")), tip=tip)
        for i in range(STATES)
    ]
    pin_ref = {key: np.array([r[key] for r in refs]) for key in refs[0]}
    if _tip_count(robot) is None:
        for key in ("G_free", "G_locked", "tip_velocity"):
            pin_ref[key] = pin_ref[key][:, 0]
    mine = _kernels(
        robot,
        *(states[k] for k in ("posture", "R", "qd", "tau")),
        pin_ref["qdd"],
        states["momentum"],
        states["impulse"],
        tip=tip,
        planar=planar,
    )
    mine = {key: np.asarray(value) for key, value in mine.items()}
    mj_ref = None
    if importlib.util.find_spec("mujoco") is not None:
        mj = MujocoSystem(mujoco_model(text), **{k: v for k, v in names.items() if k != "tips"})
        refs = [mj.state(*(states[k][i] for k in ("q", "qd", "tau", "R", "momentum"))) for i in range(STATES)]
        mj_ref = {key: np.array([r[key] for r in refs]) for key in refs[0]}
    return {
        "name": name,
        "robot": robot,
        "planar": planar,
        "states": states,
        "tip": tip,
        "pinocchio": pin_ref,
        "mujoco": mj_ref,
        "mine": mine,
    }


def _tip_count(robot):
    """The number of tips of a robot with a tip axis, else None."""
    return family_of(robot).tip_count(robot)


def _relative_error(mine, reference):
    mine, reference = np.asarray(mine), np.asarray(reference)
    assert mine.shape == reference.shape, (mine.shape, reference.shape)
    return float(np.max(np.abs(mine - reference)) / max(np.max(np.abs(reference)), 1e-300))


PINOCCHIO_QUANTITIES = (
    "mass_matrix",
    "bias_forces",
    "arm_inertia",
    "reduced_bias",
    "base_velocity",
    "tip_velocity",
    "forward_dynamics",
    "held_tau",
    "held_wrench",
    "attitude_tau",
    "attitude_wrench",
    "G_free",
    "G_locked",
    "impulse_dqd",
    "impulse_dbase",
    "impulse_locked_dbase",
)


GRADIENT_ROBOTS = ("planar", "ur5")  # the paper's and a URDF arm (each grad program compiles for long)


def pytest_generate_tests(metafunc):
    if "system" in metafunc.fixturenames:
        robots = GRADIENT_ROBOTS if "derivatives" in metafunc.fixturenames else ROBOTS
        metafunc.parametrize("system", robots, indirect=True, scope="module")


@pytest.mark.parametrize("quantity", PINOCCHIO_QUANTITIES)
def test_kernels_match_pinocchio(system, quantity):
    error = _relative_error(system["mine"][quantity], system["pinocchio"][quantity])
    assert error < TOLERANCE, f"{system['name']} {quantity}: relative error {error:.2e}"


@pytest.mark.parametrize("quantity", ("mass_matrix", "base_velocity", "forward_dynamics", "held_tau", "held_wrench"))
def test_kernels_match_mujoco(system, quantity):
    if system["mujoco"] is None:
        pytest.skip("mujoco is not installed")
    error = _relative_error(system["mine"][quantity], system["mujoco"][quantity])
    assert error < TOLERANCE, f"{system['name']} {quantity}: relative error {error:.2e}"


def test_free_inverse_dynamics_gives_back_the_torques_of_aba(system):
    """With the bus free, the torques for aba's accelerations are aba's input, with no wrench;
    the attitude mode's wrench has no force, and locked joints do not jump."""
    mine = system["mine"]
    assert _relative_error(mine["free_tau"], system["states"]["tau"]) < TOLERANCE
    assert np.all(mine["free_wrench"] == 0.0)
    assert mine["free_wrench"].shape == system["pinocchio"]["held_wrench"].shape
    # No force with only the attitude held (the bus rows computed, not written as zeros): wheels only.
    force = mine["attitude_wrench"][:, : 2 if system["planar"] else 3]
    assert np.abs(force).max() < 1e-12 * np.abs(mine["attitude_wrench"]).max()
    assert np.all(mine["impulse_locked_dqd"] == 0.0)


def test_bias_power_is_half_the_mass_matrix_rate(system):
    """Energy balance: with T = 1/2 nu^T H nu and H nu' + c = F, dT/dt = nu^T F needs
    nu^T c = 1/2 nu^T (dH/dt) nu (H depends on the joints only; dH/dt by central differences
    along qd)."""
    mine, s = system["mine"], system["states"]
    nu = np.concatenate([mine["base_velocity"], s["qd"]], axis=-1)
    H_dot = (mine["mass_matrix_ahead"] - mine["mass_matrix_behind"]) / (2 * ENERGY_STEP)
    power = np.einsum("bi,bi->b", nu, mine["bias_forces"])
    half = 0.5 * np.einsum("bi,bij,bj->b", nu, H_dot, nu)
    scale = np.abs(nu).max(axis=-1) ** 2 * np.abs(H_dot).max(axis=(-1, -2))
    assert np.max(np.abs(power - half) / scale) < 1e-7


# jit, vmap and grad --------------------------------------------------------------------------


def _objective(qdd, weights, xp=jnp):
    """A scalar of the accelerations (per row of a batch ``(..., n)``)."""
    return xp.sum(weights * qdd**2, axis=-1) + xp.sum(xp.sin(qdd), axis=-1)


@functools.partial(jax.jit, static_argnames=("planar",))
def _gradients(robot, posture, qd, tau, momentum, R, weights, planar):
    """One state, no batch axis: the objective's gradient with respect to the robot pytree and
    the state, and the accelerations themselves."""

    def objective(robot, posture, qd, tau, momentum):
        qdd = sa.forward_dynamics(robot, posture, qd, tau, base_rotation=None if planar else R, momentum=momentum)
        return _objective(qdd, weights), qdd

    return jax.grad(objective, argnums=(0, 1, 2, 3, 4), has_aux=True)(robot, posture, qd, tau, momentum)


@functools.partial(jax.jit, static_argnames=("planar",))
def _mapped(robots, posture, qd, tau, R, momentum, planar):
    """forward_dynamics under jax.vmap over robots and states together."""
    if planar:
        return jax.vmap(lambda *a: sa.forward_dynamics(*a[:4], momentum=a[4]))(robots, posture, qd, tau, momentum)
    return jax.vmap(sa.forward_dynamics)(robots, posture, qd, tau, R, momentum)


DESIGN_NUMBERS = {"base_mass": (), "link_mass": (1,)}  # leaf: index of a design number checked
STEP = 1e-6


def _design_direction(robot, rng):
    """A random direction over every design number of the robot pytree, each entry scaled by its
    size (zero on infinite entries: free joint limits)."""

    def entry(x):
        x = np.asarray(x, dtype=float)
        return np.where(np.isfinite(x), rng.normal(size=x.shape) * (np.abs(x) + 0.1), 0.0)

    return jax.tree.map(entry, robot)


@pytest.fixture(scope="module")
def derivatives(system):
    """At the last state: the gradients and accelerations of `_gradients`, and one vmapped
    call over the STATES states (robot broadcast) followed by the central-difference rows."""
    s, i, robot, planar = system["states"], STATES - 1, system["robot"], system["planar"]
    args = [np.asarray(s[k][i], dtype=float) for k in ("posture", "qd", "tau", "momentum")]
    weights = np.random.default_rng(3).normal(size=s["qd"].shape[-1])
    grads, qdd = _gradients(robot, *args, s["R"][i], weights, planar=planar)
    rows = [(robot, [s[k][j] for k in ("posture", "qd", "tau", "momentum")], s["R"][j]) for j in range(STATES)]
    expected = []
    for a, (arg, grad) in enumerate(zip(args, grads[1:], strict=True)):
        for j in range(arg.size):
            for sign in (1.0, -1.0):
                moved = [x.copy() for x in args]
                moved[a][j] += sign * STEP
                rows.append((robot, moved, s["R"][i]))
            expected.append(np.asarray(grad)[j])
    for leaf, index in DESIGN_NUMBERS.items():
        value = np.asarray(getattr(robot, leaf), dtype=float)
        scale = float(value[index])
        for sign in (1.0, -1.0):
            moved = value.copy()
            moved[index] += sign * STEP * scale
            rows.append((dataclasses.replace(robot, **{leaf: moved}), args, s["R"][i]))
        expected.append(float(np.asarray(getattr(grads[0], leaf))[index]) * scale)
    # Every design number at once: a random direction over all finite leaves, relative to their size.
    direction = _design_direction(robot, np.random.default_rng(4))
    for sign in (1.0, -1.0):
        rows.append(
            (jax.tree.map(lambda x, d, sign=sign: np.asarray(x) + sign * STEP * d, robot, direction), args, s["R"][i])
        )
    paired = jax.tree.map(lambda g, d: float(np.sum(np.asarray(g) * d)), grads[0], direction)
    expected.append(sum(jax.tree.leaves(paired)))
    robots = jax.tree.map(lambda *leaves: np.stack(leaves), *[r for r, _, _ in rows])
    stacked = [np.stack([a[k] for _, a, _ in rows]) for k in range(4)]
    R = np.stack([R for _, _, R in rows])
    mapped = np.asarray(_mapped(robots, *stacked[:3], R, stacked[3], planar=planar))
    values = _objective(mapped[STATES:], weights[None], np)
    return {
        "qdd": np.asarray(qdd),  # one state, no batch axis, under grad
        "mapped": mapped[:STATES],
        "differences": (values[0::2] - values[1::2]) / (2 * STEP),
        "gradients": np.array(expected),
    }


def test_one_state_is_the_batch_row(system):
    """A single state (no batch axis) gives Pinocchio's accelerations and the batched call's row."""
    qdd = system["mine"]["single_forward_dynamics"]
    assert qdd.shape == system["states"]["qd"].shape[1:]
    assert _relative_error(qdd, system["pinocchio"]["forward_dynamics"][-1]) < TOLERANCE
    np.testing.assert_allclose(qdd, system["mine"]["forward_dynamics"][-1], rtol=1e-12, atol=1e-12)


def test_vmap_over_robots_and_states_is_the_batched_call(system, derivatives):
    """jax.vmap over robots and states gives the batched call; the state inside jax.grad too."""
    np.testing.assert_allclose(derivatives["qdd"], system["mine"]["forward_dynamics"][-1], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(derivatives["mapped"], system["mine"]["forward_dynamics"], rtol=1e-12, atol=1e-12)


def test_gradients_match_central_differences(derivatives):
    """jax.grad of a scalar of the forward dynamics with respect to the joints (planar: phi0
    too), rates, torques, momentum and design numbers of the robot pytree (the bus mass, a link
    mass, and every design number at once along a random direction), against central
    differences of the same function (all perturbations in one vmapped call)."""
    expected = derivatives["gradients"]
    scale = np.abs(expected).max()
    np.testing.assert_allclose(derivatives["differences"], expected, rtol=1e-6, atol=1e-6 * scale)


# Held joints and bad input --------------------------------------------------------------------


@jax.jit
def _focused_kernels(robot, q, qd, tau, momentum):
    qdd = sa.forward_dynamics(robot, q, qd, tau, momentum=momentum)
    return dict(
        qdd=qdd,
        residual=sa.arm_inertia(robot, q) @ qdd + sa.reduced_bias(robot, q, qd, momentum=momentum) - tau,
        inverse=sa.inverse_dynamics(robot, q, qd, qdd, momentum=momentum)[0],
        tip=sa.tip_velocity(robot, q, qd),
        jstar=sa.generalized_jacobian(robot, q) @ (qd * robot.focus_moving),
    )


def test_held_joints_of_a_focused_tree_stay_still():
    """A tree focused on one tip with one branch held: the held joints do not accelerate (their
    drives hold them), the moving ones obey H* qdd + c* = tau with the held joints locked, the
    inverse dynamics gives the torques back, and the tip moves with J* qd (held columns zero)."""
    _, tree = random_tree(5, torso=1, branches=(2, 2))
    moving = tree.labels.joint_names[:3]  # the torso and the first branch
    robot = tree.focus(tip=tree.tip_names[0], moving=moving)
    rng = np.random.default_rng(6)
    q, qd, tau, momentum = (rng.normal(size=s) for s in (5, 5, 5, 6))
    got = _focused_kernels(robot, q, qd, tau, momentum)
    held = ~robot.moving_mask
    assert held.sum() == 2
    np.testing.assert_array_equal(np.asarray(got["qdd"])[held], 0.0)
    scale = np.abs(tau).max()
    np.testing.assert_allclose(np.asarray(got["residual"])[~held], 0.0, atol=1e-12 * scale)
    np.testing.assert_allclose(np.asarray(got["inverse"])[~held], tau[~held], atol=1e-12 * scale)
    np.testing.assert_allclose(got["tip"], got["jstar"], atol=1e-13)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda r, q: sa.forward_dynamics(r, q, q[:5], q), r"^qd: expected trailing axes \(6,\)"),
        (lambda r, q: sa.base_velocity(r, q, q, momentum=q[:3]), r"^momentum: expected trailing axes \(6,\)"),
        (lambda r, q: sa.mass_matrix(r, q, base_rotation=q[:3]), r"^base_rotation: expected trailing axes \(3, 3\)"),
        (lambda r, q: sa.inverse_dynamics(r, q[:5], q, q), r"^q: expected trailing axes \(6,\)"),
        (lambda r, q: sa.impulse_response(r, q, q, tip=1), r"^tip: 1 is not one of the robot's 1 tip"),
    ],
)
def test_bad_input_names_the_argument(call, message):
    robot = sa.load_robot(os.path.join(CONFIGS, "ur5-smallsat.yaml"))
    with pytest.raises(ValueError, match=message):
        call(robot, np.zeros(6))
