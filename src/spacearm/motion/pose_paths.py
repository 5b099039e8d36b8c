"""Straight pose paths: the tip along a line and its axes along a geodesic, at zero momentum.

The tip frame moves from its pose (p0, T0) to a target (p1, T1), both in inertial axes
(p about the system centroid, T the tip axes): p(s) = p0 + s (p1 - p0) and
T(s) = T0 exp(s [xi]x), xi = log(T0^T T1) (the SO(3) geodesic), s in [0, 1]. Its twist
per unit s is constant in inertial axes: [v; w] = [p1 - p0; T0 xi]. J* (the tip twist
[v; w] per joint rate at zero momentum, Umetani & Yoshida 1990, eq. 6, in 3-D) is
given in bus axes by the robot family, and the bus turns as the arm moves, so the
inertial tip twist is blkdiag(R, R) J*(q) q' and the joints and the bus attitude R are
integrated together:

    q' = J*(q)^+ blkdiag(R, R)^T [v; w],   R' = R [C_w(q) q']x,

with J*^+ = J*^-1 for n = 6 and the minimum-norm J*^T (J* J*^T)^-1 for n > 6 (C_w the
bus angular velocity per joint rate, bus axes). The integrator takes ``steps`` fixed
DOP853 steps of 1/steps in s (`spacearm.motion.dop853.rk_step`: 12 field evaluations
per step and a 13th at its end, whose pass over the chain also gives the check below;
the stages run in a loop, one copy of the field in the program). Away from singular
postures the field is smooth, and the 8th-order steps put the end on the target to
~1e-15 m and rad on a UR5 for a 0.2 m, 37 deg move already with 32 steps (default 128;
tests/test_pose_paths.py); the end pose error is returned so a caller can check.

After each step the path stops BEFORE a posture where the smallest singular value of
J* falls below ``sing_threshold`` (the tip twist can no longer be commanded: a
kinematic or dynamic singularity), where the step is not finite, or where a joint is
past its limit. The event is then located inside that step by bisection on the step's
length (`EVENT_BISECTIONS` halvings, keeping the side before the event, in the same
loop as the steps: one copy of the step in the program), so the end lies on the limit,
or at the threshold, to 2^-40 of a step (tests/test_pose_paths.py: joint 1 on its limit
to 1e-10 rad). The reasons are those of the straight tip paths
(`spacearm.motion.path_ends`): ``REASON_MAX_LENGTH`` means the target was reached (s = 1).

Everything the family provides goes through the seam
(`spacearm.models.family.RobotFamily.pose_maps` and ``tip_frame``), so any family
whose J* for the chosen tip is ``(6, n)`` with an SO(3) attitude plugs in.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from .._core.groups import SO3, expm, geodesic_distance, log
from ..models.family import RobotFamily, family_of
from .dop853 import rk_step
from .path_ends import REASON_JOINT_LIMIT, REASON_MAX_LENGTH, REASON_SINGULAR

__all__ = [
    "DEFAULT_POSE_STEPS",
    "EVENT_BISECTIONS",
    "POSE_REASONS",
    "PoseHistory",
    "PosePath",
    "check_pose_robot",
    "pose_on_path",
    "straight_pose_path",
]

DEFAULT_POSE_STEPS = 128
EVENT_BISECTIONS = 40  # an event is located to 2^-40 of a step in s
STEPPING, LOCATING, DONE = 0, 1, 2  # the integrator's modes
POSE_REASONS = {REASON_SINGULAR: "singular", REASON_MAX_LENGTH: "reached", REASON_JOINT_LIMIT: "joint limit"}


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class PoseHistory:
    """The states of a straight pose path at s = k / steps, k = 0..steps (after an early
    end, the later rows repeat the located end).

    Attributes:
        progress: ``(steps+1,)`` s of each row.
        joints: ``(steps+1, n)`` joint positions.
        base_rotation: ``(steps+1, 3, 3)`` bus attitude (bus axes -> inertial axes).
        tip: ``(steps+1, 3)`` tip origin, inertial axes, about the system centroid, m.
        tip_rotation: ``(steps+1, 3, 3)`` tip axes in inertial axes.
    """

    progress: jax.Array
    joints: jax.Array
    base_rotation: jax.Array
    tip: jax.Array
    tip_rotation: jax.Array


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class PosePath:
    """The end of a straight pose path (see `straight_pose_path`).

    Attributes:
        end_joints: ``(n,)`` joints where the path ended.
        end_rotation: ``(3, 3)`` bus attitude there (bus axes -> inertial axes).
        end_tip: ``(3,)`` tip origin there, inertial axes, about the system centroid, m.
        end_tip_rotation: ``(3, 3)`` tip axes there, inertial axes.
        progress: ``()`` s at the end (1 when reached; an event located inside its step).
        reason: ``()`` int32: 1 (``REASON_MAX_LENGTH``) reached the target, 0 singular
            (sigma_min of J* below the threshold next), 2 a joint limit next.
        limit_joint: ``()`` int32 index of the first joint past its limit (-1 if none).
        position_error: ``()`` |end_tip - target position|, m.
        rotation_error: ``()`` geodesic angle between the end tip axes and the target, rad.
        min_singular: ``()`` the smallest sigma_min of J* over the steps and the end.
        history: a `PoseHistory`, or None when not asked for.
    """

    end_joints: jax.Array
    end_rotation: jax.Array
    end_tip: jax.Array
    end_tip_rotation: jax.Array
    progress: jax.Array
    reason: jax.Array
    limit_joint: jax.Array
    position_error: jax.Array
    rotation_error: jax.Array
    min_singular: jax.Array
    history: PoseHistory | None

    @property
    def reached(self) -> bool:
        """Whether the path got to the target (s = 1)."""
        return bool(np.asarray(self.reason) == REASON_MAX_LENGTH)

    @property
    def outcome(self) -> str:
        """``"reached"``, ``"singular"`` or ``"joint limit"``."""
        return POSE_REASONS[int(np.asarray(self.reason))]


def check_pose_robot(robot, what: str = "straight_pose_path") -> None:
    """Refuse a robot whose tip pose cannot be commanded: the family needs a 6-row J*
    (position and orientation) on an SO(3) attitude, and at least 6 moving joints on the
    tip's own path from the base (a tree's other arms move its tip only through the bus).

    Raises:
        ConfigError: naming the family or the joint count and what to use instead.
    """
    family = family_of(robot)
    if family.task_rows != 6 or family.attitude is not SO3:
        raise ConfigError(
            f"{what}: pose targets need a spatial arm (a 6-row J*: tip position and orientation); "
            f"a {family.name} robot's tip has {family.translational_rows} translational rows and no orientation "
            "to aim; give a target point only"
        )
    if family.tip_count(robot) is not None:
        raise ConfigError(
            f"{what}: a robot with {family.tip_count(robot)} tips; choose the tip to aim with robot.focus(tip=...)"
        )
    n = int(np.sum(family.moving_joints(robot)))  # a focused tree's held joints do not count
    if n < 6:
        raise ConfigError(
            f"{what}: pose targets need at least 6 joints to set the tip's position and orientation; "
            f"the arm has {n}{' moving' if n < family.joint_count(robot) else ''}; give a target point only"
        )
    own = int(np.sum(family.tip_joints(robot)))
    if own < 6:
        raise ConfigError(
            f"{what}: pose targets need at least 6 joints to set the tip's position and orientation; "
            f"the tip's path from the bus has {own} moving (the other arms move it only through the bus, "
            "at impractical rates); give a target point only"
        )


def _joint_rates(J, twist):
    """J^-1 twist for a square J, the minimum-norm J^T (J J^T)^-1 twist for a redundant arm."""
    if J.shape[1] == J.shape[0]:
        return jnp.linalg.solve(J, twist)
    return J.T @ jnp.linalg.solve(J @ J.T, twist)


def _pose_field(family, robot, twist_inertial):
    """y' = f(y), y = [joints, bus attitude coordinates], for the constant inertial tip
    twist, and ``(1,)`` sigma_min of J* at y from the same pass."""
    group = family.attitude

    def field(y):
        joints, coords = family.split_state(robot, y)
        J, A = family.pose_maps(robot, joints)
        R = group.coords_matrix(coords)
        twist = jnp.concatenate([R.T @ twist_inertial[:3], R.T @ twist_inertial[3:]])
        dq = _joint_rates(J, twist)
        sigma = jnp.linalg.svd(J, compute_uv=False)[-1]
        return family.join_state(robot, dq, group.rate(coords, A @ dq)), sigma[None]

    return field


def _inertial_frame(family, robot, joints, R):
    p, T = family.tip_frame(robot, joints)
    return R @ p, R @ T


class _Stepper(NamedTuple):
    """What every step of one pose path needs (built in `_pose_path`)."""

    family: RobotFamily
    robot: Any
    field: Callable  # `_pose_field`
    h: jax.Array  # a full step in s: 1 / steps
    lower: jax.Array  # (n,) joint limits
    upper: jax.Array
    sing_threshold: jax.Array
    steps: int  # static


def _step(stepper: _Stepper, y, h):
    """The next state, and sigma_min of J* at the step's start (the first stage) and at
    its end (a 13th stage evaluates the field there inside the stage loop): one copy
    of the pass over the chain."""
    y_new, sigmas = rk_step(stepper.field, y, h, rolled=True, end_slope=True, aux=jnp.zeros((1,), stepper.h.dtype))
    return y_new, sigmas[0, 0], sigmas[-1, 0]


def _check(stepper: _Stepper, y, sigma):
    """(sigma_min of J*, singular, past a limit, the joints past a limit) at a state."""
    joints, _ = stepper.family.split_state(stepper.robot, y)
    outside = (joints < stepper.lower) | (joints > stepper.upper)
    singular = ~jnp.all(jnp.isfinite(y)) | ~(sigma >= stepper.sing_threshold)
    return sigma, singular, jnp.any(outside) & ~singular, outside


def _next_mode(locating, ok, k, halvings, steps: int):
    """STEPPING until an event or the last step, then LOCATING for `EVENT_BISECTIONS` halvings, then DONE."""
    return jnp.where(
        locating,
        jnp.where(halvings >= EVENT_BISECTIONS, DONE, LOCATING),
        jnp.where(ok, jnp.where(k >= steps, DONE, STEPPING), LOCATING),
    )


def _start_state(y0, dtype) -> dict:
    """The scan's state at s = 0."""
    return dict(
        y=y0,
        y_low=y0,
        mode=jnp.asarray(STEPPING),
        k=jnp.asarray(0),
        reason=jnp.asarray(REASON_MAX_LENGTH, jnp.int32),
        limit_joint=jnp.asarray(-1, jnp.int32),
        low=jnp.zeros((), dtype),
        high=jnp.ones((), dtype),
        halvings=jnp.asarray(0),
        min_sigma=jnp.asarray(jnp.inf, dtype),
    )


