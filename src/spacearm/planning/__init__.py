"""Planning: cyclic maneuvers that reorient the base, and reaching a point (section 3.2)."""

from .reach import (
    MODE_REORIENT as MODE_REORIENT,
)
from .reach import (
    MODE_REPOSITION as MODE_REPOSITION,
)
from .reach import (
    MODE_STRAIGHT as MODE_STRAIGHT,
)
from .reach import (
    PHASE_LOOP as PHASE_LOOP,
)
from .reach import (
    PHASE_REPOSITION as PHASE_REPOSITION,
)
from .reach import (
    PHASE_STRAIGHT as PHASE_STRAIGHT,
)
from .reach import (
    ReachPlan as ReachPlan,
)
from .reach import (
    plan_reach as plan_reach,
)
from .reach import (
    reachable_bounds as reachable_bounds,
)
from .reorientation import (
    LoopSettings as LoopSettings,
)
from .reorientation import (
    ReorientationLoop as ReorientationLoop,
)
from .reorientation import (
    plan_reorientation as plan_reorientation,
)
from .reorientation import (
    plan_reorientation_details as plan_reorientation_details,
)
from .reorientation import (
    rotation_curl as rotation_curl,
)
from .spatial_reach import (
    SpatialReachPlan as SpatialReachPlan,
)
from .spatial_reach import (
    candidate_rotations as candidate_rotations,
)
from .spatial_reach import (
    plan_spatial_reach as plan_spatial_reach,
)
from .spatial_reorientation import (
    SpatialLoopSettings as SpatialLoopSettings,
)
from .spatial_reorientation import (
    SpatialReorientation as SpatialReorientation,
)
from .spatial_reorientation import (
    plan_spatial_reorientation as plan_spatial_reorientation,
)
from .spatial_reorientation import (
    plan_spatial_reorientation_details as plan_spatial_reorientation_details,
)

__all__ = [
    "MODE_REORIENT",
    "MODE_REPOSITION",
    "MODE_STRAIGHT",
    "PHASE_LOOP",
    "PHASE_REPOSITION",
    "PHASE_STRAIGHT",
    "LoopSettings",
    "ReachPlan",
    "ReorientationLoop",
    "SpatialLoopSettings",
    "SpatialReachPlan",
    "SpatialReorientation",
    "candidate_rotations",
    "plan_reach",
    "plan_reorientation",
    "plan_reorientation_details",
    "plan_spatial_reach",
    "plan_spatial_reorientation",
    "plan_spatial_reorientation_details",
    "reachable_bounds",
    "rotation_curl",
]
