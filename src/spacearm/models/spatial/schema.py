"""The spatial robot file: a bus, a mount pose and a URDF arm (the ``arm:`` key).

```yaml
name: ur5-smallsat
base: {mass: 500.0, com: [-0.2, 0.05, -0.1], inertia: [[80, 1, 0], [1, 95, 2], [0, 2, 120]]}
mount: {xyz: [0.6, 0.1, 0.5], rpy: [0.1, -0.2, 0.3]}   # root-link pose in the bus frame
arm:
  urdf: {package: example-robot-data, path: robots/ur_description/urdf/ur5_robot.urdf}
  root_link: base_link
  tip: tool0
  lock_joints: {}            # joint: value (rad or m), for joints held fixed
  lock_others: false         # true: hold every movable joint off the path at 0 (or its nearest limit)
  drop_others: false         # true: leave out every movable joint off the path, with all below it
  inertia_as_written: false  # true: take link inertias that break the triangle inequality
```

``arm.urdf`` is a path relative to the robot file, or ``{package, path}``: a file of an
installed Python distribution, located through ``importlib.metadata`` (``path`` is
matched against the end of the distribution's file list, so
``robots/ur_description/urdf/ur5_robot.urdf`` finds example-robot-data's file under
its ``cmeel.prefix/share/example-robot-data/`` prefix).
"""

from __future__ import annotations

import importlib.metadata
import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..._core.errors import ConfigError
from ..._core.schema import check_keys, is_number, number, quote, read_yaml, robot_file_name
from .robot import SpatialRobot, robot_from_chain
from .urdf import check_inertia, read_urdf

__all__ = [
    "is_spatial_config",
    "load_spatial_robot",
    "locate_package_file",
    "read_base",
    "read_flag",
    "read_lock_joints",
    "read_mount",
    "spatial_robot_from_mapping",
    "urdf_path",
]

_TOP_KEYS = {"name", "description", "base", "mount", "arm"}
_BASE_KEYS = {"mass", "com", "inertia"}
_MOUNT_KEYS = {"xyz", "rpy", "rpy_deg"}
_ARM_KEYS = {"urdf", "root_link", "tip", "lock_joints", "lock_others", "drop_others", "inertia_as_written"}
_PACKAGE_KEYS = {"package", "path"}


def is_spatial_config(config: Any) -> bool:
    """True for a robot description of the spatial family (a mapping with an ``arm`` key)."""
    return isinstance(config, Mapping) and "arm" in config


def _mapping(where: str, value: Any, keys: set[str]) -> Mapping:
    if not isinstance(value, Mapping):
        raise ConfigError(f"{where}: must be a mapping with keys {', '.join(sorted(keys))}")
    return value


def _array(where: str, value: Any, shape: tuple[int, ...]) -> np.ndarray:
    """Numbers of a fixed shape (a list, or a list of lists), each finite and not huge."""
    if not isinstance(value, (list, tuple)) or len(value) != shape[0]:
        raise ConfigError(f"{where}: must be numbers of shape {list(shape)}, got {quote(value)}")
    if len(shape) > 1:
        return np.array([_array(f"{where}[{i}]", row, shape[1:]) for i, row in enumerate(value)])
    if not all(is_number(v) for v in value):
        raise ConfigError(f"{where}: must be numbers of shape {list(shape)}, got {quote(value)}")
    return np.array([number(f"{where}[{i}]", v) for i, v in enumerate(value)], dtype=float)


def locate_package_file(source: str, package: str, path: str, key: str = "arm.urdf") -> str:
    """The absolute path of ``path`` inside the installed distribution ``package``.

    Args:
        key: the robot-file field that named the file (for messages).

    Raises:
        ConfigError: when the distribution is not installed or has no such file.
    """
    try:
        distribution = importlib.metadata.distribution(package)
    except importlib.metadata.PackageNotFoundError:
        raise ConfigError(f"{source}: {key}.package: '{package}' is not installed (pip install {package})") from None
    wanted = path.strip("/").replace("\\", "/")
    for file in distribution.files or ():
        name = str(file).replace("\\", "/")
        if name == wanted or name.endswith("/" + wanted):
            return os.fspath(distribution.locate_file(file))
    raise ConfigError(f"{source}: {key}.path: package '{package}' has no file '{path}'")


def urdf_path(source: str, arm: Mapping, base_dir: str, section: str = "arm") -> str:
    """The URDF file an ``arm``-like section names: a path relative to ``base_dir``, or
    ``{package, path}`` (see `locate_package_file`). ``section`` names it in messages."""
    if "urdf" not in arm:
        raise ConfigError(f"{source}: {section}.urdf: missing required key")
    value = arm["urdf"]
    if isinstance(value, str):
        return value if os.path.isabs(value) else os.path.join(base_dir, value)
    if isinstance(value, Mapping):
        check_keys(f"{source}: {section}.urdf: ", value, _PACKAGE_KEYS)
        for key in ("package", "path"):
            if not isinstance(value.get(key), str):
                raise ConfigError(f"{source}: {section}.urdf.{key}: missing or not a string")
        return locate_package_file(source, value["package"], value["path"], f"{section}.urdf")
    raise ConfigError(f"{source}: {section}.urdf: must be a path or {{package: ..., path: ...}}, got {quote(value)}")


