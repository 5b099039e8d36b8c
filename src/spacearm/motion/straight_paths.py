"""Straight tip paths and go-and-back motions of the free-floating arm (eq. 5, 6).

With zero momentum the base turns as the joints move, I_S dphi0 + I_M . dphi_M = 0
(Umetani & Yoshida 1990, eq. 5). I_S and I_M depend on the joint angles only, so the
relation is driftless: along a joint-space path the base rotation is the line integral

    Delta phi0 = - integral (I_M(q) . dq) / I_S(q)

and does not depend on the timing. Three families of motion are integrated here:
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

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np

from .._core.batching import bucket_size, pad_leading, shapes_of
from .._core.errors import ConfigError
from ..kinematics import (
    base_rate,
    fixed_base_manipulability,
    generalized_jacobian,
    square_determinant,
    straight_path_rates,
    tip_position,
)
from ..models.family import family_of
from ..models.planar.robot import PlanarRobot
from ..models.spatial.robot import SpatialRobot
from .dop853 import error_norm, rk_step
from .path_ends import REASON_JOINT_LIMIT, REASON_MAX_LENGTH, REASON_SINGULAR, REASON_STEP_BUDGET
from .spatial_paths import spatial_straight_tip_path
from .batching import check_arm_axis, flatten_batch, is_traced

__all__ = [
    "StraightPath",
    "straight_tip_path",
    "straight_tip_path_history",
    "compile_straight_tip_path_history",
    "go_and_back",
    "REASON_SINGULAR",
    "REASON_MAX_LENGTH",
    "REASON_JOINT_LIMIT",
    "REASON_STEP_BUDGET",
]



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



def generic_straight_field(robot: PlanarRobot, direction: jax.Array, sign0):
    """The regularized straight-path field y' = f(y), y = [phi0, phi_1..phi_n, s].

    Derivatives are with respect to the joint-space arc length sigma. Returns a function
    of y giving ``(n+2,)``: [dphi0, dphi_M (unit norm), ds]. The joint rates come from
    `spacearm.kinematics.straight_path_rates` on J* (eq. 6), the base rate from
    eq. (5): both written once over the family's primitives.
    """
    n = robot.n_links

    def field(y):
        phi = y[: n + 1]
        dq, ds = straight_path_rates(generalized_jacobian(robot, phi), direction, sign0)
        return jnp.concatenate([base_rate(robot, phi, dq)[None], dq, ds[None]])

    return field


def _straight_field(robot: PlanarRobot, direction: jax.Array, sign0):
    """The family's closed-form field where it has one (chosen by type), else the generic one."""
    fast = family_of(robot).fast_paths.get("straight_path_field")
    return (fast or generic_straight_field)(robot, direction, sign0)


def _initial_sign(robot: PlanarRobot, phi) -> jax.Array:
    """sign(det J*) at the start for n = 2 (+1 when exactly singular)."""
    return jnp.where(square_determinant(generalized_jacobian(robot, phi)) < 0, -1.0, 1.0)


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
    y_new, slopes = rk_step(field, y, h, tableau, return_slopes=True)
    f_new = field(y_new)
    if adaptive:
        error = error_norm(h, slopes, f_new, y, y_new, rtol)
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


