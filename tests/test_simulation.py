"""spacearm.simulate: the free-floating robot under joint torques, against independent references.

- The UR5 on its smallsat (configs/ur5-smallsat.yaml) against Pinocchio: its ``aba`` on the
  free-flyer model of the same URDF (gravity zero), integrated by SciPy's DOP853 at
  rtol 1e-12 on the bus quaternion, the joints and Pinocchio's velocity, torques held over
  each sample: our attitude, joints, joint rates and bus velocity equal its states, and its
  own centroidal momentum stays the input (it integrates its velocity, so it conserves the
  momentum by its own dynamics); the kinetic energy (Pinocchio's, with the bus velocity from its centroidal map) constant
  without torques and changed by the joint torques' work with them.
- The planar arm of Umetani & Yoshida 1990 against the naive model of tests/reference.py
  (complex-step velocities): [Px, Py, L] and the kinetic energy along a 2 s run, and each
  coordinate of a torque-free run the time integral of its rate.
- Convergence in the number of steps, gradients by finite differences, batches of initial
  states, and the events (a joint limit, a bus rate bound).

Programs are shared: each robot's runs go through one compiled program (the same batch of
two runs, the same number of samples), so the whole file compiles a handful of programs.
"""

from __future__ import annotations

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import simpson, solve_ivp

import spacearm as sa
from spacearm._core.groups import geodesic_distance, hat, rpy_matrix
from spacearm.motion.simulation import DEFAULT_SUBSTEPS, STOP_BUS_RATE, STOP_JOINT_LIMIT, STOP_NONE

from . import reference
from .conftest import count_compiles
from .spatial_references import config_urdf

pin = pytest.importorskip("pinocchio")

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
DT = 0.01
SAMPLES = 200  # 2 s


# The UR5 on its smallsat -------------------------------------------------------------------


@pytest.fixture(scope="module")
def ur5():
    return sa.load_robot(CONFIGS / "ur5-smallsat.yaml")


@pytest.fixture(scope="module")
def ur5_case():
    """A start with nonzero momentum at a random attitude, and two torque histories
    (random, then none): the batch of two runs every UR5 test shares."""
    rng = np.random.default_rng(7)
    torques = rng.normal(size=(SAMPLES, 6)) * np.array([8.0, 8.0, 4.0, 0.5, 0.5, 0.2])
    return dict(
        q0=rng.uniform(-2.0, 2.0, 6),
        qd0=rng.normal(size=6) * 0.3,
        R0=rpy_matrix(rng.uniform(-1.0, 1.0, 3)),
        momentum=np.r_[rng.normal(size=3) * 20.0, rng.normal(size=3) * 5.0],
        torques=np.stack([torques, np.zeros_like(torques)]),
    )


def _ur5_runs(ur5, case, torques, qd0=None, **options):
    qd0 = case["qd0"] if qd0 is None else qd0
    R, q, qd = sa.simulate(
        ur5, case["q0"], qd0, torques, DT, base_rotation=case["R0"], momentum=case["momentum"], **options
    )
    return np.asarray(R), np.asarray(q), np.asarray(qd)


@pytest.fixture(scope="module")
def ur5_runs(ur5, ur5_case):
    return _ur5_runs(ur5, ur5_case, ur5_case["torques"])


