"""Named design numbers of a tree (several arms on one bus): what a sweep axis or a design variable sets.

The interface of `spacearm.models.spatial.fields` (the same functions, used by
`spacearm.studies` on numpy batches and by `spacearm.design` under ``jit``/``grad``),
for a `TreeRobot`. An arm is a root body r (its name in ``labels.root_names``, the
``name`` of an ``arms:`` entry) with every joint that hangs from it and every tip those
joints carry. The bus fields and the per-body math are the spatial ones (imported).

Fields:

===============================  =========  ======================================================
field                            value      what it sets
===============================  =========  ======================================================
``arms.<arm>.mount.xyz[i]``      m          the arm's root-link origin in the bus frame, component i
``arms.<arm>.mount.rpy[i]``      rad        the arm's mount attitude, URDF roll, pitch, yaw
``arms.<arm>.mount.rpy_deg[i]``  deg        the same in degrees
``arms.<arm>.mass``              factor     every body of that arm (root and links): masses and
                                            inertias times the value
``arms.<arm>.length``            factor     that arm's geometry times the value, as the spatial
                                            ``arm.length``: joint placements, body centroids, its
                                            tip offsets and prismatic limits times s, inertias times
                                            s^2, masses kept; the mount pose stays
``base.mass``                    kg         the bus mass (inertia unchanged)
``base.inertia``                 factor     the bus 3x3 inertia times the value
``base.com[i]``                  m          the bus centroid in the bus frame, component i
``links.<name>.mass``            kg         the mass of the moving body whose first URDF link is
                                            ``<name>``; its inertia scales with it
``links.<name>.length``          factor     that body's geometry times the value: the placement of
                                            every joint hanging from it, its centroid offset and the
                                            offset of every tip it carries times s, its inertia about
                                            the centroid times s^2 (mass kept)
===============================  =========  ======================================================

A link name may carry its arm as a prefix (``left/upper_arm_link``); it must where two
arms share a URDF (the plain name would be ambiguous).
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from ..._core.errors import ConfigError
from ..._core.schema import did_you_mean
from ..spatial import fields as spatial_fields
from ..spatial.fields import _column, _rebuild, _xp, link_mass_changes, scale_rows
from .robot import TreeRobot

__all__ = [
    "FACTOR_FIELDS",
    "FIELD_HELP",
    "arm_mass",
    "arm_names",
    "body_names",
    "canonical_name",
    "check_field",
    "conflicting_number",
    "field_columns",
    "field_stage",
    "field_unit",
    "field_writes",
    "joint_arms",
    "set_field",
    "tip_arms",
]

FIELD_HELP = (
    "arms.<arm>.mount.xyz[i] (m) | arms.<arm>.mount.rpy[i] (rad) | arms.<arm>.mount.rpy_deg[i] | "
    "arms.<arm>.mass (a factor on that arm's masses and inertias) | arms.<arm>.length (a factor on that "
    "arm's geometry; inertias with its square) | base.mass (kg) | base.inertia (a factor on the 3x3) | "
    "base.com[i] (m) | links.<name>.mass (kg) | links.<name>.length (a factor on that body's geometry)"
)
_MOUNT = re.compile(r"^arms\.([^.\[\]]+)\.mount\.(xyz|rpy|rpy_deg)\[(-?\d+)\]$")
_ARM = re.compile(r"^arms\.([^.\[\]]+)\.(\w+)$")
_BASE_INDEXED = re.compile(r"^base\.com\[(-?\d+)\]$")
_LINK = re.compile(r"^links\.([^.\[\]]+)\.(\w+)$")
_BASE = ("base.mass", "base.inertia")
_AXIS_NAMES = {"xyz": "xyz", "rpy": ("roll", "pitch", "yaw"), "rpy_deg": ("roll", "pitch", "yaw")}


class _FactorFields:
    """The fields whose value is a factor (``base.inertia``, ``arms.<arm>.mass``, ``arms.<arm>.length``)."""

    def __contains__(self, field) -> bool:
        if field == "base.inertia":
            return True
        match = _ARM.match(field) if isinstance(field, str) else None
        return bool(match) and match.group(2) in ("mass", "length")


FACTOR_FIELDS = _FactorFields()


# The tree's arms and bodies (static: from the topology and the labels) ------------------


def arm_names(robot: TreeRobot) -> tuple[str, ...]:
    """The name of each root body (arm), in root order: ``labels.root_names``, or ``arm<r>``."""
    names = robot.labels.root_names
    return tuple(names) if len(names) == robot.n_roots else tuple(f"arm{r}" for r in range(robot.n_roots))


def joint_arms(robot: TreeRobot) -> tuple[int, ...]:
    """The root (arm) index of every joint, from the static parents."""
    roots: list[int] = []
    for parent in robot.parents:
        roots.append(-1 - parent if parent < 0 else roots[parent])
    return tuple(roots)


def tip_arms(robot: TreeRobot) -> tuple[int, ...]:
    """The root (arm) index of every tip."""
    roots = joint_arms(robot)
    return tuple(roots[body] for body in robot.tip_bodies)


def body_names(robot: TreeRobot) -> dict[str, int]:
    """Every name a moving body answers to -> its index j: ``<arm>/<link>`` always, the plain
    first URDF link name where no other body has it (``body<j>`` without labels)."""
    links = robot.labels.body_links
    if len(links) == robot.n_joints and all(links):
        plain = [group[0] for group in links]
    else:
        plain = [f"body{j}" for j in range(robot.n_joints)]
    arms, roots = arm_names(robot), joint_arms(robot)
    names: dict[str, int] = {}
    for j, name in enumerate(plain):
        if plain.count(name) == 1:
            names[name] = j
        names[f"{arms[roots[j]]}/{name}" if not name.startswith(f"{arms[roots[j]]}/") else name] = j
    return names


def _shown_names(robot: TreeRobot) -> list[str]:
    """One name per body for messages: the plain name where it is unique, else the prefixed one."""
    shown: dict[int, str] = {}
    for name, j in body_names(robot).items():
        shown.setdefault(j, name)
    return [shown[j] for j in range(robot.n_joints)]


def _ambiguous(robot: TreeRobot, name: str) -> list[str]:
    """The prefixed names of the bodies whose plain name is ``name`` (several arms share it)."""
    return [f"{arm}/{name}" for arm in arm_names(robot) if f"{arm}/{name}" in body_names(robot)]


def arm_mass(robot: TreeRobot):
    """``(...)`` the mass of every arm together, kg: root bodies plus moving bodies."""
    xp = _xp(robot.root_mass, robot.link_mass)
    return xp.sum(robot.root_mass, axis=-1) + xp.sum(robot.link_mass, axis=-1)


def _arm_of(robot: TreeRobot, name: str) -> int:
    return arm_names(robot).index(name)


def _in_arm(robot: TreeRobot, arm: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Static masks of arm ``arm``'s roots ``(r,)``, joints ``(n,)`` and tips ``(k,)``."""
    roots = np.arange(robot.n_roots) == arm
    joints = np.array(joint_arms(robot)) == arm
    tips = np.array(tip_arms(robot)) == arm
    return roots, joints, tips


