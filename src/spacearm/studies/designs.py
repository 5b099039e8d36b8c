"""Design construction for a sweep: the design fields an axis may set, how each is
applied, and every sweep point as one batched robot (planar or spatial).

Planar fields: ``base.mass``, ``base.inertia``, ``base.attach``, ``links[i].FIELD`` or
``links[*].FIELD`` (mass, inertia, a, b, length), and the derived ``arm.mass``,
``arm.mass_ratio`` and ``arm.length_split`` (see `FIELD_HELP`).

Spatial fields (``mount.xyz[i]``, ``mount.rpy[i]``, ``base.com[i]``, ``arm.length``,
``links.<name>.mass``, ...) live with the spatial family,
`spacearm.models.spatial.fields` (`SPATIAL_FIELD_HELP`), shared with the
design problems; this module dispatches on the base robot's type.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Sequence
from typing import Any, Protocol

import jax
import numpy as np

from .._core.errors import ConfigError
from .._core.schema import did_you_mean
from ..models.planar import PlanarRobot
from ..models.spatial import SpatialRobot
from ..models.spatial import fields as spatial_fields

__all__ = [
    "Axis",
    "FIELD_HELP",
    "SPATIAL_FIELD_HELP",
    "SIMPLE_FIELDS",
    "DERIVED_FIELDS",
    "check_field",
    "check_axes_compatible",
    "axis_points",
    "build_designs",
    "design_columns",
    "axis_unit",
]


@dataclasses.dataclass(frozen=True)
class Axis:
    """One design axis: a field, its values, absolute or relative to the base design."""

    name: str
    field: str
    values: np.ndarray
    relative: bool = False
    family: str = "planar"  # the base robot's family: field names mean different things in each


class SweepSpec(Protocol):
    """What design construction reads of a sweep (`spacearm.studies.spec.SweepSpec`)."""

    robot: PlanarRobot | SpatialRobot
    axes: tuple[Axis, ...]
    combine: str
    source: str

    @property
    def n_designs(self) -> int: ...


_LINK_FIELD = re.compile(r"^links\[(\d+|\*)\]\.(mass|inertia|a|b|length)$")
SIMPLE_FIELDS = {
    "base.mass": ("base_mass", "kg"),
    "base.inertia": ("base_inertia", "kg_m2"),
    "base.attach": ("base_attach", "m"),
}
DERIVED_FIELDS = {
    "arm.mass": "kg",
    "arm.mass_ratio": "1",
    "arm.length_split": "1",
}
SPATIAL_FIELD_HELP = spatial_fields.FIELD_HELP
FIELD_HELP = (
    "base.mass | base.inertia | base.attach | links[i].FIELD or links[*].FIELD with FIELD in "
    "mass, inertia, a, b, length (a and b scaled together, inertia with the square) | "
    "arm.mass (link masses and inertias scaled together) | arm.mass_ratio (arm mass / base mass) | "
    "arm.length_split (l1 / L at fixed L; the other links scaled together)"
)


def check_field(where: str, field: Any, robot: PlanarRobot | SpatialRobot | int) -> str:
    """The field name of an axis, or `ConfigError` naming ``where`` (with a did-you-mean).

    ``robot``: the sweep's base robot (a planar robot's link count is accepted too)."""
    if isinstance(robot, SpatialRobot):
        return spatial_fields.check_field(where, field, robot)
    n_links = robot if isinstance(robot, int) else robot.n_links
    if not isinstance(field, str):
        raise ConfigError(f"{where}.field: must be a string, one of: {FIELD_HELP}")
    if field in SIMPLE_FIELDS or field in DERIVED_FIELDS:
        if field == "arm.length_split" and n_links < 2:
            raise ConfigError(f"{where}.field: arm.length_split needs at least 2 links")
        return field
    match = _LINK_FIELD.match(field)
    if match:
        index = match.group(1)
        if index != "*" and int(index) >= n_links:
            raise ConfigError(f"{where}.field: link index {index} out of range; the robot has {n_links} links (0..{n_links - 1})")
        return field
    known = sorted(SIMPLE_FIELDS) + sorted(DERIVED_FIELDS) + [f"links[0].{k}" for k in ("mass", "inertia", "a", "b", "length")]
    raise ConfigError(f"{where}.field: unknown design field '{field}'{did_you_mean(field, known)}; fields: {FIELD_HELP}")


def axis_points(spec: SweepSpec) -> dict[str, np.ndarray]:
    """The value of every axis at every sweep point, flattened (product: C order)."""
    if spec.combine == "zip":
        return {a.name: a.values.copy() for a in spec.axes}
    mesh = np.meshgrid(*[a.values for a in spec.axes], indexing="ij")
    return {a.name: m.reshape(-1) for a, m in zip(spec.axes, mesh)}


def _leaves(robot: PlanarRobot, count: int) -> dict[str, np.ndarray]:
    fields = ("base_mass", "base_inertia", "base_attach", "link_mass", "link_inertia", "link_a", "link_b",
              "joint_lower", "joint_upper")
    return {f: np.repeat(np.asarray(getattr(robot, f), dtype=np.float64)[None], count, axis=0) for f in fields}


def _apply(leaves: dict[str, np.ndarray], field: str, values: np.ndarray, relative: bool) -> None:
    """Set one design field to per-point values (vectorized over the sweep points)."""
    if field in SIMPLE_FIELDS:
        key = SIMPLE_FIELDS[field][0]
        leaves[key] = leaves[key] * values if relative else values.copy()
        return
    match = _LINK_FIELD.match(field)
    if match:
        index, what = match.groups()
        links = slice(None) if index == "*" else int(index)
        if what == "length":
            length = leaves["link_a"][:, links] + leaves["link_b"][:, links]
            target = values[:, None] if index == "*" else values
            factor = target if relative else target / length
            leaves["link_a"][:, links] *= factor
            leaves["link_b"][:, links] *= factor
            leaves["link_inertia"][:, links] *= factor**2
            return
        key = {"mass": "link_mass", "inertia": "link_inertia", "a": "link_a", "b": "link_b"}[what]
        column = values[:, None] if index == "*" else values
        if relative:
            leaves[key][:, links] *= column
        else:
            leaves[key][:, links] = column
        return
    arm_mass = leaves["link_mass"].sum(axis=1)
    if field in ("arm.mass", "arm.mass_ratio"):
        current = arm_mass if field == "arm.mass" else arm_mass / leaves["base_mass"]
        factor = values if relative else values / current
        leaves["link_mass"] *= factor[:, None]
        leaves["link_inertia"] *= factor[:, None]
        return
    if field == "arm.length_split":
        lengths = leaves["link_a"] + leaves["link_b"]
        reach = lengths.sum(axis=1)
        split = values * lengths[:, 0] / reach if relative else values
        factors = np.empty_like(lengths)
        factors[:, 0] = split * reach / lengths[:, 0]
        rest = lengths[:, 1:].sum(axis=1)
        factors[:, 1:] = ((1.0 - split) * reach / rest)[:, None]
        leaves["link_a"] *= factors
        leaves["link_b"] *= factors
        leaves["link_inertia"] *= factors**2
        return
    raise ConfigError(f"unknown design field {field!r}")  # unreachable after validation


def _stage(field: str) -> int:
    """When an axis is applied: numbers of the base and the links first, then the arm's
    length split (at fixed L), then the arm's mass (its ratio against the final base mass)."""
    return {"arm.length_split": 1, "arm.mass": 2, "arm.mass_ratio": 2}.get(field, 0)


