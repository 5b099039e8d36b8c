"""spacearm: a JAX design-space explorer for manipulators on free-floating spacecraft.

Starts from Umetani & Yoshida, "Workspace and Manipulability Analysis of Space
Manipulator", Trans. SICE 26(2), 1990. Importing the package changes no global JAX
setting; call :func:`enable_x64` once for float64 (the command line does).
"""

from ._version import __version__ as __version__
from .config import enable_x64 as enable_x64
from .kinematics import (
    angular_momentum as angular_momentum,
    arm_jacobian as arm_jacobian,
    base_jacobian as base_jacobian,
    base_rate as base_rate,
    centroid_positions as centroid_positions,
    design_coefficients as design_coefficients,
    fixed_base_jacobian as fixed_base_jacobian,
    fixed_base_manipulability as fixed_base_manipulability,
    generalized_jacobian as generalized_jacobian,
    manipulability as manipulability,
    manipulability_ellipse as manipulability_ellipse,
    manipulability_on_grid as manipulability_on_grid,
    momentum_inertias as momentum_inertias,
    robot_frame_tip_position as robot_frame_tip_position,
    tip_coefficients as tip_coefficients,
    tip_position as tip_position,
)
from .robot import (
    ConfigError as ConfigError,
    PlanarRobot as PlanarRobot,
    load_robot as load_robot,
    stack_robots as stack_robots,
    umetani1990 as umetani1990,
)

# Public names from the higher layers, imported on first use (keeps `import spacearm`
# light). Each entry: public name -> module under spacearm.
_LAZY = {
    "average_manipulability": "metrics",
    "normalized_areas": "metrics",
    "integrate_joint_path": "motion",
    "joint_path_history": "motion",
    "straight_tip_path": "motion",
    "straight_tip_path_history": "motion",
    "StraightPath": "motion",
    "go_and_back": "motion",
    "straight_path_workspace": "workspace",
    "fixed_vehicle_radius": "workspace",
    "attitude_constraint": "workspace",
    "maximum_reachable_radius": "workspace",
    "guaranteed_radius": "workspace",
    "path_independent_radius": "workspace",
    "dynamic_singularities": "workspace",
    "maximum_reachable_radii": "workspace",
    "workspace_relations": "workspace",
    "plan_reorientation": "planning",
    "plan_reach": "planning",
    "load_problem": "design",
    "pareto_search": "design",
    "hypervolume_2d": "design",
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(f"spacearm.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'spacearm' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
