"""The planar family's design: a planar serial chain of n >= 2 revolute links on a free base.

The design is data: every number a sweep or an optimizer may change is an array
leaf of `PlanarRobot`, so ``jit``, ``vmap`` and ``grad`` work over designs
and a batch of designs is the same pytree with a leading axis (Umetani & Yoshida
1990, Fig. 1 and Table 1, generalized to n links).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from ..._core.errors import ConfigError
from ..._core.labels import Label

__all__ = ["PlanarRobot", "stack_robots"]


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
        name: a label; static metadata, not traced, and ignored when JAX compares
            structures (renaming a design recompiles nothing).
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
    return children, Label(robot.name)


def _unflatten(name: str, children) -> PlanarRobot:
    # Bypass __init__: gradients, optimizer updates and batched placeholders are
    # PlanarRobot-shaped too, and must not be validated as physical designs.
    robot = object.__new__(PlanarRobot)
    for key, value in zip(_LEAF_FIELDS, children, strict=False):
        object.__setattr__(robot, key, value)
    object.__setattr__(robot, "name", str(name))
    return robot


jax.tree_util.register_pytree_with_keys(PlanarRobot, _flatten, _unflatten)


def _is_concrete(x) -> bool:
    if isinstance(x, jax.core.Tracer):
        return False
    return isinstance(x, (np.ndarray, np.generic, float, int, jax.Array))


def _looks_valid(robot: PlanarRobot) -> bool:
    """All checks of `_check_fields` in a few vectorized comparisons (NaN fails each one);
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
        (positive > 0).all()
        and (positive < np.inf).all()
        and (nonnegative >= 0).all()
        and (nonnegative < np.inf).all()
        and (link_a + np.asarray(robot.link_b) > 0).all()
        and (np.asarray(robot.joint_lower) < np.asarray(robot.joint_upper)).all()
    )


def _validate(robot: PlanarRobot) -> None:
    """Raise ConfigError naming the link and the field for a physically invalid design."""
    if not _looks_valid(robot):
        _check_fields(robot)


def _check_fields(robot: PlanarRobot) -> None:
    """The field-by-field checks behind `_validate`."""
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


def stack_robots(robots: list[PlanarRobot]) -> PlanarRobot:
    """Stack single designs (same n) into one batched design with a leading axis.

    Serves every family: spatial designs of one topology stack the same way (the
    result is the robots' own class).
    """
    if not robots:
        raise ValueError("stack_robots needs at least one robot")
    return jax.tree_util.tree_map(lambda *xs: np.stack([np.asarray(x) for x in xs]), *robots)
