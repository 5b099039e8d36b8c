"""Motion of the free-floating arm: the nonholonomic base attitude along paths (eq. 5, 6).

With zero momentum the base turns as the joints move, I_S dphi0 + I_M . dphi_M = 0
(Umetani & Yoshida 1990, eq. 5). I_S and I_M depend on the joint angles only, so the
relation is driftless: along a joint-space path the base rotation is the line integral

    Delta phi0 = - integral (I_M(q) . dq) / I_S(q)

and does not depend on the timing. Three families of motion are integrated here:

- joint-space polylines (cyclic loops, Fig. 2): Gauss-Legendre quadrature of the line
  integral per straight segment, exact to rounding for these analytic integrands;
- straight inertial tip paths (Fig. 3a): joint rates from inverting J* (eq. 6),
  minimum-norm for redundant arms, integrated until J* loses rank, a joint limit, or
  a length limit (the end is located by Newton steps on the event functions);
- go-and-back tip motions (Fig. 9): two straight tip paths, out and back.

Everything is written for one path and batched with ``vmap`` over paths, initial
postures and designs, inside one ``jit`` per entry point (static shapes).

Straight paths use the joint-space arc length sigma as the independent variable, with
the regularized rates of the adjugate: for n = 2,

    dphi_M/dsigma = sgn0 adj(J*) d / |adj(J*) d|,   ds/dsigma = sgn0 det(J*) / |adj(J*) d|,

(sgn0 the sign of det J* at the start, d the inertial unit direction, s the tip
distance travelled), which stays finite and smooth through det J* = 0; the path ends
where ds/dsigma = 0, i.e. where the tip stops advancing along the line. For n > 2 the
minimum-norm rates J*^T (J* J*^T)^-1 d are regularized the same way with
adj(J* J*^T). The scheme is the 8th-order Dormand-Prince method (DOP853) with its
embedded error control, written out in ``lax.while_loop`` so that the event steps, the
step control and the batch share one compiled loop; see
docs/explanation/integrators.md for the measured comparison with diffrax, SciPy and
fixed-step RK4.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from . import _dop853
from .kinematics import (
    _momentum_rows,
    _tip_columns,
    _unit_vectors,
    design_coefficients,
    fixed_base_manipulability,
    momentum_inertias,
    tip_position,
)
from .robot import ConfigError, PlanarRobot

__all__ = [
    "StraightPath",
    "integrate_joint_path",
    "joint_path_history",
    "joint_path_base_increments",
    "straight_tip_path",
    "straight_tip_path_history",
    "go_and_back",
    "REASON_SINGULAR",
    "REASON_MAX_LENGTH",
    "REASON_JOINT_LIMIT",
    "REASON_STEP_BUDGET",
]

REASON_SINGULAR = 0
REASON_MAX_LENGTH = 1
REASON_JOINT_LIMIT = 2
REASON_STEP_BUDGET = 3


# Batching helpers ----------------------------------------------------------------------


def _is_traced(*xs) -> bool:
    return any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(xs))


def _flatten_batch(robot: PlanarRobot, arrays: list[tuple[jax.Array, int]]):
    """Broadcast the design batch and the leading axes of ``arrays`` together and flatten them.

    Args:
        arrays: pairs (array, number of trailing core axes).

    Returns:
        (batch_shape, flat robot, robot_batched flag, list of flat arrays (size, *core)).
    """
    robot_batch = robot.batch_shape
    shapes = [robot_batch] + [tuple(jnp.shape(a))[: jnp.ndim(a) - core] for a, core in arrays]
    try:
        batch = tuple(np.broadcast_shapes(*shapes))
    except ValueError:
        raise ConfigError(f"batch axes do not broadcast together: {shapes}") from None
    size = math.prod(batch)
    flat = []
    for a, core in arrays:
        a = jnp.asarray(a)
        core_shape = a.shape[a.ndim - core :]
        flat.append(jnp.broadcast_to(a, batch + core_shape).reshape((size,) + core_shape))
    if robot_batch:
        nb = len(robot_batch)

        def spread(x):
            x = jnp.asarray(x)
            core_shape = x.shape[nb:]
            return jnp.broadcast_to(x, batch + core_shape).reshape((size,) + core_shape)

        robot = jax.tree_util.tree_map(spread, robot)
    return batch, robot, bool(robot_batch), flat


def _check_arm_axis(robot: PlanarRobot, name: str, array, expected: int) -> None:
    if jnp.ndim(array) < 1 or jnp.shape(array)[-1] != expected:
        raise ConfigError(
            f"{name}: expected a trailing axis of {expected} for a {robot.n_links}-link arm, "
            f"got shape {jnp.shape(array)}"
        )


# Joint-space paths -----------------------------------------------------------------------


@functools.lru_cache(maxsize=None)
def _composite_gauss(nodes: int, pieces: int) -> tuple[np.ndarray, np.ndarray]:
    """Composite Gauss-Legendre rule on [0, 1]: ``pieces`` equal panels of ``nodes`` points."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    starts = np.arange(pieces)[:, None] / pieces
    t = (starts + (x[None, :] + 1.0) / (2.0 * pieces)).reshape(-1)
    weights = np.tile(w / (2.0 * pieces), pieces)
    return t, weights


