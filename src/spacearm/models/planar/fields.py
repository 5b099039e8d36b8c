"""Named design numbers of a planar robot: the fields a sweep axis or a design variable sets.

One home for what a field name means, shared by sweeps (`spacearm.studies`, numpy over
many sweep points at once) and design problems (`spacearm.design`, traced under
``jit``/``grad``). Every function works on one design or a batch (leading axes on every
leaf, ``value`` with the batch shape), with numpy or JAX arrays alike. Link indices are
0-based (``links[0]`` is the link at the base); ``links[*]`` sets every link.

==============================  ======  ==============================================================
field                           value   what it sets
==============================  ======  ==============================================================
``base.mass``                   kg      m0 (inertia unchanged)
``base.inertia``                kg m^2  I0
``base.attach``                 m       b0, base centroid to joint 1
``links[i].mass``               kg      m_i (inertia unchanged)
``links[i].inertia``            kg m^2  I_i
``links[i].a``, ``links[i].b``  m       joint to centroid, centroid to next joint
``links[i].length``             m       l_i = a_i + b_i: a_i and b_i scaled together, I_i with the square
``links[i].length_share``       1       l_i / L at fixed reach L (i < n - 1): the last link takes the
                                        rest; a_i / l_i kept, inertias with the length squared
``links[i].mass_share``         1       m_i / m_arm at fixed arm mass (i < n - 1): the last link takes
                                        the rest; inertias with the mass (radius of gyration kept)
``links[i].centroid``           1       a_i / l_i at fixed l_i (where the centroid sits on the link)
``arm.mass``                    kg      the arm's mass: link masses and inertias scaled together
``arm.mass_ratio``              1       m_arm / m0 at fixed base mass (the links scaled)
``arm.mass_ratio_fixed_total``  1       m_arm / m0 at fixed total mass m0 + m_arm: the base's mass and
                                        inertia and the links' masses and inertias scaled
``arm.length_split``            1       l_1 / L at fixed L; the other links scaled together
==============================  ======  ==============================================================

``relative: true`` multiplies the current value instead of replacing it. Design
problems also accept the names of the first planar problem files (`ALIASES`:
``b0``, ``l1_over_L``, ``m1_over_arm``, ``a1_over_l1``, ``arm_over_base``).
"""

from __future__ import annotations

import re
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from ..._core.errors import ConfigError
from ..._core.schema import did_you_mean
from .robot import PlanarRobot

__all__ = [
    "FACTOR_FIELDS",
    "FIELD_HELP",
    "alias_names",
    "canonical_name",
    "check_field",
    "conflicting_number",
    "field_columns",
    "field_stage",
    "field_unit",
    "field_writes",
    "set_field",
]

FIELD_HELP = (
    "base.mass | base.inertia | base.attach | links[i].FIELD or links[*].FIELD with FIELD in "
    "mass, inertia, a, b, length (a and b scaled together, inertia with the square), length_share, "
    "mass_share, centroid (a / l) | arm.mass (link masses and inertias scaled together) | arm.mass_ratio "
    "(arm mass / base mass) | arm.mass_ratio_fixed_total (the same at fixed total mass) | "
    "arm.length_split (l1 / L at fixed L; the other links scaled together)"
)
FACTOR_FIELDS: tuple[str, ...] = ()
_LINK = re.compile(r"^links\[(\d+|\*)\]\.(mass|inertia|a|b|length|length_share|mass_share|centroid)$")
_SIMPLE = {
    "base.mass": ("base_mass", "kg"),
    "base.inertia": ("base_inertia", "kg_m2"),
    "base.attach": ("base_attach", "m"),
}
_DERIVED = {"arm.mass": "kg", "arm.mass_ratio": "1", "arm.mass_ratio_fixed_total": "1", "arm.length_split": "1"}
_SHARES = ("length_share", "mass_share")
_ALIAS = re.compile(r"^(?:l(\d+)_over_L|m(\d+)_over_arm|a(\d+)_over_l(\d+))$")


