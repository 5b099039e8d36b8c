"""Workspaces, singular sets, averaged metrics and bus disturbance, for every robot.

The paper's planar closed forms (the workspaces of section 3, the normalized w-bar of
eq. 12, the maps) are in `spacearm.paper`.
"""

from .averages import average_manipulability as average_manipulability
from .reaction import (
    DisturbanceMap as DisturbanceMap,
    ReactionFreePath as ReactionFreePath,
    disturbance as disturbance,
    disturbance_map as disturbance_map,
    reaction_free_rates as reaction_free_rates,
    reaction_free_tip_path as reaction_free_tip_path,
    reaction_null_space as reaction_null_space,
)
from .workspace_search import (
    maximum_reachable_inner_radius as maximum_reachable_inner_radius,
    maximum_reachable_radius as maximum_reachable_radius,
    path_independent_radius as path_independent_radius,
)

__all__ = [
    "DisturbanceMap",
    "ReactionFreePath",
    "average_manipulability",
    "disturbance",
    "disturbance_map",
    "maximum_reachable_inner_radius",
    "maximum_reachable_radius",
    "path_independent_radius",
    "reaction_free_rates",
    "reaction_free_tip_path",
    "reaction_null_space",
]