class _Pinocchio:
    """Pinocchio's free-flyer model of the UR5 smallsat, in our conventions (tests/dynamics
    conventions: nu_ours = S nu_pin, S = [[I, -[c]x, 0], [0, I, 0], [0, 0, I]], c the bus centroid)."""

    def __init__(self):
        text, com = config_urdf(CONFIGS / "ur5-smallsat.yaml")
        self.model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
        self.model.gravity.linear[:] = 0.0
        self.data = self.model.createData()
        self.S = np.eye(12)
        self.S[:3, 3:6] = -hat(com)

    def config(self, R, q):
        config = pin.neutral(self.model)
        config[3:7] = pin.Quaternion(np.asarray(R)).coeffs()
        config[7:] = q
        return config

    def base_velocity(self, config, qd, momentum):
        """nu_pin's bus part whose centroidal momentum is ``momentum`` (Pinocchio's map alone)."""
        A = pin.computeCentroidalMap(self.model, self.data, config)
        return np.linalg.solve(A[:, :6], momentum - A[:, 6:] @ qd)

    def momentum(self, R, q, nu_ours):
        config = self.config(R, q)
        return pin.computeCentroidalMomentum(self.model, self.data, config, np.linalg.solve(self.S, nu_ours)).vector

    def energy(self, R, q, qd, momentum):
        config = self.config(R, q)
        nu = np.r_[self.base_velocity(config, qd, momentum), qd]
        return pin.computeKineticEnergy(self.model, self.data, config, nu)

    def simulate(self, R0, q0, qd0, torques, momentum, dt):
        """(R, q, nu_pin) at every sample of the torque history: aba integrated by DOP853 at
        rtol 1e-12 per interval, Pinocchio's velocity nu_pin a state of its own (the momentum
        sets it at the start only), so the reference conserves the momentum by its own dynamics."""

        def field(_, y, tau):
            quat, q, nu = y[:4], y[4:10], y[10:]
            config = np.r_[np.zeros(3), quat / np.linalg.norm(quat), q]
            w = nu[3:6]
            x, v = quat[3], quat[:3]  # Pinocchio's coefficients (x, y, z, w): dq/dt = q (0, w) / 2
            quat_rate = 0.5 * np.r_[x * w + np.cross(v, w), -v @ w]
            accel = pin.aba(self.model, self.data, config, nu, np.r_[np.zeros(6), tau])
            return np.r_[quat_rate, nu[6:], accel]

        config = self.config(R0, q0)
        states = [np.r_[config[3:7], q0, self.base_velocity(config, qd0, momentum), qd0]]
        for tau in torques:
            step = solve_ivp(field, (0.0, dt), states[-1], method="DOP853", rtol=1e-12, atol=1e-12, args=(tau,))
            states.append(step.y[:, -1])
        states = np.array(states)
        rotations = []
        for coeffs in states[:, :4]:
            quat = pin.Quaternion(coeffs[3], *coeffs[:3])
            quat.normalize()
            rotations.append(quat.toRotationMatrix())
        return np.array(rotations), states[:, 4:10], states[:, 10:]


@pytest.fixture(scope="module")
def pinocchio():
    return _Pinocchio()


@pytest.fixture(scope="module")
def pinocchio_run(ur5_case, pinocchio):
    """Pinocchio's run of the driven case (the first of the batch), every sample."""
    c = ur5_case
    return pinocchio.simulate(c["R0"], c["q0"], c["qd0"], c["torques"][0], c["momentum"], DT)


def test_ur5_matches_pinocchio(ur5, ur5_case, ur5_runs, pinocchio, pinocchio_run):
    """200 steps of 0.01 s with torques and nonzero momentum: R, q, qd and the bus velocity
    after 0.57 s and 2 s equal Pinocchio's (aba, its velocity integrated as a state)."""
    R, q, qd = ur5_runs
    R_ref, q_ref, nu_ref = pinocchio_run
    samples = np.array([57, SAMPLES])
    nu_base = np.asarray(
        sa.base_velocity(ur5, q[0, samples], qd[0, samples], base_rotation=R[0, samples], momentum=ur5_case["momentum"])
    )
    for k, i in enumerate(samples):
        assert float(geodesic_distance(R[0, i], R_ref[i])) < 1e-10
        np.testing.assert_allclose(q[0, i], q_ref[i], rtol=0, atol=1e-10)
        np.testing.assert_allclose(qd[0, i], nu_ref[i, 6:], rtol=0, atol=1e-10)
        np.testing.assert_allclose(nu_base[k], (pinocchio.S @ nu_ref[i])[:6], rtol=0, atol=1e-10)


