"""Workspaces, singular sets, areas, averaged metrics and maps (sections 3-5 of the paper)."""

from .manipulability_average import (
    fixed_base_average_manipulability as fixed_base_average_manipulability,
    check_average_options as check_average_options,
)
from .averages import average_manipulability as average_manipulability
from .spatial_workspaces import (
    maximum_reachable_radius as maximum_reachable_radius,
    path_independent_radius as path_independent_radius,
)
from .manipulability_maps import (
    check_single_design as check_single_design,
    joint_grid as joint_grid,
    manipulability_map as manipulability_map,
    grid_average as grid_average,
    inverse_kinematics as inverse_kinematics,
    workspace_map as workspace_map,
)
from .workspaces import (
    fixed_vehicle_radius as fixed_vehicle_radius,
    fixed_vehicle_inner_radius as fixed_vehicle_inner_radius,
    fixed_vehicle_center as fixed_vehicle_center,
    attitude_constraint as attitude_constraint,
    attitude_constraint_inner_radius as attitude_constraint_inner_radius,
    maximum_reachable_inner_radius as maximum_reachable_inner_radius,
    guaranteed_radius as guaranteed_radius,
    kinematic_singularity_radius as kinematic_singularity_radius,
    attachment_condition as attachment_condition,
    normalized_areas as normalized_areas,
    normalized_workspace_areas as normalized_workspace_areas,
    workspace_relations as workspace_relations,
    maximum_reachable_radii as maximum_reachable_radii,
)
from .reaction import (
    reaction_null_space as reaction_null_space,
    disturbance as disturbance,
    disturbance_map as disturbance_map,
    DisturbanceMap as DisturbanceMap,
    ReactionFreePath as ReactionFreePath,
    reaction_free_rates as reaction_free_rates,
    reaction_free_tip_path as reaction_free_tip_path,
)
from .singularities import (
    SingularSet as SingularSet,
    dynamic_singularities as dynamic_singularities,
)
from .straight_workspace import (
    evenly_spaced_directions as evenly_spaced_directions,
    straight_path_ends as straight_path_ends,
    straight_path_workspace as straight_path_workspace,
    straight_path_union_radius as straight_path_union_radius,
    straight_path_intersection_radius as straight_path_intersection_radius,
    clearance_radius as clearance_radius,
    inside_straight_path_workspace as inside_straight_path_workspace,
    random_joint_postures as random_joint_postures,
    straight_path_study as straight_path_study,
    summarize_straight_paths as summarize_straight_paths,
)

__all__ = [
    'reaction_null_space',
    'disturbance',
    'disturbance_map',
    'DisturbanceMap',
    'ReactionFreePath',
    'reaction_free_rates',
    'reaction_free_tip_path',

    "average_manipulability",
    "fixed_base_average_manipulability",
    "check_average_options",
    "check_single_design",
    "joint_grid",
    "manipulability_map",
    "grid_average",
    "inverse_kinematics",
    "workspace_map",
    "fixed_vehicle_radius",
    "fixed_vehicle_inner_radius",
    "fixed_vehicle_center",
    "attitude_constraint",
    "attitude_constraint_inner_radius",
    "maximum_reachable_radius",
    "maximum_reachable_inner_radius",
    "guaranteed_radius",
    "kinematic_singularity_radius",
    "attachment_condition",
    "normalized_areas",
    "normalized_workspace_areas",
    "workspace_relations",
    "maximum_reachable_radii",
    "SingularSet",
    "dynamic_singularities",
    "path_independent_radius",
    "evenly_spaced_directions",
    "straight_path_ends",
    "straight_path_workspace",
    "straight_path_union_radius",
    "straight_path_intersection_radius",
    "clearance_radius",
    "inside_straight_path_workspace",
    "random_joint_postures",
    "straight_path_study",
    "summarize_straight_paths",
]
