"""Deprecated path (one release): use `spacearm.models.planar` and `spacearm.load_robot`."""

from ._core.errors import ConfigError as ConfigError
from .models import load_robot as load_robot
from .models.planar import (
    PlanarRobot as PlanarRobot,
    robot_from_mapping as robot_from_mapping,
    robot_to_mapping as robot_to_mapping,
    stack_robots as stack_robots,
    umetani1990 as umetani1990,
)
