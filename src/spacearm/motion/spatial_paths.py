"""Straight tip paths and go-and-back motions of a spatial arm on a free-floating bus.

The tip translates along a fixed inertial direction d (its orientation is free). The
translational Generalized Jacobian in inertial axes is R J*_v(q) (J*_v in bus axes),
so the joint rates depend on the bus attitude and the bus attitude on
the joint rates: the state (q, R) is integrated together,

    q' = regularized rates of J*_v(q) for the bus-frame direction R^T d,
    R' = R [C_w(q) q']x,
    s' = tip speed along d,

with respect to the joint-space arc length sigma. The rates are
`spacearm.kinematics.straight_path_rates`, written once for every family: for
n = 3 the adjugate form sgn0 adj(J*_v) R^T d / |adj(J*_v) R^T d| (finite through
det J*_v = 0), for n > 3 the minimum-norm rates J*_v^T (J*_v J*_v^T)^-1 R^T d,
regularized with adj(J*_v J*_v^T). The path ends where ds/dsigma = 0: the tip can no
longer advance along the line, the translational part of J* has lost rank (a dynamic
singularity; Papadopoulos & Dubowsky 1993), or at a joint limit, or after
``max_length``. As for planar arms (`straight_paths`), the scheme is DOP853
with its embedded error control in a ``lax.while_loop``, the events located by Newton
predictions on the event functions; the 9 entries of R are integrated as a vector
and projected back onto SO(3) (polar factor) at the end, a correction at the level of
the tolerance.

Written for one path and ``vmap``-ed over paths and designs inside one ``jit``.
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from ..kinematics import square_determinant, straight_path_rates
from ..models.spatial import primitives
from .._core.linalg import gram_root_determinant
from ..models.spatial.robot import SpatialRobot
from .dop853 import error_norm, rk_step
from .attitude import hat
from .batching import flatten_batch, is_traced
from .path_ends import REASON_SINGULAR, REASON_STEP_BUDGET

__all__ = ["SpatialStraightPath", "spatial_straight_tip_path", "spatial_go_and_back", "polar_rotation"]


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class SpatialStraightPath:
    """The end of a straight inertial tip path of a spatial arm.

    Attributes:
        end_joints: ``(..., n)`` joints where the path ended.
        end_rotation: ``(..., 3, 3)`` bus attitude there (bus axes -> inertial axes).
        end_tip: ``(..., 3)`` tip there, inertial axes, about the system centroid, m.
        length: ``(...)`` distance the tip travelled along the line, m.
        reason: ``(...)`` int32: 0 = J*_v lost rank (dynamic or kinematic singularity),
            1 = max_length reached, 2 = joint limit, 3 = step budget exhausted.
        fixed_manipulability: ``(...)`` the fixed-base w = sqrt det(J_v J_v^T) at the end
            (m^3): near 0 when the singular end is also a kinematic singularity.
        joint_arc: ``(...)`` joint-space arc length, rad (the integration variable).
        steps: ``(...)`` int32 accepted and rejected steps.
    """

    end_joints: jax.Array
    end_rotation: jax.Array
    end_tip: jax.Array
    length: jax.Array
    reason: jax.Array
    fixed_manipulability: jax.Array
    joint_arc: jax.Array
    steps: jax.Array


def polar_rotation(M: jax.Array) -> jax.Array:
    """The rotation nearest to a ``(..., 3, 3)`` matrix close to one (polar factor by SVD)."""
    u, _, vt = jnp.linalg.svd(M)
    return u @ vt


def _field(robot: SpatialRobot, direction, sign0):
    """y = [q (n), R (9, row-major), s] -> dy/dsigma."""
    n = robot.n_joints

    def field(y):
        q, R = y[:n], y[n : n + 9].reshape(3, 3)
        J = primitives.generalized_jacobian(robot, q)[:3]  # bus axes
        dq, ds = straight_path_rates(J, R.T @ direction, sign0)
        w = primitives.base_twist_map(robot, q)[3:] @ dq
        return jnp.concatenate([dq, (R @ hat(w)).reshape(9), ds[None]])

    return field


def _start(robot, q0, R0, direction, max_step):
    n = robot.n_joints
    dtype = q0.dtype
    direction = direction / jnp.linalg.norm(direction)
    if n == 3:
        J = primitives.generalized_jacobian(robot, q0)[:3]
        sign0 = jnp.where(square_determinant(J) < 0, -1.0, 1.0).astype(dtype)
    else:
        sign0 = jnp.asarray(1.0, dtype)
    field = _field(robot, direction, sign0)
    y0 = jnp.concatenate([q0, R0.reshape(9), jnp.zeros((1,), dtype)])
    f0 = field(y0)
    probe = 1e-7
    slope0 = (field(y0 + probe * f0)[-1] - f0[-1]) / probe
    return {
        "y": y0, "f": f0, "slope": slope0, "arc": jnp.zeros((), dtype), "count": jnp.int32(0),
        "h_control": jnp.asarray(max_step, dtype), "direction": direction, "sign0": sign0,
        "done": jnp.bool_(False), "reason": jnp.int32(REASON_STEP_BUDGET),
    }


def _step(robot, lane, max_length, max_step, tol, rtol, sing_rate, max_steps):
    """One attempted DOP853 step with event prediction (the planar scheme of .straight_paths)."""
    n = robot.n_joints
    y, f, slope, h_control = lane["y"], lane["f"], lane["slope"], lane["h_control"]
    dtype = y.dtype
    field = _field(robot, lane["direction"], lane["sign0"])
    lower = jnp.asarray(robot.joint_lower, dtype)
    upper = jnp.asarray(robot.joint_upper, dtype)
    inf = jnp.asarray(jnp.inf, dtype)
    # Square J*_v: ds/dsigma changes sign smoothly at the fold. Redundant: a one-sided
    # approach where the field turns on the scale of the distance to the singularity.
    approach = 1.0 if n == 3 else 0.5
    rate = f[-1]
    approaching = slope < 0
    h_sing = jnp.where(approaching, approach * rate / -jnp.where(approaching, slope, -1.0), inf)
    h_len = jnp.where(rate > 0, (max_length - y[-1]) / jnp.where(rate > 0, rate, 1.0), inf)
    dq, q = f[:n], y[:n]
    safe_dq = jnp.where(dq == 0, 1.0, dq)
    h_up = jnp.where(dq > 0, (upper - q) / safe_dq, inf)
    h_lo = jnp.where(dq < 0, (lower - q) / safe_dq, inf)
    h_lim = jnp.min(jnp.minimum(h_up, h_lo))
    max_h = max_step
    if n > 3:
        receding = approach * rate / jnp.where(approaching, 1.0, jnp.maximum(slope, 1e-300))
        max_h = jnp.minimum(max_step, jnp.where(approaching, inf, receding))
    candidates = jnp.stack([h_sing, h_len, h_lim])
    event = jnp.argmin(candidates).astype(jnp.int32)
    h_event = candidates[event]
    reached = jnp.abs(h_event) <= tol
    # A redundant arm may approach rank loss asymptotically (ds/dsigma decaying like a
    # geometric sequence under the halving steps): end there once the tip has stopped.
    stalled = (n > 3) & (rate <= sing_rate)
    event = jnp.where(stalled & ~reached, REASON_SINGULAR, event).astype(jnp.int32)
    reached = reached | stalled
    h = jnp.clip(jnp.minimum(h_event, max_h), -h_control, h_control)
    h = jnp.where(reached, 0.0, h)
    y_new, slopes = rk_step(field, y, h, "dop853", return_slopes=True)
    f_new = field(y_new)
    error = error_norm(h, slopes, f_new, y, y_new, rtol)
    accept = error <= 1.0
    factor = jnp.clip(0.9 * jnp.where(error > 0, error, 1e-30) ** (-1.0 / 8.0), 0.2, 10.0)
    limited = jnp.abs(h) < 0.999 * h_control
    grown = jnp.where(accept & limited, h_control, jnp.abs(h) * factor)
    h_control = jnp.where(reached, h_control, jnp.minimum(grown, max_step))
    take = accept & ~reached & ~lane["done"]
    slope_new = jnp.where(h != 0, (f_new[-1] - f[-1]) / jnp.where(h != 0, h, 1.0), slope)
    keep = lambda new, old: jnp.where(take, new, old)  # noqa: E731
    count = lane["count"] + jnp.where(reached | lane["done"], 0, 1).astype(jnp.int32)
    finished = reached | (count >= max_steps)
    return dict(
        lane,
        y=keep(y_new, y), f=keep(f_new, f), slope=keep(slope_new, slope),
        arc=lane["arc"] + jnp.where(take, h, 0.0), count=count,
        h_control=jnp.where(lane["done"], lane["h_control"], h_control),
        done=lane["done"] | finished,
        reason=jnp.where(lane["done"], lane["reason"], jnp.where(reached, event, REASON_STEP_BUDGET)),
    )


def _one_path(robot, q0, R0, direction, max_length, max_step, tol, rtol, sing_rate, max_steps):
    n = robot.n_joints
    lane = _start(robot, q0, R0, direction, max_step)
    lane = jax.lax.while_loop(
        lambda lane: ~lane["done"],
        lambda lane: _step(robot, lane, max_length, max_step, tol, rtol, sing_rate, max_steps),
        lane,
    )
    y = lane["y"]
    q, R = y[:n], polar_rotation(y[n : n + 9].reshape(3, 3))
    fixed = primitives.fixed_base_jacobian(robot, q)[:3]
    return SpatialStraightPath(
        end_joints=q,
        end_rotation=R,
        end_tip=R @ primitives.tip(robot, q),
        length=y[-1],
        reason=lane["reason"],
        fixed_manipulability=gram_root_determinant(fixed),
        joint_arc=lane["arc"],
        steps=lane["count"],
    )


@functools.partial(jax.jit, static_argnames=("robot_batched", "max_steps"))
def _straight_flat(robot, q0, R0, direction, max_length, max_step, tol, rtol, sing_rate, robot_batched, max_steps):
    one = functools.partial(_one_path, max_steps=max_steps)
    return jax.vmap(one, in_axes=(0 if robot_batched else None, 0, 0, 0, 0, None, None, None, None))(
        robot, q0, R0, direction, max_length, max_step, tol, rtol, sing_rate
    )


def spatial_straight_tip_path(
    robot: SpatialRobot,
    q_start: jax.Array,
    direction: jax.Array,
    max_length: jax.Array | float | None = None,
    *,
    base_rotation: jax.Array | None = None,
    max_step: float = 0.1,
    tol: float = 1e-11,
    rtol: float = 1e-12,
    sing_rate: float = 1e-6,
    max_steps: int = 4000,
) -> SpatialStraightPath:
    """Move the tip along a straight inertial line until J*_v loses rank (or a limit).

    Args:
        robot: a spatial design, or a batch broadcasting with the paths.
        q_start: ``(..., n)`` joints at the start (n >= 3).
        direction: ``(..., 3)`` direction of the tip motion, inertial axes (normalized here).
        max_length: ``(...)`` longest tip travel, m (default: until an event).
        base_rotation: ``(..., 3, 3)`` bus attitude at the start (default identity).
        max_step: largest step in joint arc length, rad.
        tol: the events are located to this joint arc length, rad.
        rtol: DOP853 relative tolerance.
        sing_rate: for n > 3, the path also ends (singular) once the tip advances less
            than this per radian of joint motion, m/rad (the minimum-norm flow of a
            redundant arm may approach rank loss only asymptotically; some UR5 paths
            still spend the step budget on that approach, reason 3).
        max_steps: step budget per path (static).

    Returns:
        `SpatialStraightPath` with the batch shape.
    """
    n = robot.n_joints
    if n < 3:
        raise ConfigError(f"straight tip paths in 3-D need at least 3 joints, the arm has {n}")
    dtype = jnp.result_type(float)
    q_start = jnp.asarray(q_start, dtype)
    direction = jnp.asarray(direction, dtype)
    R0 = jnp.eye(3, dtype=dtype) if base_rotation is None else jnp.asarray(base_rotation, dtype)
    if q_start.ndim < 1 or q_start.shape[-1] != n:
        raise ConfigError(f"q_start: expected shape (..., {n}), got {q_start.shape}")
    if direction.ndim < 1 or direction.shape[-1] != 3:
        raise ConfigError(f"direction: expected shape (..., 3), got {direction.shape}")
    if not is_traced(direction) and np.any(np.linalg.norm(np.asarray(direction), axis=-1) == 0):
        raise ConfigError("direction: must be a nonzero vector")
    max_length = jnp.asarray(jnp.inf if max_length is None else max_length, dtype)
    batch, flat_robot, batched, (q_flat, R_flat, d_flat, L_flat) = flatten_batch(
        robot, [(q_start, 1), (R0, 2), (direction, 1), (max_length, 0)]
    )
    out = _straight_flat(flat_robot, q_flat, R_flat, d_flat, L_flat, max_step, tol, rtol, sing_rate, batched, int(max_steps))
    return jax.tree_util.tree_map(lambda x: x.reshape(batch + x.shape[1:]), out)


def spatial_go_and_back(
    robot: SpatialRobot,
    q_start: jax.Array,
    direction: jax.Array,
    length: jax.Array | float,
    *,
    base_rotation: jax.Array | None = None,
    **options,
) -> tuple[SpatialStraightPath, SpatialStraightPath]:
    """The tip out along ``direction`` by ``length`` and straight back (Fig. 9 in 3-D).

    The field of the straight path is odd in the direction (the regularized rates of
    `spacearm.kinematics.straight_path_rates` and the bus rate both change sign
    with d), so away from singular ends the way back retraces the way out: joints and
    bus attitude return to the start up to the integration tolerance. Where the way out
    ends at a singularity (``out.reason == 0``) the way back may leave on another branch.

    Returns:
        ``(out, back)``: the two `SpatialStraightPath`; ``back.length`` equals
        ``out.length`` unless the way back met an event first.
    """
    out = spatial_straight_tip_path(robot, q_start, direction, length, base_rotation=base_rotation, **options)
    back = spatial_straight_tip_path(
        robot, out.end_joints, -jnp.asarray(direction), out.length, base_rotation=out.end_rotation, **options
    )
    return out, back