def _segment_integrals(robot: PlanarRobot, starts: jax.Array, steps: jax.Array, t, weights) -> jax.Array:
    """Base rotation over straight joint segments q(t) = start + t step, t in [t_a, t_b].

    Args:
        starts, steps: ``(m, n)`` segment start points and displacements, rad.
        t: ``(m, Q)`` or ``(Q,)`` quadrature nodes in segment parameter; weights the same shape.

    Returns:
        ``(m,)`` increments of phi0, rad: sum_q w_q * (-(I_M . step) / I_S)(q(t_q)).
    """
    t = jnp.broadcast_to(jnp.asarray(t), (starts.shape[0],) + jnp.shape(t)[-1:])
    q = starts[:, None, :] + t[..., None] * steps[:, None, :]
    phi = jnp.concatenate([jnp.zeros(q.shape[:-1] + (1,), q.dtype), q], axis=-1)
    i_s, i_m = momentum_inertias(robot, phi)
    integrand = -jnp.sum(i_m * steps[:, None, :], axis=-1) / i_s
    return jnp.sum(integrand * weights, axis=-1)


# Widest panel of the default rule, in rad of the largest joint excursion: 24 nodes per
# pi/2 reach rounding level (docs/explanation/integrators.md: Table 1 and random 2-,
# 3- and 4-link designs, segments up to 4 pi per joint; 16 nodes per pi/2 leave 7e-12
# on 3-link designs). This is the panel width of the former fixed default, 8 panels of
# 24 nodes, on 4 pi segments; segments up to pi/2 now take one panel (8x cheaper).
_PANEL_WIDTH = 0.5 * np.pi
_TRACED_PIECES = 8  # traced waypoints: the longest segment is unknown; 4 pi per joint


def _default_pieces(joint_waypoints, pieces):
    """``pieces`` if given; else enough panels that none spans more than pi/2 of any joint."""
    if pieces is not None:
        return int(pieces)
    if _is_traced(joint_waypoints):
        return _TRACED_PIECES
    longest = float(np.max(np.abs(np.diff(np.asarray(joint_waypoints), axis=-2)), initial=0.0))
    if not np.isfinite(longest):
        return _TRACED_PIECES
    return max(1, math.ceil(longest / _PANEL_WIDTH - 1e-9))


@functools.partial(jax.jit, static_argnames=("robot_batched", "nodes", "pieces"))
def _joint_path_flat(robot, phi_start, waypoints, robot_batched, nodes, pieces):
    t, w = _composite_gauss(nodes, pieces)
    t, w = jnp.asarray(t, phi_start.dtype), jnp.asarray(w, phi_start.dtype)

    def one(robot, phi, wp):
        increments = _segment_integrals(robot, wp[:-1], wp[1:] - wp[:-1], t, w)
        return jnp.concatenate([phi[:1] + jnp.sum(increments), wp[-1]])

    return jax.vmap(one, in_axes=(0 if robot_batched else None, 0, 0))(robot, phi_start, waypoints)


def _prepare_joint_path(robot, phi_start, joint_waypoints):
    n = robot.n_links
    dtype = jnp.result_type(float)
    phi_start = jnp.asarray(phi_start, dtype)
    joint_waypoints = jnp.asarray(joint_waypoints, dtype)
    _check_arm_axis(robot, "phi_start", phi_start, n + 1)
    _check_arm_axis(robot, "joint_waypoints", joint_waypoints, n)
    if joint_waypoints.ndim < 2 or joint_waypoints.shape[-2] < 2:
        raise ConfigError(f"joint_waypoints: expected shape (..., k, {n}) with k >= 2, got {joint_waypoints.shape}")
    if not _is_traced(phi_start, joint_waypoints):
        gap = np.max(np.abs(np.asarray(joint_waypoints[..., 0, :]) - np.asarray(phi_start[..., 1:])), initial=0.0)
        if not gap <= 1e-9:
            raise ConfigError(
                f"joint_waypoints: the first row must equal phi_start[..., 1:] (largest gap {gap:.3g} rad)"
            )
    return phi_start, joint_waypoints


