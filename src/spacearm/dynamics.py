"""Free-floating dynamics written once for every robot (gravity zero, any momentum).

State: joints q ``(..., n)`` and rates qd ``(..., n)``, the bus attitude R (``base_rotation``,
bus axes -> inertial axes, default identity) and the system momentum m = [P; L]: the linear
momentum and the angular momentum about the system centroid, inertial axes (default zero,
the assumption of Umetani & Yoshida 1990, eq. 3-5). A planar robot passes its posture
phi = [phi0, q] instead of (q, R), and every 6-vector shrinks to its in-plane part
[x, y, rz] (the family's ``twist_axes``): momentum [Px, Py, L], base velocity [vx, vy, w].

Coordinates: nu = [v; w; qd], v the velocity of the bus centroid and w the bus angular
velocity, both in bus axes. With H the system mass matrix in these coordinates and c the
bias forces (`spacearm.models.dynamics`: one pass over the robot's tree, c by Newton-Euler
on it), the free-floating system under joint torques tau and a bus wrench
[f; n] (force at the bus centroid, torque about it, bus axes) is

    H nu' + c(q, nu) = [f; n; tau].

Partitioned as H = [[H_b, H_bm], [H_bm^T, H_m]], c = [c_b; c_m]:

- base velocity from the momentum: H_b [v; w] + H_bm qd = [R^T P; R^T L + (g - b) x R^T P]
  (g - b the system centroid about the bus centroid, bus axes), eq. 4-5 with any momentum;
- free bus (f = n = 0): H* qdd + c* = tau with the reduced inertia H* = H_m - H_bm^T H_b^-1 H_bm
  and the reduced bias c* = c_m - H_bm^T H_b^-1 c_b;
- tip twist J nu, J = [J_S, J_M] (SpaceDyn's calc_gj11 with its momentum term), and the
  extended inversed inertia tensor G = J H^-1 J^T (Yoshida): the tip's velocity jump per
  tip impulse; with the joints locked, G = J_S H_b^-1 J_S^T (one rigid body).
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

from ._core.groups import vee
from .models.dynamics import free_dynamics, mass_and_bias, system_mass_matrix, tip_maps
from .models.family import family_of

__all__ = [
    "BASE_MODES",
    "arm_inertia",
    "base_velocity",
    "bias_forces",
    "forward_dynamics",
    "free_motion",
    "impulse_response",
    "inverse_dynamics",
    "joint_mass_matrix",
    "mass_matrix",
    "reduced_bias",
    "tip_inverse_inertia",
    "tip_velocity",
]

BASE_MODES = ("free", "held", "attitude")
_JOINT_MODES = ("free", "locked")


# The state ---------------------------------------------------------------------------------


class _System:
    """One state of a robot: its dynamic tree, joints ``(*batch, n)``, attitude ``(*batch, 3, 3)``,
    the kept twist components and the tip weights, with the other arrays broadcast to the batch."""

    def __init__(self, robot, posture, base_rotation, *arrays):
        family = family_of(robot)
        self.family = family
        self.tree = family.dynamic_tree(robot)
        self.keep = np.asarray(family.twist_axes)
        self.tips = family.dynamic_tips(robot)
        posture = jnp.asarray(posture)
        offset = family.posture_offset
        if offset:
            if base_rotation is not None:
                raise TypeError(f"base_rotation: a {family.name} posture carries its base attitude (phi0 first)")
            R = family.attitude.rotation(posture[..., 0])
            q = posture[..., offset:]
        else:
            q = posture
            R = jnp.eye(3, dtype=q.dtype) if base_rotation is None else jnp.asarray(base_rotation)
        n = q.shape[-1]
        self.n = n
        shaped = [(jnp.asarray(a), core) for a, core in arrays]
        batch = jnp.broadcast_shapes(q.shape[:-1], R.shape[:-2], *[a.shape[: a.ndim - core] for a, core in shaped])
        self.batch = batch
        self.q = jnp.broadcast_to(q, batch + (n,))
        self.R = jnp.broadcast_to(R, batch + (3, 3))
        self.arrays = [jnp.broadcast_to(a, batch + a.shape[a.ndim - core :]) for a, core in shaped]
        self.coords = np.concatenate([self.keep, 6 + np.arange(n)])

    def embed(self, x):
        """A 6-vector's kept components ``(..., len(keep))`` -> ``(..., 6)`` (zeros elsewhere)."""
        x = jnp.asarray(x)
        if len(self.keep) == 6:
            return x
        return jnp.zeros(x.shape[:-1] + (6,), x.dtype).at[..., self.keep].set(x)

    def reduce(self, x):
        """``(..., 6)`` -> its kept components."""
        return x if len(self.keep) == 6 else x[..., self.keep]

    def rotate(self, x):
        """blkdiag(R, R) x for 6-vectors ``(*batch, [k,] 6)``: bus axes -> inertial axes."""
        R = self.R.reshape(self.batch + (1,) * (x.ndim - 1 - len(self.batch)) + (3, 3))
        return jnp.concatenate([_apply(R, x[..., :3]), _apply(R, x[..., 3:])], axis=-1)

    def unrotate(self, x):
        """blkdiag(R, R)^T x: inertial axes -> bus axes."""
        Rt = jnp.swapaxes(self.R, -1, -2).reshape(self.batch + (1,) * (x.ndim - 1 - len(self.batch)) + (3, 3))
        return jnp.concatenate([_apply(Rt, x[..., :3]), _apply(Rt, x[..., 3:])], axis=-1)

    def tip_maps(self):
        """``(*batch, [k,] 6, 6 + n)`` J of every tip, or of the chosen one, bus axes."""
        J = tip_maps(self.tree, self.q)
        if self.tips is None:
            return J
        return jnp.einsum("t,...tij->...ij", jnp.asarray(self.tips, J.dtype), J)


