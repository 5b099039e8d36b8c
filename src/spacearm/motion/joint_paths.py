"""Joint-space paths of the free-floating arm: the base attitude along polylines (eq. 5).

With zero momentum the base turns as the joints move, I_S dphi0 + I_M . dphi_M = 0
(Umetani & Yoshida 1990, eq. 5). I_S and I_M depend on the joint angles only, so the
relation is driftless: along a joint-space path the base rotation is the line integral

    Delta phi0 = - integral (I_M(q) . dq) / I_S(q)

and does not depend on the timing. Joint-space polylines (cyclic loops, Fig. 2) are
integrated by Gauss-Legendre quadrature of the line integral per straight segment,
exact to rounding for these analytic integrands. Written for one path and batched with
``vmap`` over paths, initial postures and designs, inside one ``jit`` per entry point.
"""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from .._core.magnus import composite_gauss, line_integral
from ..kinematics import tip_position
from ..models.family import family_of
from .attitude import DEFAULT_ORDER, integrate_so3_joint_path, so3_joint_path_history
from .batching import check_arm_axis, flatten_batch, is_traced

__all__ = ["integrate_joint_path", "joint_path_base_increments", "joint_path_history"]


def _segment_integrals(robot, starts: jax.Array, steps: jax.Array, t, weights) -> jax.Array:
    """Base rotation of an abelian attitude (SO(2)) over straight joint segments q(t) = start + t step.

    Returns ``(m,)`` increments of phi0, rad: sum_q w_q (-(I_M . step) / I_S)(q(t_q)) (eq. 5).
    """
    return line_integral(functools.partial(family_of(robot).attitude_rate_map, robot), starts, steps, t, weights)


# Widest panel of the default rule, in rad of the largest joint excursion: 24 nodes per
# pi/2 reach rounding level (docs/explanation/integrators.md: Table 1 and random 2-,
# 3- and 4-link designs, segments up to 4 pi per joint; 16 nodes per pi/2 leave 7e-12
# on 3-link designs). Segments up to pi/2 take one panel.
_PANEL_WIDTH = 0.5 * np.pi
_TRACED_PIECES = 8  # traced waypoints: the longest segment is unknown; 4 pi per joint


def _default_pieces(joint_waypoints, pieces):
    """``pieces`` if given; else enough panels that none spans more than pi/2 of any joint."""
    if pieces is not None:
        return int(pieces)
    if is_traced(joint_waypoints):
        return _TRACED_PIECES
    longest = float(np.max(np.abs(np.diff(np.asarray(joint_waypoints), axis=-2)), initial=0.0))
    if not np.isfinite(longest):
        return _TRACED_PIECES
    return max(1, math.ceil(longest / _PANEL_WIDTH - 1e-9))


@functools.partial(jax.jit, static_argnames=("robot_batched", "nodes", "pieces"))
def _joint_path_flat(robot, phi_start, waypoints, robot_batched, nodes, pieces):
    def one(robot, phi, wp):
        turn = family_of(robot).loop_holonomy(robot, wp, nodes=nodes, pieces=pieces)
        return jnp.concatenate([phi[:1] + turn, wp[-1]])

    return jax.vmap(one, in_axes=(0 if robot_batched else None, 0, 0))(robot, phi_start, waypoints)


def _prepare_joint_path(robot, phi_start, joint_waypoints):
    n = robot.n_links
    dtype = jnp.result_type(float)
    phi_start = jnp.asarray(phi_start, dtype)
    joint_waypoints = jnp.asarray(joint_waypoints, dtype)
    check_arm_axis(robot, "phi_start", phi_start, n + 1)
    check_arm_axis(robot, "joint_waypoints", joint_waypoints, n)
    if joint_waypoints.ndim < 2 or joint_waypoints.shape[-2] < 2:
        raise ConfigError(f"joint_waypoints: expected shape (..., k, {n}) with k >= 2, got {joint_waypoints.shape}")
    if not is_traced(phi_start, joint_waypoints):
        gap = np.max(np.abs(np.asarray(joint_waypoints[..., 0, :]) - np.asarray(phi_start[..., 1:])), initial=0.0)
        if not gap <= 1e-9:
            raise ConfigError(
                f"joint_waypoints: the first row must equal phi_start[..., 1:] (largest gap {gap:.3g} rad)"
            )
    return phi_start, joint_waypoints


def _check_options(what: str, group, quadrature: dict, base_rotation, steps, order) -> None:
    """Refuse the options of the other attitude group: a quadrature (``nodes``, ``pieces``) for an
    abelian attitude, ``base_rotation``, ``steps`` and ``order`` (Magnus steps) for SO(3)."""
    if not group.abelian:
        if any(value is not None for value in quadrature.values()):
            raise TypeError(
                f"{what}: {' and '.join(quadrature)} set the quadrature of an abelian attitude; the "
                f"{group.name} attitude is integrated by Magnus steps (use steps=, order=)"
            )
        return
    for name, value in (("base_rotation", base_rotation), ("steps", steps), ("order", order)):
        if value is not None:
            raise TypeError(
                f"{what}: {name} applies to a non-abelian attitude (spatial robots); the "
                f"{group.name} attitude is a line integral (use {', '.join(f'{k}=' for k in quadrature)}; "
                "a planar posture carries phi0)"
            )


