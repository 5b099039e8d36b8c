"""The spatial family: URDF arms on a free-floating bus (issue 14).

- :mod:`.urdf`: the stdlib-XML URDF reader (fixed and locked joints merged);
- :mod:`.robot`: the :class:`SpatialRobot` pytree and its validation;
- :mod:`.schema`: the robot file (``arm:`` key) and :func:`load_spatial_robot`;
- :mod:`.primitives`: per-posture primitives and closed forms (one design, one posture);
- :mod:`.family`: the family object the generic kernels dispatch on.
"""

from .primitives import (
    arm_inertia as arm_inertia,
    base_twist_map as base_twist_map,
    chain_constants as chain_constants,
    fixed_base_jacobian as fixed_base_jacobian,
    generalized_jacobian as generalized_jacobian,
    jacobians as jacobians,
    mass_matrix as mass_matrix,
    momentum_map as momentum_map,
    tip as tip,
    tip_pose as tip_pose,
)
from .robot import Labels as Labels, SpatialRobot as SpatialRobot, stack_spatial_robots as stack_spatial_robots
from .schema import (
    is_spatial_config as is_spatial_config,
    load_spatial_robot as load_spatial_robot,
    spatial_robot_from_mapping as spatial_robot_from_mapping,
)
from .urdf import ArmChain as ArmChain, parse_urdf as parse_urdf, read_urdf as read_urdf
