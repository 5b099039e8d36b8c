"""One lane integrator: DOP853 with event location, lane refill and power-of-two buckets.

Written once for every robot family. A path is a state y = [family state, s] (the
family's joints and base-attitude coordinates, `spacearm.models.RobotFamily.split_state`,
then the tip distance s) integrated in joint-space arc length sigma by an explicit
Runge-Kutta scheme (DOP853 with its embedded error control, or fixed RK4 steps), until
an event, located by Newton predictions on the event functions to ``tol``:

- singular: ds/dsigma reaches 0 (a sign change when the translational J* is square,
  a one-sided approach otherwise, where every step stays within half the predicted
  distance), or, for a redundant arm, a stall: the tip advances less than ``sing_rate``
  per radian of joint motion, or the rate is flat (its predicted zero lies beyond the
  next joint limit) and the tip travel left until that limit, predicted from the rate
  and its slope, is below ``tip_tol`` (see `step_lane`);
- length: s reaches ``max_length``;
- limit: a joint reaches its limit;
- the step budget ``max_steps`` runs out (reason 3, not converged).

The lane state (a dict pytree of arrays: y, f = field(y), the secant slope of
ds/dsigma, arc, count, the controller's step, and the per-path field parameters) is
advanced by `step_lane`, written for one path. `run_queue` integrates a padded batch on
a few vectorized lanes: a lane whose path ends writes its result and takes the next
path from the queue, so short paths do not wait for long ones, and the number of real
paths is traced, so any batch up to the padded size runs in one compiled program.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from .dop853 import error_norm, rk_step
from .path_ends import REASON_SINGULAR, REASON_STEP_BUDGET

__all__ = ["PATH_BUCKET", "lane_count", "run_queue", "start_lane", "step_lane"]

# Batches of paths are padded to PATH_BUCKET or the next power of two beyond.
PATH_BUCKET = 512
# The forward-difference step of the start's slope of ds/dsigma, rad of joint arc.
PROBE = 1e-7


def lane_count(padded: int, lanes: int | None = None) -> int:
    """Lanes for a padded batch: ``lanes`` when given (at most ``padded``), else padded / 16,
    at least 64 and at most 512.

    Narrow queues run faster on CPU, because a lane that finishes takes the next path
    at once; wider ones only pay off on many-core backends, so the width grows with the
    bucket.
    """
    if lanes is not None:
        return int(max(1, min(lanes, padded)))
    return int(min(512, max(64, padded // 16), padded))


def start_lane(field, y0: jax.Array, max_step, params: dict, *, rolled: bool = False, aux: int = 0) -> dict:
    """The lane state at the start of one path (``params``: the field's per-path parameters;
    ``rolled``: the field holds a loop, static).

    The slope of ds/dsigma, for the Newton prediction of the singular end, is a secant
    through the last two steps (a forward difference at the start): cheaper than a jvp of
    the field, and exact enough, since the end test is on ds/dsigma itself. Where the
    field holds a loop (``rolled``), nothing is evaluated here: the lane starts ``fresh``
    and `step_lane` takes its two start evaluations from its own stage loop, so the
    program holds one copy of the field (a spatial field is a pass over the chain, costly
    to compile), not three (the start, the refill, the step).

    ``aux`` > 0 (rolled only, static): the field returns ``(slope, aux vector (aux,))``,
    and the lane keeps the aux vector of its current y (``"aux"``, written with the
    results by `run_queue`): quantities of the path's end from the field's own pass.
    """
    dtype = y0.dtype
    lane = dict(params, y=y0, arc=jnp.zeros((), dtype), count=jnp.int32(0), h_control=jnp.asarray(max_step, dtype))
    if rolled:
        lane = dict(lane, f=jnp.zeros_like(y0), slope=jnp.zeros((), dtype), fresh=jnp.bool_(True))
        return dict(lane, aux=jnp.zeros((aux,), dtype)) if aux else lane
    f0 = field(y0)
    f1 = field(y0 + PROBE * f0)
    return dict(lane, f=f0, slope=(f1[-1] - f0[-1]) / PROBE)


class _LaneSettings(NamedTuple):
    """The settings of `step_lane` that every step of a batch shares."""

    square: bool  # static
    max_length: jax.Array
    max_step: jax.Array
    tol: jax.Array
    rtol: jax.Array
    sing_rate: jax.Array
    max_steps: jax.Array
    tip_tol: jax.Array
    tableau: str  # static
    rolled: bool  # static


def step_lane(
    field,
    lane: dict,
    joints,
    lower,
    upper,
    *,
    square: bool,
    max_length,
    max_step,
    tol,
    rtol,
    sing_rate,
    max_steps,
    tip_tol=-jnp.inf,
    tableau: str = "dop853",
    rolled: bool = False,
):
    """One attempted step of one path.

    Args:
        field: y -> dy/dsigma of this path.
        joints: ``(start, n)``: where the joints sit in y (static).
        lower, upper: ``(n,)`` joint limits.
        square: whether the translational J* is square (the singular end is a sign change).
        sing_rate: the stall rate of a redundant arm, m/rad (-inf: no stall event).
        tip_tol: the stall travel of a redundant arm, m (-inf: none; see below).
        rolled: the Runge-Kutta stages in a loop (for fields that hold a loop), static; the
            call on a fresh lane (`start_lane`) is the start: f and the slope, no step.

    The stall by travel. The minimum-norm flow of a redundant arm can reach a slow
    manifold instead of the rank loss: on the UR5 (benchmarks/bench_spatial_straight.py)
    the five arm joints reach the elbow singularity and only joint 6, whose axis nearly
    passes through the tip, still moves it, through the bus reaction. ds/dsigma then
    stays small and flat until joint 6 meets its limit, and the field is stiff there
    (Jacobian eigenvalues near -0.18 / sigma_3(J*_v)), so explicit steps stay tiny:
    thousands of steps for under a millimetre of tip travel. The path ends there,
    singular, when the rate's linear model rate + slope t stays positive up to the next
    joint limit h_lim (along the current joint direction) and predicts a travel
    h_lim (rate + slope h_lim / 2) <= ``tip_tol`` to it; a limit within ``max_step`` is
    located as usual, and so is a length event before the limit. The end then falls
    short of the exact one by at most ``tip_tol`` of tip travel (as far as the rate
    stays near its linear model and the joints keep their direction, as on the creep),
    while the joints skip the rest of the creep (joint 6 by up to its range).

    Returns:
        (new lane state, finished, reason): finished when an event is located to ``tol``
        (reason = the event) or the step budget is spent (reason 3).
    """
    settings = _LaneSettings(square, max_length, max_step, tol, rtol, sing_rate, max_steps, tip_tol, tableau, rolled)
    first, n = joints
    y, f, slope, h_control = lane["y"], lane["f"], lane["slope"], lane["h_control"]
    h_sing, h_len, h_lim = _event_steps(settings, y, f, slope, joints, lower, upper)
    max_h = _largest_step(settings, f[-1], slope, y.dtype)
    event, h_event, reached = _nearest_event(h_sing, h_len, h_lim, tol)
    if not square:
        event, reached = _stall(settings, f[-1], slope, h_len, h_lim, event, reached)
    fresh = lane["fresh"] if rolled else jnp.bool_(False)  # f and slope not evaluated yet
    reached = reached & ~fresh
    h = _step_size(settings, h_event, max_h, h_control, reached, fresh)
    y_new, slopes, auxes, f_new = _runge_kutta(settings, field, lane, h)
    accept, h_control = _error_control(settings, h, slopes, f_new, y, y_new, h_control, reached | fresh)
    count = lane["count"] + jnp.where(reached | fresh, 0, 1).astype(jnp.int32)
    new_lane = _advanced_lane(lane, accept & ~reached, h, y_new, f_new, count, h_control, auxes)
    if rolled:  # a fresh lane keeps y and takes f0 and the secant along the probe (unit joint rates)
        started = _started_lane(lane, y[first : first + n], y_new[first : first + n], f_new, slopes, auxes)
        new_lane = jax.tree_util.tree_map(lambda a, b: jnp.where(fresh, a, b), started, new_lane)
    finished = (reached | (count >= max_steps)) & ~fresh
    reason = jnp.where(reached, event, REASON_STEP_BUDGET)
    return new_lane, finished, reason


def _event_steps(settings: _LaneSettings, y, f, slope, joints, lower, upper):
    """Newton predictions of the step to each event, ``(h_sing, h_len, h_lim)`` (negative:
    step back after overshoot; inf: not ahead). The singular end is predicted from the
    secant ``slope`` of ds/dsigma, at half the distance for a one-sided approach."""
    first, n = joints
    inf = jnp.asarray(jnp.inf, y.dtype)
    approach = 1.0 if settings.square else 0.5
    rate = f[-1]
    approaching = slope < 0
    h_sing = jnp.where(approaching, approach * rate / -jnp.where(approaching, slope, -1.0), inf)
    h_len = jnp.where(rate > 0, (settings.max_length - y[-1]) / jnp.where(rate > 0, rate, 1.0), inf)
    dq, q = f[first : first + n], y[first : first + n]
    safe_dq = jnp.where(dq == 0, 1.0, dq)
    h_up = jnp.where(dq > 0, (upper - q) / safe_dq, inf)
    h_lo = jnp.where(dq < 0, (lower - q) / safe_dq, inf)
    h_lim = jnp.min(jnp.minimum(h_up, h_lo))
    return h_sing, h_len, h_lim


def _largest_step(settings: _LaneSettings, rate, slope, dtype):
    """``max_step``; for a one-sided approach (not square) also, while ds/dsigma recedes from
    zero, half the distance its secant predicts back to zero."""
    if settings.square:
        return settings.max_step
    approaching = slope < 0
    receding = 0.5 * rate / jnp.where(approaching, 1.0, jnp.maximum(slope, 1e-300))
    return jnp.minimum(settings.max_step, jnp.where(approaching, jnp.asarray(jnp.inf, dtype), receding))


def _nearest_event(h_sing, h_len, h_lim, tol):
    """The event predicted first (its reason), the step to it, and whether it is located to ``tol``."""
    candidates = jnp.stack([h_sing, h_len, h_lim])
    event = jnp.argmin(candidates).astype(jnp.int32)
    h_event = candidates[event]
    return event, h_event, jnp.abs(h_event) <= tol


def _stall(settings: _LaneSettings, rate, slope, h_len, h_lim, event, reached):
    """The stall of a redundant arm (see `step_lane`): a slow rate, or a flat one whose travel
    to the next limit is below ``tip_tol``, ends the path singular."""
    finite = jnp.isfinite(h_lim)
    span = jnp.where(finite, h_lim, 0.0)
    flat = finite & ((slope >= 0) | (rate > -slope * span)) & (span > settings.max_step) & (h_len > span)
    travel = span * (rate + 0.5 * slope * span)
    stalled = (rate <= settings.sing_rate) | (flat & (travel <= settings.tip_tol))
    event = jnp.where(stalled & ~reached, REASON_SINGULAR, event).astype(jnp.int32)
    return event, reached | stalled


def _step_size(settings: _LaneSettings, h_event, max_h, h_control, reached, fresh):
    """The step to attempt: to the nearest event, within ``max_h`` and the error controller's
    step (either sign); 0 once an event is located; `PROBE` on a fresh rolled lane."""
    h = jnp.minimum(h_event, max_h)
    if settings.tableau == "dop853":
        # The error controller's step bounds the event-limited step (either sign).
        h = jnp.clip(h, -h_control, h_control)
    h = jnp.where(reached, 0.0, h)
    if settings.rolled:
        # A fresh lane's step is the start's probe: with f = 0 and h = PROBE the second
        # stage is field(y) = f0 and the last field(y + PROBE * (sum of b_i k_i, i > 1)).
        h = jnp.where(fresh, PROBE, h)
    return h


def _runge_kutta(settings: _LaneSettings, field, lane: dict, h):
    """One Runge-Kutta step from the lane's y: ``(y_new, stage slopes, aux vectors or None, field(y_new))``."""
    y, f = lane["y"], lane["f"]
    if not settings.rolled:
        y_new, slopes = rk_step(field, y, h, settings.tableau, return_slopes=True, first_slope=f)
        return y_new, slopes, None, field(y_new)
    # field(y_new) as the loop's last stage: one copy of the field in the program.
    # With an aux vector: its value at y_new (last stage), at y for a fresh lane (second).
    stepped = rk_step(
        field, y, h, settings.tableau, True, rolled=True, first_slope=f, end_slope=True, aux=lane.get("aux")
    )
    y_new, slopes, auxes = stepped if "aux" in lane else (*stepped, None)
    return y_new, slopes, auxes, slopes[-1]


