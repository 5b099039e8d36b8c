"""Workspaces, singular sets, areas, averaged metrics and maps (sections 3-5 of the paper)."""

from .averages import average_manipulability as average_manipulability
from .manipulability_average import (
    check_average_options as check_average_options,
)
from .manipulability_average import (
    fixed_base_average_manipulability as fixed_base_average_manipulability,
)
from .manipulability_maps import (
    check_single_design as check_single_design,
)
from .manipulability_maps import (
    grid_average as grid_average,
)
from .manipulability_maps import (
    inverse_kinematics as inverse_kinematics,
)
from .manipulability_maps import (
    joint_grid as joint_grid,
)
from .manipulability_maps import (
    manipulability_map as manipulability_map,
)
from .manipulability_maps import (
    workspace_map as workspace_map,
)
from .reaction import (
    DisturbanceMap as DisturbanceMap,
)
from .reaction import (
    ReactionFreePath as ReactionFreePath,
)
from .reaction import (
    disturbance as disturbance,
)
from .reaction import (
    disturbance_map as disturbance_map,
)
from .reaction import (
    reaction_free_rates as reaction_free_rates,
)
from .reaction import (
    reaction_free_tip_path as reaction_free_tip_path,
)
from .reaction import (
    reaction_null_space as reaction_null_space,
)
from .singularities import (
    SingularSet as SingularSet,
)
from .singularities import (
    dynamic_singularities as dynamic_singularities,
)
from .spatial_workspaces import (
    maximum_reachable_radius as maximum_reachable_radius,
)
from .spatial_workspaces import (
    path_independent_radius as path_independent_radius,
)
from .straight_workspace import (
    clearance_radius as clearance_radius,
)
from .straight_workspace import (
    evenly_spaced_directions as evenly_spaced_directions,
)
from .straight_workspace import (
    inside_straight_path_workspace as inside_straight_path_workspace,
)
from .straight_workspace import (
    random_joint_postures as random_joint_postures,
)
from .straight_workspace import (
    straight_path_ends as straight_path_ends,
)
from .straight_workspace import (
    straight_path_intersection_radius as straight_path_intersection_radius,
)
from .straight_workspace import (
    straight_path_study as straight_path_study,
)
from .straight_workspace import (
    straight_path_union_radius as straight_path_union_radius,
)
from .straight_workspace import (
    straight_path_workspace as straight_path_workspace,
)
from .straight_workspace import (
    summarize_straight_paths as summarize_straight_paths,
)
from .workspaces import (
    attachment_condition as attachment_condition,
)
from .workspaces import (
    attitude_constraint as attitude_constraint,
)
from .workspaces import (
    attitude_constraint_inner_radius as attitude_constraint_inner_radius,
)
from .workspaces import (
    fixed_vehicle_center as fixed_vehicle_center,
)
from .workspaces import (
    fixed_vehicle_inner_radius as fixed_vehicle_inner_radius,
)
from .workspaces import (
    fixed_vehicle_radius as fixed_vehicle_radius,
)
from .workspaces import (
    guaranteed_radius as guaranteed_radius,
)
from .workspaces import (
    kinematic_singularity_radius as kinematic_singularity_radius,
)
from .workspaces import (
    maximum_reachable_inner_radius as maximum_reachable_inner_radius,
)
from .workspaces import (
    maximum_reachable_radii as maximum_reachable_radii,
)
from .workspaces import (
    normalized_areas as normalized_areas,
)
from .workspaces import (
    normalized_workspace_areas as normalized_workspace_areas,
)
from .workspaces import (
    workspace_relations as workspace_relations,
)

__all__ = [
    "DisturbanceMap",
    "ReactionFreePath",
    "SingularSet",
    "attachment_condition",
    "attitude_constraint",
    "attitude_constraint_inner_radius",
    "average_manipulability",
    "check_average_options",
    "check_single_design",
    "clearance_radius",
    "disturbance",
    "disturbance_map",
    "dynamic_singularities",
    "evenly_spaced_directions",
    "fixed_base_average_manipulability",
    "fixed_vehicle_center",
    "fixed_vehicle_inner_radius",
    "fixed_vehicle_radius",
    "grid_average",
    "guaranteed_radius",
    "inside_straight_path_workspace",
    "inverse_kinematics",
    "joint_grid",
    "kinematic_singularity_radius",
    "manipulability_map",
    "maximum_reachable_inner_radius",
    "maximum_reachable_radii",
    "maximum_reachable_radius",
    "normalized_areas",
    "normalized_workspace_areas",
    "path_independent_radius",
    "random_joint_postures",
    "reaction_free_rates",
    "reaction_free_tip_path",
    "reaction_null_space",
    "straight_path_ends",
    "straight_path_intersection_radius",
    "straight_path_study",
    "straight_path_union_radius",
    "straight_path_workspace",
    "summarize_straight_paths",
    "workspace_map",
    "workspace_relations",
]