def _writes(field: str, n_links: int) -> set[str]:
    """The design numbers an axis sets, as ``leaf[i]`` names."""
    links = range(n_links)
    if field in SIMPLE_FIELDS:
        return {SIMPLE_FIELDS[field][0]}
    if field in ("arm.mass", "arm.mass_ratio"):
        return {f"{leaf}[{i}]" for leaf in ("link_mass", "link_inertia") for i in links}
    if field == "arm.length_split":
        return {f"{leaf}[{i}]" for leaf in ("link_a", "link_b", "link_inertia") for i in links}
    index, what = _LINK_FIELD.match(field).groups()
    chosen = links if index == "*" else [int(index)]
    leaves = {"mass": ["link_mass"], "inertia": ["link_inertia"], "a": ["link_a"], "b": ["link_b"],
              "length": ["link_a", "link_b", "link_inertia"]}[what]
    return {f"{leaf}[{i}]" for leaf in leaves for i in chosen}


def check_axes_compatible(where: str, axes: Sequence[Axis], robot: PlanarRobot | SpatialRobot | int) -> None:
    """Refuse two axes that set the same design number: the result would depend on the
    order of application. A length axis and an arm-mass axis both scale the link
    inertias, by commuting factors, so such pairs are allowed."""
    if isinstance(robot, SpatialRobot):
        for i, first in enumerate(axes):
            for second in axes[i + 1:]:
                shared = (spatial_fields.field_writes(first.field, robot)
                          & spatial_fields.field_writes(second.field, robot))
                if shared:
                    raise ConfigError(
                        f"{where}: axes.{first.name} ({first.field}) and axes.{second.name} ({second.field}) both set "
                        f"{sorted(shared)[0]}; give each design number one axis")
        return
    n_links = robot if isinstance(robot, int) else robot.n_links
    for i, first in enumerate(axes):
        for second in axes[i + 1:]:
            shared = _writes(first.field, n_links) & _writes(second.field, n_links)
            if {_scaling(first.field), _scaling(second.field)} == {"length", "mass"}:
                shared = {name for name in shared if not name.startswith("link_inertia")}
            if shared:
                raise ConfigError(
                    f"{where}: axes.{first.name} ({first.field}) and axes.{second.name} ({second.field}) both set "
                    f"{_leaf_label(sorted(shared)[0])}; give each design number one axis"
                )