def _apply(matrix, vector):
    return jnp.einsum("...ij,...j->...i", matrix, vector)


def _solve(matrix, rhs):
    """Solve with a symmetric positive definite matrix (Cholesky) for one right-hand side ``(..., m)``."""
    factor = jax.scipy.linalg.cho_factor(matrix)
    return jax.scipy.linalg.cho_solve(factor, rhs[..., None])[..., 0]


def _solve_columns(matrix, rhs):
    factor = jax.scipy.linalg.cho_factor(matrix)
    return jax.scipy.linalg.cho_solve(factor, rhs)


def _base_from_momentum(H, qd, R, momentum):
    """``(..., 6)`` [v; w], bus axes, whose system momentum is ``momentum`` [P; L about the
    system centroid], inertial axes."""
    Rt = jnp.swapaxes(R, -1, -2)
    P, L = _apply(Rt, momentum[..., :3]), _apply(Rt, momentum[..., 3:])
    offset = vee(H[..., 3:6, 0:3]) / H[..., 0, 0, None]
    target = jnp.concatenate([P, L + jnp.cross(offset, P)], axis=-1)
    return _solve(H[..., :6, :6], target - _apply(H[..., :6, 6:], qd))


def _velocity(system: _System, qd, momentum):
    """nu = [v; w; qd] ``(..., 6 + n)`` for the momentum (zero when ``None``)."""
    H = system_mass_matrix(system.tree, system.q)
    m = jnp.zeros(system.batch + (6,), qd.dtype) if momentum is None else system.embed(momentum)
    return jnp.concatenate([_base_from_momentum(H, qd, system.R, m), qd], axis=-1)


def _momentum_array(momentum):
    return [] if momentum is None else [(momentum, 1)]


# Mass matrix and bias ----------------------------------------------------------------------


@jax.jit
def mass_matrix(robot, q: jax.Array, base_rotation: jax.Array | None = None) -> jax.Array:
    """``(..., 6 + n, 6 + n)`` H in the coordinates [v; w; qd]: v the bus centroid's velocity and
    w the bus angular velocity, both in BUS axes (planar: ``(..., 3 + n, 3 + n)`` over
    [vx, vy, w; qd]). In these coordinates H does not depend on the attitude."""
    system = _System(robot, q, base_rotation)
    H = system_mass_matrix(system.tree, system.q)
    return H[..., system.coords[:, None], system.coords[None, :]]