def test_ur5_momentum_conserved(ur5_case, pinocchio, pinocchio_run):
    """Pinocchio's centroidal momentum of its own run's states stays the input [P; L]: the
    reference integrates its velocity from aba, so this checks it (and the momentum convention
    it shares with sa.simulate) independently of our kernels; the test above then ties our
    run to it sample by sample."""
    R_ref, q_ref, nu_ref = pinocchio_run
    for i in (0, 57, 130, SAMPLES):
        got = pinocchio.momentum(R_ref[i], q_ref[i], pinocchio.S @ nu_ref[i])
        np.testing.assert_allclose(got, ur5_case["momentum"], rtol=0, atol=1e-10)


def test_ur5_energy(ur5_case, ur5_runs, pinocchio):
    """No torque: the kinetic energy is constant. With torques held over each interval, its
    change is the work sum_k tau_k . (q_{k+1} - q_k), exactly."""
    R, q, qd = ur5_runs
    m = ur5_case["momentum"]
    free = np.array([pinocchio.energy(R[1, i], q[1, i], qd[1, i], m) for i in range(0, SAMPLES + 1, 20)])
    assert np.ptp(free) < 1e-9 * free[0]
    driven = [pinocchio.energy(R[0, i], q[0, i], qd[0, i], m) for i in (0, SAMPLES)]
    work = np.sum(ur5_case["torques"][0] * np.diff(q[0], axis=0))
    assert abs(work) > 1.0  # the torques do work
    np.testing.assert_allclose(driven[1] - driven[0], work, rtol=1e-9)


