"""The paper's planar model in closed form: Umetani & Yoshida, Trans. SICE 26(2), 1990.

One flat namespace for what reproduces the paper and holds for its planar arm only: the
virtual-manipulator coefficients K_i (eq. 1), the five workspaces of section 3 and their
normalized areas S_M and S_G (eq. 7-9, Table 2), the normalized average manipulability
w-bar of eq. 12, the dynamic singularities of the two-link arm, and the maps of Fig. 6-9.
The quantities that serve every robot (J*, w*, the joint-box averages, reach radii,
straight paths) are the names of `spacearm` itself; this is the one package above
`spacearm.models` that may know the planar family by name.
"""

from ..models.planar import PlanarRobot as PlanarRobot, umetani1990 as umetani1990
from ..models.planar.closed_forms import (
    design_coefficients as design_coefficients,
    manipulability_ellipse as manipulability_ellipse,
    robot_frame_tip_position as robot_frame_tip_position,
    tip_coefficients as tip_coefficients,
)
from ..models.planar.singularities import SingularSet as SingularSet, dynamic_singularities as dynamic_singularities
from .manipulability_average import (
    check_average_options as check_average_options,
    fixed_base_average_manipulability as fixed_base_average_manipulability,
    normalized_wbar as normalized_wbar,
)
from .manipulability_maps import (
    check_single_design as check_single_design,
    grid_average as grid_average,
    inverse_kinematics as inverse_kinematics,
    joint_grid as joint_grid,
    manipulability_map as manipulability_map,
    workspace_map as workspace_map,
)
from .straight_workspace import (
    clearance_radius as clearance_radius,
    evenly_spaced_directions as evenly_spaced_directions,
    inside_straight_path_workspace as inside_straight_path_workspace,
    random_joint_postures as random_joint_postures,
    straight_path_ends as straight_path_ends,
    straight_path_intersection_radius as straight_path_intersection_radius,
    straight_path_study as straight_path_study,
    straight_path_union_radius as straight_path_union_radius,
    straight_path_workspace as straight_path_workspace,
    summarize_straight_paths as summarize_straight_paths,
)
from .workspaces import (
    attachment_condition as attachment_condition,
    attitude_constraint as attitude_constraint,
    attitude_constraint_inner_radius as attitude_constraint_inner_radius,
    fixed_vehicle_center as fixed_vehicle_center,
    fixed_vehicle_inner_radius as fixed_vehicle_inner_radius,
    fixed_vehicle_radius as fixed_vehicle_radius,
    guaranteed_radius as guaranteed_radius,
    kinematic_singularity_radius as kinematic_singularity_radius,
    maximum_reachable_radii as maximum_reachable_radii,
    normalized_areas as normalized_areas,
    normalized_workspace_areas as normalized_workspace_areas,
    workspace_relations as workspace_relations,
)

__all__ = [
    "PlanarRobot",
    "SingularSet",
    "attachment_condition",
    "attitude_constraint",
    "attitude_constraint_inner_radius",
    "check_average_options",
    "check_single_design",
    "clearance_radius",
    "design_coefficients",
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
    "manipulability_ellipse",
    "manipulability_map",
    "maximum_reachable_radii",
    "normalized_areas",
    "normalized_wbar",
    "normalized_workspace_areas",
    "random_joint_postures",
    "robot_frame_tip_position",
    "straight_path_ends",
    "straight_path_intersection_radius",
    "straight_path_study",
    "straight_path_union_radius",
    "straight_path_workspace",
    "summarize_straight_paths",
    "tip_coefficients",
    "umetani1990",
    "workspace_map",
    "workspace_relations",
]