def integrate_joint_path(
    robot,
    phi_start: jax.Array,
    joint_waypoints: jax.Array,
    *,
    nodes: int | None = None,
    pieces: int | None = None,
    base_rotation: jax.Array | None = None,
    steps: int | None = None,
    order=None,
):
    """The base attitude and the joints at the end of a joint-space polyline (eq. 5, zero momentum).

    Every robot gets ``(attitude, joints)``: the attitude as its group holds it (a rotation
    matrix on SO(3), the angle phi0 on SO(2)) and the joints at the last waypoint. SO(3)
    (spatial robots): ``R_end, q_end = integrate_joint_path(robot, q_start, joint_waypoints,
    base_rotation=R0)`` integrates the bus attitude by the 6th-order Magnus scheme
    (`spacearm.motion.attitude.integrate_so3_joint_path`: ``steps`` Magnus steps
    per segment, by default from the segment lengths; ``order`` the scheme, default 6);
    ``nodes`` and ``pieces`` are refused there. SO(2) is abelian, so the attitude is a
    plain line integral, evaluated exactly by Gauss-Legendre quadrature (planar robots,
    the rest of this docstring); ``base_rotation``, ``steps`` and ``order`` are refused there.

    The base rotation is the line integral of -(I_M . dq)/I_S along the straight
    joint-space segments (Umetani & Yoshida 1990, eq. 5, zero momentum), evaluated with
    a composite Gauss-Legendre rule per segment (``pieces`` panels of ``nodes`` points).
    The integrand is analytic, so the default reaches rounding level (a few 1e-15 rad
    for segments up to two full turns of every joint; see tests/test_motion.py): by
    default each segment gets ceil(e / (pi/2)) panels, e the largest joint excursion of
    any segment in the batch (8 when the waypoints are traced), so short segments cost
    less (1 panel, 24 points, up to pi/2 rad per joint).

    Args:
        robot: the design, or a batch of designs broadcasting with the path batch.
        phi_start: ``(..., n+1)`` initial posture [phi0, phi1..phin], rad.
        joint_waypoints: ``(..., k, n)`` joint angles joined by straight segments, rad;
            the first row equals ``phi_start[..., 1:]``.
        nodes: quadrature points per panel (static; ``None``: 24).
        pieces: panels per segment (static; ``None``: from the longest segment, as above).

    Returns:
        ``(phi0_end (...), joints (..., n))`` planar; ``(R_end (..., 3, 3), q_end (..., n))``
        on SO(3): the attitude and the joints at the last waypoint.
    """
    group = family_of(robot).attitude
    _check_options("integrate_joint_path", group, {"nodes": nodes, "pieces": pieces}, base_rotation, steps, order)
    if not group.abelian:
        return integrate_so3_joint_path(
            robot,
            phi_start,
            joint_waypoints,
            base_rotation,
            steps=steps,
            order=DEFAULT_ORDER if order is None else order,
        )
    nodes = 24 if nodes is None else nodes
    phi_start, joint_waypoints = _prepare_joint_path(robot, phi_start, joint_waypoints)
    pieces = _default_pieces(joint_waypoints, pieces)
    batch, flat_robot, batched, (phi_flat, wp_flat) = flatten_batch(robot, [(phi_start, 1), (joint_waypoints, 2)])
    out = _joint_path_flat(flat_robot, phi_flat, wp_flat, batched, nodes, pieces).reshape(batch + (robot.n_links + 1,))
    return out[..., 0], out[..., 1:]


@functools.partial(jax.jit, static_argnames=("robot_batched", "nodes", "pieces"))
def _increments_flat(robot, waypoints, robot_batched, nodes, pieces):
    t, w = composite_gauss(nodes, pieces)
    t, w = jnp.asarray(t, waypoints.dtype), jnp.asarray(w, waypoints.dtype)

    def one(robot, wp):
        return _segment_integrals(robot, wp[:-1], wp[1:] - wp[:-1], t, w)

    return jax.vmap(one, in_axes=(0 if robot_batched else None, 0))(robot, waypoints)


