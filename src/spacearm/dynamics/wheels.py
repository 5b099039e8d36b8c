"""The reaction-wheel momentum that holds the bus attitude while the arm moves.

Wheels that keep the bus from turning (w = 0) carry the part of the system angular momentum
that the bodies do not: with the bus translating freely under the linear momentum P,

    h = R^T L - L_bodies(q, qd),

L the system angular momentum about the system centroid (inertial axes), and L_bodies the
bodies' angular momentum about the system centroid with the bus at [v; 0] (v from P), bus
axes. The torque the wheels apply to the bus is -dh/dt: the ``"attitude"`` wrench of
`spacearm.dynamics.inverse_dynamics` (the reaction null space of Yoshida and Nenchev keeps h
constant).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .._core.groups import vee
from ..models.dynamics import system_mass_matrix
from .equations import held_attitude_velocity
from .state import DynamicState, apply

__all__ = ["wheel_momentum"]


@jax.jit
def wheel_momentum(robot, q: jax.Array, qd: jax.Array, base_rotation=None, momentum=None) -> jax.Array:
    """``(..., 3)`` h, BUS axes, N m s: the angular momentum the reaction wheels hold for the bus
    not to turn while the arm is at (q, qd), the bus translating with the momentum's P (planar
    ``(...,)``, about z). The system momentum ``momentum`` [P; L] is in inertial axes (zero
    when ``None``)."""
    system = DynamicState(robot, q, base_rotation, joints={"qd": qd}, momentum=momentum)
    qd = system.rates("qd")
    H = system_mass_matrix(system.tree, system.q)
    nu = jnp.concatenate([held_attitude_velocity(system, H, qd), qd], axis=-1)
    p = apply(H, nu)  # [P; L about the bus centroid; joint momenta], bus axes
    offset = vee(H[..., 3:6, 0:3]) / H[..., 0, 0, None]  # system centroid about the bus centroid
    bodies = p[..., 3:6] - jnp.cross(offset, p[..., :3])
    h = system.momentum[..., 3:] - bodies  # the system's L, bus axes, less the bodies'
    axes = system.family.attitude.angular_axes  # the plane's normal alone for a planar robot
    return h[..., axes[0]] if len(axes) == 1 else h
