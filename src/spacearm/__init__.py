"""spacearm: a JAX design-space explorer for manipulators on free-floating spacecraft.

Starts from Umetani & Yoshida, "Workspace and Manipulability Analysis of Space
Manipulator", Trans. SICE 26(2), 1990. Importing the package changes no global JAX
setting; call `enable_x64` once for float64, and `enable_compilation_cache` to keep
compiled programs on disk across processes (the command line does both).

The names below (``__all__``) are the public API: the loaders and the functions that
serve every robot family (they dispatch by `family_of`). A few planar closed forms of
the paper stay here under their familiar names; each says "planar arms only" and raises
TypeError for another family. The paper's own quantities (the normalized w-bar of
eq. 12, the workspaces of section 3, the areas of Table 2, the maps) are in
`spacearm.paper`; family-specific kernels in `spacearm.models.planar` and
`spacearm.models.spatial` (for example `spacearm.models.spatial.as_tree`). The
kernels of the lower layers are imported at once; the higher layers (analysis, motion,
planning, design, io, paper) on first use, so ``import spacearm`` stays light.
"""

import importlib
from typing import TYPE_CHECKING

from ._core.errors import ConfigError as ConfigError
from ._core.numeric import enable_compilation_cache as enable_compilation_cache, enable_x64 as enable_x64
from ._version import __version__ as __version__
from .dynamics import (
    arm_inertia as arm_inertia,
    base_velocity as base_velocity,
    bias_forces as bias_forces,
    bus_rate_jump as bus_rate_jump,
    capture as capture,
    forward_dynamics as forward_dynamics,
    free_motion as free_motion,
    grasped_robot as grasped_robot,
    impulse_response as impulse_response,
    inverse_dynamics as inverse_dynamics,
    joint_mass_matrix as joint_mass_matrix,
    mass_matrix as mass_matrix,
    reduced_bias as reduced_bias,
    system_momentum as system_momentum,
    target_from_tip_frame as target_from_tip_frame,
    target_in_tip_frame as target_in_tip_frame,
    tip_inverse_inertia as tip_inverse_inertia,
    tip_velocity as tip_velocity,
    virtual_mass as virtual_mass,
    wheel_momentum as wheel_momentum,
)
from .inertia import (
    base_twist_map as base_twist_map,
    dynamic_manipulability as dynamic_manipulability,
    fixed_base_ellipsoid as fixed_base_ellipsoid,
    full_manipulability as full_manipulability,
    rotational_ellipsoid as rotational_ellipsoid,
    rotational_manipulability as rotational_manipulability,
)
from .kinematics import (
    base_rate as base_rate,
    base_rate_matrix as base_rate_matrix,
    fixed_base_jacobian as fixed_base_jacobian,
    fixed_base_manipulability as fixed_base_manipulability,
    generalized_jacobian as generalized_jacobian,
    manipulability as manipulability,
    manipulability_ellipsoid as manipulability_ellipsoid,
    relative_jacobian as relative_jacobian,
    tip_pose as tip_pose,
    tip_position as tip_position,
)
from .models import family_of as family_of, load_robot as load_robot
from .models.budget import MassLine as MassLine, mass_budget as mass_budget
from .models.payload import with_payload as with_payload
from .models.planar import PlanarRobot as PlanarRobot, stack_robots as stack_robots, umetani1990 as umetani1990
from .models.planar.closed_forms import (
    angular_momentum as angular_momentum,
    arm_jacobian as arm_jacobian,
    base_jacobian as base_jacobian,
    centroid_positions as centroid_positions,
    design_coefficients as design_coefficients,
    manipulability_ellipse as manipulability_ellipse,
    manipulability_on_grid as manipulability_on_grid,
    momentum_inertias as momentum_inertias,
    robot_frame_tip_position as robot_frame_tip_position,
    tip_coefficients as tip_coefficients,
)
from .models.spatial import SpatialRobot as SpatialRobot
from .models.tree import TreeRobot as TreeRobot