def _scaling(field: str) -> str | None:
    """'length' or 'mass' for fields that change link inertias by a factor (length^2 or
    mass); such factors commute, so a length axis and a mass axis may share inertias."""
    if field == "arm.length_split" or field.endswith("].length"):
        return "length"
    if field in ("arm.mass", "arm.mass_ratio"):
        return "mass"
    return None


def _leaf_label(name: str) -> str:
    """``link_inertia[0]`` -> ``links[0].inertia``; ``base_mass`` -> ``base.mass``."""
    match = re.fullmatch(r"link_(\w+)\[(\d+)\]", name)
    if match:
        return f"links[{match.group(2)}].{match.group(1)}"
    return name.replace("_", ".", 1)


def build_designs(spec: SweepSpec) -> tuple[PlanarRobot, dict[str, np.ndarray]]:
    """Every sweep point as one batched PlanarRobot, and the axis values per point.

    Axes are applied in a fixed order whatever their order in the file (see ``_stage``).

    Raises:
        ConfigError: naming the first invalid sweep point, its axis values and the field.
    """
    points = axis_points(spec)
    count = spec.n_designs
    if isinstance(spec.robot, SpatialRobot):
        return _build_spatial(spec, points, count), points
    leaves = _leaves(spec.robot, count)
    for axis in sorted(spec.axes, key=lambda a: _stage(a.field)):
        _apply(leaves, axis.field, points[axis.name], axis.relative)
    try:
        robot = PlanarRobot(**leaves, name=spec.robot.name)
    except ConfigError:
        for i in range(count):  # error path only: find and name the first bad point
            try:
                PlanarRobot(**{k: v[i] for k, v in leaves.items()}, name=spec.robot.name)
            except ConfigError as error:
                at = ", ".join(f"{name}={points[name][i]:g}" for name in points)
                raise ConfigError(f"{spec.source}: sweep point {i} ({at}) gives an invalid robot: {error}") from None
        raise
    return robot, points


def _build_spatial(spec: SweepSpec, points: dict[str, np.ndarray], count: int) -> SpatialRobot:
    """Every sweep point as one batched SpatialRobot (fields applied in numpy, then validated)."""
    robot = jax.tree_util.tree_map(lambda x: np.repeat(np.asarray(x, dtype=np.float64)[None], count, axis=0),
                                   spec.robot)
    for axis in sorted(spec.axes, key=lambda a: spatial_fields.field_stage(a.field)):
        robot = spatial_fields.set_field(robot, axis.field, points[axis.name], axis.relative)
    try:
        return robot.replace()  # validated (every design)
    except ConfigError:
        for i in range(count):  # error path only: find and name the first bad point
            try:
                jax.tree_util.tree_map(lambda x: x[i], robot).replace()
            except ConfigError as error:
                at = ", ".join(f"{name}={points[name][i]:g}" for name in points)
                raise ConfigError(f"{spec.source}: sweep point {i} ({at}) gives an invalid robot: {error}") from None
        raise


def design_columns(robot: PlanarRobot | SpatialRobot, axes: Sequence[Axis]) -> dict[str, np.ndarray]:
    """The varied design numbers per point, SI units in the column names."""
    if isinstance(robot, SpatialRobot):
        return spatial_fields.field_columns(robot, [axis.field for axis in axes])
    columns: dict[str, np.ndarray] = {}
    for axis in axes:
        if axis.field in SIMPLE_FIELDS:
            key, unit = SIMPLE_FIELDS[axis.field]
            columns[f"{key}_{unit}"] = np.asarray(getattr(robot, key))
        elif axis.field in ("arm.mass", "arm.mass_ratio"):
            columns["arm_mass_kg"] = np.asarray(robot.link_mass).sum(axis=1)
        else:
            lengths = np.asarray(robot.link_length)
            for i in range(lengths.shape[1]):
                columns[f"l{i + 1}_m"] = lengths[:, i]
            if axis.field.endswith((".mass", ".inertia")):
                for i in range(lengths.shape[1]):
                    columns[f"m{i + 1}_kg"] = np.asarray(robot.link_mass)[:, i]
    return columns


def axis_unit(axis: Axis) -> str:
    """The unit of an axis's values: "relative" for a relative axis, else the field's SI unit
    ("1" for a ratio)."""
    if axis.relative:
        return "relative"
    if axis.family == "spatial":
        return spatial_fields.field_unit(axis.field).replace("1", "factor" if axis.field in
                                                             spatial_fields.FACTOR_FIELDS else "1")
    if axis.field in SIMPLE_FIELDS:
        return SIMPLE_FIELDS[axis.field][1].replace("_m2", " m^2")
    if axis.field in DERIVED_FIELDS:
        return DERIVED_FIELDS[axis.field]
    return {"mass": "kg", "inertia": "kg m^2"}.get(axis.field.rsplit(".", 1)[1], "m")
