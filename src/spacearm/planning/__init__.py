"""Planning: cyclic maneuvers that reorient the base, reaching a point (section 3.2), reaching a pose."""

from .pose_reach import MODE_POSE as MODE_POSE, PoseReachPlan as PoseReachPlan, plan_pose_reach as plan_pose_reach
from .reach import (
    MODE_REORIENT as MODE_REORIENT,
    MODE_REPOSITION as MODE_REPOSITION,
    MODE_STRAIGHT as MODE_STRAIGHT,
    PHASE_LOOP as PHASE_LOOP,
    PHASE_REPOSITION as PHASE_REPOSITION,
    PHASE_STRAIGHT as PHASE_STRAIGHT,
    ReachPlan as ReachPlan,
    loop_settings as loop_settings,
    plan_reach as plan_reach,
    reachable_bounds as reachable_bounds,
)
from .reorientation import (
    LoopSettings as LoopSettings,
    ReorientationLoop as ReorientationLoop,
    plan_reorientation as plan_reorientation,
    plan_reorientation_details as plan_reorientation_details,
    rotation_curl as rotation_curl,
)
from .spatial_reach import SpatialReachPlan as SpatialReachPlan
from .spatial_reorientation import (
    SpatialLoopSettings as SpatialLoopSettings,
    SpatialReorientation as SpatialReorientation,
    plan_spatial_reorientation as plan_spatial_reorientation,
    plan_spatial_reorientation_details as plan_spatial_reorientation_details,
)

__all__ = [
    "MODE_POSE",
    "MODE_REORIENT",
    "MODE_REPOSITION",
    "MODE_STRAIGHT",
    "PHASE_LOOP",
    "PHASE_REPOSITION",
    "PHASE_STRAIGHT",
    "LoopSettings",
    "PoseReachPlan",
    "ReachPlan",
    "ReorientationLoop",
    "SpatialLoopSettings",
    "SpatialReachPlan",
    "SpatialReorientation",
    "loop_settings",
    "plan_pose_reach",
    "plan_reach",
    "plan_reorientation",
    "plan_reorientation_details",
    "plan_spatial_reorientation",
    "plan_spatial_reorientation_details",
    "reachable_bounds",
    "rotation_curl",
]
