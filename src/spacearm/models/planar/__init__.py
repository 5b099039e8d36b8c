"""The planar family (Umetani & Yoshida 1990, section 2): n >= 2 revolute links in a plane."""

from .family import PLANAR as PLANAR, PlanarFamily as PlanarFamily
from .robot import PlanarRobot as PlanarRobot, stack_robots as stack_robots
from .schema import (
    is_planar_mapping as is_planar_mapping,
    robot_from_mapping as robot_from_mapping,
    robot_to_mapping as robot_to_mapping,
    umetani1990 as umetani1990,
)