def _straight_queue(robot, phi_start, direction, max_length, max_step, tol, rtol, real, *, robot_batched, lanes,
                    max_steps, tableau):
    """Integrate the first ``real`` of P (padded) straight paths on ``lanes`` vectorized lanes with refill.

    A plain ``vmap`` of a while loop runs every path for as many steps as the longest
    one needs (here 3-4x the mean). Instead each lane, when its path ends, writes the
    result and takes the next path from the queue, so the batch does about
    (total steps / lanes + longest path) iterations. ``real`` is traced: the padding
    rows beyond it are never integrated (their results stay zero), so any number of
    paths up to P runs in the same compiled program.
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
    state0 = (lanes0, index0, index0 < real, jnp.int32(width), results0)

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
        refill = finished & (next_index + rank < real)
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
def _straight_flat(robot, phi_start, direction, max_length, max_step, tol, rtol, real, robot_batched, lanes,
                   max_steps, tableau):
    return _straight_queue(
        robot, phi_start, direction, max_length, max_step, tol, rtol, real,
        robot_batched=robot_batched, lanes=lanes, max_steps=max_steps, tableau=tableau,
    )


# Batches of straight paths are padded to PATH_BUCKET or the next power of two beyond.
PATH_BUCKET = 512


def lane_count(padded: int, lanes: int | None = None) -> int:
    """Lanes for a padded batch: ``lanes`` when given (at most ``padded``), else padded / 16,
    at least 64 and at most 512.

    Narrow queues run faster on CPU, because a lane that finishes takes the next path
    at once (CPU time of 1,000 random Table 1 paths: 95 ms on 64 lanes, 212 ms on 512;
    4,000 paths: 361 ms vs 525 ms); wider ones only pay off on many-core backends, so the
    width grows with the bucket.
    """
    if lanes is not None:
        return int(max(1, min(lanes, padded)))
    return int(min(512, max(64, padded // 16), padded))


def _as_array(x, dtype):
    """``x`` as an array of ``dtype``: NumPy when concrete, ``jnp`` when traced."""
    return jnp.asarray(x, dtype) if is_traced(x) else np.asarray(x, dtype)


def _prepare_straight(robot, phi_start, direction, max_length):
    n = robot.n_links
    dtype = jnp.result_type(float)
    # Concrete inputs stay NumPy until the compiled kernel takes them: jnp.asarray of a
    # NumPy array compiles a small staging program per shape.
    phi_start, direction = (_as_array(x, dtype) for x in (phi_start, direction))
    check_arm_axis(robot, "phi_start", phi_start, n + 1)
    if direction.ndim < 1 or direction.shape[-1] != 2:
        raise ConfigError(f"direction: expected shape (..., 2), got {direction.shape}")
    if not is_traced(direction) and np.any(np.linalg.norm(np.asarray(direction), axis=-1) == 0):
        raise ConfigError("direction: must be a nonzero vector")
    max_length = _as_array(np.inf if max_length is None else max_length, dtype)
    if not is_traced(max_length) and np.any(np.asarray(max_length) < 0):
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
    lanes: int | None = None,
    base_rotation: jax.Array | None = None,
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
        lanes: paths integrated side by side (static; None: `lane_count` of the
            padded batch, 64 to 512); a lane whose path ends takes the next one, so short
            paths do not wait for long ones (``lanes`` = the batch size is a plain vmap).
            The batch is padded to 512 paths or the next power of two (one compiled
            program per bucket, not per batch size); the padding is never integrated.

    Returns:
        `StraightPath` with batch shape ``(...)``.

    Spatial robots: ``straight_tip_path(robot, q_start, direction_xyz, max_length=...,
    base_rotation=R0)`` runs `spacearm.motion.spatial_paths.spatial_straight_tip_path`
    (the bus attitude integrated with the joints) and returns its `SpatialStraightPath`.
    """
    if isinstance(robot, SpatialRobot):
        if tableau != "dop853" or lanes is not None:
            raise TypeError("straight_tip_path: tableau and lanes apply to planar robots only")
        spatial = {"max_step": max_step} if max_step != 0.25 else {}
        spatial.update({k: v for k, v in (("tol", tol), ("rtol", rtol)) if v is not None})
        return spatial_straight_tip_path(
            robot, phi_start, direction, max_length, base_rotation=base_rotation, max_steps=max_steps, **spatial
        )
    if base_rotation is not None:
        raise TypeError("base_rotation applies to spatial robots; a planar posture carries its base attitude")
    phi_start, direction, max_length = _prepare_straight(robot, phi_start, direction, max_length)
    batch, flat_robot, batched, (phi_flat, dir_flat, len_flat) = flatten_batch(
        robot, [(phi_start, 1), (direction, 1), (max_length, 0)]
    )
    dtype = phi_flat.dtype
    default_tol = 1e-12 if jnp.finfo(dtype).bits >= 64 else 1e-5
    tol = default_tol if tol is None else tol
    rtol = default_tol if rtol is None else rtol
    # One program for every batch of up to 512 paths, and one per power of two beyond:
    # the batch is padded (the padding is never integrated, see _straight_queue).
    count = phi_flat.shape[0]
    padded = bucket_size(count, minimum=PATH_BUCKET)
    if batched:
        flat_robot = pad_leading(flat_robot, padded)
    phi_flat, dir_flat, len_flat = pad_leading((phi_flat, dir_flat, len_flat), padded)
    out = _straight_flat(
        flat_robot, phi_flat, dir_flat, len_flat, _as_array(max_step, dtype), _as_array(tol, dtype),
        _as_array(rtol, dtype), np.int32(count), batched, lane_count(padded, lanes), int(max_steps), tableau,
    )
    return _unpad(out, count, batch)


