"""The spatial family: URDF arms on a free-floating bus.

- `urdf`: the stdlib-XML URDF reader (fixed and locked joints merged);
- `robot`: the `SpatialRobot` pytree and its validation;
- `schema`: the robot file (``arm:`` key) and `load_spatial_robot`;
- `primitives`: per-posture primitives and closed forms (one design, one posture);
- `family`: `SPATIAL`, the family the generic kernels dispatch on;
- `fields`: named design numbers (``mount.xyz[0]``, ``arm.length``, ...) that sweeps
  and design problems set.

The kernels over H* and the rotational rows of J* serve every robot: `spacearm.inertia`.
"""

from .family import SPATIAL as SPATIAL, SpatialFamily as SpatialFamily
from .robot import Labels as Labels, SpatialRobot as SpatialRobot, stack_spatial_robots as stack_spatial_robots
from .schema import (
    is_spatial_config as is_spatial_config,
    load_spatial_robot as load_spatial_robot,
    locate_package_file as locate_package_file,
    spatial_robot_from_mapping as spatial_robot_from_mapping,
)
from .urdf import ArmChain as ArmChain, parse_urdf as parse_urdf, read_urdf as read_urdf
