"""The robot design: a planar serial chain of n >= 2 revolute links on a free base.

The design is data: every number a sweep or an optimizer may change is an array
leaf of :class:`PlanarRobot`, so ``jit``, ``vmap`` and ``grad`` work over designs
and a batch of designs is the same pytree with a leading axis (Umetani & Yoshida
1990, Fig. 1 and Table 1, generalized to n links).
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
from collections.abc import Mapping
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import yaml

__all__ = [
    "ConfigError",
    "PlanarRobot",
    "load_robot",
    "robot_from_mapping",
    "robot_to_mapping",
    "umetani1990",
    "stack_robots",
]


class ConfigError(ValueError):
    """A robot or sweep description is invalid; the message names the field and the reason."""


@dataclasses.dataclass(frozen=True)
class PlanarRobot:
    """A free-floating planar manipulator (link 0 is the base, links 1..n the arm).

    All leaves are arrays; a batch of designs carries the same leading axes on
    every leaf. SI units: kg, kg m^2, m, rad.

    Attributes:
        base_mass: ``(...)`` m_0, kg.
        base_inertia: ``(...)`` I_0 about the base centroid, kg m^2.
        base_attach: ``(...)`` b_0, base centroid -> joint 1 along the base x axis, m.
        link_mass: ``(..., n)`` m_i, kg.
        link_inertia: ``(..., n)`` I_i about each link centroid, kg m^2.
        link_a: ``(..., n)`` a_i, joint i -> centroid i, m.
        link_b: ``(..., n)`` b_i, centroid i -> joint i+1 (or the tip), m.
        joint_lower: ``(..., n)`` lower joint limits, rad (``-inf`` when free).
        joint_upper: ``(..., n)`` upper joint limits, rad (``+inf`` when free).
        name: a label; static metadata, not traced.
    """

    base_mass: jax.Array
    base_inertia: jax.Array
    base_attach: jax.Array
    link_mass: jax.Array
    link_inertia: jax.Array
    link_a: jax.Array
    link_b: jax.Array
    joint_lower: jax.Array = None  # type: ignore[assignment]
    joint_upper: jax.Array = None  # type: ignore[assignment]
    name: str = "robot"

    def __post_init__(self):
        # Fill free joint limits. Leaves that are not concrete numbers (tracers,
        # placeholders JAX uses while unflattening) pass through untouched.
        if self.joint_lower is None and _is_concrete(self.link_a):
            object.__setattr__(self, "joint_lower", jnp.full(jnp.shape(self.link_a), -jnp.inf))
        if self.joint_upper is None and _is_concrete(self.link_a):
            object.__setattr__(self, "joint_upper", jnp.full(jnp.shape(self.link_a), jnp.inf))
        if all(_is_concrete(x) for x in self._numbers()):
            _validate(self)

    def _numbers(self):
        return [getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "name"]

    # Derived quantities -------------------------------------------------------------
    @property
    def n_links(self) -> int:
        """Number of arm links n (static)."""
        return int(jnp.shape(self.link_a)[-1])

    @property
    def batch_shape(self) -> tuple[int, ...]:
        """Leading design-batch shape (``()`` for a single design)."""
        return tuple(jnp.shape(self.link_a)[:-1])

    @property
    def link_length(self) -> jax.Array:
        """``(..., n)`` l_i = a_i + b_i, m."""
        return self.link_a + self.link_b

    @property
    def reach(self) -> jax.Array:
        """``(...)`` L = sum of the arm link lengths, m (eq. 11)."""
        return jnp.sum(self.link_length, axis=-1)

    @property
    def total_mass(self) -> jax.Array:
        """``(...)`` w = m_0 + sum m_i, kg (eq. 1)."""
        return self.base_mass + jnp.sum(self.link_mass, axis=-1)

    def replace(self, **changes) -> PlanarRobot:
        """A copy with some fields changed (validated again when concrete)."""
        return dataclasses.replace(self, **changes)


_LEAF_FIELDS = tuple(f.name for f in dataclasses.fields(PlanarRobot) if f.name != "name")


def _flatten(robot: PlanarRobot):
    children = [(jax.tree_util.GetAttrKey(k), getattr(robot, k)) for k in _LEAF_FIELDS]
    return children, robot.name


def _unflatten(name: str, children) -> PlanarRobot:
    # Bypass __init__: gradients, optimizer updates and batched placeholders are
    # PlanarRobot-shaped too, and must not be validated as physical designs.
    robot = object.__new__(PlanarRobot)
    for key, value in zip(_LEAF_FIELDS, children):
        object.__setattr__(robot, key, value)
    object.__setattr__(robot, "name", name)
    return robot


jax.tree_util.register_pytree_with_keys(PlanarRobot, _flatten, _unflatten)


def _is_concrete(x) -> bool:
    if isinstance(x, jax.core.Tracer):
        return False
    return isinstance(x, (np.ndarray, np.generic, float, int, jax.Array))


def _looks_valid(robot: PlanarRobot) -> bool:
    """All checks of :func:`_check_fields` in a few vectorized comparisons (NaN fails each one);
    only a design that fails them pays for the field-by-field pass that names the culprit.
    Keeps building designs in a Python loop cheap (~10x faster than the detailed pass)."""
    link_a = np.asarray(robot.link_a)
    if link_a.ndim < 1 or link_a.shape[-1] < 2:
        return False
    n = link_a.shape[-1]
    positive = [robot.base_mass, robot.base_inertia, robot.link_mass, robot.link_inertia]
    nonnegative = [robot.base_attach, robot.link_a, robot.link_b]
    per_link = [robot.link_mass, robot.link_inertia, robot.link_b, robot.joint_lower, robot.joint_upper]
    if any(np.shape(v)[-1:] != (n,) for v in per_link):
        return False
    positive, nonnegative = (np.concatenate([np.ravel(v) for v in group]) for group in (positive, nonnegative))
    return bool(
        (positive > 0).all() and (positive < np.inf).all()
        and (nonnegative >= 0).all() and (nonnegative < np.inf).all()
        and (link_a + np.asarray(robot.link_b) > 0).all()
        and (np.asarray(robot.joint_lower) < np.asarray(robot.joint_upper)).all()
    )


def _validate(robot: PlanarRobot) -> None:
    """Raise ConfigError naming the link and the field for a physically invalid design."""
    if not _looks_valid(robot):
        _check_fields(robot)


def _check_fields(robot: PlanarRobot) -> None:
    """The field-by-field checks behind :func:`_validate`."""
    link_a = np.asarray(robot.link_a)
    if link_a.ndim < 1:
        raise ConfigError("links: the per-link arrays need a trailing link axis")
    n = link_a.shape[-1]
    if n < 2:
        raise ConfigError(f"links: at least 2 links are required, got {n}")
    scalars = {
        "base.mass": (robot.base_mass, "positive"),
        "base.inertia": (robot.base_inertia, "positive"),
        "base.attach": (robot.base_attach, "nonnegative"),
    }
    for field, (value, rule) in scalars.items():
        _check_values(field, np.asarray(value), rule)
    per_link = {
        "mass": (robot.link_mass, "positive"),
        "a": (robot.link_a, "nonnegative"),
        "b": (robot.link_b, "nonnegative"),
        "inertia": (robot.link_inertia, "positive"),
    }
    for field, (value, rule) in per_link.items():
        value = np.asarray(value)
        if value.shape[-1:] != (n,):
            raise ConfigError(f"links[*].{field}: expected {n} values, got shape {value.shape}")
        for i in range(n):
            _check_values(f"links[{i}].{field}", value[..., i], rule)
        if field == "b":  # a zero length first: it also zeroes an inertia scaled with the length
            length = np.asarray(robot.link_a) + value
            for i in range(n):
                if np.any(length[..., i] <= 0):
                    raise ConfigError(f"links[{i}]: the length a + b must be positive")
    lower, upper = np.asarray(robot.joint_lower), np.asarray(robot.joint_upper)
    for i in range(n):
        if np.any(np.isnan(lower[..., i])) or np.any(np.isnan(upper[..., i])):
            raise ConfigError(f"links[{i}].limit: joint limits must not be NaN")
        if np.any(lower[..., i] >= upper[..., i]):
            raise ConfigError(f"links[{i}].limit: the lower limit must be below the upper limit")


def _check_values(field: str, value: np.ndarray, rule: str) -> None:
    if not np.all(np.isfinite(value)):
        raise ConfigError(f"{field}: must be a finite number, got {_show(value)}")
    if rule == "positive" and np.any(value <= 0):
        raise ConfigError(f"{field}: must be positive, got {_show(value)}")
    if rule == "nonnegative" and np.any(value < 0):
        raise ConfigError(f"{field}: must not be negative, got {_show(value)}")


def _show(value: np.ndarray) -> str:
    return str(value.item()) if value.size == 1 else np.array2string(value, threshold=6)


# YAML ------------------------------------------------------------------------------

_TOP_KEYS = {"name", "description", "base", "links"}
_BASE_KEYS = {"mass", "inertia", "attach"}
_LINK_KEYS = {"mass", "inertia", "a", "b", "limit", "limit_deg"}


def _unknown_keys(where: str, mapping: Mapping, allowed: set[str]) -> None:
    for key in mapping:
        if key not in allowed:
            hint = difflib.get_close_matches(str(key), sorted(allowed), n=1)
            extra = f" (did you mean '{hint[0]}'?)" if hint else ""
            allowed_list = ", ".join(sorted(allowed))
            raise ConfigError(f"{where}unknown key '{key}'{extra}; allowed keys: {allowed_list}")


def _number(where: str, mapping: Mapping, key: str) -> float:
    if key not in mapping:
        raise ConfigError(f"{where}{key}: missing required key")
    value = mapping[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{where}{key}: must be a number, got {type(value).__name__} {value!r}")
    if not math.isfinite(value):
        raise ConfigError(f"{where}{key}: must be a finite number, got {value!r}")
    return float(value)


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
    """Build a validated :class:`PlanarRobot` from the YAML schema of DESIGN.md.

    Args:
        config: the parsed mapping (``name``, ``base: {mass, inertia, attach}``,
            ``links: [{mass, inertia, a, b, limit | limit_deg}, ...]``).
        source: a label for error messages (usually the file name).

    Raises:
        ConfigError: naming the field and the reason.
    """
    if not isinstance(config, Mapping):
        raise ConfigError(f"{source}: the robot description must be a mapping, got {type(config).__name__}")
    _unknown_keys(f"{source}: ", config, _TOP_KEYS)
    name = config.get("name", "robot")
    if not isinstance(name, str):
        raise ConfigError(f"{source}: name: must be a string, got {name!r}")
    if "base" not in config:
        raise ConfigError(f"{source}: base: missing required key")
    base = config["base"]
    if not isinstance(base, Mapping):
        raise ConfigError(f"{source}: base: must be a mapping with keys mass, inertia, attach")
    _unknown_keys(f"{source}: base: ", base, _BASE_KEYS)
    base_values = {k: _number(f"{source}: base.", base, k) for k in ("mass", "inertia", "attach")}
    if "links" not in config:
        raise ConfigError(f"{source}: links: missing required key")
    links = config["links"]
    if not isinstance(links, (list, tuple)):
        raise ConfigError(f"{source}: links: must be a list of link mappings")
    if len(links) < 2:
        raise ConfigError(f"{source}: links: at least 2 links are required, got {len(links)}")
    columns: dict[str, list[float]] = {k: [] for k in ("mass", "inertia", "a", "b", "lower", "upper")}
    for i, link in enumerate(links):
        where = f"{source}: links[{i}]"
        if not isinstance(link, Mapping):
            raise ConfigError(f"{where}: must be a mapping with keys mass, inertia, a, b")
        _unknown_keys(f"{where}: ", link, _LINK_KEYS)
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


def describe_yaml_error(error: yaml.YAMLError) -> str:
    """One line for a YAML syntax error: ``line L, column C: what is wrong``."""
    mark = getattr(error, "problem_mark", None)
    problem = getattr(error, "problem", None) or str(error).splitlines()[0]
    where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
    return f"malformed YAML at {where}{problem}"


def load_robot(source: str | os.PathLike | Mapping[str, Any]) -> PlanarRobot:
    """Load and validate a robot from a YAML file path or an already parsed mapping.

    Raises:
        ConfigError: for a missing or malformed file and for any invalid field.
    """
    if isinstance(source, Mapping):
        return robot_from_mapping(source)
    path = os.fspath(source)
    try:
        with open(path, encoding="utf-8") as handle:
            config = yaml.safe_load(handle)
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such robot file") from None
    except IsADirectoryError:
        raise ConfigError(f"{path}: is a directory, not a robot file") from None
    except yaml.YAMLError as error:
        raise ConfigError(f"{path}: {describe_yaml_error(error)}") from None
    return robot_from_mapping(config, source=path)


def robot_to_mapping(robot: PlanarRobot) -> dict[str, Any]:
    """The YAML mapping of a single design (inverse of :func:`robot_from_mapping`)."""
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


def stack_robots(robots: list[PlanarRobot]) -> PlanarRobot:
    """Stack single designs (same n) into one batched design with a leading axis."""
    if not robots:
        raise ValueError("stack_robots needs at least one robot")
    return jax.tree_util.tree_map(lambda *xs: np.stack([np.asarray(x) for x in xs]), *robots)