def canonical_name(name: Any) -> Any:
    """A field's name from a first-generation planar problem name, else ``name`` unchanged.

    ``b0`` -> ``base.attach``; ``l{i}_over_L`` -> ``links[i-1].length_share``;
    ``m{i}_over_arm`` -> ``links[i-1].mass_share``; ``a{i}_over_l{i}`` -> ``links[i-1].centroid``;
    ``arm_over_base`` -> ``arm.mass_ratio_fixed_total`` (those problems hold the total mass).
    """
    if not isinstance(name, str):
        return name
    if name == "b0":
        return "base.attach"
    if name == "arm_over_base":
        return "arm.mass_ratio_fixed_total"
    match = _ALIAS.match(name)
    if match:
        length, mass, a, a_link = match.groups()
        if length:
            return f"links[{int(length) - 1}].length_share"
        if mass:
            return f"links[{int(mass) - 1}].mass_share"
        if a == a_link:
            return f"links[{int(a) - 1}].centroid"
    return name


def alias_names(n_links: int) -> tuple[str, ...]:
    """The first-generation planar problem names for an n-link arm (see `canonical_name`)."""
    names = ["b0", "arm_over_base"]
    names += [f"l{i}_over_L" for i in range(1, n_links)]
    names += [f"m{i}_over_arm" for i in range(1, n_links)]
    names += [f"a{i}_over_l{i}" for i in range(1, n_links + 1)]
    return tuple(names)


def check_field(where: str, field: Any, robot: PlanarRobot | int) -> str:
    """The field name, or `ConfigError` naming ``where`` (with a did-you-mean).

    ``robot``: the base design (its link count is what is checked; an int is accepted)."""
    n_links = robot if isinstance(robot, int) else robot.n_links
    if not isinstance(field, str):
        raise ConfigError(f"{where}.field: must be a string, one of: {FIELD_HELP}")
    if field in _SIMPLE or field in _DERIVED:
        if field == "arm.length_split" and n_links < 2:
            raise ConfigError(f"{where}.field: arm.length_split needs at least 2 links")
        return field
    match = _LINK.match(field)
    if match:
        index, what = match.groups()
        if index != "*" and int(index) >= n_links:
            raise ConfigError(
                f"{where}.field: link index {index} out of range; the robot has {n_links} links (0..{n_links - 1})"
            )
        if what in _SHARES and (index == "*" or int(index) == n_links - 1):
            raise ConfigError(
                f"{where}.field: {field}: the last link (links[{n_links - 1}]) takes the rest of the "
                f"total; set the {what} of links 0..{n_links - 2}"
            )
        return field
    known = (
        sorted(_SIMPLE)
        + sorted(_DERIVED)
        + [f"links[0].{k}" for k in ("mass", "inertia", "a", "b", "length", "length_share", "mass_share", "centroid")]
    )
    known += list(alias_names(n_links))
    raise ConfigError(
        f"{where}.field: unknown design field '{field}'{did_you_mean(field, known)}; fields: {FIELD_HELP}"
    )


def _xp(*arrays):
    """numpy when every array is a numpy value (sweeps), else jax.numpy (traced designs)."""
    return jnp if any(isinstance(a, (jax.Array, jax.core.Tracer)) for a in arrays) else np


def _rebuild(robot: PlanarRobot, changes: dict) -> PlanarRobot:
    leaves, structure = jax.tree_util.tree_flatten(robot)
    rebuilt = jax.tree_util.tree_unflatten(structure, leaves)  # unvalidated copy
    for key, value in changes.items():
        object.__setattr__(rebuilt, key, value)
    return rebuilt