def _error_control(settings: _LaneSettings, h, slopes, f_new, y, y_new, h_control, hold):
    """DOP853's embedded error estimate: whether the step is accepted, and the controller's
    next step (kept where ``hold``: an event located or a fresh lane). RK4 accepts every step."""
    if settings.tableau != "dop853":
        return jnp.bool_(True), h_control
    error = error_norm(h, slopes, f_new, y, y_new, settings.rtol)
    accept = error <= 1.0
    factor = jnp.clip(0.9 * jnp.where(error > 0, error, 1e-30) ** (-1.0 / 8.0), 0.2, 10.0)
    limited = jnp.abs(h) < 0.999 * h_control
    grown = jnp.where(accept & limited, h_control, jnp.abs(h) * factor)
    return accept, jnp.where(hold, h_control, jnp.minimum(grown, settings.max_step))


def _advanced_lane(lane: dict, take, h, y_new, f_new, count, h_control, auxes) -> dict:
    """The lane after the attempt: y, f, the secant slope of ds/dsigma, the arc and the aux
    vector move where the step is taken."""
    y, f, slope = lane["y"], lane["f"], lane["slope"]
    slope_new = jnp.where(h != 0, (f_new[-1] - f[-1]) / jnp.where(h != 0, h, 1.0), slope)

    def keep(new, old):
        return jnp.where(take, new, old)

    new_lane = dict(
        lane,
        y=keep(y_new, y),
        f=keep(f_new, f),
        slope=keep(slope_new, slope),
        arc=lane["arc"] + jnp.where(take, h, 0.0),
        count=count,
        h_control=h_control,
    )
    if "aux" in lane:
        new_lane["aux"] = keep(auxes[-1], lane["aux"])
    return new_lane