# Checking a field name ----------------------------------------------------------------


def canonical_name(name: Any) -> Any:
    """The field's name (tree fields have no older aliases)."""
    return name


def _check_arm(where: str, field: str, arm: str, robot: TreeRobot) -> None:
    arms = arm_names(robot)
    if arm not in arms:
        raise ConfigError(
            f"{where}.field: {field}: unknown arm '{arm}'{did_you_mean(arm, arms)}; the arms: {', '.join(arms)}"
        )


def check_field(where: str, field: Any, robot: TreeRobot) -> str:
    """The field name, or `ConfigError` naming ``where`` and the field: an unknown field,
    arm or link (with a did-you-mean) or an index out of range."""
    if not isinstance(field, str):
        raise ConfigError(f"{where}.field: must be a string, one of: {FIELD_HELP}")
    if field in _BASE:
        return field
    arms = arm_names(robot)
    match = _MOUNT.match(field)
    if match:
        arm, what, index = match.group(1), match.group(2), int(match.group(3))
        _check_arm(where, field, arm, robot)
        if not 0 <= index <= 2:
            raise ConfigError(
                f"{where}.field: {field}: index {index} out of range; use 0, 1 or 2 "
                f"({'x, y, z' if what == 'xyz' else 'roll, pitch, yaw'})"
            )
        return field
    match = _BASE_INDEXED.match(field)
    if match:
        if not 0 <= int(match.group(1)) <= 2:
            raise ConfigError(f"{where}.field: {field}: index {match.group(1)} out of range; use 0, 1 or 2 (x, y, z)")
        return field
    match = _LINK.match(field)
    if match:
        name, what = match.groups()
        if what not in ("mass", "length"):
            raise ConfigError(
                f"{where}.field: {field}: a link field is 'mass' or 'length' (links.{name}.mass, links.{name}.length)"
            )
        names = body_names(robot)
        if name not in names:
            shared = _ambiguous(robot, name)
            if shared:
                raise ConfigError(
                    f"{where}.field: {field}: several arms have a link '{name}'; name one: "
                    + ", ".join(f"links.{s}.{what}" for s in shared)
                )
            merged: dict[str, str] = {}
            shown = _shown_names(robot)
            for j, group in enumerate(robot.labels.body_links):
                for link in group[1:]:
                    merged[f"{arms[joint_arms(robot)[j]]}/{link}"] = shown[j]
                    merged[link] = shown[j] if link not in merged else ""  # "": several arms have it
            if merged.get(name):
                raise ConfigError(
                    f"{where}.field: {field}: link '{name}' is merged into body '{merged[name]}' (fixed joint); "
                    f"use links.{merged[name]}.{what}"
                )
            raise ConfigError(
                f"{where}.field: {field}: unknown link '{name}'{did_you_mean(name, list(names))}; the tree's moving "
                f"bodies: {', '.join(_shown_names(robot))}"
            )
        return field
    match = _ARM.match(field)
    if match:
        arm, what = match.groups()
        _check_arm(where, field, arm, robot)
        if what in ("mass", "length"):
            return field
        raise ConfigError(
            f"{where}.field: {field}: an arm field is mount.xyz[i], mount.rpy[i], mount.rpy_deg[i], mass or length "
            f"(arms.{arm}.mass, arms.{arm}.mount.xyz[0])"
        )
    known = list(_BASE) + ["base.com[0]"]
    known += [f"arms.{arm}.{what}" for arm in arms for what in ("mass", "length", "mount.xyz[0]", "mount.rpy[0]")]
    known += [f"links.{name}.{what}" for name in _shown_names(robot) for what in ("mass", "length")]
    hint = ""
    spatial = field.split("[")[0]
    if spatial in ("mount.xyz", "mount.rpy", "mount.rpy_deg", "arm.mass", "arm.length", "arm.mass_ratio"):
        hint = (
            f"; a tree's arms each have their own: arms.<arm>.{spatial.removeprefix('arm.')} (arms: {', '.join(arms)})"
        )
    raise ConfigError(
        f"{where}.field: unknown design field '{field}' for a tree robot{did_you_mean(field, known)}{hint}; "
        f"fields: {FIELD_HELP}"
    )


