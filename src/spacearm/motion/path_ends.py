"""Why a straight tip path ended: the reason codes shared by the planar and spatial paths."""

__all__ = ["REASON_JOINT_LIMIT", "REASON_MAX_LENGTH", "REASON_SINGULAR", "REASON_STEP_BUDGET"]

REASON_SINGULAR = 0  # J* (its translational rows) lost rank: a dynamic singularity
REASON_MAX_LENGTH = 1  # the requested length was travelled
REASON_JOINT_LIMIT = 2  # a joint reached its limit
REASON_STEP_BUDGET = 3  # the step budget ran out before any event