def set_field(robot: PlanarRobot, field: str, value, relative: bool = False) -> PlanarRobot:
    """The design(s) with one field set (see the module docstring); traceable.

    Args:
        robot: one design or a batch (leading axes on every leaf).
        field: a field name checked by `check_field`.
        value: ``(...)`` the batch shape (or a scalar), in the field's unit.
        relative: multiply the current value instead of replacing it.

    Returns:
        The new design, built without validation (the caller validates concrete designs).
    """
    xp = _xp(value, robot.base_mass, robot.link_mass)
    value = xp.asarray(value, dtype=xp.result_type(robot.base_mass, value))
    value = xp.broadcast_to(value, np.shape(robot.base_mass))
    col = value[..., None]
    mass, inertia = robot.link_mass, robot.link_inertia
    a, b = robot.link_a, robot.link_b
    n = np.shape(mass)[-1]
    if field in _SIMPLE:
        key = _SIMPLE[field][0]
        return _rebuild(robot, {key: getattr(robot, key) * value if relative else value})
    match = _LINK.match(field)
    if match:
        index, what = match.groups()
        chosen = np.arange(n) == int(index) if index != "*" else np.ones(n, bool)
        length = a + b
        if what == "length":
            factor = col if relative else col / length
            factor = xp.where(chosen, factor, 1.0)
            return _rebuild(robot, {"link_a": a * factor, "link_b": b * factor, "link_inertia": inertia * factor**2})
        if what == "centroid":
            ratio = a / length * col if relative else col
            new_a = xp.where(chosen, ratio * length, a)
            return _rebuild(robot, {"link_a": new_a, "link_b": length - new_a})
        if what in _SHARES:
            last = np.arange(n) == n - 1
            amount = length if what == "length_share" else mass
            total = xp.sum(amount, axis=-1, keepdims=True)
            share = amount / total * col if relative else col
            new = xp.where(chosen, share * total, amount)
            rest = total - xp.sum(xp.where(last, 0.0, new), axis=-1, keepdims=True)
            new = xp.where(last, rest, new)
            factor = new / amount
            if what == "length_share":
                return _rebuild(
                    robot, {"link_a": a * factor, "link_b": b * factor, "link_inertia": inertia * factor**2}
                )
            return _rebuild(robot, {"link_mass": new, "link_inertia": inertia * factor})
        key = {"mass": "link_mass", "inertia": "link_inertia", "a": "link_a", "b": "link_b"}[what]
        leaf = getattr(robot, key)
        return _rebuild(robot, {key: xp.where(chosen, leaf * col if relative else col, leaf)})
    arm = xp.sum(mass, axis=-1)
    if field in ("arm.mass", "arm.mass_ratio"):
        current = arm if field == "arm.mass" else arm / robot.base_mass
        factor = (value if relative else value / current)[..., None]
        return _rebuild(robot, {"link_mass": mass * factor, "link_inertia": inertia * factor})
    if field == "arm.mass_ratio_fixed_total":
        ratio = arm / robot.base_mass * value if relative else value
        total = robot.base_mass + arm
        base = total / (1.0 + ratio)
        base_factor, arm_factor = base / robot.base_mass, ((total - base) / arm)[..., None]
        return _rebuild(
            robot,
            {
                "base_mass": base,
                "base_inertia": robot.base_inertia * base_factor,
                "link_mass": mass * arm_factor,
                "link_inertia": inertia * arm_factor,
            },
        )
    if field == "arm.length_split":
        lengths = a + b
        reach = xp.sum(lengths, axis=-1)
        split = value * lengths[..., 0] / reach if relative else value
        first = split * reach / lengths[..., 0]
        others = (1.0 - split) * reach / (reach - lengths[..., 0])
        factors = xp.where(np.arange(n) == 0, first[..., None], others[..., None])
        return _rebuild(robot, {"link_a": a * factors, "link_b": b * factors, "link_inertia": inertia * factors**2})
    raise ConfigError(f"unknown design field {field!r}")  # unreachable after check_field


def field_stage(field: str) -> int:
    """When a field is applied when several are set: the numbers of the base and the
    links first, then shares and splits at a fixed total, then the arm's mass (its ratio
    against the final base mass)."""
    if field == "arm.length_split" or field.endswith(("_share", ".centroid")):
        return 1
    return {"arm.mass": 2, "arm.mass_ratio": 2, "arm.mass_ratio_fixed_total": 2}.get(field, 0)


