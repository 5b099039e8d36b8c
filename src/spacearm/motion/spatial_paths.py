"""Straight tip paths and go-and-back motions of a spatial arm on a free-floating bus.

The tip translates along a fixed inertial direction d (its orientation is free); the
joints and the bus attitude R are integrated together by the one straight-path
integrator of `spacearm.motion.straight_paths` (the bus attitude on SO(3), J*_v and
C_w from one pass over the chain per field evaluation, DOP853 stages in a loop, lane
refill and power-of-two batch buckets). This module keeps the spatial entry points
with the spatial defaults and the go-and-back motion.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .._core.errors import ConfigError
from .._core.groups import polar_rotation
from .straight_paths import SpatialStraightPath, straight_tip_path

__all__ = ["SpatialStraightPath", "polar_rotation", "spatial_go_and_back", "spatial_straight_tip_path"]


def spatial_straight_tip_path(
    robot,
    q_start: jax.Array,
    direction: jax.Array,
    max_length: jax.Array | float | None = None,
    *,
    base_rotation: jax.Array | None = None,
    max_step: float = 0.1,
    tol: float = 1e-11,
    rtol: float = 1e-12,
    sing_rate: float = 1e-6,
    tip_tol: float = 1e-3,
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
            redundant arm may approach rank loss only asymptotically).
        tip_tol: for n > 3, the path also ends (singular) once ds/dsigma is flat and
            the tip travel it predicts up to the next joint limit is below this, m (the
            UR5's creep on the bus reaction to joint 6; `spacearm.motion.lanes.step_lane`).
        max_steps: step budget per path (traced: a new budget does not recompile).

    Returns:
        `SpatialStraightPath` with the batch shape.
    """
    n = robot.n_joints
    if n < 3:
        raise ConfigError(f"straight tip paths in 3-D need at least 3 joints, the arm has {n}")
    return straight_tip_path(
        robot,
        q_start,
        direction,
        max_length=max_length,
        base_rotation=base_rotation,
        max_step=max_step,
        tol=tol,
        rtol=rtol,
        sing_rate=sing_rate,
        tip_tol=tip_tol,
        max_steps=max_steps,
    )


def spatial_go_and_back(
    robot,
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