def integrate_joint_path(
    robot: PlanarRobot,
    phi_start: jax.Array,
    joint_waypoints: jax.Array,
    *,
    nodes: int = 24,
    pieces: int | None = None,
) -> jax.Array:
    """Posture at the end of a joint-space polyline, the base attitude following eq. (5).

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
        nodes, pieces: quadrature points per panel and panels per segment (static;
            ``pieces=None``: from the longest segment, as above).

    Returns:
        ``(..., n+1)`` posture at the last waypoint, base attitude included, rad.
    """
    phi_start, joint_waypoints = _prepare_joint_path(robot, phi_start, joint_waypoints)
    pieces = _default_pieces(joint_waypoints, pieces)
    batch, flat_robot, batched, (phi_flat, wp_flat) = _flatten_batch(
        robot, [(phi_start, 1), (joint_waypoints, 2)]
    )
    out = _joint_path_flat(flat_robot, phi_flat, wp_flat, batched, nodes, pieces)
    return out.reshape(batch + (robot.n_links + 1,))


@functools.partial(jax.jit, static_argnames=("robot_batched", "nodes", "pieces"))
def _increments_flat(robot, waypoints, robot_batched, nodes, pieces):
    t, w = _composite_gauss(nodes, pieces)
    t, w = jnp.asarray(t, waypoints.dtype), jnp.asarray(w, waypoints.dtype)

    def one(robot, wp):
        return _segment_integrals(robot, wp[:-1], wp[1:] - wp[:-1], t, w)

    return jax.vmap(one, in_axes=(0 if robot_batched else None, 0))(robot, waypoints)


def joint_path_base_increments(
    robot: PlanarRobot, joint_waypoints: jax.Array, *, nodes: int = 24, pieces: int | None = None
) -> jax.Array:
    """Base rotation over each segment of a joint polyline (eq. 5).

    Args:
        joint_waypoints: ``(..., k, n)`` joint angles, rad.
        nodes, pieces: the quadrature rule, as in :func:`integrate_joint_path`.

    Returns:
        ``(..., k-1)`` increments of phi0, rad.
    """
    joint_waypoints = jnp.asarray(joint_waypoints, jnp.result_type(float))
    _check_arm_axis(robot, "joint_waypoints", joint_waypoints, robot.n_links)
    if joint_waypoints.ndim < 2 or joint_waypoints.shape[-2] < 2:
        raise ConfigError(f"joint_waypoints: expected shape (..., k, n) with k >= 2, got {joint_waypoints.shape}")
    pieces = _default_pieces(joint_waypoints, pieces)
    batch, flat_robot, batched, (wp_flat,) = _flatten_batch(robot, [(joint_waypoints, 2)])
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
    robot: PlanarRobot,
    phi_start: jax.Array,
    joint_waypoints: jax.Array,
    samples_per_segment: int = 32,
    *,
    nodes: int = 16,
) -> tuple[jax.Array, jax.Array]:
    """Postures and inertial tip positions along a joint-space polyline (eq. 1, 5).

    Each segment is sampled at ``samples_per_segment`` equally spaced points (the
    segment's end is the next segment's start); the base attitude between samples is
    integrated with ``nodes`` Gauss-Legendre points.

    Args:
        phi_start: ``(..., n+1)`` initial posture, rad.
        joint_waypoints: ``(..., k, n)`` waypoints, first row = ``phi_start[..., 1:]``, rad.

    Returns:
        ``postures (..., S, n+1)`` rad and ``tips (..., S, 2)`` inertial, m, with
        S = (k - 1) * samples_per_segment + 1; the last posture equals
        :func:`integrate_joint_path`'s result.
    """
    phi_start, joint_waypoints = _prepare_joint_path(robot, phi_start, joint_waypoints)
    batch, flat_robot, batched, (phi_flat, wp_flat) = _flatten_batch(
        robot, [(phi_start, 1), (joint_waypoints, 2)]
    )
    postures, tips = _joint_history_flat(flat_robot, phi_flat, wp_flat, batched, int(samples_per_segment), nodes)
    count = postures.shape[1]
    return (
        postures.reshape(batch + (count, robot.n_links + 1)),
        tips.reshape(batch + (count, 2)),
    )


