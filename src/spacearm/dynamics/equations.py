"""The equations of motion of the free-floating robot: H, c, H*, c*, forward and inverse dynamics.

With H the system mass matrix in the coordinates nu = [v; w; qd] (v the bus centroid's
velocity, w the bus angular velocity, bus axes) and c the bias forces (one pass over the
robot's tree, `spacearm.models.dynamics`), the robot under joint torques tau and a bus
wrench [f; n] (force at the bus centroid, torque about it, bus axes) obeys

    H nu' + c(q, nu) = [f; n; tau].

Partitioned as H = [[H_b, H_bm], [H_bm^T, H_m]], c = [c_b; c_m], the free bus (f = n = 0)
gives H* qdd + c* = tau with the reduced inertia H* = H_m - H_bm^T H_b^-1 H_bm and the
reduced bias c* = c_m - H_bm^T H_b^-1 c_b. Inverse dynamics takes one of three buses: free,
held at rest (the paper's fixed vehicle), or held in attitude only (reaction wheels; the
bus translates freely).
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp

from ..models.dynamics import free_dynamics, mass_and_bias, system_mass_matrix
from .state import DynamicState, apply, full_velocity, solve_columns

__all__ = [
    "BASE_MODES",
    "arm_inertia",
    "bias_forces",
    "forward_dynamics",
    "free_motion",
    "held_attitude_velocity",
    "inverse_dynamics",
    "joint_mass_matrix",
    "mass_matrix",
    "reduced_bias",
]

BASE_MODES = ("free", "held", "attitude")


@jax.jit
def mass_matrix(robot, q: jax.Array, base_rotation: jax.Array | None = None) -> jax.Array:
    """``(..., 6 + n, 6 + n)`` H in the coordinates [v; w; qd]: v the bus centroid's velocity and
    w the bus angular velocity, both in BUS axes (planar: ``(..., 3 + n, 3 + n)`` over
    [vx, vy, w; qd]). In these coordinates H does not depend on the attitude."""
    system = DynamicState(robot, q, base_rotation)
    H = system_mass_matrix(system.tree, system.q)
    return H[..., system.coords[:, None], system.coords[None, :]]


@jax.jit
def bias_forces(robot, q: jax.Array, qd: jax.Array, base_rotation=None, momentum=None) -> jax.Array:
    """``(..., 6 + n)`` c(q, nu) of H nu' + c = [f; n; tau], at the bus velocity the momentum
    gives (bus rows: force at the bus centroid and torque about it, bus axes)."""
    system = DynamicState(robot, q, base_rotation, joints={"qd": qd}, momentum=momentum)
    _, c = mass_and_bias(system.tree, system.q, full_velocity(system, system.rates("qd")))
    return c[..., system.coords]


@jax.jit
def joint_mass_matrix(robot, q: jax.Array) -> jax.Array:
    """``(..., n, n)`` H_m, the joint-space inertia with the bus held fixed (a focused tree:
    its held joints locked)."""
    system = DynamicState(robot, q)
    return system.locked(system_mass_matrix(system.tree, system.q))[..., 6:, 6:]


@jax.jit
def arm_inertia(robot, q: jax.Array) -> jax.Array:
    """``(..., n, n)`` the reduced inertia H* = H_m - H_bm^T H_b^-1 H_bm: joint torque per joint
    acceleration with the bus free, any momentum (Yoshida's generalized inertia; a focused tree:
    its held joints locked)."""
    system = DynamicState(robot, q)
    H = system.locked(system_mass_matrix(system.tree, system.q))
    coupling = solve_columns(H[..., :6, :6], H[..., :6, 6:])
    return H[..., 6:, 6:] - jnp.swapaxes(H[..., :6, 6:], -1, -2) @ coupling


@jax.jit
def reduced_bias(robot, q: jax.Array, qd: jax.Array, base_rotation=None, momentum=None) -> jax.Array:
    """``(..., n)`` c* = c_m - H_bm^T H_b^-1 c_b: with the bus free, H* qdd + c* = tau (the free
    bus's inverse dynamics at qdd = 0)."""
    system = DynamicState(robot, q, base_rotation, joints={"qd": qd}, momentum=momentum)
    qd = system.rates("qd")
    return free_dynamics(system.tree, system.q, qd, jnp.zeros_like(qd), system.momentum, system.moving, forward=False)


@jax.jit
def forward_dynamics(robot, q: jax.Array, qd: jax.Array, tau: jax.Array, base_rotation=None, momentum=None):
    """``(..., n)`` joint accelerations of the free-floating system under joint torques ``tau``
    (no external wrench): H* qdd = tau - c*."""
    return free_motion(robot, q, qd, tau, base_rotation, momentum)[1]


@jax.jit
def free_motion(robot, q: jax.Array, qd: jax.Array, tau: jax.Array, base_rotation=None, momentum=None):
    """``(base velocity (..., 6), qdd (..., n))``: `base_velocity` and `forward_dynamics` from one
    pass (what a simulation's every stage needs; planar ``(..., 3)`` [vx, vy, w])."""
    system = DynamicState(robot, q, base_rotation, joints={"qd": qd, "tau": tau}, momentum=momentum)
    motion = free_dynamics(
        system.tree, system.q, system.rates("qd"), system.joints["tau"], system.momentum, system.moving
    )
    return system.reduce(motion[..., :6]), motion[..., 6:]


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
    system = DynamicState(robot, q, base_rotation, joints={"qd": qd, "qdd": qdd}, momentum=momentum)
    qd, qdd = system.rates("qd"), system.rates("qdd")
    if base == "free":
        tau = free_dynamics(system.tree, system.q, qd, qdd, system.momentum, system.moving, forward=False)
        return tau, jnp.zeros(system.batch + (len(system.keep),), tau.dtype)
    if base == "held":
        bus = jnp.zeros(system.batch + (6,), qd.dtype)
    else:
        bus = held_attitude_velocity(system, system_mass_matrix(system.tree, system.q), qd)
    H, c = mass_and_bias(system.tree, system.q, jnp.concatenate([bus, qd], axis=-1))
    forces = apply(H, jnp.concatenate([_base_acceleration(H, c, qdd, base), qdd], axis=-1)) + c
    return forces[..., 6:], system.reduce(forces[..., :6])  # "attitude": the force rows are zero


def held_attitude_velocity(system: DynamicState, H, qd):
    """[v; 0]: the bus centroid's velocity (bus axes) whose linear momentum is the state's P, the
    bus not turning."""
    v = (system.momentum[..., :3] - apply(H[..., :3, 6:], qd)) / H[..., 0, 0, None]
    return jnp.concatenate([v, jnp.zeros_like(v)], axis=-1)


def _base_acceleration(H, c, qdd, base: str):
    """nu_b' of a held bus mode: zero when held, [v'; 0] when only turning is held."""
    if base == "held":
        return jnp.zeros(qdd.shape[:-1] + (6,), qdd.dtype)
    v_dot = -(apply(H[..., :3, 6:], qdd) + c[..., :3]) / H[..., 0, 0, None]
    return jnp.concatenate([v_dot, jnp.zeros_like(v_dot)], axis=-1)
