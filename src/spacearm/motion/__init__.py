"""Motion of the free-floating arm: the base attitude along joint paths, straight tip paths and pose paths,
and the simulation under joint torques."""

from .attitude import geodesic_distance as geodesic_distance
from .joint_paths import (
    integrate_joint_path as integrate_joint_path,
    joint_path_base_increments as joint_path_base_increments,
    joint_path_history as joint_path_history,
)
from .path_ends import (
    REASON_JOINT_LIMIT as REASON_JOINT_LIMIT,
    REASON_MAX_LENGTH as REASON_MAX_LENGTH,
    REASON_SINGULAR as REASON_SINGULAR,
    REASON_STEP_BUDGET as REASON_STEP_BUDGET,
)
from .pose_paths import (
    PoseHistory as PoseHistory,
    PosePath as PosePath,
    pose_on_path as pose_on_path,
    straight_pose_path as straight_pose_path,
)
from .simulation import SimulationStop as SimulationStop, simulate as simulate
from .spatial_paths import (
    SpatialStraightPath as SpatialStraightPath,
    spatial_go_and_back as spatial_go_and_back,
    spatial_straight_tip_path as spatial_straight_tip_path,
)
from .straight_paths import (
    StraightPath as StraightPath,
    compile_straight_tip_path_history as compile_straight_tip_path_history,
    go_and_back as go_and_back,
    straight_tip_path as straight_tip_path,
    straight_tip_path_history as straight_tip_path_history,
)
from .tasks import (
    TimedTask as TimedTask,
    task_peaks as task_peaks,
    task_states as task_states,
    wheel_peaks as wheel_peaks,
)

__all__ = [
    "REASON_JOINT_LIMIT",
    "REASON_MAX_LENGTH",
    "REASON_SINGULAR",
    "REASON_STEP_BUDGET",
    "PoseHistory",
    "PosePath",
    "SimulationStop",
    "SpatialStraightPath",
    "StraightPath",
    "TimedTask",
    "compile_straight_tip_path_history",
    "geodesic_distance",
    "go_and_back",
    "integrate_joint_path",
    "joint_path_base_increments",
    "joint_path_history",
    "pose_on_path",
    "simulate",
    "spatial_go_and_back",
    "spatial_straight_tip_path",
    "straight_pose_path",
    "straight_tip_path",
    "straight_tip_path_history",
    "task_peaks",
    "task_states",
    "wheel_peaks",
]