# Straight tip paths ----------------------------------------------------------------------


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class StraightPath:
    """The end of a straight inertial tip path (Umetani & Yoshida 1990, section 3.1 (3-b)).

    Attributes:
        end_posture: ``(..., n+1)`` posture where the path ended, rad.
        end_tip: ``(..., 2)`` tip there, inertial frame (origin at the system centroid), m.
        length: ``(...)`` distance the tip travelled along the line, m.
        reason: ``(...)`` int32 why it ended: 0 = J* singular (the tip cannot advance along
            the line), 1 = max_length reached, 2 = joint limit, 3 = step budget exhausted
            (not converged; raise ``max_steps``).
        kinematic: ``(...)`` bool, True when the singular end is also a singularity of the
            fixed-base arm (for n = 2: phi2 at 0 or pi), False for a dynamic singularity.
        joint_arc: ``(...)`` joint-space arc length of the path, rad (the integration variable).
        steps: ``(...)`` int32 integration steps taken.
    """

    end_posture: jax.Array
    end_tip: jax.Array
    length: jax.Array
    reason: jax.Array
    kinematic: jax.Array
    joint_arc: jax.Array
    steps: jax.Array


_STAGE_TIMES = _dop853.STAGE_TIMES
_STAGE_WEIGHTS = _dop853.STAGE_WEIGHTS
_SOLUTION_WEIGHTS = _dop853.SOLUTION_WEIGHTS


def _tableau_arrays(tableau: str):
    """(stage weights (S, S) lower triangular, solution weights (S,)) as NumPy arrays."""
    if tableau == "rk4":
        a = np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1.0, 0]])
        return a, np.array([1.0, 2.0, 2.0, 1.0]) / 6.0
    if tableau == "dop853":
        stages = len(_STAGE_WEIGHTS)
        a = np.zeros((stages, stages))
        for i, row in enumerate(_STAGE_WEIGHTS):
            a[i, : len(row)] = row
        return a, np.asarray(_SOLUTION_WEIGHTS)
    raise ConfigError(f"tableau: unknown scheme {tableau!r}; use 'dop853' or 'rk4'")


def _rk_step(field, y, h, tableau="dop853", return_slopes=False):
    """One explicit Runge-Kutta step of size h (may be negative) of y' = field(y).

    The stages are unrolled at trace time: under vmap on CPU this runs about 5x faster
    than a ``lax.scan`` over the stages (which carries and updates a stage array), at
    the price of a longer compile (measured in benchmarks/bench_motion.py).
    """
    a, b = _tableau_arrays(tableau)
    slopes = []
    for row in a:
        increment = sum((w * k for w, k in zip(row, slopes) if w != 0.0), jnp.zeros_like(y))
        slopes.append(field(y + h * increment))
    y_new = y + h * sum(w * k for w, k in zip(b, slopes) if w != 0.0)
    return (y_new, slopes) if return_slopes else y_new


def _dop853_error(h, slopes, slope_new, y, y_new, rtol):
    """Hairer's DOP853 error norm of one step (<= 1: accept), from the stage slopes."""
    every = list(slopes) + [slope_new]  # 13 slopes (m,)
    scale = rtol * (1.0 + jnp.maximum(jnp.abs(y), jnp.abs(y_new)))
    err5 = sum(w * k for w, k in zip(_dop853.ERROR_WEIGHTS_5, every) if w != 0.0) / scale
    err3 = sum(w * k for w, k in zip(_dop853.ERROR_WEIGHTS_3, every) if w != 0.0) / scale
    e5, e3 = jnp.sum(err5**2), jnp.sum(err3**2)
    denom = e5 + 0.01 * e3
    safe = jnp.where(denom > 0, denom, 1.0)
    return jnp.where(denom > 0, jnp.abs(h) * e5 / jnp.sqrt(safe * y.shape[0]), 0.0)


def _straight_field(robot: PlanarRobot, direction: jax.Array, sign0):
    """The regularized straight-path field y' = f(y), y = [phi0, phi_1..phi_n, s].

    Derivatives are with respect to the joint-space arc length sigma. Returns a function
    of y giving ``(n+2,)``: [dphi0, dphi_M (unit norm), ds].
    """
    coeffs = design_coefficients(robot)
    n = robot.n_links
    dx, dy = direction[0], direction[1]

    def field(y):
        c, s = _unit_vectors(y[: n + 1])
        xs, ys = _tip_columns(coeffs, c, s)
        H = _momentum_rows(coeffs, c, s)
        inv_is = 1.0 / H[0]
        # Columns of J* = J_M - J_S I_M / I_S (eq. 6), inertial frame.
        gx = [xs[j] - xs[0] * (H[j] * inv_is) for j in range(1, n + 1)]
        gy = [ys[j] - ys[0] * (H[j] * inv_is) for j in range(1, n + 1)]
        if n == 2:
            det = gx[0] * gy[1] - gx[1] * gy[0]
            v = [sign0 * (gy[1] * dx - gx[1] * dy), sign0 * (-gy[0] * dx + gx[0] * dy)]
            rate = sign0 * det
        else:
            a = sum(g * g for g in gx)
            b = sum(p * q for p, q in zip(gx, gy))
            d = sum(g * g for g in gy)
            # det(J* J*^T) by Cauchy-Binet: no cancellation near singular postures.
            rate = sum((gx[i] * gy[j] - gx[j] * gy[i]) ** 2 for i in range(n) for j in range(i + 1, n))
            ax, ay = d * dx - b * dy, -b * dx + a * dy  # adj(J* J*^T) d
            v = [gx[j] * ax + gy[j] * ay for j in range(n)]
        norm_sq = sum(vj * vj for vj in v)
        positive = norm_sq > 0
        inv_norm = jnp.where(positive, 1.0 / jnp.sqrt(jnp.where(positive, norm_sq, 1.0)), 0.0)
        dq = [vj * inv_norm for vj in v]
        dphi0 = -sum(H[j + 1] * dq[j] for j in range(n)) * inv_is  # eq. (5)
        return jnp.stack([dphi0] + dq + [rate * inv_norm])

    return field


