"""Named design numbers of a spatial robot: the fields a sweep axis or a design variable sets.

One home for what a field name means, shared by sweeps (`spacearm.studies`, numpy
over many sweep points at once) and design problems (`spacearm.design`, traced
under ``jit``/``grad``). Every function here works on a single design or on a batch
(leading axes on every leaf, ``value`` with the batch shape) and with numpy or JAX
arrays alike.

Fields:

=========================  =========  ==========================================================
field                      value      what it sets
=========================  =========  ==========================================================
``mount.xyz[i]``           m          the root-link origin in the bus frame, component i (0..2)
``mount.rpy[i]``           rad        the mount attitude, URDF roll, pitch, yaw (i = 0, 1, 2)
``mount.rpy_deg[i]``       deg        the same in degrees
``base.mass``              kg         the bus mass (inertia unchanged)
``base.inertia``           factor     the bus 3x3 inertia times the value
``base.com[i]``            m          the bus centroid in the bus frame, component i
``arm.mass``               factor     every arm body (root body and links): masses and
                                      inertias times the value (the shape is kept)
``arm.mass_ratio``         1          arm mass / bus mass, reached by scaling the arm's masses
                                      and inertias at fixed bus mass
``arm.length``             factor     the arm's geometry times the value: joint placements,
                                      body centroids and the tip offset times s, body inertias
                                      times s^2 (masses kept: I = m r^2 with r times s), prismatic
                                      joint limits times s; the mount pose is the bus's and stays
``links.<name>.mass``      kg         the mass of the body whose first URDF link is ``<name>``
                                      (the root link too); its inertia scales with it (the radius
                                      of gyration is kept; a body of zero mass keeps its inertia)
``links.<name>.length``    factor     that body's geometry times the value: the placement of the
                                      next joint, the body's centroid offset and the tip offset
                                      if the body carries the tip times s, its inertia about the
                                      centroid times s^2 (mass kept); 1 is the identity
=========================  =========  ==========================================================

The "arm" is everything read from the URDF: the root body (root link and its rigid
attachments) and the n moving bodies. ``relative: true`` on an absolute field multiplies
the base design's value; on a factor field (``base.inertia``, ``arm.mass``,
``arm.length``) it changes nothing, the value being a factor already.
"""

from __future__ import annotations

import re
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from ..._core.errors import ConfigError
from ..._core.schema import did_you_mean
from .robot import SpatialRobot

__all__ = [
    "FACTOR_FIELDS",
    "FIELD_HELP",
    "arm_mass",
    "canonical_name",
    "check_field",
    "conflicting_number",
    "field_columns",
    "field_stage",
    "field_unit",
    "field_writes",
    "path_length",
    "set_field",
]

FIELD_HELP = (
    "mount.xyz[i] (m) | mount.rpy[i] (rad) | mount.rpy_deg[i] | base.mass (kg) | base.inertia (a factor on "
    "the 3x3) | base.com[i] (m) | arm.mass (a factor on every arm mass and inertia) | arm.mass_ratio "
    "(arm mass / bus mass) | arm.length (a factor on the arm's geometry; inertias with its square) | "
    "links.<name>.mass (kg; the body's inertia scales with it) | links.<name>.length (a factor on that body's "
    "geometry: next joint, centroid, tip; its inertia with the square)"
)
FACTOR_FIELDS = ("base.inertia", "arm.mass", "arm.length")
_INDEXED = re.compile(r"^(mount\.xyz|mount\.rpy|mount\.rpy_deg|base\.com)\[(-?\d+)\]$")
_LINK = re.compile(r"^links\.([^.\[\]]+)\.(\w+)$")
_PLAIN = ("base.mass", "base.inertia", "arm.mass", "arm.mass_ratio", "arm.length")
_AXIS_NAMES = {
    "mount.xyz": "xyz",
    "mount.rpy": ("roll", "pitch", "yaw"),
    "mount.rpy_deg": ("roll", "pitch", "yaw"),
    "base.com": "xyz",
}


def _body_names(robot: SpatialRobot) -> tuple[str, ...]:
    """The name of each body (its first URDF link): root body first, then bodies 1..n."""
    links = robot.labels.body_links
    if len(links) == robot.n_joints + 1:
        return tuple(group[0] for group in links)
    return ("root",) + tuple(f"body{i}" for i in range(1, robot.n_joints + 1))


def _merged_into(robot: SpatialRobot) -> dict[str, str]:
    """URDF links merged into a body (not its first link) -> the body's name."""
    return {name: group[0] for group in robot.labels.body_links for name in group[1:]}


def canonical_name(name: Any) -> Any:
    """The field's name (spatial fields have no older aliases)."""
    return name