def read_base(source: str, config: Mapping) -> tuple[float, np.ndarray, np.ndarray]:
    """The ``base:`` section (the bus): mass (positive), com (default 0) and inertia (checked)."""
    base = _mapping(f"{source}: base", config["base"], _BASE_KEYS)
    check_keys(f"{source}: base: ", base, _BASE_KEYS)
    for key in ("mass", "inertia"):
        if key not in base:
            raise ConfigError(f"{source}: base.{key}: missing required key")
    base_mass = number(f"{source}: base.mass", base["mass"])
    if base_mass <= 0:
        raise ConfigError(f"{source}: base.mass: must be positive, got {base_mass!r}")
    base_com = _array(f"{source}: base.com", base.get("com", [0.0, 0.0, 0.0]), (3,))
    base_inertia = _array(f"{source}: base.inertia", base["inertia"], (3, 3))
    check_inertia(f"{source}: base.inertia", base_inertia, positive=True, triangle=True)
    return base_mass, base_com, base_inertia


def read_mount(where: str, value: Any) -> tuple[np.ndarray, np.ndarray]:
    """A ``mount:`` section ``{xyz, rpy | rpy_deg}`` (``where``: ``"robot.yaml: mount"``): xyz and rpy in rad."""
    mount = _mapping(where, value, _MOUNT_KEYS)
    check_keys(f"{where}: ", mount, _MOUNT_KEYS)
    if "rpy" in mount and "rpy_deg" in mount:
        raise ConfigError(f"{where}: give either 'rpy' (rad) or 'rpy_deg', not both")
    mount_xyz = _array(f"{where}.xyz", mount.get("xyz", [0.0, 0.0, 0.0]), (3,))
    if "rpy_deg" in mount:
        mount_rpy = np.deg2rad(_array(f"{where}.rpy_deg", mount["rpy_deg"], (3,)))
    else:
        mount_rpy = _array(f"{where}.rpy", mount.get("rpy", [0.0, 0.0, 0.0]), (3,))
    return mount_xyz, mount_rpy


def read_flag(where: str, value: Any) -> bool:
    """A true/false switch, else `ConfigError` naming ``where``."""
    if not isinstance(value, bool):
        raise ConfigError(f"{where}: must be true or false, got {quote(value)}")
    return value


def read_lock_joints(where: str, value: Any) -> dict[str, float]:
    """A ``lock_joints`` mapping joint: value (numbers; the URDF reader checks names and limits)."""
    lock = value or {}
    if not isinstance(lock, Mapping):
        raise ConfigError(f"{where}: must be a mapping joint: value")
    return {str(k): number(f"{where}.{quote(str(k), 60)}", v) for k, v in lock.items()}


def spatial_robot_from_mapping(
    config: Mapping[str, Any], *, source: str = "robot", base_dir: str | os.PathLike = "."
) -> SpatialRobot:
    """Build a validated `SpatialRobot` from a parsed robot file.

    Args:
        config: the mapping (``name``, ``base``, ``mount``, ``arm``).
        source: a label for messages (the file name).
        base_dir: the folder relative URDF paths start from (the robot file's folder).

    Raises:
        ConfigError: naming the file and the field.
    """
    name = robot_file_name(source, config, _TOP_KEYS)
    base_mass, base_com, base_inertia = read_base(source, config)
    mount_xyz, mount_rpy = read_mount(f"{source}: mount", config.get("mount", {}))

    if "arm" not in config:
        raise ConfigError(f"{source}: arm: missing required key")
    arm = _mapping(f"{source}: arm", config["arm"], _ARM_KEYS)
    check_keys(f"{source}: arm: ", arm, _ARM_KEYS)
    for key in ("root_link", "tip"):
        if not isinstance(arm.get(key), str):
            raise ConfigError(f"{source}: arm.{key}: missing or not a link name")
    lock = read_lock_joints(f"{source}: arm.lock_joints", arm.get("lock_joints"))
    as_written = read_flag(f"{source}: arm.inertia_as_written", arm.get("inertia_as_written", False))
    lock_others = read_flag(f"{source}: arm.lock_others", arm.get("lock_others", False))
    drop_others = read_flag(f"{source}: arm.drop_others", arm.get("drop_others", False))
    urdf = urdf_path(source, arm, os.fspath(base_dir))
    try:
        chain = read_urdf(
            urdf,
            root_link=arm["root_link"],
            tip=arm["tip"],
            lock_joints=lock,
            inertia_as_written=as_written,
            fields=f"{source}: arm.",
            lock_others=lock_others,
            drop_others=drop_others,
        )
    except ConfigError as error:  # a problem inside the URDF: name the robot file's field first
        if str(error).startswith(f"{source}: "):
            raise
        raise ConfigError(f"{source}: arm.urdf: {error}") from None
    try:
        return robot_from_chain(
            chain,
            base_mass=base_mass,
            base_com=base_com,
            base_inertia=base_inertia,
            mount_xyz=mount_xyz,
            mount_rpy=mount_rpy,
            name=name,
        )
    except ConfigError as error:
        raise ConfigError(f"{source}: {error}") from None


def load_spatial_robot(source: str | os.PathLike | Mapping[str, Any], *, base_dir=None) -> SpatialRobot:
    """Load and validate a spatial robot from a YAML file path or an already parsed mapping.

    Args:
        source: the robot file, or its parsed mapping.
        base_dir: where relative URDF paths start for a mapping (default: the current
            folder); for a file, its folder.

    Raises:
        ConfigError: for a missing or malformed file and for any invalid field.
    """
    if isinstance(source, Mapping):
        return spatial_robot_from_mapping(source, base_dir=base_dir or ".")
    path = os.fspath(source)
    config = read_yaml(path, what="robot file")
    return spatial_robot_from_mapping(config, source=path, base_dir=base_dir or os.path.dirname(path) or ".")
