"""Reaching a pose: the tip frame to a target position and orientation by one straight pose path.

The position part is checked first against the family's tip shell (a point no posture
and no bus attitude reaches is refused before any integration, as `plan_reach` does);
then the straight pose path of `spacearm.motion.pose_paths` runs from the start: the
tip origin along the line, the tip axes along the SO(3) geodesic, the joints through
the whole J* and the bus attitude integrated with them. There is no reorientation
fallback: a path that stops before a singular posture or a joint limit is reported
as a `ConfigError` naming where and why it stopped.
"""

from __future__ import annotations

import dataclasses

import jax
import numpy as np

from .._core.errors import ConfigError
from ..motion.path_ends import REASON_JOINT_LIMIT, REASON_SINGULAR
from ..motion.pose_paths import DEFAULT_POSE_STEPS, check_pose_robot, straight_pose_path
from ._reach_steps import PHASE_STRAIGHT
from .reach import check_in_shell

__all__ = ["MODE_POSE", "PoseReachPlan", "plan_pose_reach"]

MODE_POSE = "pose"


@dataclasses.dataclass(frozen=True)
class PoseReachPlan:
    """A plan that brings the tip frame to a target pose (see `plan_pose_reach`).

    Attributes:
        mode: ``"pose"``.
        target: ``(3,)`` target tip origin, inertial axes, about the system centroid, m.
        target_rotation: ``(3, 3)`` target tip axes, inertial axes.
        joints: ``(S, n)`` the history of the joints (S = steps + 1 samples, equal steps in s).
        base_rotation: ``(S, 3, 3)`` bus attitude along it.
        tips: ``(S, 3)`` tip origin along it, inertial, m.
        tip_rotations: ``(S, 3, 3)`` tip axes along it, inertial.
        progress: ``(S,)`` the path parameter s in [0, 1].
        phase: ``(S,)`` int, all `PHASE_STRAIGHT` (one straight leg).
        loops: 0 (no reorientation loop).
        bus_turn: angle of the bus rotation from start to end, rad.
        straight_length: distance from the start tip to the target, m.
        tip_turn: angle of the tip axes' rotation from start to target, rad.
        end_joints, end_rotation, end_tip, end_tip_rotation: the last row of each history.
        error: |end_tip - target|, m.
        rotation_error: geodesic angle between the end tip axes and the target, rad.
        min_singular: the smallest sigma_min of J* along the path.
    """

    mode: str
    target: np.ndarray
    target_rotation: np.ndarray
    joints: np.ndarray
    base_rotation: np.ndarray
    tips: np.ndarray
    tip_rotations: np.ndarray
    progress: np.ndarray
    phase: np.ndarray
    loops: int
    bus_turn: float
    straight_length: float
    tip_turn: float
    end_joints: np.ndarray
    end_rotation: np.ndarray
    end_tip: np.ndarray
    end_tip_rotation: np.ndarray
    error: float
    rotation_error: float
    min_singular: float


def _angle(R: np.ndarray) -> float:
    """The rotation angle of a (3, 3) rotation matrix, rad (atan2 form, accurate over [0, pi])."""
    skew = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return float(np.arctan2(np.linalg.norm(skew), 0.5 * (np.trace(R) - 1.0)))


def plan_pose_reach(
    robot,
    start,
    target_position,
    target_rotation,
    *,
    base_rotation=None,
    steps: int = DEFAULT_POSE_STEPS,
    sing_threshold: float = 1e-3,
    tolerance: float | None = None,
) -> PoseReachPlan:
    """Plan how the tip frame reaches an inertial target pose by one straight pose path.

    Args:
        robot: one design whose tip pose can be commanded (6-row J*, at least 6 joints).
        start: ``(n,)`` joints at the start.
        target_position: ``(3,)`` inertial target (origin at the system centroid), m.
        target_rotation: ``(3, 3)`` target tip axes, inertial axes.
        base_rotation: ``(3, 3)`` bus attitude at the start (default identity).
        steps: DOP853 steps of the path (history samples: steps + 1).
        sing_threshold: the path stops before sigma_min(J*) falls below this.
        tolerance: accepted end error, m and rad (default 1e-6 in float64, 1e-3 in float32).

    Returns:
        `PoseReachPlan`.

    Raises:
        ConfigError: a robot whose tip pose cannot be commanded, bad input, a target
            outside the tip shell, or a path that stops before the target (singular
            posture or joint limit) or ends farther than ``tolerance`` from it.
    """
    check_pose_robot(robot, "pose targets")
    target = np.asarray(target_position, float)
    if target.shape != (3,) or not np.all(np.isfinite(target)):
        raise ConfigError(f"target: expected three finite numbers (x, y, z) in m, got {np.asarray(target).tolist()!r}")
    check_in_shell(robot, target)
    if tolerance is not None and not float(tolerance) > 0:
        raise ConfigError(f"tolerance: expected a positive number (m and rad), got {tolerance!r}")
    if tolerance is None:
        tolerance = 1e-6 if jax.config.jax_enable_x64 else 1e-3
    path = straight_pose_path(
        robot,
        start,
        target,
        target_rotation,
        base_rotation=base_rotation,
        steps=steps,
        sing_threshold=sing_threshold,
        history=True,
    )
    history = path.history
    joints, rotations, tips, tip_rotations = (
        np.asarray(x) for x in (history.joints, history.base_rotation, history.tip, history.tip_rotation)
    )
    T1 = np.asarray(target_rotation, float)
    error, rotation_error = float(path.position_error), float(path.rotation_error)
    reason = int(path.reason)
    if reason in (REASON_SINGULAR, REASON_JOINT_LIMIT):
        s = float(path.progress)
        left = f"the tip is {error:.3g} m and {np.degrees(rotation_error):.3g} deg from the target there"
        if reason == REASON_SINGULAR:
            why = f"J* nears a singular posture (its sigma_min reaches the threshold {sing_threshold:.3g})"
        else:
            j = int(path.limit_joint)
            lower = np.broadcast_to(np.asarray(robot.joint_lower, float), joints.shape[1:])[j]
            upper = np.broadcast_to(np.asarray(robot.joint_upper, float), joints.shape[1:])[j]
            why = f"joint {j + 1} reaches its limit [{lower:.6g}, {upper:.6g}] ({robot.joint_names[j]})"
        raise ConfigError(
            f"target: the straight pose path stops at s = {s:.3f} of the way: {why}; {left} "
            "(a straight pose path has no reorientation fallback: try another start posture or target)"
        )
    if not (error <= tolerance and rotation_error <= tolerance):
        raise ConfigError(
            f"target: the pose path ends {error:.3g} m and {rotation_error:.3g} rad from the target "
            f"(tolerance {tolerance:.3g}); raise the number of steps"
        )
    return PoseReachPlan(
        mode=MODE_POSE,
        target=target,
        target_rotation=T1,
        joints=joints,
        base_rotation=rotations,
        tips=tips,
        tip_rotations=tip_rotations,
        progress=np.asarray(history.progress),
        phase=np.full(len(joints), PHASE_STRAIGHT),
        loops=0,
        bus_turn=_angle(rotations[0].T @ rotations[-1]),
        straight_length=float(np.linalg.norm(target - tips[0])),
        tip_turn=_angle(tip_rotations[0].T @ T1),
        end_joints=joints[-1],
        end_rotation=rotations[-1],
        end_tip=tips[-1],
        end_tip_rotation=tip_rotations[-1],
        error=error,
        rotation_error=rotation_error,
        min_singular=float(path.min_singular),
    )