def _initial_sign(robot: PlanarRobot, phi) -> jax.Array:
    """sign(det J*) at the start for n = 2 (+1 when exactly singular)."""
    coeffs = design_coefficients(robot)
    c, s = _unit_vectors(phi)
    xs, ys = _tip_columns(coeffs, c, s)
    H = _momentum_rows(coeffs, c, s)
    gx = [xs[j] - xs[0] * H[j] / H[0] for j in (1, 2)]
    gy = [ys[j] - ys[0] * H[j] / H[0] for j in (1, 2)]
    return jnp.where(gx[0] * gy[1] - gx[1] * gy[0] < 0, -1.0, 1.0)


def _lane_start(robot, phi_start, direction, max_step):
    """Integration state at the start of one straight path (a dict of arrays)."""
    n = robot.n_links
    dtype = phi_start.dtype
    direction = direction / jnp.linalg.norm(direction)
    sign0 = _initial_sign(robot, phi_start) if n == 2 else jnp.asarray(1.0, dtype)
    field = _straight_field(robot, direction, sign0)
    y0 = jnp.concatenate([phi_start, jnp.zeros((1,), dtype)])
    f0 = field(y0)
    # The slope of ds/dsigma, for the Newton prediction of the singular end, is a secant
    # through the last two steps (a forward difference at the start): cheaper than a jvp
    # of the field, and exact enough, since the end test is on ds/dsigma itself.
    probe = 1e-7
    slope0 = (field(y0 + probe * f0)[-1] - f0[-1]) / probe
    return {
        "y": y0,
        "f": f0,
        "slope": slope0,
        "arc": jnp.zeros((), dtype),
        "count": jnp.int32(0),
        "h_control": jnp.asarray(max_step, dtype),
        "direction": direction,
        "sign0": jnp.asarray(sign0, dtype),
    }


