"""Free-floating dynamics on the tree pass: the system mass matrix, the bias forces, the tip maps.

Coordinates nu = [v; w; qdot]: v the velocity of the bus centroid and w the bus angular
velocity, both in bus axes, then the joint rates. The kinetic energy is
T = 1/2 nu^T H(q) nu with

    H = [[H_b, H_bm], [H_bm^T, H_m]],

H_b = I_S and H_bm = I_M the momentum map of one pass over the tree (so H nu is the
momentum [P; L_c] in bus axes, L_c about the bus centroid, then the joint momenta) and
H_m the joint-space inertia (Umetani & Yoshida 1990, eq. 4-5, in 3-D; Yoshida's
generalized inertia).

The bias forces follow from the same H. The bus coordinates are body-fixed, so the bus
rows are Kirchhoff's equations and the joint rows Lagrange's (the Euler-Poincare
equations of SE(3) x joints, gravity zero):

    d/dt P + w x P = f,   d/dt L_c + w x L_c + v x P = n,   d/dt p_q - dT/dq = tau,

with f the force at the bus centroid and n the torque about it (bus axes). Hence
H nu' + c(q, nu) = [f; n; tau] with

    c = (dH/dq . qdot) nu + [w x P; w x L_c + v x P; -1/2 nu^T (dH/dq) nu].

dH/dq . qdot is a forward derivative and dT/dq a reverse one, both of the pass that
builds H, so c is exact to rounding and written once for every tree.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .tree.algebra import _add, _bus_momentum_matrix, _cross, _rows, _sub, _vec, batched
from .tree.primitives import _fixed_columns, _mass_from, _tip_rows, _tree_pass
from .tree.robot import TreeRobot

__all__ = ["mass_and_bias", "system_mass_matrix", "tip_maps"]


def _system_mass_minor(robot: TreeRobot, q):
    """``(6 + n, 6 + n, *batch)`` H for ``q (n, *batch)``, from one pass."""
    state = _tree_pass(robot, q)
    base_com = _vec(jnp.asarray(robot.base_com))
    angular = _sub(state.angular, _cross(base_com, state.momentum))
    batch = q.shape[1:]
    h_b = jnp.broadcast_to(_bus_momentum_matrix(state, base_com), (6, 6) + batch)
    h_bm = _rows(state.momentum, angular)
    top = jnp.concatenate([h_b, h_bm], axis=1)
    bottom = jnp.concatenate([jnp.swapaxes(h_bm, 0, 1), _mass_from(robot, state)], axis=1)
    return jnp.concatenate([top, bottom], axis=0)


def _mass_and_bias_minor(robot: TreeRobot, x):
    """``(6 + n, 7 + n, *batch)``: [H | c] for ``x = [q; nu] (2 n + 6, *batch)``."""
    n = robot.n_joints
    q, nu = x[:n], x[n:]
    mass = lambda joints: _system_mass_minor(robot, joints)
    H, H_dot = jax.jvp(mass, (q,), (nu[6:],))
    _, pullback = jax.vjp(mass, q)
    (energy_slope,) = pullback(0.5 * nu[:, None] * nu[None, :])
    p = jnp.einsum("ij...,j...->i...", H, nu)
    v, w, P, L = _vec(nu[:3]), _vec(nu[3:6]), _vec(p[:3]), _vec(p[3:6])
    gyroscopic = _rows(_cross(w, P), _add(_cross(w, L), _cross(v, P)))
    bias = jnp.einsum("ij...,j...->i...", H_dot, nu) + jnp.concatenate([gyroscopic, -energy_slope], axis=0)
    return jnp.concatenate([H, bias[:, None]], axis=1)


def _tip_maps_minor(robot: TreeRobot, q):
    """``(k, 6, 6 + n, *batch)``: the twist [v; w] of every tip origin per nu, bus axes."""
    state = _tree_pass(robot, q, with_momentum=False)
    x, y, z = _sub(state.tips, _vec(jnp.asarray(robot.base_com)))  # (k, *batch) each
    zero = jnp.zeros_like(x)
    lever = jnp.stack([jnp.stack(row) for row in ((zero, z, -y), (-z, zero, x), (y, -x, zero))])  # -[r]x
    eye = jnp.broadcast_to(jnp.eye(3, dtype=x.dtype).reshape((3, 3) + (1,) * x.ndim), lever.shape)
    bus = jnp.concatenate(
        [jnp.concatenate([eye, lever], axis=1), jnp.concatenate([jnp.zeros_like(eye), eye], axis=1)], axis=0
    )
    return jnp.concatenate([jnp.moveaxis(bus, 2, 0), _tip_rows(*_fixed_columns(robot, state))], axis=2)


system_mass_matrix = batched(_system_mass_minor, 2)
system_mass_matrix.__doc__ = """``(..., 6 + n, 6 + n)`` H in the coordinates [v; w; qdot] of the module docstring."""

_mass_and_bias = batched(_mass_and_bias_minor, 2)


def mass_and_bias(robot: TreeRobot, q: jax.Array, nu: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(H (..., 6 + n, 6 + n), c (..., 6 + n))`` at joints ``q (..., n)`` and velocity
    ``nu (..., 6 + n)`` (the module docstring's coordinates), from one pass and its derivatives."""
    q, nu = jnp.asarray(q), jnp.asarray(nu)
    batch = jnp.broadcast_shapes(q.shape[:-1], nu.shape[:-1])
    q, nu = jnp.broadcast_to(q, batch + q.shape[-1:]), jnp.broadcast_to(nu, batch + nu.shape[-1:])
    stacked = _mass_and_bias(robot, jnp.concatenate([q, nu], axis=-1))
    return stacked[..., :-1], stacked[..., -1]


tip_maps = batched(_tip_maps_minor, 3)
tip_maps.__doc__ = """``(..., k, 6, 6 + n)`` J: the twist [v; w] of every tip origin per [v; w; qdot], bus axes.

The first six columns move the tip with the bus (v + w x (tip - bus centroid), w); the
others are the fixed-base Jacobian. G = J H^-1 J^T is Yoshida's extended inversed inertia."""
