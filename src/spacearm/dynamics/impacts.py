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
    H = system.locked(system_mass_matrix(system.tree, system.q))
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


def _chosen_tip(system: DynamicState, per_tip, tip):
    """The ``tip``-th of a tree's per-tip maps ``(*batch, k, ...)``; a robot without a tip axis
    (one tip, or a tree focused on one) takes only ``tip=0``. Checked where ``tip`` is concrete."""
    k = None if system.tips is not None else len(system.tree.tip_bodies)
    if not isinstance(tip, jax.core.Tracer) and not 0 <= int(tip) < (k or 1):
        raise ValueError(f"tip: {tip} is not one of the robot's {k or 1} tip(s) (numbered from 0)")
    if per_tip is None or k is None:
        return per_tip
    return jnp.take(per_tip, tip, axis=len(system.batch))


def impulse_response(robot, q, impulse, base_rotation=None, tip=0, joints: str = "free"):
    """``(dqd (..., n), dbase (..., 6))``: the jump of the joint rates and of [v of the bus
    centroid; w of the bus] (INERTIAL axes) under an impulse [linear; angular] at the tip
    frame's origin, inertial axes (planar [px, py, angular], dbase [vx, vy, w]).

    ``tip`` indexes a tree's tips (checked here when it is a number; a robot without a tip
    axis takes 0); ``joints="locked"`` holds the joint rates (dqd = 0).
    """
    check_joints(joints)
    if not isinstance(tip, jax.core.Tracer):
        _chosen_tip(DynamicState(robot, q, base_rotation), None, tip)
    return _impulse_response(robot, q, impulse, base_rotation, tip, joints)


@functools.partial(jax.jit, static_argnames=("joints",))
def _impulse_response(robot, q, impulse, base_rotation, tip, joints: str):
    system = DynamicState(robot, q, base_rotation, twists={"impulse": impulse})
    _, X = _response_map(system, joints)
    X = _chosen_tip(system, X, tip)
    jump = apply(X, system.unrotate(system.twists["impulse"]))
    return jump[..., 6:], system.reduce(system.rotate(jump[..., :6]))