def _advance(stepper: _Stepper, state: dict) -> dict:
    """A full step while no event; after one, a halving of the rejected step's fraction,
    keeping the side before the event (``low``: the last fraction before it)."""
    y, mode = state["y"], state["mode"]
    locating = mode == LOCATING
    middle = 0.5 * (state["low"] + state["high"])
    y_try, sigma_start, sigma_try = _step(stepper, y, jnp.where(locating, middle, 1.0) * stepper.h)
    sigma, singular, limit, outside = _check(stepper, y_try, sigma_try)
    ok = ~(singular | limit)
    k = state["k"] + jnp.where(~locating & ok, 1, 0)
    event = ~locating & ~ok
    low = jnp.where(locating & ok, middle, state["low"])
    halvings = state["halvings"] + jnp.where(locating, 1, 0)
    return dict(
        y=jnp.where(~locating & ok, y_try, y),
        y_low=jnp.where(locating & ok, y_try, jnp.where(event, y, state["y_low"])),
        mode=_next_mode(locating, ok, k, halvings, stepper.steps),
        k=k,
        reason=jnp.where(event, jnp.where(singular, REASON_SINGULAR, REASON_JOINT_LIMIT), state["reason"]),
        limit_joint=jnp.where(event & limit, jnp.argmax(outside).astype(jnp.int32), state["limit_joint"]),
        low=low,
        high=jnp.where(locating & ~ok, middle, state["high"]),
        halvings=halvings,
        # The current state's sigma (the start's at the first step), and the new one's.
        min_sigma=jnp.minimum(jnp.minimum(state["min_sigma"], sigma_start), jnp.where(ok, sigma, state["min_sigma"])),
    )