def joint_path_base_increments(
    robot, joint_waypoints: jax.Array, *, nodes: int = 24, pieces: int | None = None
) -> jax.Array:
    """Base rotation over each segment of a joint polyline (eq. 5).

    Args:
        joint_waypoints: ``(..., k, n)`` joint angles, rad.
        nodes: quadrature points per panel, as in `integrate_joint_path`.
        pieces: panels per segment, as in `integrate_joint_path`.

    Returns:
        ``(..., k-1)`` increments of phi0, rad.
    """
    joint_waypoints = jnp.asarray(joint_waypoints, jnp.result_type(float))
    check_arm_axis(robot, "joint_waypoints", joint_waypoints, robot.n_links)
    if joint_waypoints.ndim < 2 or joint_waypoints.shape[-2] < 2:
        raise ConfigError(f"joint_waypoints: expected shape (..., k, n) with k >= 2, got {joint_waypoints.shape}")
    pieces = _default_pieces(joint_waypoints, pieces)
    batch, flat_robot, batched, (wp_flat,) = flatten_batch(robot, [(joint_waypoints, 2)])
    out = _increments_flat(flat_robot, wp_flat, batched, nodes, pieces)
    return out.reshape(batch + (joint_waypoints.shape[-2] - 1,))


@functools.partial(jax.jit, static_argnames=("robot_batched", "samples", "nodes"))
def _joint_history_flat(robot, phi_start, waypoints, robot_batched, samples, nodes):
    x, w = np.polynomial.legendre.leggauss(nodes)
    fractions = jnp.asarray(np.arange(samples) / samples, phi_start.dtype)

    def one(robot, phi, wp):
        starts, steps = wp[:-1], wp[1:] - wp[:-1]
        # Split each segment into `samples` sub-segments, integrate each with `nodes` points.
        sub_starts = (starts[:, None, :] + fractions[None, :, None] * steps[:, None, :]).reshape(-1, steps.shape[-1])
        sub_steps = jnp.repeat(steps / samples, samples, axis=0)
        sub_t = jnp.asarray(np.broadcast_to((x + 1.0) / 2.0, (1, nodes)), phi.dtype)
        sub_w = jnp.asarray(np.broadcast_to(w / 2.0, (1, nodes)), phi.dtype)
        increments = _segment_integrals(robot, sub_starts, sub_steps, sub_t, sub_w)
        phi0 = phi[0] + jnp.concatenate([jnp.zeros((1,), phi.dtype), jnp.cumsum(increments)])
        joints = jnp.concatenate([sub_starts, wp[-1:]], axis=0)
        postures = jnp.concatenate([phi0[:, None], joints], axis=-1)
        return postures, tip_position(robot, postures)

    return jax.vmap(one, in_axes=(0 if robot_batched else None, 0, 0))(robot, phi_start, waypoints)


def joint_path_history(
    robot,
    start: jax.Array,
    joint_waypoints: jax.Array,
    samples_per_segment: int = 32,
    *,
    nodes: int | None = None,
    base_rotation: jax.Array | None = None,
    steps: int | None = None,
    order=None,
) -> tuple[jax.Array, jax.Array, jax.Array]:
    """The base attitude, the joints and the inertial tip sampled along a joint-space polyline (eq. 1, 5).

    Each segment is sampled at ``samples_per_segment`` equally spaced points (the segment's
    end is the next segment's start; the last sample is the last waypoint). The attitude
    follows the family's group, as in `integrate_joint_path`: on SO(2) a Gauss-Legendre
    line integral between samples (``nodes`` points, default 16; ``start`` is the posture
    [phi0, joints]), on SO(3) ``steps`` Magnus steps per sample (default 1, ``order``
    default 6; ``start`` is the joints, ``base_rotation`` the bus attitude there).

    Returns:
        ``(attitudes, joints (..., S, n), tips)`` with S = (k - 1) * samples_per_segment + 1:
        planar ``phi0 (..., S)`` and tips ``(..., S, 2)``; on SO(3) ``R (..., S, 3, 3)`` and
        tips ``(..., S, 3)`` (``(..., S, k, 3)`` for k tips), inertial, m. The last attitude
        equals `integrate_joint_path`'s.
    """
    group = family_of(robot).attitude
    _check_options("joint_path_history", group, {"nodes": nodes}, base_rotation, steps, order)
    samples = int(samples_per_segment)
    if not group.abelian:
        order = DEFAULT_ORDER if order is None else order
        R, q = so3_joint_path_history(
            robot, start, joint_waypoints, base_rotation, samples, steps=steps or 1, order=order
        )
        return R, q, tip_position(robot, q, R)
    start, joint_waypoints = _prepare_joint_path(robot, start, joint_waypoints)
    batch, flat_robot, batched, (phi_flat, wp_flat) = flatten_batch(robot, [(start, 1), (joint_waypoints, 2)])
    postures, tips = _joint_history_flat(
        flat_robot, phi_flat, wp_flat, batched, samples, 16 if nodes is None else nodes
    )
    count = postures.shape[1]
    postures = postures.reshape(batch + (count, robot.n_links + 1))
    return postures[..., 0], postures[..., 1:], tips.reshape(batch + (count, 2))
