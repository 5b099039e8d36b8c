"""Deprecated path (one release): use `spacearm.analysis`."""

from .analysis import (
    average_manipulability as average_manipulability,
    check_average_options as check_average_options,
    fixed_base_average_manipulability as fixed_base_average_manipulability,
    inverse_kinematics as inverse_kinematics,
    joint_grid as joint_grid,
    manipulability_map as manipulability_map,
    normalized_areas as normalized_areas,
    workspace_map as workspace_map,
)