def _lane_step(robot, lane, max_length, max_step, tol, rtol, *, max_steps, tableau):
    """One attempted step of one straight path.

    Returns:
        (new lane state, finished, reason): finished when an event is located to ``tol``
        (reason = the event) or the step budget is spent (reason 3).
    """
    n = robot.n_links
    y, f, slope, h_control = lane["y"], lane["f"], lane["slope"], lane["h_control"]
    dtype = y.dtype
    field = _straight_field(robot, lane["direction"], lane["sign0"])
    lower = jnp.broadcast_to(robot.joint_lower, (n,)).astype(dtype)
    upper = jnp.broadcast_to(robot.joint_upper, (n,)).astype(dtype)
    inf = jnp.asarray(jnp.inf, dtype)
    # The singular event is a sign change of ds/dsigma for n = 2 (smooth through the
    # fold), but a one-sided approach for n > 2, where the field turns on the scale of
    # the distance to the singular posture: there every step stays within half the
    # predicted distance, approaching or receding.
    approach = 1.0 if n == 2 else 0.5

    # Newton predictions of the step to each event (negative: step back after overshoot).
    rate = f[-1]
    approaching = slope < 0
    h_sing = jnp.where(approaching, approach * rate / -jnp.where(approaching, slope, -1.0), inf)
    h_len = jnp.where(rate > 0, (max_length - y[-1]) / jnp.where(rate > 0, rate, 1.0), inf)
    dq, q = f[1 : n + 1], y[1 : n + 1]
    safe_dq = jnp.where(dq == 0, 1.0, dq)
    h_up = jnp.where(dq > 0, (upper - q) / safe_dq, inf)
    h_lo = jnp.where(dq < 0, (lower - q) / safe_dq, inf)
    h_lim = jnp.min(jnp.minimum(h_up, h_lo))
    max_h = max_step
    if n > 2:
        receding = approach * rate / jnp.where(approaching, 1.0, jnp.maximum(slope, 1e-300))
        max_h = jnp.minimum(max_step, jnp.where(approaching, inf, receding))
    candidates = jnp.stack([h_sing, h_len, h_lim])
    event = jnp.argmin(candidates).astype(jnp.int32)
    h_event = candidates[event]
    reached = jnp.abs(h_event) <= tol
    h = jnp.minimum(h_event, max_h)

    adaptive = tableau == "dop853"
    if adaptive:
        # The error controller's step bounds the event-limited step (either sign).
        h = jnp.clip(h, -h_control, h_control)
    h = jnp.where(reached, 0.0, h)
    y_new, slopes = _rk_step(field, y, h, tableau, return_slopes=True)
    f_new = field(y_new)
    if adaptive:
        error = _dop853_error(h, slopes, f_new, y, y_new, rtol)
        accept = error <= 1.0
        factor = jnp.clip(0.9 * jnp.where(error > 0, error, 1e-30) ** (-1.0 / 8.0), 0.2, 10.0)
        limited = jnp.abs(h) < 0.999 * h_control
        grown = jnp.where(accept & limited, h_control, jnp.abs(h) * factor)
        h_control = jnp.where(reached, h_control, jnp.minimum(grown, max_step))
    else:
        accept = jnp.bool_(True)
    take = accept & ~reached
    slope_new = jnp.where(h != 0, (f_new[-1] - f[-1]) / jnp.where(h != 0, h, 1.0), slope)
    keep = lambda new, old: jnp.where(take, new, old)  # noqa: E731
    count = lane["count"] + jnp.where(reached, 0, 1).astype(jnp.int32)
    new_lane = dict(
        lane,
        y=keep(y_new, y),
        f=keep(f_new, f),
        slope=keep(slope_new, slope),
        arc=lane["arc"] + jnp.where(take, h, 0.0),
        count=count,
        h_control=h_control,
    )
    finished = reached | (count >= max_steps)
    reason = jnp.where(reached, event, REASON_STEP_BUDGET)
    return new_lane, finished, reason


def _straight_queue(robot, phi_start, direction, max_length, max_step, tol, rtol, *, robot_batched, lanes,
                    max_steps, tableau):
    """Integrate P straight paths on ``lanes`` vectorized lanes with refill.

    A plain ``vmap`` of a while loop runs every path for as many steps as the longest
    one needs (here 3-4x the mean). Instead each lane, when its path ends, writes the
    result and takes the next path from the queue, so the batch does about
    (total steps / lanes + longest path) iterations.
    """
    count = phi_start.shape[0]
    n = robot.n_links
    width = min(lanes, count)
    robot_axis = 0 if robot_batched else None

    def robot_for(index):
        return jax.tree_util.tree_map(lambda x: x[index], robot) if robot_batched else robot

    start = jax.vmap(_lane_start, in_axes=(robot_axis, 0, 0, None))
    step = jax.vmap(
        functools.partial(_lane_step, max_steps=max_steps, tableau=tableau),
        in_axes=(robot_axis, 0, 0, None, None, None),
    )
    index0 = jnp.arange(width, dtype=jnp.int32)
    lanes0 = start(robot_for(index0), phi_start[index0], direction[index0], max_step)
    dtype = phi_start.dtype
    results0 = {
        "y": jnp.zeros((count, n + 2), dtype),
        "arc": jnp.zeros((count,), dtype),
        "count": jnp.zeros((count,), jnp.int32),
        "reason": jnp.zeros((count,), jnp.int32),
    }
    state0 = (lanes0, index0, jnp.ones((width,), bool), jnp.int32(width), results0)

    def cond(state):
        return jnp.any(state[2])

    def body(state):
        lane, index, active, next_index, results = state
        lane, finished, reason = step(robot_for(index), lane, max_length[index], max_step, tol, rtol)
        finished = finished & active
        target = jnp.where(finished, index, count)  # out of range: dropped
        results = {
            "y": results["y"].at[target].set(lane["y"], mode="drop"),
            "arc": results["arc"].at[target].set(lane["arc"], mode="drop"),
            "count": results["count"].at[target].set(lane["count"], mode="drop"),
            "reason": results["reason"].at[target].set(reason, mode="drop"),
        }
        rank = jnp.cumsum(finished.astype(jnp.int32)) - 1
        refill = finished & (next_index + rank < count)
        index = jnp.where(refill, next_index + rank, index)
        fresh = start(robot_for(index), phi_start[index], direction[index], max_step)
        lane = jax.tree_util.tree_map(
            lambda new, old: jnp.where(refill.reshape((-1,) + (1,) * (old.ndim - 1)), new, old), fresh, lane
        )
        active = jnp.where(finished, refill, active)
        next_index = next_index + jnp.sum(finished, dtype=jnp.int32)
        return lane, index, active, next_index, results

    results = jax.lax.while_loop(cond, body, state0)[-1]
    posture = results["y"][:, : n + 1]
    reason = results["reason"]
    fixed_w = fixed_base_manipulability(robot, posture[:, 1:]) / robot.reach**2
    return StraightPath(
        end_posture=posture,
        end_tip=tip_position(robot, posture),
        length=results["y"][:, -1],
        reason=reason,
        kinematic=(reason == REASON_SINGULAR) & (fixed_w < 1e-6),
        joint_arc=results["arc"],
        steps=results["count"],
    )