# Setting a field ----------------------------------------------------------------------


def set_field(robot: TreeRobot, field: str, value, relative: bool = False) -> TreeRobot:
    """The design(s) with one field set (see the module docstring); traceable.

    Args:
        robot: one design or a batch (leading axes on every leaf).
        field: a field name checked by `check_field`.
        value: ``(...)`` the batch shape (or a scalar for one design), in the field's unit.
        relative: multiply the base design's value instead of replacing it (absolute fields;
            a factor field is a factor already).

    Returns:
        The new design, built without validation (the caller validates concrete designs).
    """
    if field in _BASE or _BASE_INDEXED.match(field):
        return spatial_fields.set_field(robot, field, value, relative)  # the same bus leaves
    xp = _xp(value, robot.base_mass, robot.link_mass)
    value = xp.asarray(value, dtype=xp.result_type(robot.base_mass, value))
    value = xp.broadcast_to(value, np.shape(robot.base_mass))
    changes: dict[str, Any] = {}
    mount = _MOUNT.match(field)
    arm_field = _ARM.match(field)
    if mount:
        arm, what, index = _arm_of(robot, mount.group(1)), mount.group(2), int(mount.group(3))
        key = "mount_xyz" if what == "xyz" else "mount_rpy"
        leaf = getattr(robot, key)
        mask = (np.arange(robot.n_roots)[:, None] == arm) & (np.arange(3)[None, :] == index)
        if relative:
            changes[key] = leaf * xp.where(mask, _column(value, 2), 1.0)
        else:
            value = value * (np.pi / 180.0) if what == "rpy_deg" else value
            changes[key] = xp.where(mask, _column(value, 2), leaf)
    elif arm_field:
        roots, joints, tips = _in_arm(robot, _arm_of(robot, arm_field.group(1)))
        s = value
        if arm_field.group(2) == "mass":
            changes.update(
                root_mass=scale_rows(xp, robot.root_mass, roots, s, 0),
                root_inertia=scale_rows(xp, robot.root_inertia, roots, s, 2),
                link_mass=scale_rows(xp, robot.link_mass, joints, s, 0),
                link_inertia=scale_rows(xp, robot.link_inertia, joints, s, 2),
            )
        else:
            prismatic = joints & np.array([kind == "prismatic" for kind in robot.joint_kinds])
            changes.update(
                joint_translation=scale_rows(xp, robot.joint_translation, joints, s, 1),
                root_com=scale_rows(xp, robot.root_com, roots, s, 1),
                link_com=scale_rows(xp, robot.link_com, joints, s, 1),
                tip_translation=scale_rows(xp, robot.tip_translation, tips, s, 1),
                root_inertia=scale_rows(xp, robot.root_inertia, roots, s * s, 2),
                link_inertia=scale_rows(xp, robot.link_inertia, joints, s * s, 2),
                joint_lower=scale_rows(xp, robot.joint_lower, prismatic, s, 0),
                joint_upper=scale_rows(xp, robot.joint_upper, prismatic, s, 0),
            )
    else:
        name, what = _LINK.match(field).groups()
        body = body_names(robot)[name]
        if what == "mass":
            changes.update(link_mass_changes(xp, robot, body, value, relative))
        else:
            s, this = value, np.arange(robot.n_joints) == body
            children = np.array(robot.parents) == body
            carried = np.array(robot.tip_bodies) == body
            changes.update(
                joint_translation=scale_rows(xp, robot.joint_translation, children, s, 1),
                link_com=scale_rows(xp, robot.link_com, this, s, 1),
                link_inertia=scale_rows(xp, robot.link_inertia, this, s * s, 2),
                tip_translation=scale_rows(xp, robot.tip_translation, carried, s, 1),
            )
    return _rebuild(robot, changes)