def check_field(where: str, field: Any, robot: SpatialRobot) -> str:
    """The field name, or `ConfigError` naming ``where``: an unknown field or link
    (with a did-you-mean) or an index out of range."""
    if not isinstance(field, str):
        raise ConfigError(f"{where}.field: must be a string, one of: {FIELD_HELP}")
    if field in _PLAIN:
        return field
    match = _INDEXED.match(field)
    if match:
        index = int(match.group(2))
        if not 0 <= index <= 2:
            raise ConfigError(
                f"{where}.field: index {index} of {match.group(1)} out of range; use 0, 1 or 2 "
                f"({'x, y, z' if 'xyz' in field or 'com' in field else 'roll, pitch, yaw'})"
            )
        return field
    match = _LINK.match(field)
    if match:
        name, what = match.groups()
        bodies = _body_names(robot)
        if what not in ("mass", "length"):
            raise ConfigError(
                f"{where}.field: links.{name}.{what}: a link field is 'mass' or 'length' "
                f"(links.{name}.mass, links.{name}.length)"
            )
        if name not in bodies:
            merged = _merged_into(robot)
            if name in merged:
                raise ConfigError(
                    f"{where}.field: link '{name}' is merged into body '{merged[name]}' (fixed "
                    f"joint); use links.{merged[name]}.{what}"
                )
            raise ConfigError(
                f"{where}.field: unknown link '{name}'{did_you_mean(name, bodies)}; the arm's links: "
                f"{', '.join(bodies)}"
            )
        return field
    known = list(_PLAIN) + ["mount.xyz[0]", "mount.rpy[0]", "mount.rpy_deg[0]", "base.com[0]"]
    known += [f"links.{name}.{what}" for name in _body_names(robot) for what in ("mass", "length")]
    raise ConfigError(
        f"{where}.field: unknown design field '{field}' for a spatial robot"
        f"{did_you_mean(field, known)}; fields: {FIELD_HELP}"
    )


def _xp(*arrays):
    """numpy when every array is a numpy value (sweeps), else jax.numpy (traced designs)."""
    traced = any(isinstance(a, (jax.Array, jax.core.Tracer)) for a in arrays)
    return jnp if traced else np


def _column(value, trailing: int):
    """``value`` (batch shape) with ``trailing`` unit axes, to broadcast against a leaf."""
    return value.reshape(value.shape + (1,) * trailing) if trailing else value


def _replace_entry(xp, leaf, index: int, value):
    """``leaf`` with ``leaf[..., index]`` replaced by ``value`` (batch shape)."""
    count = leaf.shape[-1]
    return xp.stack([value if k == index else leaf[..., k] for k in range(count)], axis=-1)


def arm_mass(robot: SpatialRobot):
    """``(...)`` the arm's mass, kg: the root body plus the n moving bodies."""
    xp = _xp(robot.root_mass, robot.link_mass)
    return robot.root_mass + xp.sum(robot.link_mass, axis=-1)


def path_length(robot: SpatialRobot):
    """``(...)`` the arm's path length, m: the distances between consecutive joint origins,
    from the root-link origin to the tip (what ``arm.length`` scales)."""
    xp = _xp(robot.joint_translation, robot.tip_translation)
    return xp.sum(xp.linalg.norm(robot.joint_translation, axis=-1), axis=-1) + xp.linalg.norm(
        robot.tip_translation, axis=-1
    )