@functools.partial(jax.jit, static_argnames=("robot_batched", "lanes", "max_steps", "tableau"))
def _straight_flat(robot, phi_start, direction, max_length, max_step, tol, rtol, robot_batched, lanes, max_steps,
                   tableau):
    return _straight_queue(
        robot, phi_start, direction, max_length, max_step, tol, rtol,
        robot_batched=robot_batched, lanes=lanes, max_steps=max_steps, tableau=tableau,
    )


def _prepare_straight(robot, phi_start, direction, max_length):
    n = robot.n_links
    dtype = jnp.result_type(float)
    phi_start = jnp.asarray(phi_start, dtype)
    direction = jnp.asarray(direction, dtype)
    _check_arm_axis(robot, "phi_start", phi_start, n + 1)
    if direction.ndim < 1 or direction.shape[-1] != 2:
        raise ConfigError(f"direction: expected shape (..., 2), got {direction.shape}")
    if not _is_traced(direction) and np.any(np.linalg.norm(np.asarray(direction), axis=-1) == 0):
        raise ConfigError("direction: must be a nonzero vector")
    max_length = jnp.asarray(jnp.inf if max_length is None else max_length, dtype)
    if not _is_traced(max_length) and np.any(np.asarray(max_length) < 0):
        raise ConfigError("max_length: must not be negative")
    return phi_start, direction, max_length


def straight_tip_path(
    robot: PlanarRobot,
    phi_start: jax.Array,
    direction: jax.Array,
    *,
    max_length=None,
    max_step: float = 0.25,
    tol: float | None = None,
    rtol: float | None = None,
    max_steps: int = 4096,
    tableau: str = "dop853",
    lanes: int = 512,
) -> StraightPath:
    """Move the tip along a straight inertial line until J* loses rank (Fig. 3a).

    Joint rates invert the Generalized Jacobian (eq. 6), minimum-norm for n > 2, and the
    base follows eq. (5). Integration runs in joint-space arc length with the adjugate
    regularization (module docstring) and DOP853 steps of at most ``max_step`` rad sized
    by the embedded error estimate, shortened near an event; the end is located by
    Newton steps on the event functions to ``tol`` rad of joint arc. Batched over directions, initial postures and designs (all broadcast).

    Args:
        robot: the design (or a batch of designs).
        phi_start: ``(..., n+1)`` initial posture, rad.
        direction: ``(..., 2)`` direction of travel in the inertial frame (normalized here).
        max_length: scalar or ``(...)`` length limit, m (None: none).
        max_step: largest integration step, rad of joint arc.
        tol: event location tolerance, rad of joint arc (None: 1e-12 in float64,
            1e-5 in float32, where 1e-12 is below rounding and no step would pass).
        rtol: local error tolerance of the DOP853 step controller (relative to 1 + |y|);
            ignored by "rk4", which takes fixed steps of ``max_step`` (None: as ``tol``).
        max_steps: step budget (static); paths that exhaust it get reason 3.
        tableau: "dop853" (8th order with its embedded error control, default) or "rk4"
            (fixed steps, a baseline; static).
        lanes: paths integrated side by side (static); a lane whose path ends takes the
            next one, so short paths do not wait for long ones.

    Returns:
        :class:`StraightPath` with batch shape ``(...)``.
    """
    phi_start, direction, max_length = _prepare_straight(robot, phi_start, direction, max_length)
    batch, flat_robot, batched, (phi_flat, dir_flat, len_flat) = _flatten_batch(
        robot, [(phi_start, 1), (direction, 1), (max_length, 0)]
    )
    dtype = phi_flat.dtype
    default_tol = 1e-12 if jnp.finfo(dtype).bits >= 64 else 1e-5
    tol = default_tol if tol is None else tol
    rtol = default_tol if rtol is None else rtol
    out = _straight_flat(
        flat_robot, phi_flat, dir_flat, len_flat, jnp.asarray(max_step, dtype), jnp.asarray(tol, dtype),
        jnp.asarray(rtol, dtype), batched, int(min(lanes, max(1, phi_flat.shape[0]))), int(max_steps), tableau,
    )
    return jax.tree_util.tree_map(lambda x: x.reshape(batch + x.shape[1:]), out)