@jax.jit
def bias_forces(robot, q: jax.Array, qd: jax.Array, base_rotation=None, momentum=None) -> jax.Array:
    """``(..., 6 + n)`` c(q, nu) of H nu' + c = [f; n; tau], at the bus velocity the momentum
    gives (bus rows: force at the bus centroid and torque about it, bus axes)."""
    system = _System(robot, q, base_rotation, (qd, 1), *_momentum_array(momentum))
    nu = _velocity(system, system.arrays[0], None if momentum is None else system.arrays[1])
    _, c = mass_and_bias(system.tree, system.q, nu)
    return c[..., system.coords]


def _moving_lock(robot, inertia):
    """Held joints of a focused robot locked: the moving block, identity on the held joints."""
    mask = jnp.asarray(family_of(robot).moving_joints(robot), inertia.dtype)
    return inertia * (mask[..., :, None] * mask[..., None, :]) + jnp.eye(inertia.shape[-1]) * (1.0 - mask)[..., None]


@jax.jit
def joint_mass_matrix(robot, q: jax.Array) -> jax.Array:
    """``(..., n, n)`` H_m, the joint-space inertia with the bus held fixed (a focused tree:
    its held joints locked)."""
    system = _System(robot, q, None)
    return _moving_lock(robot, system_mass_matrix(system.tree, system.q)[..., 6:, 6:])


@jax.jit
def arm_inertia(robot, q: jax.Array) -> jax.Array:
    """``(..., n, n)`` the reduced inertia H* = H_m - H_bm^T H_b^-1 H_bm: joint torque per joint
    acceleration with the bus free, any momentum (Yoshida's generalized inertia; a focused tree:
    its held joints locked)."""
    system = _System(robot, q, None)
    H = system_mass_matrix(system.tree, system.q)
    coupling = _solve_columns(H[..., :6, :6], H[..., :6, 6:])
    return _moving_lock(robot, H[..., 6:, 6:] - jnp.swapaxes(H[..., :6, 6:], -1, -2) @ coupling)


@jax.jit
def reduced_bias(robot, q: jax.Array, qd: jax.Array, base_rotation=None, momentum=None) -> jax.Array:
    """``(..., n)`` c* = c_m - H_bm^T H_b^-1 c_b: with the bus free, H* qdd + c* = tau (the free
    bus's inverse dynamics at qdd = 0)."""
    system = _System(robot, q, base_rotation, (qd, 1), *_momentum_array(momentum))
    qd = system.arrays[0]
    still = jnp.zeros_like(qd)
    return free_dynamics(system.tree, system.q, qd, still, _bus_momentum(system, momentum, qd.dtype), forward=False)


# Velocities --------------------------------------------------------------------------------


@jax.jit
def base_velocity(robot, q: jax.Array, qd: jax.Array, base_rotation=None, momentum=None) -> jax.Array:
    """``(..., 6)`` [v of the bus centroid; w of the bus], BUS axes, at joint rates ``qd`` with
    the system momentum ``momentum`` (planar ``(..., 3)`` [vx, vy, w])."""
    system = _System(robot, q, base_rotation, (qd, 1), *_momentum_array(momentum))
    nu = _velocity(system, system.arrays[0], None if momentum is None else system.arrays[1])
    return system.reduce(nu[..., :6])


@jax.jit
def tip_velocity(robot, q: jax.Array, qd: jax.Array, base_rotation=None, momentum=None) -> jax.Array:
    """``(..., 6)`` (trees ``(..., k, 6)``) the twist [v; w] of the tip frame's origin, INERTIAL
    axes: J* qd plus the drift the momentum adds (SpaceDyn's calc_gj11)."""
    system = _System(robot, q, base_rotation, (qd, 1), *_momentum_array(momentum))
    nu = _velocity(system, system.arrays[0], None if momentum is None else system.arrays[1])
    J = system.tip_maps()
    twist = jnp.einsum("...ij,...j->...i", J, nu if J.ndim == nu.ndim + 1 else nu[..., None, :])
    return system.reduce(system.rotate(twist))