def field_stage(field: str) -> int:
    """When a field is applied when several are set: absolute numbers first, then the arms'
    length factors, then their mass factors."""
    match = _ARM.match(field)
    if match:
        return {"length": 1, "mass": 2}.get(match.group(2), 0)
    return 0


def field_writes(field: str, robot: TreeRobot) -> set[str]:
    """The design numbers a field sets, named as fields (to refuse two axes that set the
    same number). Length factors commute with each other and with mass factors."""
    if field in _BASE or _BASE_INDEXED.match(field):
        return spatial_fields.field_writes(field, robot)
    mount = _MOUNT.match(field)
    if mount:
        what = "xyz" if mount.group(2) == "xyz" else "rpy"
        return {f"arms.{mount.group(1)}.mount.{what}[{mount.group(3)}]"}
    shown = _shown_names(robot)
    if _ARM.match(field):
        arm, what = _ARM.match(field).groups()
        if what == "length":
            return {f"arms.{arm}.geometry"}
        _, joints, _ = _in_arm(robot, _arm_of(robot, arm))
        return {f"arms.{arm}.root mass"} | {f"links.{shown[j]}.mass" for j in np.flatnonzero(joints)}
    name, what = _LINK.match(field).groups()
    return {f"links.{shown[body_names(robot)[name]]}.{what}"}