def _scan_body(stepper: _Stepper, state: dict, _):
    state = jax.lax.cond(state["mode"] == DONE, lambda state: state, functools.partial(_advance, stepper), state)
    return state, state["y"]


def _pose_history(family, robot, y0, end: dict, outputs, steps: int, dtype) -> tuple[PoseHistory, jax.Array]:
    """The history (`PoseHistory`: the scan's full steps, then the located end), and the
    progress s at the end."""
    k_end, reason = end["k"], end["reason"]
    stopped = reason != REASON_MAX_LENGTH
    y = jnp.where(stopped, end["y_low"], end["y"])
    progress = (k_end.astype(dtype) + jnp.where(stopped, end["low"], jnp.zeros((), dtype))) / steps
    rows = jnp.arange(steps + 1)
    ys = jnp.concatenate([y0[None], outputs[:steps]], axis=0)
    ys = jnp.where((rows > k_end)[:, None], y, ys)  # after the end: the located end

    def frame(y):
        joints, coords = family.split_state(robot, y)
        R = family.attitude.from_coords(coords)
        p, T = _inertial_frame(family, robot, joints, R)
        return joints, R, p, T

    joints, R, p, T = jax.vmap(frame)(ys)
    history = PoseHistory(
        progress=jnp.where(rows > k_end, progress, rows.astype(dtype) / steps),
        joints=joints,
        base_rotation=R,
        tip=p,
        tip_rotation=T,
    )
    return history, progress