def set_field(robot: SpatialRobot, field: str, value, relative: bool = False) -> SpatialRobot:
    """The design(s) with one field set (see the module docstring); traceable.

    Args:
        robot: one design or a batch (leading axes on every leaf).
        field: a field name checked by `check_field`.
        value: ``(...)`` the batch shape (or a scalar for one design), in the field's unit.
        relative: multiply the base design's value instead of replacing it (absolute fields).

    Returns:
        The new design, built without validation (the caller validates concrete designs).
    """
    xp = _xp(value, robot.base_mass, robot.link_mass)
    value = xp.asarray(value, dtype=xp.result_type(robot.base_mass, value))
    value = xp.broadcast_to(value, np.shape(robot.base_mass))
    changes: dict[str, Any] = {}
    match = _INDEXED.match(field)
    if match:
        name, index = match.group(1), int(match.group(2))
        key = {
            "mount.xyz": "mount_xyz",
            "mount.rpy": "mount_rpy",
            "mount.rpy_deg": "mount_rpy",
            "base.com": "base_com",
        }[name]
        leaf = getattr(robot, key)
        if name == "mount.rpy_deg" and not relative:
            value = value * (np.pi / 180.0)
        new = leaf[..., index] * value if relative else value
        changes[key] = _replace_entry(xp, leaf, index, new)
    elif field == "base.mass":
        changes["base_mass"] = robot.base_mass * value if relative else value
    elif field == "base.inertia":
        changes["base_inertia"] = robot.base_inertia * _column(value, 2)
    elif field in ("arm.mass", "arm.mass_ratio"):
        factor = value if field == "arm.mass" or relative else value * robot.base_mass / arm_mass(robot)
        changes.update(
            root_mass=robot.root_mass * factor,
            root_inertia=robot.root_inertia * _column(factor, 2),
            link_mass=robot.link_mass * _column(factor, 1),
            link_inertia=robot.link_inertia * _column(factor, 3),
        )
    elif field == "arm.length":
        s = value
        prismatic = np.array([kind == "prismatic" for kind in robot.joint_kinds])
        limit_scale = xp.where(prismatic, _column(s, 1), 1.0)
        changes.update(
            joint_translation=robot.joint_translation * _column(s, 2),
            root_com=robot.root_com * _column(s, 1),
            link_com=robot.link_com * _column(s, 2),
            tip_translation=robot.tip_translation * _column(s, 1),
            root_inertia=robot.root_inertia * _column(s * s, 2),
            link_inertia=robot.link_inertia * _column(s * s, 3),
            joint_lower=robot.joint_lower * limit_scale,
            joint_upper=robot.joint_upper * limit_scale,
        )
    elif _LINK.match(field).group(2) == "length":
        changes.update(_body_length(xp, robot, _body_names(robot).index(_LINK.match(field).group(1)), value))
    else:
        name = _LINK.match(field).group(1)
        body = _body_names(robot).index(name)
        if body == 0:
            new = robot.root_mass * value if relative else value
            ratio = mass_ratio(xp, robot.root_mass, new)
            changes.update(root_mass=new, root_inertia=robot.root_inertia * _column(ratio, 2))
        else:
            changes.update(link_mass_changes(xp, robot, body - 1, value, relative))
    return _rebuild(robot, changes)


def mass_ratio(xp, old, new):
    """``new / old`` where ``old > 0``, else 1: the factor a body's inertia takes with its mass
    (same shape, same radius of gyration; a body of zero mass keeps its inertia as written)."""
    return xp.where(old > 0, new / xp.where(old > 0, old, 1.0), 1.0)


def link_mass_changes(xp, robot, link: int, value, relative: bool) -> dict:
    """The leaves ``links.<name>.mass = value`` changes for moving body ``link`` (0..n-1) of any
    robot with ``link_mass (..., n)`` and ``link_inertia (..., n, 3, 3)`` leaves: its mass,
    and its inertia times the mass ratio (`mass_ratio`)."""
    old = robot.link_mass[..., link]
    new = old * value if relative else value
    inertia = robot.link_inertia
    scaled = inertia[..., link, :, :] * _column(mass_ratio(xp, old, new), 2)
    count = inertia.shape[-3]
    return {
        "link_mass": _replace_entry(xp, robot.link_mass, link, new),
        "link_inertia": xp.stack([scaled if k == link else inertia[..., k, :, :] for k in range(count)], axis=-3),
    }


def scale_rows(xp, leaf, rows, factor, trailing: int):
    """``leaf (..., m, *t)`` with the rows picked by the static booleans ``rows (m,)`` times
    ``factor`` (batch shape), the others as they are; ``trailing`` = len(t)."""
    mask = np.asarray(rows, dtype=bool).reshape((-1,) + (1,) * trailing)
    return leaf * xp.where(mask, _column(factor, 1 + trailing), 1.0)


def _body_length(xp, robot: SpatialRobot, body: int, s) -> dict:
    """The leaves ``links.<name>.length = s`` changes for body ``body`` (0 = the root body):
    the next joint's placement (joint ``body + 1``), the centroid and, on the last body
    (which carries the tip), the tip offset times s; the inertia about the centroid times s^2."""
    n = robot.n_joints
    changes: dict[str, Any] = {}
    if body < n:
        translation = robot.joint_translation
        changes["joint_translation"] = xp.stack(
            [translation[..., k, :] * (_column(s, 1) if k == body else 1.0) for k in range(n)], axis=-2
        )
    else:
        changes["tip_translation"] = robot.tip_translation * _column(s, 1)
    if body == 0:
        changes.update(root_com=robot.root_com * _column(s, 1), root_inertia=robot.root_inertia * _column(s * s, 2))
    else:
        com, inertia = robot.link_com, robot.link_inertia
        changes.update(
            link_com=xp.stack([com[..., k, :] * (_column(s, 1) if k == body - 1 else 1.0) for k in range(n)], axis=-2),
            link_inertia=xp.stack(
                [inertia[..., k, :, :] * (_column(s * s, 2) if k == body - 1 else 1.0) for k in range(n)], axis=-3
            ),
        )
    return changes


