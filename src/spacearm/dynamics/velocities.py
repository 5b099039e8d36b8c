"""The velocities a momentum gives: the bus's, and the tip's with its drift term.

The base velocity solves H_b [v; w] + H_bm qd = (the momentum about the bus centroid, bus
axes); the tip twist is J nu with J = [J_S, J_M] the tip maps, J* qd plus the drift the
momentum adds (SpaceDyn's calc_gj11).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .state import DynamicState, full_velocity

__all__ = ["base_velocity", "tip_velocity"]


@jax.jit
def base_velocity(robot, q: jax.Array, qd: jax.Array, base_rotation=None, momentum=None) -> jax.Array:
    """``(..., 6)`` [v of the bus centroid; w of the bus], BUS axes, at joint rates ``qd`` with
    the system momentum ``momentum`` (planar ``(..., 3)`` [vx, vy, w])."""
    system = DynamicState(robot, q, base_rotation, joints={"qd": qd}, momentum=momentum)
    nu = full_velocity(system, system.rates("qd"))
    return system.reduce(nu[..., :6])


@jax.jit
def tip_velocity(robot, q: jax.Array, qd: jax.Array, base_rotation=None, momentum=None) -> jax.Array:
    """``(..., 6)`` (trees ``(..., k, 6)``) the twist [v; w] of the tip frame's origin, INERTIAL
    axes: J* qd plus the drift the momentum adds (SpaceDyn's calc_gj11)."""
    system = DynamicState(robot, q, base_rotation, joints={"qd": qd}, momentum=momentum)
    nu = full_velocity(system, system.rates("qd"))
    J = system.tip_maps()
    twist = jnp.einsum("...ij,...j->...i", J, nu if J.ndim == nu.ndim + 1 else nu[..., None, :])
    return system.reduce(system.rotate(twist))