def field_writes(field: str, robot: PlanarRobot | int) -> set[str]:
    """The design numbers a field sets, as ``leaf[i]`` names. A share or a centroid
    ratio sets a part of a total (``link_length[i]``, ``link_mass_share[i]``,
    ``link_centroid[i]``), which the fields that set the number itself also write."""
    n_links = robot if isinstance(robot, int) else robot.n_links
    links = range(n_links)
    if field in _SIMPLE:
        return {_SIMPLE[field][0]}
    if field in ("arm.mass", "arm.mass_ratio"):
        return {f"{leaf}[{i}]" for leaf in ("link_mass", "link_inertia") for i in links}
    if field == "arm.mass_ratio_fixed_total":
        return {f"{leaf}[{i}]" for leaf in ("link_mass", "link_inertia") for i in links} | {"base_mass", "base_inertia"}
    if field == "arm.length_split":
        return {f"{leaf}[{i}]" for leaf in ("link_a", "link_b", "link_inertia", "link_length") for i in links}
    index, what = _LINK.match(field).groups()
    chosen = links if index == "*" else [int(index)]
    leaves = {
        "mass": ["link_mass", "link_mass_share"],
        "inertia": ["link_inertia"],
        "a": ["link_a", "link_length", "link_centroid"],
        "b": ["link_b", "link_length", "link_centroid"],
        "length": ["link_a", "link_b", "link_inertia", "link_length"],
        "length_share": ["link_length", "link_inertia"],
        "mass_share": ["link_mass_share", "link_inertia"],
        "centroid": ["link_centroid"],
    }[what]
    return {f"{leaf}[{i}]" for leaf in leaves for i in chosen}


def _scaling(field: str) -> bool:
    """Whether a field changes link inertias only by a factor (length squared or mass)."""
    return field in ("arm.length_split", "arm.mass", "arm.mass_ratio", "arm.mass_ratio_fixed_total") or field.endswith(
        ("].length", "_share")
    )


def _label(name: str) -> str:
    """``link_inertia[0]`` -> ``links[0].inertia``; ``base_mass`` -> ``base.mass``."""
    match = re.fullmatch(r"link_(\w+)\[(\d+)\]", name)
    if match:
        return f"links[{match.group(2)}].{match.group(1)}"
    return name.replace("_", ".", 1)


def conflicting_number(first: str, second: str, robot: PlanarRobot | int) -> str | None:
    """A design number both fields set (the result would depend on their order), or None.

    Fields that change link inertias by factors (lengths squared, masses) commute, so
    two such fields may share inertias; a share and the scaling of its total commute too.
    """
    shared = field_writes(first, robot) & field_writes(second, robot)
    if _scaling(first) and _scaling(second):
        shared = {name for name in shared if not name.startswith("link_inertia")}
    return _label(sorted(shared)[0]) if shared else None


def field_unit(field: str) -> str:
    """The SI unit of a field's values ("1" for a ratio or share)."""
    if field in _SIMPLE:
        return _SIMPLE[field][1].replace("_m2", " m^2")
    if field in _DERIVED:
        return _DERIVED[field]
    what = field.rsplit(".", 1)[1]
    return {"mass": "kg", "inertia": "kg m^2", "length_share": "1", "mass_share": "1", "centroid": "1"}.get(what, "m")


def field_columns(robot: PlanarRobot, fields) -> dict[str, np.ndarray]:
    """The design numbers the fields vary, one column per number, SI units in the names."""
    columns: dict[str, np.ndarray] = {}
    for field in fields:
        if field in _SIMPLE:
            key, unit = _SIMPLE[field]
            columns[f"{key}_{unit}"] = np.asarray(getattr(robot, key))
            continue
        if field in ("arm.mass", "arm.mass_ratio", "arm.mass_ratio_fixed_total"):
            columns["arm_mass_kg"] = np.asarray(robot.link_mass).sum(axis=-1)
            if field == "arm.mass_ratio_fixed_total":
                columns["base_mass_kg"] = np.asarray(robot.base_mass)
            continue
        lengths = np.asarray(robot.link_length)
        for i in range(lengths.shape[-1]):
            columns[f"l{i + 1}_m"] = lengths[..., i]
        if field.endswith((".mass", ".inertia", ".mass_share")):
            for i in range(lengths.shape[-1]):
                columns[f"m{i + 1}_kg"] = np.asarray(robot.link_mass)[..., i]
        if field.endswith(".centroid"):
            for i in range(lengths.shape[-1]):
                columns[f"a{i + 1}_m"] = np.asarray(robot.link_a)[..., i]
    return columns