# Public names from the higher layers, imported on first use. Each entry: public name ->
# module under spacearm.
_LAZY = {
    "average_manipulability": "analysis",
    "normalized_areas": "paper",
    "straight_path_workspace": "paper",
    "maximum_reachable_radius": "analysis",
    "path_independent_radius": "analysis",
    "maximum_reachable_radii": "paper",
    "integrate_joint_path": "motion",
    "joint_path_history": "motion",
    "straight_tip_path": "motion",
    "straight_tip_path_history": "motion",
    "StraightPath": "motion",
    "go_and_back": "motion",
    "straight_pose_path": "motion",
    "PosePath": "motion",
    "simulate": "motion",
    "TimedTask": "motion",
    "task_peaks": "motion",
    "task_states": "motion",
    "wheel_peaks": "motion",
    "plan_reorientation": "planning",
    "plan_reach": "planning",
    "loop_settings": "planning",
    "plan_pose_reach": "planning",
    "load_problem": "design",
    "pareto_search": "design",
    "hypervolume_2d": "design",
    "open_results": "io",
}

__all__ = [
    "MassLine",
    "ConfigError",
    "PlanarRobot",
    "SpatialRobot",
    "TreeRobot",
    "__version__",
    "angular_momentum",
    "arm_inertia",
    "base_velocity",
    "bias_forces",
    "bus_rate_jump",
    "capture",
    "forward_dynamics",
    "free_motion",
    "grasped_robot",
    "impulse_response",
    "inverse_dynamics",
    "joint_mass_matrix",
    "mass_matrix",
    "reduced_bias",
    "system_momentum",
    "target_from_tip_frame",
    "target_in_tip_frame",
    "tip_inverse_inertia",
    "tip_velocity",
    "virtual_mass",
    "wheel_momentum",
    "arm_jacobian",
    "base_jacobian",
    "base_rate",
    "base_rate_matrix",
    "base_twist_map",
    "centroid_positions",
    "design_coefficients",
    "enable_compilation_cache",
    "enable_x64",
    "dynamic_manipulability",
    "family_of",
    "fixed_base_ellipsoid",
    "fixed_base_jacobian",
    "fixed_base_manipulability",
    "full_manipulability",
    "generalized_jacobian",
    "load_robot",
    "mass_budget",
    "manipulability",
    "manipulability_ellipse",
    "manipulability_ellipsoid",
    "manipulability_on_grid",
    "momentum_inertias",
    "relative_jacobian",
    "robot_frame_tip_position",
    "rotational_ellipsoid",
    "rotational_manipulability",
    "stack_robots",
    "tip_coefficients",
    "tip_pose",
    "tip_position",
    "umetani1990",
    "with_payload",
    *_LAZY,
]

if TYPE_CHECKING:  # the same names, visible to type checkers and the API reference
    from .analysis import (
        average_manipulability as average_manipulability,
        maximum_reachable_radius as maximum_reachable_radius,
        path_independent_radius as path_independent_radius,
    )
    from .design import hypervolume_2d as hypervolume_2d, load_problem as load_problem, pareto_search as pareto_search
    from .io import open_results as open_results
    from .motion import (
        PosePath as PosePath,
        StraightPath as StraightPath,
        TimedTask as TimedTask,
        go_and_back as go_and_back,
        integrate_joint_path as integrate_joint_path,
        joint_path_history as joint_path_history,
        simulate as simulate,
        straight_pose_path as straight_pose_path,
        straight_tip_path as straight_tip_path,
        straight_tip_path_history as straight_tip_path_history,
        task_peaks as task_peaks,
        task_states as task_states,
        wheel_peaks as wheel_peaks,
    )
    from .paper import (
        maximum_reachable_radii as maximum_reachable_radii,
        normalized_areas as normalized_areas,
        straight_path_workspace as straight_path_workspace,
    )
    from .planning import (
        loop_settings as loop_settings,
        plan_pose_reach as plan_pose_reach,
        plan_reach as plan_reach,
        plan_reorientation as plan_reorientation,
    )


def __getattr__(name):
    if name == "paper":  # the paper's planar closed forms, a subpackage
        return importlib.import_module("spacearm.paper")
    if name in _LAZY:
        value = getattr(importlib.import_module(f"spacearm.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'spacearm' has no attribute {name!r}")


def __dir__():
    return sorted(__all__)