def test_default_substeps_converged(ur5, ur5_case):
    """The default number of steps per interval is converged: under torques that drive the
    joints to 10 rad/s, 4x as many steps change the state after 2 s by less than 1e-9 rad."""
    torques = 6.0 * ur5_case["torques"]
    R, q, qd = _ur5_runs(ur5, ur5_case, torques)
    assert np.abs(qd).max() > 5.0
    R4, q4, qd4 = _ur5_runs(ur5, ur5_case, torques, substeps=4 * DEFAULT_SUBSTEPS)
    assert float(jnp.max(geodesic_distance(R4[:, -1], R[:, -1]))) < 1e-9
    np.testing.assert_allclose(q4[:, -1], q[:, -1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(qd4[:, -1], qd[:, -1], rtol=0, atol=1e-8)


def test_batch_axes(ur5, ur5_case, ur5_runs):
    """Leading axes are independent runs: swapping the rows of the batch swaps the results
    (bitwise; the same program, so nothing compiles again)."""
    c = ur5_case
    R, q, qd = _ur5_runs(ur5, c, c["torques"][::-1])
    np.testing.assert_array_equal(qd[::-1], ur5_runs[2])
    np.testing.assert_array_equal(q[::-1], ur5_runs[1])
    np.testing.assert_array_equal(R[::-1], ur5_runs[0])


# The planar arm of the paper ---------------------------------------------------------------


@pytest.fixture(scope="module")
def planar():
    return sa.umetani1990()


@pytest.fixture(scope="module")
def planar_case(planar):
    rng = np.random.default_rng(11)
    n = planar.n_links
    torques = rng.normal(size=(SAMPLES, n)) * 30.0
    return dict(
        phi0=np.r_[0.3, rng.uniform(-1.0, 1.0, n)],
        qd0=rng.normal(size=n) * 0.2,
        momentum=np.array([40.0, -25.0, 30.0]),
        torques=np.stack([torques, np.zeros_like(torques)]),
    )


def _planar_runs(robot, case, max_bus_rate=1e9, qd0=None, torques=None):
    """Every planar run goes through the one program with both events armed."""
    phi, qd, stop = sa.simulate(
        robot,
        case["phi0"],
        case["qd0"] if qd0 is None else qd0,
        case["torques"] if torques is None else torques,
        DT,
        momentum=case["momentum"],
        stop_at_limits=True,
        max_bus_rate=max_bus_rate,
    )
    return np.asarray(phi), np.asarray(qd), stop


@pytest.fixture(scope="module")
def planar_runs(planar, planar_case):
    return _planar_runs(planar, planar_case)


@pytest.fixture(scope="module")
def planar_base(planar, planar_case, planar_runs):
    phi, qd, _ = planar_runs
    return np.asarray(sa.base_velocity(planar, phi, qd, momentum=planar_case["momentum"]))


def _planar_reference(robot, phi, qd, base):
    """([Px, Py, L], kinetic energy) of the naive model at one state, bus velocity ``base``
    [vx, vy, w] (bus axes): the bodies' velocities about the system centroid by complex step,
    plus the centroid's own motion."""
    d = reference.design(robot)
    rates = np.r_[base[2], qd]
    (_, angular) = reference.momentum(d, phi, rates)
    h = 1e-30
    step, _ = reference.bodies_and_tip(d, phi + 1j * h * rates)
    relative = step.imag / h  # body centroid velocities about the system centroid, inertial
    c, s = np.cos(phi[0]), np.sin(phi[0])
    bus = np.array([[c, -s], [s, c]]) @ base[:2]
    centroid = bus - relative[0]  # the system centroid's velocity
    masses, inertias = np.array(d["m"]), np.array(d["inertia"])
    total = masses.sum()
    energy = 0.5 * total * centroid @ centroid + 0.5 * np.sum(masses * np.sum(relative**2, axis=1))
    energy += 0.5 * np.sum(inertias * np.cumsum(rates) ** 2)
    return np.r_[total * centroid, angular], energy


def test_planar_conserves_momentum(planar, planar_case, planar_runs, planar_base):
    """A 2 s run of the paper's arm with torques and momentum [Px, Py, L]. The naive model's
    momentum of our states and bus velocities is the input (this checks the bus velocity that
    the momentum sets, not the integration). What checks the integration: without torques the
    energy is constant and every coordinate [phi0, q] is the time integral of its rate
    [w, qd] (Simpson's rule over the samples); with torques the energy changes by their work."""
    phi, qd, stop = planar_runs
    assert np.all(np.asarray(stop.reason) == STOP_NONE) and np.all(np.asarray(stop.step) == SAMPLES)
    assert phi.shape == (2, SAMPLES + 1, planar.n_links + 1)
    for i in range(0, SAMPLES + 1, 25):
        for run in range(2):
            momentum, _ = _planar_reference(planar, phi[run, i], qd[run, i], planar_base[run, i])
            np.testing.assert_allclose(momentum, planar_case["momentum"], rtol=0, atol=1e-10)
    energies = [_planar_reference(planar, phi[1, i], qd[1, i], planar_base[1, i])[1] for i in range(0, SAMPLES + 1, 25)]
    assert np.ptp(energies) < 1e-10 * energies[0]
    rates = np.c_[planar_base[1, :, 2], qd[1]]  # (SAMPLES + 1, n + 1): [w, qd] of the torque-free run
    integral = np.array([simpson(rates[: i + 1], dx=DT, axis=0) for i in range(2, SAMPLES + 1, 2)])
    np.testing.assert_allclose(phi[1, 2::2] - phi[1, 0], integral, rtol=0, atol=1e-12)
    start, end = (_planar_reference(planar, phi[0, i], qd[0, i], planar_base[0, i])[1] for i in (0, SAMPLES))
    work = np.sum(planar_case["torques"][0] * np.diff(phi[0, :, 1:], axis=0))
    np.testing.assert_allclose(end - start, work, rtol=1e-9)


def test_events(planar, planar_case, planar_runs, planar_base):
    """The run stops at the first sample past a joint limit, or above the bus rate bound, and
    holds that state; the program is the one the free runs compiled (the bound is traced)."""
    phi, qd, _ = planar_runs
    speed = np.abs(planar_base[..., 2])
    bound = 0.5 * (speed[0, 0] + speed[0].max())
    expected = np.argmax(speed > bound, axis=1)
    expected = np.where(np.any(speed > bound, axis=1), expected, SAMPLES)
    with count_compiles() as compiled:
        got_phi, got_qd, stop = _planar_runs(planar, planar_case, max_bus_rate=bound)
    assert compiled["_simulate_flat"] == 0  # a new bound (and below, new limits) is a new value, not a new program
    np.testing.assert_array_equal(np.asarray(stop.step), expected)
    assert np.asarray(stop.reason)[0] == STOP_BUS_RATE
    k = expected[0]
    np.testing.assert_array_equal(got_phi[0, : k + 1], phi[0, : k + 1])
    np.testing.assert_array_equal(got_phi[0, k:], np.broadcast_to(phi[0, k], got_phi[0, k:].shape))
    np.testing.assert_array_equal(got_qd[0, k:], np.broadcast_to(qd[0, k], got_qd[0, k:].shape))

    joint = phi[0, :, 2]  # joint 2 of the driven run
    upper = 0.5 * (joint[0] + joint.max())
    limited = planar.replace(joint_upper=np.array([np.inf, upper]))
    with count_compiles() as compiled:
        _, _, stop = _planar_runs(limited, planar_case)
    assert compiled["_simulate_flat"] == 0
    assert np.asarray(stop.reason)[0] == STOP_JOINT_LIMIT
    assert np.asarray(stop.step)[0] == np.argmax(joint >= upper)


def test_grad_and_vmap(planar, planar_case):
    """jax.vmap over initial rates of jax.grad with respect to the torques (and through the
    armed events) equals central differences; the differences run through the shared program."""
    c = planar_case
    weights = np.array([1.0, 0.5, -2.0])  # the final bus angle and joints

    def final(qd0, torques):
        phi, _, _ = sa.simulate(
            planar, c["phi0"], qd0, torques, DT, momentum=c["momentum"], stop_at_limits=True, max_bus_rate=1e9
        )
        return phi[-1] @ weights

    starts = np.stack([c["qd0"], -c["qd0"]])
    grads = jax.jit(jax.vmap(jax.grad(final, argnums=1), in_axes=(0, None)))(starts, c["torques"][0])
    direction = np.random.default_rng(3).normal(size=c["torques"].shape[1:])
    eps = 1e-3
    for start, grad in zip(starts, np.asarray(grads), strict=True):
        plus_minus = c["torques"][0] + np.array([eps, -eps])[:, None, None] * direction
        phi, _, _ = _planar_runs(planar, c, qd0=start, torques=plus_minus)
        difference = (phi[0, -1] - phi[1, -1]) @ weights / (2 * eps)
        np.testing.assert_allclose(np.sum(grad * direction), difference, rtol=1e-7)


def test_bad_input(ur5, planar):
    with pytest.raises(sa.ConfigError, match="dt"):
        sa.simulate(ur5, np.zeros(6), np.zeros(6), np.zeros((3, 6)), 0.0)
    with pytest.raises(sa.ConfigError, match="torques"):
        sa.simulate(ur5, np.zeros(6), np.zeros(6), np.zeros((3, 5)), 0.01)
    with pytest.raises(TypeError, match="base_rotation"):
        sa.simulate(planar, np.zeros(3), np.zeros(2), np.zeros((3, 2)), 0.01, base_rotation=np.eye(3))


def test_free_motion_is_base_velocity_and_forward_dynamics(planar):
    """The simulation's one-pass field equals the two kernels it stands for (planar: [vx, vy, w])."""
    rng = np.random.default_rng(12)
    phi, qd, tau = rng.normal(size=(4, 3)), rng.normal(size=(4, 2)), rng.normal(size=(4, 2))
    momentum = rng.normal(size=(4, 3))
    base, qdd = sa.free_motion(planar, phi, qd, tau, momentum=momentum)
    np.testing.assert_allclose(base, sa.base_velocity(planar, phi, qd, momentum=momentum), rtol=0, atol=1e-14)
    np.testing.assert_allclose(qdd, sa.forward_dynamics(planar, phi, qd, tau, momentum=momentum), rtol=0, atol=1e-14)