def _history_one(robot, phi_start, direction, joint_arc, *, intervals, substeps, tableau):
    n = robot.n_links
    dtype = phi_start.dtype
    direction = direction / jnp.linalg.norm(direction)
    sign0 = _initial_sign(robot, phi_start) if n == 2 else jnp.asarray(1.0, dtype)
    field = _straight_field(robot, direction, sign0)
    h = joint_arc / (intervals * substeps)

    def advance(y, _):
        for _ in range(substeps):
            y = _rk_step(field, y, h, tableau)
        return y, y

    y0 = jnp.concatenate([phi_start, jnp.zeros((1,), dtype)])
    _, ys = jax.lax.scan(advance, y0, None, length=intervals)
    ys = jnp.concatenate([y0[None], ys], axis=0)
    postures = ys[:, : n + 1]
    return postures, tip_position(robot, postures)


@functools.partial(jax.jit, static_argnames=("robot_batched", "intervals", "substeps", "tableau"))
def _history_flat(robot, phi_start, direction, joint_arc, robot_batched, intervals, substeps, tableau):
    one = functools.partial(_history_one, intervals=intervals, substeps=substeps, tableau=tableau)
    return jax.vmap(one, in_axes=(0 if robot_batched else None, 0, 0, 0))(robot, phi_start, direction, joint_arc)


def straight_tip_path_history(
    robot: PlanarRobot,
    phi_start: jax.Array,
    direction: jax.Array,
    n_samples: int = 101,
    *,
    max_length=None,
    substeps: int = 4,
    **options,
) -> tuple[jax.Array, jax.Array]:
    """Postures and inertial tips along a straight tip path, for plots (Fig. 3a, 9).

    Finds the end with :func:`straight_tip_path` (``options`` are passed on), then
    samples the path at ``n_samples`` points equally spaced in joint-space arc length.

    Returns:
        ``postures (..., n_samples, n+1)`` rad and ``tips (..., n_samples, 2)`` m, inertial.
    """
    if n_samples < 2:
        raise ConfigError("n_samples: must be at least 2")
    path = straight_tip_path(robot, phi_start, direction, max_length=max_length, **options)
    phi_start, direction, _ = _prepare_straight(robot, phi_start, direction, max_length)
    batch, flat_robot, batched, (phi_flat, dir_flat, arc_flat) = _flatten_batch(
        robot, [(phi_start, 1), (direction, 1), (path.joint_arc, 0)]
    )
    postures, tips = _history_flat(
        flat_robot, phi_flat, dir_flat, arc_flat, batched, int(n_samples) - 1, int(substeps),
        options.get("tableau", "dop853"),
    )
    return (
        postures.reshape(batch + postures.shape[1:]),
        tips.reshape(batch + tips.shape[1:]),
    )


def go_and_back(
    robot: PlanarRobot,
    phi_start: jax.Array,
    direction: jax.Array,
    distance,
    n_samples: int = 51,
    **options,
) -> tuple[jax.Array, jax.Array, jax.Array]:
    """A small go-and-back tip motion: out along ``direction`` by ``distance``, then back (Fig. 9).

    Args:
        phi_start: ``(..., n+1)`` initial posture, rad.
        direction: ``(..., 2)`` inertial direction of the outward leg.
        distance: scalar or ``(...)`` leg length, m.

    Returns:
        ``postures (..., 2 n_samples - 1, n+1)``, ``tips (..., 2 n_samples - 1, 2)`` (out then
        back, the turning point shared) and ``travelled (..., 2 n_samples - 1)``, the tip's
        cumulative path length, m. Each leg stops early at a singularity of J*.
    """
    direction = jnp.asarray(direction, jnp.result_type(float))
    out_postures, out_tips = straight_tip_path_history(
        robot, phi_start, direction, n_samples, max_length=distance, **options
    )
    back_postures, back_tips = straight_tip_path_history(
        robot, out_postures[..., -1, :], -direction, n_samples, max_length=distance, **options
    )
    postures = jnp.concatenate([out_postures, back_postures[..., 1:, :]], axis=-2)
    tips = jnp.concatenate([out_tips, back_tips[..., 1:, :]], axis=-2)
    steps = jnp.linalg.norm(jnp.diff(tips, axis=-2), axis=-1)
    travelled = jnp.concatenate([jnp.zeros_like(steps[..., :1]), jnp.cumsum(steps, axis=-1)], axis=-1)
    return postures, tips, travelled