def _started_lane(lane: dict, q, q_probe, f_new, slopes, auxes) -> dict:
    """A fresh rolled lane after its probe step: y kept, f0 (the second stage) and the secant
    of ds/dsigma along the probe from joints ``q`` to ``q_probe``."""
    f0 = slopes[1]
    probe = jnp.linalg.norm(q_probe - q)
    slope0 = (f_new[-1] - f0[-1]) / jnp.where(probe > 0, probe, 1.0)
    started = dict(lane, f=f0, slope=jnp.where(probe > 0, slope0, 0.0), fresh=jnp.bool_(False))
    if "aux" in lane:
        started["aux"] = auxes[1]
    return started


def run_queue(start, step, count: int, width: int, real) -> dict:
    """Integrate the first ``real`` of ``count`` (padded) paths on ``width`` lanes with refill.

    Args:
        start: ``indices (width,) -> lanes``: the start states of those paths (vectorized).
        step: ``(indices, lanes) -> (lanes, finished, reason)`` (vectorized `step_lane`).
        count: the padded batch size (static).
        width: the lanes (static, at most ``count``).
        real: the number of real paths (traced): the padding rows are never integrated
            and their results stay zero.

    Returns:
        ``{"y": (count, m), "arc": (count,), "count": (count,), "reason": (count,)}``, and
        ``"aux": (count, p)`` where the lanes keep an aux vector (`start_lane`).
    """
    index0 = jnp.arange(width, dtype=jnp.int32)
    lanes0 = start(index0)
    y0 = lanes0["y"]
    results0 = {
        "y": jnp.zeros((count,) + y0.shape[1:], y0.dtype),
        "arc": jnp.zeros((count,), y0.dtype),
        "count": jnp.zeros((count,), jnp.int32),
        "reason": jnp.zeros((count,), jnp.int32),
    }
    if "aux" in lanes0:
        results0["aux"] = jnp.zeros((count,) + lanes0["aux"].shape[1:], y0.dtype)
    state0 = (lanes0, index0, index0 < real, jnp.int32(width), results0)

    def cond(state):
        return jnp.any(state[2])

    def body(state):
        lane, index, active, next_index, results = state
        lane, finished, reason = step(index, lane)
        finished = finished & active
        target = jnp.where(finished, index, count)  # out of range: dropped
        written = {"y": lane["y"], "arc": lane["arc"], "count": lane["count"], "reason": reason}
        if "aux" in lane:
            written["aux"] = lane["aux"]
        results = {k: results[k].at[target].set(written[k], mode="drop") for k in results}
        rank = jnp.cumsum(finished.astype(jnp.int32)) - 1
        refill = finished & (next_index + rank < real)
        index = jnp.where(refill, next_index + rank, index)

        def refilled():  # an unrolled start costs two field evaluations: only when a lane takes a path
            fresh = start(index)
            return jax.tree_util.tree_map(
                lambda new, old: jnp.where(refill.reshape((-1,) + (1,) * (old.ndim - 1)), new, old), fresh, lane
            )

        lane = jax.lax.cond(jnp.any(refill), refilled, lambda: lane)
        active = jnp.where(finished, refill, active)
        next_index = next_index + jnp.sum(finished, dtype=jnp.int32)
        return lane, index, active, next_index, results

    return jax.lax.while_loop(cond, body, state0)[-1]
