"""Design construction for a sweep: the design fields an axis may set, how each is
applied, and every sweep point as one batched robot (planar or spatial).

The fields live with each family (`RobotFamily.fields`: `spacearm.models.planar.fields`,
`spacearm.models.spatial.fields`, `spacearm.models.tree.fields`), shared with the design problems; this module asks
the base robot's family.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any, Protocol

import jax
import numpy as np

from .._core.errors import ConfigError
from ..models.family import family_of, known_families

__all__ = [
    "DERIVED_FIELDS",
    "FIELD_HELP",
    "SIMPLE_FIELDS",
    "Axis",
    "axis_points",
    "axis_unit",
    "build_designs",
    "check_axes_compatible",
    "check_field",
    "design_columns",
]


@dataclasses.dataclass(frozen=True)
class Axis:
    """One design axis: a field, its values, absolute or relative to the base design."""

    name: str
    field: str
    values: np.ndarray
    relative: bool = False
    unit: str = ""  # of the values: the field's SI unit, "factor", "1" (a ratio) or "relative"


class SweepSpec(Protocol):
    """What design construction reads of a sweep (`spacearm.studies.spec.SweepSpec`)."""

    robot: Any  # a robot of any family (`spacearm.models.family_of` gives its record)
    axes: tuple[Axis, ...]
    combine: str
    source: str

    @property
    def n_designs(self) -> int: ...


# The design fields of every family, one line each (a robot's own: ``family_of(robot).fields.FIELD_HELP``).
FIELD_HELP = "\n".join(f"{family.name} robots: {family.fields.FIELD_HELP}" for family in known_families())
SIMPLE_FIELDS = {
    "base.mass": ("base_mass", "kg"),
    "base.inertia": ("base_inertia", "kg_m2"),
    "base.attach": ("base_attach", "m"),
}
DERIVED_FIELDS = {"arm.mass": "kg", "arm.mass_ratio": "1", "arm.length_split": "1"}


def check_field(where: str, field: Any, robot: Any) -> str:
    """The field name of an axis, or `ConfigError` naming ``where`` (with a did-you-mean).

    ``robot``: the sweep's base robot (its family's `RobotFamily.fields` name the fields)."""
    return family_of(robot).fields.check_field(where, field, robot)


def axis_points(spec: SweepSpec) -> dict[str, np.ndarray]:
    """The value of every axis at every sweep point, flattened (product: C order)."""
    if spec.combine == "zip":
        return {a.name: a.values.copy() for a in spec.axes}
    mesh = np.meshgrid(*[a.values for a in spec.axes], indexing="ij")
    return {a.name: m.reshape(-1) for a, m in zip(spec.axes, mesh, strict=False)}


def check_axes_compatible(where: str, axes: Sequence[Axis], robot: Any) -> None:
    """Refuse two axes that set the same design number: the result would depend on the
    order of application (the family's `conflicting_number`)."""
    fields = family_of(robot).fields
    for i, first in enumerate(axes):
        for second in axes[i + 1 :]:
            shared = fields.conflicting_number(first.field, second.field, robot)
            if shared:
                raise ConfigError(
                    f"{where}: axes.{first.name} ({first.field}) and axes.{second.name} ({second.field}) both set "
                    f"{shared}; give each design number one axis"
                )


def build_designs(spec: SweepSpec) -> tuple[Any, dict[str, np.ndarray]]:
    """Every sweep point as one batched robot of the base robot's family, and the axis values per point.

    Axes are applied in a fixed order whatever their order in the file (the family's
    ``field_stage``), in numpy, then every design is validated.

    Raises:
        ConfigError: naming the first invalid sweep point, its axis values and the field.
    """
    points = axis_points(spec)
    count = spec.n_designs
    fields = family_of(spec.robot).fields
    robot = jax.tree_util.tree_map(
        lambda x: np.repeat(np.asarray(x, dtype=np.float64)[None], count, axis=0), spec.robot
    )
    for axis in sorted(spec.axes, key=lambda a: fields.field_stage(a.field)):
        robot = fields.set_field(robot, axis.field, points[axis.name], axis.relative)
    try:
        return robot.replace(), points  # validated (every design)
    except ConfigError:
        for i in range(count):  # error path only: find and name the first bad point
            try:
                jax.tree_util.tree_map(lambda x, i=i: x[i], robot).replace()
            except ConfigError as error:
                at = ", ".join(f"{name}={points[name][i]:g}" for name in points)
                raise ConfigError(f"{spec.source}: sweep point {i} ({at}) gives an invalid robot: {error}") from None
        raise


def design_columns(robot: Any, axes: Sequence[Axis]) -> dict[str, np.ndarray]:
    """The varied design numbers per point, SI units in the column names."""
    return family_of(robot).fields.field_columns(robot, [axis.field for axis in axes])


def axis_unit(axis: Axis) -> str:
    """The unit of an axis's values (`field_axis_unit` of its field, set when the sweep was read)."""
    return axis.unit


def field_axis_unit(robot, field: str, relative: bool) -> str:
    """The unit of an axis over ``field`` on ``robot``'s family: "relative" for a relative axis,
    else the field's SI unit ("1" for a ratio, "factor" for a factor field)."""
    if relative:
        return "relative"
    fields = family_of(robot).fields
    return "factor" if field in fields.FACTOR_FIELDS else fields.field_unit(field)