# Forward and inverse dynamics --------------------------------------------------------------


@jax.jit
def forward_dynamics(robot, q: jax.Array, qd: jax.Array, tau: jax.Array, base_rotation=None, momentum=None):
    """``(..., n)`` joint accelerations of the free-floating system under joint torques ``tau``
    (no external wrench): H* qdd = tau - c*."""
    return free_motion(robot, q, qd, tau, base_rotation, momentum)[1]


@jax.jit
def free_motion(robot, q: jax.Array, qd: jax.Array, tau: jax.Array, base_rotation=None, momentum=None):
    """``(base velocity (..., 6), qdd (..., n))``: `base_velocity` and `forward_dynamics` from one
    pass (what a simulation's every stage needs; planar ``(..., 3)`` [vx, vy, w])."""
    system = _System(robot, q, base_rotation, (qd, 1), (tau, 1), *_momentum_array(momentum))
    qd, tau = system.arrays[:2]
    motion = free_dynamics(system.tree, system.q, qd, tau, _bus_momentum(system, momentum, qd.dtype))
    return system.reduce(motion[..., :6]), motion[..., 6:]


def _bus_momentum(system: _System, momentum, dtype):
    """``(*batch, 6)`` the system momentum [P; L about the system centroid] in BUS axes (zero
    when ``momentum`` is ``None``; else it is the state's last array)."""
    if momentum is None:
        return jnp.zeros(system.batch + (6,), dtype)
    return system.unrotate(system.embed(system.arrays[-1]))


@functools.partial(jax.jit, static_argnames=("base",))
def inverse_dynamics(robot, q, qd, qdd, base_rotation=None, momentum=None, base: str = "free"):
    """``(tau (..., n), wrench (..., 6))``: the joint torques for joint accelerations ``qdd``, and
    the wrench the bus's actuators apply to it (force at the bus centroid, torque about it,
    bus axes; planar [fx, fy, m]).

    Args:
        base: ``"free"``: the bus floats, the wrench is zero. ``"held"``: thrusters and wheels
            keep the bus at rest (the paper's fixed vehicle; the momentum is ignored).
            ``"attitude"``: wheels hold the attitude, the bus translates freely with the
            momentum's P and no force; the wrench is [0, 0, 0, wheel torque on the bus].
    """
    if base not in BASE_MODES:
        raise ValueError(f"base: one of {', '.join(BASE_MODES)}, got {base!r}")
    system = _System(robot, q, base_rotation, (qd, 1), (qdd, 1), *_momentum_array(momentum))
    qd, qdd = system.arrays[:2]
    if base == "free":
        tau = free_dynamics(system.tree, system.q, qd, qdd, _bus_momentum(system, momentum, qd.dtype), forward=False)
        return tau, jnp.zeros(system.batch + (len(system.keep),), tau.dtype)
    momentum = None if momentum is None else system.embed(system.arrays[2])
    H_full = system_mass_matrix(system.tree, system.q)
    if base == "held":
        nu = jnp.concatenate([jnp.zeros(system.batch + (6,), qd.dtype), qd], axis=-1)
    else:
        nu = jnp.concatenate([_held_attitude_velocity(system, H_full, qd, momentum), qd], axis=-1)
    H, c = mass_and_bias(system.tree, system.q, nu)
    base_accel = _base_acceleration(H, c, qdd, base)
    forces = _apply(H, jnp.concatenate([base_accel, qdd], axis=-1)) + c
    wrench = forces[..., :6]
    if base == "attitude":
        wrench = wrench.at[..., :3].set(0.0)
    return forces[..., 6:], system.reduce(wrench)