@functools.partial(jax.jit, static_argnames=("steps",))
def _pose_path(robot, q0, R0, target_position, target_rotation, sing_threshold, steps):
    """One straight pose path and its history (module docstring); one program per shape and ``steps``."""
    family = family_of(robot)
    n = family.joint_count(robot)
    dtype = q0.dtype
    lower = jnp.broadcast_to(robot.joint_lower, (n,)).astype(dtype)
    upper = jnp.broadcast_to(robot.joint_upper, (n,)).astype(dtype)
    p0, T0 = _inertial_frame(family, robot, q0, R0)
    xi = log(T0.T @ target_rotation)
    twist = jnp.concatenate([target_position - p0, T0 @ xi])
    field = _pose_field(family, robot, twist)
    stepper = _Stepper(family, robot, field, jnp.asarray(1.0 / steps, dtype), lower, upper, sing_threshold, steps)
    y0 = family.join_state(robot, q0, family.attitude.to_coords(R0))
    # One scan, one copy of the step in the program: full steps while no event; after
    # one, bisection on the rejected step's fraction, keeping the side before the event.
    # Every step before an event is accepted, so output i is the state at s = (i + 1) / steps.
    body = functools.partial(_scan_body, stepper)
    end, outputs = jax.lax.scan(body, _start_state(y0, dtype), None, length=steps + EVENT_BISECTIONS)
    history, progress = _pose_history(family, robot, y0, end, outputs, steps, dtype)
    # The last row is the end (rows after the end hold it): its frame is the history's.
    q_end, R_end = history.joints[-1], history.base_rotation[-1]
    p_end, T_end = history.tip[-1], history.tip_rotation[-1]
    return PosePath(
        end_joints=q_end,
        end_rotation=R_end,
        end_tip=p_end,
        end_tip_rotation=T_end,
        progress=progress,
        reason=end["reason"],
        limit_joint=end["limit_joint"],
        position_error=jnp.linalg.norm(p_end - target_position),
        rotation_error=geodesic_distance(T_end, target_rotation),
        min_singular=end["min_sigma"],
        history=history,
    )


def _rotation(value, name: str) -> np.ndarray:
    R = np.asarray(value, float)
    if (
        R.shape != (3, 3)
        or not np.all(np.isfinite(R))
        or np.max(np.abs(R.T @ R - np.eye(3))) > 1e-9
        or np.linalg.det(R) < 0
    ):
        raise ConfigError(f"{name}: expected a (3, 3) rotation matrix")
    return R