def conflicting_number(first: str, second: str, robot: TreeRobot) -> str | None:
    """A design number both fields set (the result would depend on their order), or None."""
    shared = field_writes(first, robot) & field_writes(second, robot)
    return sorted(shared)[0] if shared else None


def field_unit(field: str) -> str:
    """The unit of a field's values ("1" for a factor)."""
    if field in FACTOR_FIELDS or field.endswith(".length"):
        return "1"
    if ".mount.xyz" in field or field.startswith("base.com"):
        return "m"
    if ".mount.rpy_deg" in field:
        return "deg"
    if ".mount.rpy" in field:
        return "rad"
    return "kg"


def _label(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]", "_", name)


def field_columns(robot: TreeRobot, fields) -> dict[str, np.ndarray]:
    """The design numbers the fields vary, one column per number, SI units in the names."""
    columns: dict[str, np.ndarray] = {}
    shown = _shown_names(robot)
    for field in fields:
        mount = _MOUNT.match(field)
        if field in _BASE or _BASE_INDEXED.match(field):
            columns.update(spatial_fields.field_columns(robot, [field]))
        elif mount:
            arm, what, index = mount.group(1), mount.group(2), int(mount.group(3))
            key, unit = ("mount_xyz", "m") if what == "xyz" else ("mount_rpy", "rad")
            value = np.asarray(getattr(robot, key))[..., _arm_of(robot, arm), index]
            columns[f"{_label(arm)}_mount_{_AXIS_NAMES[what][index]}_{unit}"] = value
        elif _ARM.match(field):
            arm, what = _ARM.match(field).groups()
            roots, joints, tips = _in_arm(robot, _arm_of(robot, arm))
            if what == "mass":
                mass = np.sum(np.asarray(robot.root_mass)[..., roots], axis=-1)
                columns[f"{_label(arm)}_mass_kg"] = mass + np.sum(np.asarray(robot.link_mass)[..., joints], axis=-1)
            else:
                norms = np.linalg.norm(np.asarray(robot.joint_translation)[..., joints, :], axis=-1)
                tip = np.linalg.norm(np.asarray(robot.tip_translation)[..., tips, :], axis=-1)
                columns[f"{_label(arm)}_path_length_m"] = np.sum(norms, axis=-1) + np.sum(tip, axis=-1)
        else:
            name, what = _LINK.match(field).groups()
            body = body_names(robot)[name]
            if what == "mass":
                columns[f"{_label(shown[body])}_mass_kg"] = np.asarray(robot.link_mass)[..., body]
            else:
                children = [j for j, parent in enumerate(robot.parents) if parent == body]
                carried = [t for t, b in enumerate(robot.tip_bodies) if b == body]
                offset = (
                    np.asarray(robot.joint_translation)[..., children[0], :]
                    if children
                    else np.asarray(robot.tip_translation)[..., carried[0], :]
                    if carried
                    else np.asarray(robot.link_com)[..., body, :]
                )
                columns[f"{_label(shown[body])}_length_m"] = np.linalg.norm(offset, axis=-1)
    return columns