def _rebuild(robot: SpatialRobot, changes: dict) -> SpatialRobot:
    leaves, structure = jax.tree_util.tree_flatten(robot)
    rebuilt = jax.tree_util.tree_unflatten(structure, leaves)  # unvalidated copy
    for key, value in changes.items():
        object.__setattr__(rebuilt, key, value)
    return rebuilt


def field_stage(field: str) -> int:
    """When a field is applied when several are set: absolute numbers first, then the
    arm's length, then its mass (``arm.mass_ratio`` against the final bus mass)."""
    return {"arm.length": 1, "arm.mass": 2, "arm.mass_ratio": 2}.get(field, 0)


def field_writes(field: str, robot: SpatialRobot) -> set[str]:
    """The design numbers a field sets, as ``leaf[i]`` names (to refuse two axes that set
    the same number). Length and mass factors both scale inertias, by commuting
    factors: those inertias are tagged ``~inertia`` and do not conflict with each other."""
    n = robot.n_joints
    match = _INDEXED.match(field)
    if match:
        key = {
            "mount.xyz": "mount.xyz",
            "mount.rpy": "mount.rpy",
            "mount.rpy_deg": "mount.rpy",
            "base.com": "base.com",
        }[match.group(1)]
        return {f"{key}[{match.group(2)}]"}
    if field in ("base.mass", "base.inertia"):
        return {field}
    if field in ("arm.mass", "arm.mass_ratio"):
        return {"links.mass[root]"} | {f"links.mass[{i}]" for i in range(n)}
    if field == "arm.length":
        return {"arm.geometry"}
    name, what = _LINK.match(field).groups()
    body = _body_names(robot).index(name)
    # A body's length factor commutes with arm.length and with mass factors (all scale).
    return {f"links.{what}[{'root' if body == 0 else body - 1}]"}


def conflicting_number(first: str, second: str, robot: SpatialRobot) -> str | None:
    """A design number both fields set (the result would depend on their order), or None."""
    shared = field_writes(first, robot) & field_writes(second, robot)
    return sorted(shared)[0] if shared else None


def field_unit(field: str) -> str:
    """The unit of a field's values ("1" for a factor or a ratio)."""
    if field in FACTOR_FIELDS or field == "arm.mass_ratio" or field.endswith(".length"):
        return "1"
    if field.startswith(("mount.xyz", "base.com")):
        return "m"
    if field.startswith("mount.rpy_deg"):
        return "deg"
    if field.startswith("mount.rpy"):
        return "rad"
    return "kg"


def field_columns(robot: SpatialRobot, fields) -> dict[str, np.ndarray]:
    """The design numbers the fields vary, one column per number, SI units in the names."""
    columns: dict[str, np.ndarray] = {}
    for field in fields:
        match = _INDEXED.match(field)
        if match:
            name, index = match.group(1), int(match.group(2))
            label = _AXIS_NAMES[name][index]
            key = "mount_xyz" if name == "mount.xyz" else "base_com" if name == "base.com" else "mount_rpy"
            prefix = {"mount.xyz": "mount", "base.com": "base_com"}.get(name, "mount")
            unit = "rad" if key == "mount_rpy" else "m"
            columns[f"{prefix}_{label}_{unit}"] = np.asarray(getattr(robot, key))[..., index]
        elif field == "base.mass":
            columns["base_mass_kg"] = np.asarray(robot.base_mass)
        elif field == "base.inertia":
            columns["base_inertia_trace_kg_m2"] = np.trace(np.asarray(robot.base_inertia), axis1=-2, axis2=-1)
        elif field in ("arm.mass", "arm.mass_ratio"):
            mass = np.asarray(arm_mass(robot))
            columns["arm_mass_kg"] = mass
            columns["arm_over_base"] = mass / np.asarray(robot.base_mass)
        elif field == "arm.length":
            columns["arm_path_length_m"] = np.asarray(path_length(robot))
        elif _LINK.match(field).group(2) == "length":
            name = _LINK.match(field).group(1)
            body = _body_names(robot).index(name)
            columns[f"{re.sub(r'[^A-Za-z0-9_]', '_', name)}_length_m"] = np.asarray(
                np.linalg.norm(np.asarray(robot.joint_translation)[..., body, :], axis=-1)
                if body < robot.n_joints
                else np.linalg.norm(np.asarray(robot.tip_translation), axis=-1)
            )
        else:
            name = _LINK.match(field).group(1)
            body = _body_names(robot).index(name)
            mass = robot.root_mass if body == 0 else np.asarray(robot.link_mass)[..., body - 1]
            columns[f"{re.sub(r'[^A-Za-z0-9_]', '_', name)}_mass_kg"] = np.asarray(mass)
    return columns
