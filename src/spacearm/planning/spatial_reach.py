"""Reaching an inertial point with a spatial arm: straight, or turn the bus first (3-D sec. 3.2).

1. If the straight tip path towards the target (translation, bus attitude integrated
   with the joints; `spacearm.motion.spatial_straight_tip_path`) gets there
   before J*_v loses rank or a joint limit, that path is the plan.
2. Otherwise turn the bus first. A closed joint loop leaves the joints at q0 and turns
   the bus by Q (bus frame): the tip moves to R0 Q p_bus(q0) and the straight paths
   start from (q0, R0 Q). For a set of candidate rotations (rotation vectors on a
   Fibonacci sphere of axes times a few angles; one batched call) the straight path
   towards the target is run from (q0, R0 Q); the smallest rotation whose path gets
   there is planned with `spacearm.planning.plan_spatial_reorientation_details`,
   then the straight path runs from the attitude actually reached.

The target is about the system centroid, inertial axes (zero momentum fixes the
centroid: with no external force the system centroid does not move).
"""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from ..kinematics import tip_position
from ..models.spatial.robot import SpatialRobot
from ..motion.attitude import expm
from ..motion.joint_paths import integrate_joint_path
from ..motion.spatial_paths import spatial_straight_tip_path
from ..motion.path_ends import REASON_MAX_LENGTH
from .spatial_reorientation import SpatialLoopSettings, plan_spatial_reorientation_details

__all__ = ["SpatialReachPlan", "plan_spatial_reach", "candidate_rotations"]


@dataclasses.dataclass(frozen=True)
class SpatialReachPlan:
    """How the tip reaches the target.

    Attributes:
        mode: ``"straight"`` or ``"reorient"``.
        loop_waypoints: ``(k, n)`` closed joint path turning the bus first (``(1, n)``: none).
        bus_rotation: ``(3, 3)`` the bus rotation planned by the loop (bus frame).
        end_joints: ``(n,)``, end_rotation: ``(3, 3)``, end_tip: ``(3,)`` at the end.
        straight_length: tip distance of the final straight path, m.
        error: distance from the end tip to the target, m.
    """

    mode: str
    loop_waypoints: np.ndarray
    bus_rotation: np.ndarray
    end_joints: np.ndarray
    end_rotation: np.ndarray
    end_tip: np.ndarray
    straight_length: float
    error: float


def candidate_rotations(axes: int = 64, angles=(0.02, 0.05, 0.1, 0.2)) -> np.ndarray:
    """``(axes * len(angles), 3)`` rotation vectors, smallest angles first (Fibonacci sphere of axes)."""
    k = np.arange(axes) + 0.5
    z = 1.0 - 2.0 * k / axes
    phi = np.pi * (1.0 + 5.0**0.5) * k
    r = np.sqrt(1.0 - z * z)
    unit = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    return np.concatenate([angle * unit for angle in angles], axis=0)


def _straight(robot, q, R, target, tolerance):
    q, R = np.atleast_2d(q), np.asarray(R).reshape(-1, 3, 3)
    start = np.einsum("pij,pj->pi", R, np.asarray(tip_position(robot, jnp.asarray(q))))
    offset = np.asarray(target)[None] - start
    distance = np.linalg.norm(offset, axis=1)
    direction = offset / np.where(distance > 0, distance, 1.0)[:, None]
    path = spatial_straight_tip_path(robot, q, direction, distance, base_rotation=R)
    error = np.linalg.norm(np.asarray(path.end_tip) - np.asarray(target)[None], axis=1)
    reached = (np.asarray(path.reason) == REASON_MAX_LENGTH) & (error <= tolerance)
    return path, reached, error


def plan_spatial_reach(
    robot: SpatialRobot,
    q_start,
    target,
    *,
    base_rotation=None,
    rotations: np.ndarray | None = None,
    tolerance: float = 1e-6,
    settings: SpatialLoopSettings | None = None,
) -> SpatialReachPlan:
    """Plan how the tip of a spatial arm reaches an inertial point.

    Args:
        robot: one spatial design.
        q_start: ``(n,)`` joints at the start.
        target: ``(3,)`` inertial point about the system centroid, m.
        base_rotation: ``(3, 3)`` bus attitude at the start (default identity).
        rotations: ``(c, 3)`` candidate bus rotation vectors (default `candidate_rotations`).
        tolerance: accepted tip error at the end, m.

    Raises:
        ConfigError: when neither the straight path nor any candidate rotation reaches.
    """
    q0 = np.asarray(q_start, float)
    target = np.asarray(target, float)
    if target.shape != (3,):
        raise ConfigError(f"target: expected 3 coordinates, got shape {target.shape}")
    R0 = np.eye(3) if base_rotation is None else np.asarray(base_rotation, float)
    path, reached, error = _straight(robot, q0, R0, target, tolerance)
    none = q0[None]
    if reached[0]:
        return SpatialReachPlan("straight", none, np.eye(3), np.asarray(path.end_joints[0]), np.asarray(path.end_rotation[0]),
                                np.asarray(path.end_tip[0]), float(path.length[0]), float(error[0]))
    vectors = candidate_rotations() if rotations is None else np.asarray(rotations, float)
    Q = np.asarray(expm(jnp.asarray(vectors)))
    starts = np.einsum("ij,cjk->cik", R0, Q)
    _, reached, _ = _straight(robot, np.broadcast_to(q0, (len(Q), q0.size)), starts, target, tolerance)
    if not reached.any():
        raise ConfigError("plan_reach: the straight path does not reach the target, nor after any candidate bus rotation")
    pick = np.flatnonzero(reached)[np.argmin(np.linalg.norm(vectors[reached], axis=1))]
    loop = plan_spatial_reorientation_details(robot, q0, Q[pick], settings)
    R_after, _ = integrate_joint_path(robot, q0, loop.waypoints, base_rotation=R0)
    path, reached, error = _straight(robot, q0, np.asarray(R_after), target, tolerance)
    if not reached[0]:
        raise ConfigError(f"plan_reach: after the planned loop the straight path misses the target by {error[0]:.3g} m")
    return SpatialReachPlan("reorient", loop.waypoints, Q[pick], np.asarray(path.end_joints[0]), np.asarray(path.end_rotation[0]),
                            np.asarray(path.end_tip[0]), float(path.length[0]), float(error[0]))