def straight_pose_path(
    robot,
    q_start,
    target_position,
    target_rotation,
    *,
    base_rotation=None,
    steps: int = DEFAULT_POSE_STEPS,
    sing_threshold: float = 1e-3,
    history: bool = False,
) -> PosePath:
    """Move the tip frame straight to a target pose: position on a line, axes on the geodesic.

    Joint rates invert the whole 6 x n J* (minimum-norm for n > 6), the bus attitude
    is integrated with them (zero momentum: the inertial tip twist is
    blkdiag(R, R) J*(q) q'), and the path stops before a singular posture or a joint
    limit (module docstring). One design, one path; compiled once per shape and ``steps``.

    Args:
        robot: one design whose family has a 6-row J* and an SO(3) attitude (spatial
            arms), with at least 6 joints.
        q_start: ``(n,)`` joints at the start (rad; m for prismatic joints).
        target_position: ``(3,)`` target tip origin, inertial axes, about the system centroid, m.
        target_rotation: ``(3, 3)`` target tip axes in inertial axes.
        base_rotation: ``(3, 3)`` bus attitude at the start (default identity).
        steps: fixed DOP853 steps over s in [0, 1] (static; default 128).
        sing_threshold: the path stops before sigma_min(J*) falls below this (m/rad and
            rad/rad rows mixed, as J* is).
        history: also return the states at every step (`PoseHistory`).

    Returns:
        `PosePath`.

    Raises:
        ConfigError: a robot whose tip pose cannot be commanded (`check_pose_robot`),
            bad shapes, a start outside the joint limits, or not a rotation.
    """
    check_pose_robot(robot)
    family = family_of(robot)
    if robot.batch_shape:
        raise ConfigError("robot: one design at a time (got a batch of designs)")
    n = family.joint_count(robot)
    q0 = np.asarray(q_start, float)
    if q0.shape != (n,) or not np.all(np.isfinite(q0)):
        raise ConfigError(f"q_start: expected {n} finite joint positions, got shape {q0.shape}")
    lower = np.broadcast_to(np.asarray(robot.joint_lower, float), (n,))
    upper = np.broadcast_to(np.asarray(robot.joint_upper, float), (n,))
    outside = (q0 < lower) | (q0 > upper)
    if np.any(outside):
        j = int(np.argmax(outside))
        raise ConfigError(
            f"q_start: joint {j + 1} = {q0[j]:.6g} is outside its limits [{lower[j]:.6g}, {upper[j]:.6g}]"
            f" ({robot.joint_names[j]})"
        )
    p1 = np.asarray(target_position, float)
    if p1.shape != (3,) or not np.all(np.isfinite(p1)):
        raise ConfigError(f"target_position: expected three finite numbers (x, y, z) in m, got shape {p1.shape}")
    T1 = _rotation(target_rotation, "target_rotation")
    R0 = np.eye(3) if base_rotation is None else _rotation(base_rotation, "base_rotation")
    if int(steps) < 1:
        raise ConfigError(f"steps: expected a positive number of steps, got {steps!r}")
    if not float(sing_threshold) >= 0:
        raise ConfigError(f"sing_threshold: expected a non-negative number, got {sing_threshold!r}")
    dtype = jnp.result_type(float)
    path = _pose_path(  # NumPy inputs: no eager conversion programs before the path's own
        robot,
        np.asarray(q0, dtype),
        np.asarray(R0, dtype),
        np.asarray(p1, dtype),
        np.asarray(T1, dtype),
        np.asarray(sing_threshold, dtype),
        int(steps),
    )
    return path if history else dataclasses.replace(path, history=None)


# The geodesic the path follows, for checks and plots.
def pose_on_path(start_position, start_rotation, target_position, target_rotation, s):
    """The tip pose of the straight pose path at progress ``s (...)``: ``(p (..., 3), T (..., 3, 3))``."""
    s = jnp.asarray(s)
    p0, T0 = jnp.asarray(start_position), jnp.asarray(start_rotation)
    xi = log(T0.T @ jnp.asarray(target_rotation))
    p = p0 + s[..., None] * (jnp.asarray(target_position) - p0)
    return p, T0 @ expm(s[..., None] * xi)