def _unpad(tree, count: int, batch: tuple[int, ...]):
    """The first ``count`` rows of each leaf, reshaped to ``batch``; in NumPy when concrete
    (eager slicing and reshaping would compile a small program per shape)."""
    if is_traced(tree):
        return jax.tree_util.tree_map(lambda x: x[:count].reshape(batch + x.shape[1:]), tree)
    return jax.tree_util.tree_map(lambda x: jax.device_put(np.asarray(x)[:count].reshape(batch + x.shape[1:])), tree)


def _history_one(robot, phi_start, direction, joint_arc, *, intervals, substeps, tableau):
    n = robot.n_links
    dtype = phi_start.dtype
    direction = direction / jnp.linalg.norm(direction)
    sign0 = _initial_sign(robot, phi_start) if n == 2 else jnp.asarray(1.0, dtype)
    field = _straight_field(robot, direction, sign0)
    h = joint_arc / (intervals * substeps)

    def advance(y, _):
        # A loop over the substeps rather than an unrolled body: the DOP853 stages are
        # already unrolled inside one step, so unrolling the substeps only lengthens compiles
        # (measured, 100 intervals x 4 substeps, CPU time: compile 1.5 s looped vs 2.5 s
        # unrolled; run 1.0 ms vs 1.4 ms for one path, 9.6 ms vs 10.5 ms for 16).
        y = jax.lax.fori_loop(0, substeps, lambda _, y: rk_step(field, y, h, tableau), y)
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


def compile_straight_tip_path_history(robot: PlanarRobot, count: int = 1, n_samples: int = 101, *,
                                      substeps: int = 4, tableau: str = "dop853") -> None:
    """Compile, without running, the sampler `straight_tip_path_history` uses for
    ``count`` paths of one design; a later call with those sizes finds the program.

    XLA compiles outside Python's GIL, so a caller can compile this on a second core (in
    a thread) while it integrates the paths it will sample (``planning.plan_reach`` does).
    """
    dtype = jnp.result_type(float)
    padded = bucket_size(count)
    n = robot.n_links
    shapes = [jax.ShapeDtypeStruct(shape, dtype) for shape in ((padded, n + 1), (padded, 2), (padded,))]
    _history_flat.lower(shapes_of(robot), *shapes, False, int(n_samples) - 1, int(substeps), tableau).compile()


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

    Finds the end with `straight_tip_path` (``options`` are passed on), then
    samples the path at ``n_samples`` points equally spaced in joint-space arc length.

    Returns:
        ``postures (..., n_samples, n+1)`` rad and ``tips (..., n_samples, 2)`` m, inertial.
    """
    if n_samples < 2:
        raise ConfigError("n_samples: must be at least 2")
    path = straight_tip_path(robot, phi_start, direction, max_length=max_length, **options)
    phi_start, direction, _ = _prepare_straight(robot, phi_start, direction, max_length)
    batch, flat_robot, batched, (phi_flat, dir_flat, arc_flat) = flatten_batch(
        robot, [(phi_start, 1), (direction, 1), (path.joint_arc, 0)]
    )
    count = phi_flat.shape[0]
    padded = bucket_size(count)  # one program per power of two of paths
    if batched:
        flat_robot = pad_leading(flat_robot, padded)
    phi_flat, dir_flat, arc_flat = pad_leading((phi_flat, dir_flat, arc_flat), padded)
    postures, tips = _history_flat(
        flat_robot, phi_flat, dir_flat, arc_flat, batched, int(n_samples) - 1, int(substeps),
        options.get("tableau", "dop853"),
    )
    return _unpad((postures, tips), count, batch)


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
