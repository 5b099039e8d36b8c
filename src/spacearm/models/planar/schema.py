"""The planar robot file (``base`` and ``links``): mapping <-> `PlanarRobot`."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..._core.errors import ConfigError
from ..._core.schema import check_keys, number, robot_file_name
from .robot import PlanarRobot

__all__ = ["is_planar_mapping", "robot_from_mapping", "robot_to_mapping", "umetani1990"]


def is_planar_mapping(config: Any) -> bool:
    """Whether a parsed file describes a planar robot (``base`` and ``links``, no ``arm``)."""
    return isinstance(config, Mapping) and "arm" not in config and ("links" in config or "base" in config)


_TOP_KEYS = {"name", "description", "base", "links"}
# Links of a planar arm: the reach planner's compile and memory grow steeply with them
# (16 links: about 3 minutes and 4.4 GB on two cores).
MAX_PLANAR_LINKS = 16
_BASE_KEYS = {"mass", "inertia", "attach"}
_LINK_KEYS = {"mass", "inertia", "a", "b", "limit", "limit_deg"}


def _number(where: str, mapping: Mapping, key: str) -> float:
    if key not in mapping:
        raise ConfigError(f"{where}{key}: missing required key")
    return number(f"{where}{key}", mapping[key])


def _limits(where: str, link: Mapping) -> tuple[float, float]:
    if "limit" in link and "limit_deg" in link:
        raise ConfigError(f"{where}: give either 'limit' (rad) or 'limit_deg', not both")
    for key, scale in (("limit", 1.0), ("limit_deg", math.pi / 180.0)):
        if key in link:
            value = link[key]
            if (
                not isinstance(value, (list, tuple))
                or len(value) != 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
            ):
                raise ConfigError(f"{where}.{key}: must be a list [lower, upper] of two numbers")
            lower, upper = float(value[0]) * scale, float(value[1]) * scale
            if math.isnan(lower) or math.isnan(upper) or lower >= upper:
                raise ConfigError(f"{where}.{key}: the lower limit must be below the upper limit")
            return lower, upper
    return -math.inf, math.inf


def robot_from_mapping(config: Mapping[str, Any], *, source: str = "robot") -> PlanarRobot:
    """Build a validated `PlanarRobot` from the planar robot file's mapping.

    Args:
        config: the parsed mapping (``name``, ``base: {mass, inertia, attach}``,
            ``links: [{mass, inertia, a, b, limit | limit_deg}, ...]``).
        source: a label for error messages (usually the file name).

    Raises:
        ConfigError: naming the field and the reason.
    """
    name = robot_file_name(source, config, _TOP_KEYS)
    base = config["base"]
    if not isinstance(base, Mapping):
        raise ConfigError(f"{source}: base: must be a mapping with keys mass, inertia, attach")
    check_keys(f"{source}: base: ", base, _BASE_KEYS)
    base_values = {k: _number(f"{source}: base.", base, k) for k in ("mass", "inertia", "attach")}
    if "links" not in config:
        raise ConfigError(f"{source}: links: missing required key")
    links = config["links"]
    if not isinstance(links, (list, tuple)):
        raise ConfigError(f"{source}: links: must be a list of link mappings")
    if not 2 <= len(links) <= MAX_PLANAR_LINKS:
        raise ConfigError(f"{source}: links: 2 to {MAX_PLANAR_LINKS} links are supported, got {len(links)}")
    columns: dict[str, list[float]] = {k: [] for k in ("mass", "inertia", "a", "b", "lower", "upper")}
    for i, link in enumerate(links):
        where = f"{source}: links[{i}]"
        if not isinstance(link, Mapping):
            raise ConfigError(f"{where}: must be a mapping with keys mass, inertia, a, b")
        check_keys(f"{where}: ", link, _LINK_KEYS)
        for key in ("mass", "inertia", "a", "b"):
            columns[key].append(_number(f"{where}.", link, key))
        lower, upper = _limits(where, link)
        columns["lower"].append(lower)
        columns["upper"].append(upper)
    try:
        return PlanarRobot(
            base_mass=np.float64(base_values["mass"]),
            base_inertia=np.float64(base_values["inertia"]),
            base_attach=np.float64(base_values["attach"]),
            link_mass=np.array(columns["mass"]),
            link_inertia=np.array(columns["inertia"]),
            link_a=np.array(columns["a"]),
            link_b=np.array(columns["b"]),
            joint_lower=np.array(columns["lower"]),
            joint_upper=np.array(columns["upper"]),
            name=name,
        )
    except ConfigError as error:
        raise ConfigError(f"{source}: {error}") from None


def robot_to_mapping(robot: PlanarRobot) -> dict[str, Any]:
    """The YAML mapping of a single design (inverse of `robot_from_mapping`)."""
    if robot.batch_shape:
        raise ValueError("robot_to_mapping takes a single design, not a batch")
    links = []
    for i in range(robot.n_links):
        link = {
            "mass": float(robot.link_mass[i]),
            "inertia": float(robot.link_inertia[i]),
            "a": float(robot.link_a[i]),
            "b": float(robot.link_b[i]),
        }
        lower, upper = float(robot.joint_lower[i]), float(robot.joint_upper[i])
        if math.isfinite(lower) or math.isfinite(upper):
            link["limit"] = [lower, upper]
        links.append(link)
    return {
        "name": robot.name,
        "base": {
            "mass": float(robot.base_mass),
            "inertia": float(robot.base_inertia),
            "attach": float(robot.base_attach),
        },
        "links": links,
    }


def umetani1990() -> PlanarRobot:
    """Table 1 of Umetani & Yoshida 1990: 1000 kg base, two 2 m, 100 kg links."""
    return robot_from_mapping(
        {
            "name": "umetani1990",
            "base": {"mass": 1000.0, "inertia": 635.3, "attach": 1.4},
            "links": [
                {"mass": 100.0, "inertia": 33.3, "a": 1.0, "b": 1.0},
                {"mass": 100.0, "inertia": 33.3, "a": 1.0, "b": 1.0},
            ],
        },
        source="umetani1990",
    )