def _held_attitude_velocity(system: _System, H, qd, momentum):
    """[v; 0]: the bus centroid's velocity (bus axes) whose linear momentum is P, bus not turning."""
    P = jnp.zeros(system.batch + (3,), qd.dtype) if momentum is None else momentum[..., :3]
    P_bus = _apply(jnp.swapaxes(system.R, -1, -2), P)
    v = (P_bus - _apply(H[..., :3, 6:], qd)) / H[..., 0, 0, None]
    return jnp.concatenate([v, jnp.zeros_like(v)], axis=-1)


def _base_acceleration(H, c, qdd, base: str):
    """nu_b' of a held bus mode: zero when held, [v'; 0] when only turning is held."""
    if base == "held":
        return jnp.zeros(qdd.shape[:-1] + (6,), qdd.dtype)
    v_dot = -(_apply(H[..., :3, 6:], qdd) + c[..., :3]) / H[..., 0, 0, None]
    return jnp.concatenate([v_dot, jnp.zeros_like(v_dot)], axis=-1)


# Impacts at the tip ------------------------------------------------------------------------


def _check_joints(joints: str) -> None:
    if joints not in _JOINT_MODES:
        raise ValueError(f"joints: one of {', '.join(_JOINT_MODES)}, got {joints!r}")


def _response_map(system: _System, joints: str):
    """``(J (*batch, [k,] 6, 6 + n), X (*batch, 6 + n, [k,] 6 ...))``: X = H^-1 J^T (``"locked"``:
    only the bus columns, H_b^-1 J_S^T, joint rows zero), bus axes."""
    H = system_mass_matrix(system.tree, system.q)
    J = system.tip_maps()
    per_tip = J.ndim == system.R.ndim + 1
    Jt = jnp.swapaxes(J, -1, -2)
    if per_tip:
        H = jnp.broadcast_to(H[..., None, :, :], Jt.shape[:-2] + H.shape[-2:])
    if joints == "free":
        return J, _solve_columns(H, Jt)
    bus = _solve_columns(H[..., :6, :6], Jt[..., :6, :])
    return J, jnp.concatenate([bus, jnp.zeros(bus.shape[:-2] + (system.n, 6), bus.dtype)], axis=-2)


@functools.partial(jax.jit, static_argnames=("joints",))
def tip_inverse_inertia(robot, q: jax.Array, base_rotation=None, joints: str = "free") -> jax.Array:
    """``(..., 6, 6)`` (trees ``(..., k, 6, 6)``) G = J H^-1 J^T of the tip frame's origin, rows
    [v; w], inertial axes: Yoshida's extended inversed inertia tensor, the tip twist jump per
    tip impulse [linear; angular]. ``joints="locked"``: the whole robot as one rigid body
    (planar ``(..., 3, 3)``)."""
    _check_joints(joints)
    system = _System(robot, q, base_rotation)
    J, X = _response_map(system, joints)
    G = J @ X
    rotated = system.rotate(jnp.swapaxes(system.rotate(G), -1, -2))  # blkdiag(R, R) G blkdiag(R, R)^T
    rows = system.keep
    return rotated[..., rows[:, None], rows[None, :]]


@functools.partial(jax.jit, static_argnames=("joints",))
def impulse_response(robot, q, impulse, base_rotation=None, tip=0, joints: str = "free"):
    """``(dqd (..., n), dbase (..., 6))``: the jump of the joint rates and of [v of the bus
    centroid; w of the bus] (INERTIAL axes) under an impulse [linear; angular] at the tip
    frame's origin, inertial axes (planar [px, py, angular], dbase [vx, vy, w]).

    ``tip`` indexes a tree's tips; ``joints="locked"`` holds the joint rates (dqd = 0).
    """
    _check_joints(joints)
    system = _System(robot, q, base_rotation, (impulse, 1))
    _, X = _response_map(system, joints)
    if X.ndim == system.R.ndim + 1:  # per tip: (batch, k, 6 + n, 6)
        X = jnp.take(X, tip, axis=-3)
    jump = _apply(X, system.unrotate(system.embed(system.arrays[0])))
    return jump[..., 6:], system.reduce(system.rotate(jump[..., :6]))
