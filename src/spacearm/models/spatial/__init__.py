"""The spatial family: URDF arms on a free-floating bus.

- `urdf`: the stdlib-XML URDF reader (fixed and locked joints merged);
- `robot`: the `SpatialRobot` pytree and its validation;
- `schema`: the robot file (``arm:`` key) and `load_spatial_robot`;
- `primitives`: per-posture primitives and closed forms (one design, one posture);
- `family`: `SPATIAL`, the family the generic kernels dispatch on;
- `fields`: named design numbers (``mount.xyz[0]``, ``arm.length``, ...) that sweeps
  and design problems set;
- `metrics`: spatial-only batched kernels (rotational/full/dynamic
  manipulability, H_m, H*, C(q), rotational and fixed-base ellipsoids).
"""

from .family import SPATIAL as SPATIAL
from .family import SpatialFamily as SpatialFamily
from .metrics import (
    arm_inertia as arm_inertia,
)
from .metrics import (
    base_twist_map as base_twist_map,
)
from .metrics import (
    dynamic_manipulability as dynamic_manipulability,
)
from .metrics import (
    fixed_base_ellipsoid as fixed_base_ellipsoid,
)
from .metrics import (
    full_manipulability as full_manipulability,
)
from .metrics import (
    mass_matrix as mass_matrix,
)
from .metrics import (
    rotational_ellipsoid as rotational_ellipsoid,
)
from .metrics import (
    rotational_manipulability as rotational_manipulability,
)
from .robot import Labels as Labels
from .robot import SpatialRobot as SpatialRobot
from .robot import stack_spatial_robots as stack_spatial_robots
from .schema import (
    is_spatial_config as is_spatial_config,
)
from .schema import (
    load_spatial_robot as load_spatial_robot,
)
from .schema import (
    locate_package_file as locate_package_file,
)
from .schema import (
    spatial_robot_from_mapping as spatial_robot_from_mapping,
)
from .urdf import ArmChain as ArmChain
from .urdf import parse_urdf as parse_urdf
from .urdf import read_urdf as read_urdf
