"""spacearm: a JAX design-space explorer for manipulators on free-floating spacecraft.

Starts from Umetani & Yoshida, "Workspace and Manipulability Analysis of Space
Manipulator", Trans. SICE 26(2), 1990. Importing the package changes no global JAX
setting; call `enable_x64` once for float64, and `enable_compilation_cache` to keep
compiled programs on disk across processes (the command line does both).

The names below are the public API. The kernels of the
lower layers are imported at once; the higher layers (analysis, motion, planning,
design, io) on first use, so ``import spacearm`` stays light.
"""

import importlib
from typing import TYPE_CHECKING

from ._core.errors import ConfigError as ConfigError
from ._core.numeric import enable_compilation_cache as enable_compilation_cache
from ._core.numeric import enable_x64 as enable_x64
from ._version import __version__ as __version__
from .kinematics import (
    base_rate as base_rate,
)
from .kinematics import (
    base_rate_matrix as base_rate_matrix,
)
from .kinematics import (
    fixed_base_jacobian as fixed_base_jacobian,
)
from .kinematics import (
    fixed_base_manipulability as fixed_base_manipulability,
)
from .kinematics import (
    generalized_jacobian as generalized_jacobian,
)
from .kinematics import (
    manipulability as manipulability,
)
from .kinematics import (
    manipulability_ellipsoid as manipulability_ellipsoid,
)
from .kinematics import (
    tip_position as tip_position,
)
from .models import family_of as family_of
from .models import load_robot as load_robot
from .models.planar import PlanarRobot as PlanarRobot
from .models.planar import stack_robots as stack_robots
from .models.planar import umetani1990 as umetani1990
from .models.planar.closed_forms import (
    angular_momentum as angular_momentum,
)
from .models.planar.closed_forms import (
    arm_jacobian as arm_jacobian,
)
from .models.planar.closed_forms import (
    base_jacobian as base_jacobian,
)
from .models.planar.closed_forms import (
    centroid_positions as centroid_positions,
)
from .models.planar.closed_forms import (
    design_coefficients as design_coefficients,
)
from .models.planar.closed_forms import (
    manipulability_ellipse as manipulability_ellipse,
)
from .models.planar.closed_forms import (
    manipulability_on_grid as manipulability_on_grid,
)
from .models.planar.closed_forms import (
    momentum_inertias as momentum_inertias,
)
from .models.planar.closed_forms import (
    robot_frame_tip_position as robot_frame_tip_position,
)
from .models.planar.closed_forms import (
    tip_coefficients as tip_coefficients,
)
from .models.spatial import (
    SpatialRobot as SpatialRobot,
)
from .models.spatial import (
    arm_inertia as arm_inertia,
)
from .models.spatial import (
    base_twist_map as base_twist_map,
)
from .models.spatial import (
    dynamic_manipulability as dynamic_manipulability,
)
from .models.spatial import (
    fixed_base_ellipsoid as fixed_base_ellipsoid,
)
from .models.spatial import (
    full_manipulability as full_manipulability,
)
from .models.spatial import (
    mass_matrix as mass_matrix,
)
from .models.spatial import (
    rotational_ellipsoid as rotational_ellipsoid,
)
from .models.spatial import (
    rotational_manipulability as rotational_manipulability,
)
from .models.spatial import (
    stack_spatial_robots as stack_spatial_robots,
)

# Public names from the higher layers, imported on first use. Each entry: public name ->
# module under spacearm.
_LAZY = {
    "average_manipulability": "analysis",
    "normalized_areas": "analysis",
    "straight_path_workspace": "analysis",
    "fixed_vehicle_radius": "analysis",
    "attitude_constraint": "analysis",
    "maximum_reachable_radius": "analysis",
    "guaranteed_radius": "analysis",
    "path_independent_radius": "analysis",
    "dynamic_singularities": "analysis",
    "maximum_reachable_radii": "analysis",
    "workspace_relations": "analysis",
    "integrate_joint_path": "motion",
    "joint_path_history": "motion",
    "straight_tip_path": "motion",
    "straight_tip_path_history": "motion",
    "StraightPath": "motion",
    "go_and_back": "motion",
    "plan_reorientation": "planning",
    "plan_reach": "planning",
    "load_problem": "design",
    "pareto_search": "design",
    "hypervolume_2d": "design",
    "open_results": "io",
}

if TYPE_CHECKING:  # the same names, visible to type checkers and the API reference
    from .analysis import (
        attitude_constraint as attitude_constraint,
    )
    from .analysis import (
        average_manipulability as average_manipulability,
    )
    from .analysis import (
        dynamic_singularities as dynamic_singularities,
    )
    from .analysis import (
        fixed_vehicle_radius as fixed_vehicle_radius,
    )
    from .analysis import (
        guaranteed_radius as guaranteed_radius,
    )
    from .analysis import (
        maximum_reachable_radii as maximum_reachable_radii,
    )
    from .analysis import (
        maximum_reachable_radius as maximum_reachable_radius,
    )
    from .analysis import (
        normalized_areas as normalized_areas,
    )
    from .analysis import (
        path_independent_radius as path_independent_radius,
    )
    from .analysis import (
        straight_path_workspace as straight_path_workspace,
    )
    from .analysis import (
        workspace_relations as workspace_relations,
    )
    from .design import hypervolume_2d as hypervolume_2d
    from .design import load_problem as load_problem
    from .design import pareto_search as pareto_search
    from .io import open_results as open_results
    from .motion import (
        StraightPath as StraightPath,
    )
    from .motion import (
        go_and_back as go_and_back,
    )
    from .motion import (
        integrate_joint_path as integrate_joint_path,
    )
    from .motion import (
        joint_path_history as joint_path_history,
    )
    from .motion import (
        straight_tip_path as straight_tip_path,
    )
    from .motion import (
        straight_tip_path_history as straight_tip_path_history,
    )
    from .planning import plan_reach as plan_reach
    from .planning import plan_reorientation as plan_reorientation


def __getattr__(name):
    if name in _LAZY:
        value = getattr(importlib.import_module(f"spacearm.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'spacearm' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
