"""Impulses at the tip: Yoshida's extended inversed inertia tensor and the response to an impulse.

G = J H^-1 J^T (J = [J_S, J_M] the tip map, H the system mass matrix) is the tip's twist jump
per tip impulse [linear; angular about the tip origin] (Yoshida 1994); with the joints locked
the robot is one rigid body and G = J_S H_b^-1 J_S^T.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp

from ..models.dynamics import system_mass_matrix
from .state import DynamicState, apply, solve_columns

__all__ = ["JOINT_MODES", "check_joints", "impulse_response", "tip_inverse_inertia"]

JOINT_MODES = ("free", "locked")


def check_joints(joints: str) -> None:
    if joints not in JOINT_MODES:
        raise ValueError(f"joints: one of {', '.join(JOINT_MODES)}, got {joints!r}")


def _response_map(system: DynamicState, joints: str):
    """``(J (*batch, [k,] 6, 6 + n), X (*batch, 6 + n, [k,] 6 ...))``: X = H^-1 J^T (``"locked"``:
    only the bus columns, H_b^-1 J_S^T, joint rows zero), bus axes."""
    H = system_mass_matrix(system.tree, system.q)
    J = system.tip_maps()
    per_tip = J.ndim == system.R.ndim + 1
    Jt = jnp.swapaxes(J, -1, -2)
    if per_tip:
        H = jnp.broadcast_to(H[..., None, :, :], Jt.shape[:-2] + H.shape[-2:])
    if joints == "free":
        return J, solve_columns(H, Jt)
    bus = solve_columns(H[..., :6, :6], Jt[..., :6, :])
    return J, jnp.concatenate([bus, jnp.zeros(bus.shape[:-2] + (system.n, 6), bus.dtype)], axis=-2)


@functools.partial(jax.jit, static_argnames=("joints",))
def tip_inverse_inertia(robot, q: jax.Array, base_rotation=None, joints: str = "free") -> jax.Array:
    """``(..., 6, 6)`` (trees ``(..., k, 6, 6)``) G = J H^-1 J^T of the tip frame's origin, rows
    [v; w], inertial axes: Yoshida's extended inversed inertia tensor, the tip twist jump per
    tip impulse [linear; angular]. ``joints="locked"``: the whole robot as one rigid body
    (planar ``(..., 3, 3)``)."""
    check_joints(joints)
    system = DynamicState(robot, q, base_rotation)
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
    check_joints(joints)
    system = DynamicState(robot, q, base_rotation, (impulse, 1))
    _, X = _response_map(system, joints)
    if X.ndim == system.R.ndim + 1:  # per tip: (batch, k, 6 + n, 6)
        X = jnp.take(X, tip, axis=-3)
    jump = apply(X, system.unrotate(system.embed(system.arrays[0])))
    return jump[..., 6:], system.reduce(system.rotate(jump[..., :6]))
