"""The robot families and the robot file: ``load_robot`` returns the right family.

A robot file with an ``arm:`` key is a spatial arm from a URDF
(`spacearm.models.spatial.schema`); one with ``arms:`` (several arms on a bus) or
``system:`` (one URDF whose base link is the bus) is a tree of arms
(`spacearm.models.tree.schema`); one with ``base`` and ``links`` is a planar arm
(`spacearm.models.planar.schema`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from .._core.schema import read_yaml
from .family import RobotFamily as RobotFamily, family_of as family_of
from .planar import PlanarRobot, is_planar_mapping, robot_from_mapping
from .spatial import SpatialRobot, spatial_robot_from_mapping
from .tree.robot import TreeRobot
from .tree.schema import is_tree_config, tree_robot_from_mapping

__all__ = ["RobotFamily", "family_of", "is_robot_mapping", "load_robot", "robot_from_file_mapping"]


def is_robot_mapping(config: Any) -> bool:
    """Whether a parsed YAML file is a robot file of either family."""
    return isinstance(config, Mapping) and ("arm" in config or is_tree_config(config) or is_planar_mapping(config))


def robot_from_file_mapping(config: Any, *, source: str = "robot", base_dir: str | None = None):
    """Build a robot of the right family from a parsed robot file.

    Args:
        config: the parsed mapping.
        source: a label for error messages (the file name).
        base_dir: the folder relative paths in the file (a URDF) are resolved against.
    """
    if is_tree_config(config):
        return tree_robot_from_mapping(config, source=source, base_dir=base_dir or os.getcwd())
    if isinstance(config, Mapping) and "arm" in config:
        return spatial_robot_from_mapping(config, source=source, base_dir=base_dir or os.getcwd())
    return robot_from_mapping(config, source=source)


def load_robot(source: str | os.PathLike | Mapping[str, Any]) -> PlanarRobot | SpatialRobot | TreeRobot:
    """Load and validate a robot from a YAML file path or an already parsed mapping.

    Returns a `PlanarRobot` for a planar file, a spatial robot for a file with an
    ``arm:`` key, and a `TreeRobot` (k tips) for a file with ``arms:`` or ``system:``.

    Raises:
        ConfigError: for a missing or malformed file and for any invalid field, naming
            the file, the field and the reason.
    """
    if isinstance(source, Mapping):
        return robot_from_file_mapping(source, base_dir=os.getcwd())
    path = os.fspath(source)
    config = read_yaml(path, what="robot file")
    return robot_from_file_mapping(config, source=path, base_dir=os.path.dirname(os.path.abspath(path)))
