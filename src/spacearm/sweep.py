"""YAML-driven design studies: sweep files -> one batched design pytree -> tables, grids, figures.

A sweep file names a base robot (a file in ``configs/`` or an inline mapping), the
design axes to vary, how to combine them, and the metrics to compute::

    name: table2
    robot: ../configs/umetani1990.yaml
    axes:
      b0_over_B0: {field: base.attach, relative: true, values: [0, 0.5, 1.0, 1.5, 2.0]}
    metrics: [wbar, S_M, S_G]

All designs are stacked into one :class:`~spacearm.robot.PlanarRobot` with a leading
axis and evaluated by one compiled, vmapped function in chunks of bounded size; the
chunk axis is sharded over every JAX device. Finished chunks are kept on disk, so an
interrupted sweep resumes where it stopped.
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import functools
import json
import math
import os
import re
import shutil
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import yaml

from . import results
from .robot import ConfigError, PlanarRobot, describe_yaml_error, load_robot, robot_from_mapping

__all__ = [
    "SweepSpec",
    "load_sweep",
    "build_designs",
    "run_sweep",
    "METRICS",
    "add_sweep_command",
    "add_figures_command",
]

# Designs vmapped together inside a chunk (see run_sweep): small enough for the cache.
DESIGNS_PER_STEP = 32

# Sweep file schema -----------------------------------------------------------------

_TOP_KEYS = {
    "name", "description", "robot", "axes", "combine", "metrics", "output", "chunk_size", "report",
}
_AXIS_KEYS = {"field", "values", "range", "relative"}
_RANGE_KEYS = {"start", "stop", "num", "step"}

_LINK_FIELD = re.compile(r"^links\[(\d+|\*)\]\.(mass|inertia|a|b|length)$")
_SIMPLE_FIELDS = {
    "base.mass": ("base_mass", "kg"),
    "base.inertia": ("base_inertia", "kg_m2"),
    "base.attach": ("base_attach", "m"),
}
_DERIVED_FIELDS = {
    "arm.mass": "kg",
    "arm.mass_ratio": "1",
    "arm.length_split": "1",
}
FIELD_HELP = (
    "base.mass | base.inertia | base.attach | links[i].FIELD or links[*].FIELD with FIELD in "
    "mass, inertia, a, b, length (a and b scaled together, inertia with the square) | "
    "arm.mass (link masses and inertias scaled together) | arm.mass_ratio (arm mass / base mass) | "
    "arm.length_split (l1 / L at fixed L; the other links scaled together)"
)


@dataclasses.dataclass(frozen=True)
class Axis:
    """One design axis: a field, its values, absolute or relative to the base design."""

    name: str
    field: str
    values: np.ndarray
    relative: bool = False


@dataclasses.dataclass(frozen=True)
class MetricSpec:
    name: str
    options: dict


@dataclasses.dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: the resolved config, the base robot, axes and metrics."""

    name: str
    config: dict
    robot: PlanarRobot
    axes: tuple[Axis, ...]
    combine: str
    metrics: tuple[MetricSpec, ...]
    chunk_size: int
    output: str
    report: str | None
    source: str
    robot_source: str = "inline"  # the robot file named by the sweep file, for the manifest

    @property
    def n_designs(self) -> int:
        sizes = [len(axis.values) for axis in self.axes]
        return int(np.prod(sizes)) if self.combine == "product" else sizes[0]

    @property
    def shape(self) -> tuple[int, ...]:
        """The grid shape of a product sweep (one entry per axis); (N,) for zip."""
        if self.combine == "product":
            return tuple(len(axis.values) for axis in self.axes)
        return (self.n_designs,)

    def summary(self) -> str:
        axes = ", ".join(f"{a.name} ({len(a.values)})" for a in self.axes)
        names = ", ".join(m.name for m in self.metrics)
        count = f"{self.n_designs} design" + ("s" if self.n_designs != 1 else "")
        return f"{self.name}: {count} over {axes} [{self.combine}]; metrics {names}"


def _unknown(where: str, mapping: Mapping, allowed: set[str]) -> None:
    for key in mapping:
        if key not in allowed:
            hint = difflib.get_close_matches(str(key), sorted(allowed), n=1)
            extra = f" (did you mean '{hint[0]}'?)" if hint else ""
            raise ConfigError(f"{where}unknown key '{key}'{extra}; allowed keys: {', '.join(sorted(allowed))}")


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _axis_values(where: str, spec: Mapping, n_links: int) -> np.ndarray:
    if ("values" in spec) == ("range" in spec):
        raise ConfigError(f"{where}: give exactly one of 'values' (a list) or 'range' (start, stop, num | step)")
    if "values" in spec:
        values = spec["values"]
        if not isinstance(values, (list, tuple)):
            raise ConfigError(f"{where}.values: must be a list of numbers, got {type(values).__name__}")
        if not values:
            raise ConfigError(f"{where}.values: is empty; an axis needs at least one value")
        for i, value in enumerate(values):
            if not _is_number(value) or not math.isfinite(value):
                raise ConfigError(f"{where}.values[{i}]: must be a finite number, got {value!r}")
        return np.asarray(values, dtype=np.float64)
    rng = spec["range"]
    if not isinstance(rng, Mapping):
        raise ConfigError(f"{where}.range: must be a mapping with start, stop and num or step")
    _unknown(f"{where}.range: ", rng, _RANGE_KEYS)
    for key in ("start", "stop"):
        if key not in rng:
            raise ConfigError(f"{where}.range.{key}: missing required key")
        if not _is_number(rng[key]) or not math.isfinite(rng[key]):
            raise ConfigError(f"{where}.range.{key}: must be a finite number, got {rng[key]!r}")
    if ("num" in rng) == ("step" in rng):
        raise ConfigError(f"{where}.range: give exactly one of 'num' or 'step'")
    start, stop = float(rng["start"]), float(rng["stop"])
    if not math.isfinite(stop - start):
        raise ConfigError(f"{where}.range: stop - start overflows ({start:g} to {stop:g})")
    if "num" in rng:
        num = rng["num"]
        if not isinstance(num, int) or isinstance(num, bool) or num < 1:
            raise ConfigError(f"{where}.range.num: must be a positive integer, got {num!r}")
        _check_size(f"{where}.range", num, f"num: {num}", n_links)
        return np.linspace(start, stop, num)
    step = rng["step"]
    if not _is_number(step) or step == 0 or not math.isfinite(step):
        raise ConfigError(f"{where}.range.step: must be a nonzero number (negative for a descending axis), got {step!r}")
    steps = (stop - start) / step
    if not math.isfinite(steps) or steps > 2**53:
        raise ConfigError(f"{where}.range.step: {step:g} from {start:g} to {stop:g} gives too many values")
    count = int(math.floor(steps + 1e-9)) + 1
    if count < 1:
        raise ConfigError(f"{where}.range: stepping by {step:g} from {start:g} never reaches {stop:g}; the axis is empty")
    _check_size(f"{where}.range", count, f"{count} steps", n_links)
    return start + step * np.arange(count)


def _check_field(where: str, field: Any, n_links: int) -> str:
    if not isinstance(field, str):
        raise ConfigError(f"{where}.field: must be a string, one of: {FIELD_HELP}")
    if field in _SIMPLE_FIELDS or field in _DERIVED_FIELDS:
        if field == "arm.length_split" and n_links < 2:
            raise ConfigError(f"{where}.field: arm.length_split needs at least 2 links")
        return field
    match = _LINK_FIELD.match(field)
    if match:
        index = match.group(1)
        if index != "*" and int(index) >= n_links:
            raise ConfigError(f"{where}.field: link index {index} out of range; the robot has {n_links} links (0..{n_links - 1})")
        return field
    known = sorted(_SIMPLE_FIELDS) + sorted(_DERIVED_FIELDS) + [f"links[0].{k}" for k in ("mass", "inertia", "a", "b", "length")]
    hint = difflib.get_close_matches(field, known, n=1)
    extra = f" (did you mean '{hint[0]}'?)" if hint else ""
    raise ConfigError(f"{where}.field: unknown design field '{field}'{extra}; fields: {FIELD_HELP}")


def _metric_specs(where: str, entries: Any) -> tuple[MetricSpec, ...]:
    if entries is None:
        raise ConfigError(f"{where}: missing required key; e.g. metrics: [wbar, S_M, S_G]")
    if not isinstance(entries, (list, tuple)) or not entries:
        raise ConfigError(f"{where}: must be a non-empty list of metric names; known: {', '.join(sorted(METRICS))}")
    specs = []
    for i, entry in enumerate(entries):
        if isinstance(entry, str):
            name, options = entry, {}
        elif isinstance(entry, Mapping) and isinstance(entry.get("name"), str):
            name, options = entry["name"], {k: v for k, v in entry.items() if k != "name"}
        else:
            raise ConfigError(f"{where}[{i}]: must be a metric name or a mapping with 'name'")
        if name not in METRICS:
            hint = difflib.get_close_matches(name, sorted(METRICS), n=1)
            extra = f" (did you mean '{hint[0]}'?)" if hint else ""
            raise ConfigError(f"{where}[{i}]: unknown metric '{name}'{extra}; known: {', '.join(sorted(METRICS))}")
        METRICS[name].check(f"{where}[{i}]", options)
        specs.append(MetricSpec(name, dict(options)))
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        raise ConfigError(f"{where}: a metric is listed twice")
    return tuple(specs)


def _apply_overrides(config: dict, overrides: Sequence[str]) -> dict:
    """``--set a.b.c=value``: value parsed as YAML, path through mappings (created if
    missing); ``--set a.b=null`` removes the key."""
    config = copy.deepcopy(config)
    for item in overrides:
        if "=" not in item:
            raise ConfigError(f"--set {item}: expected KEY=VALUE, e.g. --set chunk_size=64")
        key, raw = item.split("=", 1)
        parts = key.strip().split(".")
        if not all(parts):
            raise ConfigError(f"--set {item}: the key must be a dotted path of names, e.g. axes.b0_over_B0.values")
        _unknown(f"--set {key}: ", {parts[0]: None}, _TOP_KEYS)
        try:
            value = yaml.safe_load(raw)
        except yaml.YAMLError as error:
            raise ConfigError(f"--set {key}: {describe_yaml_error(error)}") from None
        node = config
        for part in parts[:-1]:
            if not isinstance(node, dict):
                raise ConfigError(f"--set {key}: '{part}' is not a mapping in the sweep file")
            if value is None and part not in node:
                break  # nothing to remove
            node = node.setdefault(part, {})
        else:
            if not isinstance(node, dict):
                raise ConfigError(f"--set {key}: cannot set a key inside a non-mapping")
            if value is None:
                node.pop(parts[-1], None)
            else:
                node[parts[-1]] = value
    return config


def load_sweep(source: str | os.PathLike | Mapping, overrides: Sequence[str] = ()) -> SweepSpec:
    """Read and validate a sweep file (or mapping), with ``--set`` overrides applied.

    Validates everything a run needs, including every sweep point's design, so an
    invalid sweep fails before anything is written.

    Raises:
        ConfigError: naming the key (and the sweep point) and the reason.
    """
    if isinstance(source, Mapping):
        config, where, base_dir = dict(source), "sweep", Path.cwd()
    else:
        from .validate import read_yaml

        path = Path(source)
        config, where, base_dir = read_yaml(path), str(path), path.resolve().parent
        if not isinstance(config, dict):
            raise ConfigError(f"{where}: a sweep file must be a mapping with robot, axes and metrics")
    config = _apply_overrides(config, overrides)
    _unknown(f"{where}: ", config, _TOP_KEYS)
    name = config.get("name", Path(where).stem if where != "sweep" else "sweep")
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_.-]+", name):
        raise ConfigError(f"{where}: name: must be a plain name (letters, digits, _ . -), got {name!r}")

    # The base robot: a path (relative to the sweep file) or an inline mapping.
    if "robot" not in config:
        raise ConfigError(f"{where}: robot: missing required key (a robot file path or an inline robot)")
    robot_entry = config["robot"]
    if isinstance(robot_entry, str):
        robot_path = Path(robot_entry)
        if not robot_path.is_absolute():
            candidate = base_dir / robot_path
            robot_path = candidate if candidate.exists() or not robot_path.exists() else robot_path
        if not robot_path.exists():
            raise ConfigError(f"{where}: robot: no such robot file '{robot_entry}' (looked in {base_dir})")
        if robot_path.is_dir():
            raise ConfigError(f"{where}: robot: '{robot_entry}' is a folder, not a robot file")
        robot = load_robot(robot_path)
        robot_source = str(robot_entry)
    elif isinstance(robot_entry, Mapping):
        robot = robot_from_mapping(robot_entry, source=f"{where}: robot")
        robot_source = "inline"
    else:
        raise ConfigError(f"{where}: robot: must be a file path or an inline robot mapping")

    axes_entry = config.get("axes")
    if not isinstance(axes_entry, Mapping) or not axes_entry:
        raise ConfigError(f"{where}: axes: must be a non-empty mapping of axis name -> {{field, values | range}}")
    axes = []
    for axis_name, spec in axes_entry.items():
        at = f"{where}: axes.{axis_name}"
        if not isinstance(axis_name, str) or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", axis_name):
            raise ConfigError(f"{at}: axis names must be identifiers (letters, digits, _)")
        if not isinstance(spec, Mapping):
            raise ConfigError(f"{at}: must be a mapping with field and values or range")
        _unknown(f"{at}: ", spec, _AXIS_KEYS)
        if "field" not in spec:
            raise ConfigError(f"{at}.field: missing required key; fields: {FIELD_HELP}")
        field = _check_field(at, spec["field"], robot.n_links)
        relative = spec.get("relative", False)
        if not isinstance(relative, bool):
            raise ConfigError(f"{at}.relative: must be true or false, got {relative!r}")
        axes.append(Axis(axis_name, field, _axis_values(at, spec, robot.n_links), relative))

    _check_axes_compatible(where, axes, robot.n_links)
    if config.get("combine", "product") == "product":
        _check_size(f"{where}: axes", math.prod(len(a.values) for a in axes),
                    " x ".join(str(len(a.values)) for a in axes), robot.n_links)

    combine = config.get("combine", "product")
    if combine not in ("product", "zip"):
        raise ConfigError(f"{where}: combine: must be 'product' or 'zip', got {combine!r}")
    if combine == "zip" and len({len(a.values) for a in axes}) > 1:
        sizes = ", ".join(f"{a.name}: {len(a.values)}" for a in axes)
        raise ConfigError(f"{where}: combine: zip needs axes of equal length ({sizes})")

    metrics = _metric_specs(f"{where}: metrics", config.get("metrics"))
    chunk_size = config.get("chunk_size", 256)
    if not isinstance(chunk_size, int) or isinstance(chunk_size, bool) or chunk_size < 1:
        raise ConfigError(f"{where}: chunk_size: must be a positive integer, got {chunk_size!r}")
    output = config.get("output", f"results/{name}")
    if not isinstance(output, str):
        raise ConfigError(f"{where}: output: must be a folder path")
    report = config.get("report")
    if report is not None:
        from .reports import REPORTS

        if report not in REPORTS:
            raise ConfigError(f"{where}: report: unknown report {report!r}; known: {', '.join(sorted(REPORTS))}")

    resolved = {
        "name": name,
        "description": config.get("description", ""),
        "robot": _robot_mapping(robot),  # inline, so the resolved config is itself a sweep file
        "axes": {a.name: {"field": a.field, "relative": a.relative, "values": a.values.tolist()} for a in axes},
        "combine": combine,
        "metrics": [{"name": m.name, **m.options} for m in metrics],
        "chunk_size": chunk_size,
        "output": output,
        "report": report,
    }
    spec = SweepSpec(
        name=name, config=resolved, robot=robot, axes=tuple(axes), combine=combine, metrics=metrics,
        chunk_size=chunk_size, output=output, report=report, source=where, robot_source=robot_source,
    )
    if report is not None:
        from .reports import REPORT_CHECKS

        REPORT_CHECKS[report](spec)
    for i, metric in enumerate(metrics):
        METRICS[metric.name].check_robot(f"{where}: metrics[{i}]", metric.options, robot)
    build_designs(spec)  # validates every sweep point before anything is written
    return spec


def _check_size(where: str, count: int, sizes: str, n_links: int) -> None:
    """Refuse a sweep whose designs alone would not fit in memory (they are built at once),
    before anything that large is allocated."""
    need = count * 8 * (3 + 6 * n_links) * 4  # float64 leaves, with room for temporaries
    try:
        have = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return
    if need > have / 2:
        raise ConfigError(
            f"{where}: {count:,} designs ({sizes}) need about {need / 2**30:,.0f} GiB to hold, "
            f"more than half of this machine's {have / 2**30:.0f} GiB; split the sweep into several files"
        )


def _robot_mapping(robot: PlanarRobot) -> dict:
    from .robot import robot_to_mapping

    return robot_to_mapping(robot)


# Designs ------------------------------------------------------------------------------


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
    if field in _SIMPLE_FIELDS:
        key = _SIMPLE_FIELDS[field][0]
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
    if field in _SIMPLE_FIELDS:
        return {_SIMPLE_FIELDS[field][0]}
    if field in ("arm.mass", "arm.mass_ratio"):
        return {f"{leaf}[{i}]" for leaf in ("link_mass", "link_inertia") for i in links}
    if field == "arm.length_split":
        return {f"{leaf}[{i}]" for leaf in ("link_a", "link_b", "link_inertia") for i in links}
    index, what = _LINK_FIELD.match(field).groups()
    chosen = links if index == "*" else [int(index)]
    leaves = {"mass": ["link_mass"], "inertia": ["link_inertia"], "a": ["link_a"], "b": ["link_b"],
              "length": ["link_a", "link_b", "link_inertia"]}[what]
    return {f"{leaf}[{i}]" for leaf in leaves for i in chosen}


def _check_axes_compatible(where: str, axes: Sequence[Axis], n_links: int) -> None:
    """Refuse two axes that set the same design number: the result would depend on the
    order of application. A length axis and an arm-mass axis both scale the link
    inertias, by commuting factors, so such pairs are allowed."""
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


# Metrics ------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Metric:
    """Per-design scalars: ``fn(robot, options) -> {column: value}``, traceable."""

    fn: Callable[[PlanarRobot, dict], dict]
    columns: Callable[[dict], list[str]]
    check: Callable[[str, dict], None] = lambda where, options: _no_options(where, options)
    description: str = ""
    # Checks that need the base robot (e.g. its number of links).
    check_robot: Callable[[str, dict, PlanarRobot], None] = lambda where, options, robot: None


def _no_options(where: str, options: dict) -> None:
    if options:
        raise ConfigError(f"{where}: this metric takes no options, got {', '.join(options)}")


# The options of metrics.average_manipulability a sweep file may set (the rest are
# about batching, which the sweep does itself).
_WBAR_OPTIONS = ("measure", "elbow", "rule", "phi1_panels", "phi2_panels", "order", "newton_steps", "n_points_joint")


def _check_wbar(where: str, options: dict) -> None:
    from .metrics import check_average_options

    _unknown(f"{where}: ", options, set(_WBAR_OPTIONS))
    check_average_options(where=f"{where}.", **options)


def _check_wbar_robot(where: str, options: dict, robot: PlanarRobot) -> None:
    if robot.n_links != 2 and options.get("measure", "area") == "area":
        raise ConfigError(
            f"{where}: wbar's area average (eq. 12) is defined for 2 links, the robot has {robot.n_links}; "
            "use {name: wbar, measure: joint}"
        )


def _check_straight_robot(where: str, options: dict, robot: PlanarRobot) -> None:
    phi = options.get("phi_start_deg", [0.0, -60.0, 120.0])
    if len(phi) != robot.n_links + 1:
        raise ConfigError(
            f"{where}.phi_start_deg: needs {robot.n_links + 1} angles [phi0, phi1, ..., phi{robot.n_links}] "
            f"for a {robot.n_links}-link robot, got {len(phi)}"
        )


def _wbar(robot, options):
    from .metrics import average_manipulability

    return {"wbar": average_manipulability(robot, **options)}


def _areas(robot, options):
    from .metrics import normalized_areas

    s_m, s_g = normalized_areas(robot)
    return {"S_M": s_m, "S_G": s_g}


def _radii(robot, options):
    from .kinematics import tip_coefficients

    K = tip_coefficients(robot)
    arm = jnp.sum(K[1:])
    return {
        "K0_m": K[0],
        "R_attitude_m": arm,
        "R_max_m": K[0] + arm,
        "R_guaranteed_m": jnp.abs(K[0] - arm),
        "L_m": robot.reach,
    }


def _workspace_areas(robot, options):
    from .workspace import attachment_condition, normalized_areas

    areas = normalized_areas(robot)
    return {
        "S_fixed_vehicle": areas["fixed_vehicle"],
        "S_attitude_constraint": areas["attitude_constraint"],
        "S_maximum_reachable": areas["maximum_reachable"],
        "S_guaranteed": areas["guaranteed"],
        "eq9_holds": attachment_condition(robot).astype(areas["guaranteed"].dtype),
    }


def _check_straight(where: str, options: dict) -> None:
    allowed = {"phi_start_deg", "n_directions"}
    _unknown(f"{where}: ", options, allowed)
    phi = options.get("phi_start_deg", [0.0, -60.0, 120.0])
    if not isinstance(phi, (list, tuple)) or not all(_is_number(v) for v in phi):
        raise ConfigError(f"{where}.phi_start_deg: must be a list of numbers [phi0, phi1, ..., phin] in degrees")
    count = options.get("n_directions", 72)
    if not isinstance(count, int) or isinstance(count, bool) or count < 8:
        raise ConfigError(f"{where}.n_directions: must be an integer >= 8, got {count!r}")


def _straight_area(robot, options):
    from .workspace import straight_path_workspace

    phi = jnp.radians(jnp.asarray(options.get("phi_start_deg", [0.0, -60.0, 120.0]), dtype=float))
    boundary = straight_path_workspace(robot, phi, n_directions=options.get("n_directions", 72))
    x, y = boundary[:, 0], boundary[:, 1]
    area = 0.5 * jnp.abs(jnp.sum(x * jnp.roll(y, -1) - jnp.roll(x, -1) * y))  # shoelace
    return {"S_straight": area / (jnp.pi * robot.reach**2)}


METRICS: dict[str, Metric] = {
    "wbar": Metric(_wbar, lambda o: ["wbar"], check=_check_wbar, check_robot=_check_wbar_robot, description="eq. 12: average of w*/L^2 over the elbow-down area, robot frame"),
    "S_M": Metric(_areas, lambda o: ["S_M"], description="Maximum Reachable area / (pi L^2)"),
    "S_G": Metric(_areas, lambda o: ["S_G"], description="Guaranteed Workspace area / (pi L^2) (eq. 8)"),
    "radii": Metric(_radii, lambda o: ["K0_m", "R_attitude_m", "R_max_m", "R_guaranteed_m", "L_m"],
                    description="K0, the Attitude-Constraint, Maximum-Reachable and Guaranteed radii, and L, in m"),
    "workspace_areas": Metric(_workspace_areas, lambda o: ["S_fixed_vehicle", "S_attitude_constraint",
                                                          "S_maximum_reachable", "S_guaranteed", "eq9_holds"],
                              description="Areas 1-3 and 5 with their holes removed / (pi L^2), and eq. 9 (1 or 0)"),
    "straight_path_area": Metric(_straight_area, lambda o: ["S_straight"], check=_check_straight,
                                 check_robot=_check_straight_robot,
                                 description="Straight-Path workspace area from phi_start_deg / (pi L^2)"),
}


def _columns(spec: SweepSpec) -> list[str]:
    names: list[str] = []
    for metric in spec.metrics:
        for column in METRICS[metric.name].columns(metric.options):
            if column not in names:
                names.append(column)
    return names


def design_function(spec: SweepSpec) -> Callable[[PlanarRobot], dict]:
    """The per-design function of a sweep: robot -> {column: scalar}."""
    wanted = _columns(spec)

    def evaluate(robot: PlanarRobot) -> dict:
        values: dict = {}
        done: set = set()
        for metric in spec.metrics:
            entry = METRICS[metric.name]
            if entry.fn in done:
                continue
            done.add(entry.fn)
            values.update(entry.fn(robot, metric.options))
        return {column: values[column] for column in wanted}

    return evaluate


# Running --------------------------------------------------------------------------------


def _design_columns(robot: PlanarRobot, spec: SweepSpec) -> dict[str, np.ndarray]:
    """The varied design numbers per point, SI units in the column names."""
    columns: dict[str, np.ndarray] = {}
    for axis in spec.axes:
        if axis.field in _SIMPLE_FIELDS:
            key, unit = _SIMPLE_FIELDS[axis.field]
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


def _mesh():
    devices = np.array(jax.devices())
    return jax.sharding.Mesh(devices, ("designs",))


def _chunks(total: int, size: int) -> list[tuple[int, int]]:
    return [(start, min(start + size, total)) for start in range(0, total, size)]


def _take(robot: PlanarRobot, start: int, stop: int, size: int, devices: int) -> PlanarRobot:
    """Rows start:stop, padded to ``size`` by repeating the last row (static shapes),
    as ``(devices, size // devices, ...)``: one row of designs per device."""
    index = np.minimum(np.arange(start, start + size), stop - 1).reshape(devices, -1)
    return jax.tree_util.tree_map(lambda x: np.asarray(x)[index], robot)


def _shard(tree, sharding):
    """Place a host batch on the device mesh; every process supplies the shards it owns,
    so the same code runs on one device, many devices, or many hosts (jax.distributed)."""
    def place(x):
        x = np.asarray(x)
        return jax.make_array_from_callback(x.shape, sharding, lambda index: x[index])

    return jax.tree_util.tree_map(place, tree)


def _gather(array) -> np.ndarray:
    """A global result as a host array (all-gathered across processes when multi-host)."""
    if getattr(array, "is_fully_addressable", True):
        return np.asarray(array)
    from jax.experimental import multihost_utils

    return np.asarray(multihost_utils.process_allgather(array, tiled=True))


@dataclasses.dataclass
class SweepResult:
    out_dir: Path
    table: dict[str, np.ndarray]
    manifest: dict
    files: list[Path]


def run_sweep(spec: SweepSpec, out_dir: str | os.PathLike | None = None, *, progress: bool = True,
              command: Sequence[str] | None = None, stop_after_chunks: int | None = None) -> SweepResult:
    """Evaluate every design of a sweep and write ``table.csv``, ``grids.npz``, ``manifest.json``
    and figures into ``out_dir`` (default: the sweep's ``output``).

    Finished chunks are saved under ``out_dir/.partial-<hash>/``; a re-run of the same
    resolved sweep loads them and computes only the rest. ``stop_after_chunks`` simulates
    an interruption (for tests).
    """
    from tqdm.auto import tqdm

    wall_start = time.perf_counter()
    out_dir = Path(out_dir if out_dir is not None else spec.output)
    _check_output_dir(out_dir)
    code_state = results.git_state()  # before this run changes any tracked result file
    robot, points = build_designs(spec)
    total = spec.n_designs
    devices = jax.device_count()
    chunk = max(devices, int(math.ceil(min(spec.chunk_size, total) / devices)) * devices)
    # Saved chunks are reused only by a run that would compute them bit for bit alike:
    # same resolved config, effective chunk size, precision and package versions.
    from . import __version__

    resume_key = {"config": spec.config, "axis_order": [a.name for a in spec.axes], "chunk": chunk, "float64": bool(jax.config.jax_enable_x64),
                  "spacearm": __version__, "jax": jax.__version__}
    partial = out_dir / f".partial-{results.config_hash(resume_key)[:16]}"

    mesh = _mesh()
    sharding = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("designs"))
    # Each device walks its share of a chunk in vmapped steps of a few designs: the
    # quadratures' intermediates then stay in cache (a whole chunk in one vmap is 3-7x
    # slower per design on CPU), while chunk_size alone bounds the memory.
    per_device = chunk // devices
    step = jax.vmap(functools.partial(jax.lax.map, design_function(spec), batch_size=min(DESIGNS_PER_STEP, per_device)))
    evaluate = jax.jit(lambda batch: jax.tree_util.tree_map(lambda v: v.reshape(-1), step(batch)))
    columns = _columns(spec)

    compile_s = 0.0
    compiled = None
    pieces: dict[int, dict[str, np.ndarray]] = {}
    spans = _chunks(total, chunk)
    for number, (start, stop) in enumerate(spans):
        saved = partial / f"chunk_{number:06d}.npz"
        if saved.exists():
            try:
                with np.load(saved) as data:
                    piece = {c: data[c] for c in columns}
            except Exception:  # damaged (e.g. the disk filled up): compute it again
                saved.unlink()
                continue
            if all(v.shape == (stop - start,) for v in piece.values()):
                pieces[number] = piece
    todo = [n for n in range(len(spans)) if n not in pieces]
    run_start = time.perf_counter()
    bar = tqdm(total=total, desc=f"sweep {spec.name}", unit="design", disable=not progress, file=sys.stderr,
               initial=sum(stop - start for n, (start, stop) in enumerate(spans) if n in pieces))
    try:
        for done, number in enumerate(todo):
            if stop_after_chunks is not None and done >= stop_after_chunks:
                raise KeyboardInterrupt
            start, stop = spans[number]
            batch = _shard(_take(robot, start, stop, chunk, devices), sharding)
            if compiled is None:
                t0 = time.perf_counter()
                compiled = evaluate.lower(batch).compile()
                compile_s = time.perf_counter() - t0
            values = compiled(batch)
            piece = {c: _gather(values[c])[: stop - start] for c in columns}
            if jax.process_index() == 0:
                results.write_npz(partial / f"chunk_{number:06d}.npz", **piece)
            pieces[number] = piece
            bar.update(stop - start)
    except KeyboardInterrupt:
        bar.close()
        kept = sum(stop - start for n, (start, stop) in enumerate(spans) if n in pieces)
        print(f"{kept:,} of {total:,} designs kept in {partial}; run the same command again to resume",
              file=sys.stderr)
        raise
    finally:
        bar.close()
    run_s = time.perf_counter() - run_start - compile_s

    metric_values = {c: np.concatenate([pieces[n][c] for n in range(len(spans))]) for c in columns}
    table: dict[str, np.ndarray] = {"design": np.arange(total)}
    table.update(points)
    table.update(_design_columns(robot, spec))
    table.update(metric_values)

    if jax.process_index() != 0:  # multi-host: the first process writes the results
        return SweepResult(out_dir, table, {}, [])
    files = [results.write_csv(out_dir / "table.csv", table)]
    grid_arrays = {f"axis/{a.name}": a.values for a in spec.axes}
    grid_arrays.update({f"metric/{c}": metric_values[c].reshape(spec.shape) for c in columns})
    grid_arrays["dims"] = np.array([a.name for a in spec.axes] if spec.combine == "product" else ["design"])
    files.append(results.write_npz(out_dir / "grids.npz", **grid_arrays))
    files.extend(_sweep_figures(spec, out_dir, metric_values))
    if spec.report:
        from .reports import REPORTS

        rows = [{k: float(v[i]) for k, v in table.items()} for i in range(total)]
        files.extend(REPORTS[spec.report](out_dir, rows, spec))
    timings = {"compile": compile_s, "run": run_s, "wall": time.perf_counter() - wall_start}
    data = results.manifest(
        spec.config, command=command, timings=timings, git=code_state,
        extra={"robot_file": spec.robot_source, "n_designs": total, "chunk_size": chunk, "resumed_chunks": len(spans) - len(todo),
               "files": sorted(str(p.relative_to(out_dir)) for p in files)},
    )
    previous = _previous_files(out_dir)
    files.append(results.write_json(out_dir / "manifest.json", data))
    shutil.rmtree(partial, ignore_errors=True)
    for name in previous - {str(p.relative_to(out_dir)) for p in files}:
        try:
            (out_dir / name).unlink(missing_ok=True)  # an earlier sweep's figure this run did not draw
        except OSError:
            pass
    others = sorted(p.name for p in out_dir.glob(".partial-*") if p.is_dir())
    if others:
        print(f"note: {out_dir} also holds {', '.join(others)} (chunks of another sweep run into this folder; "
              "delete them if no run needs them)", file=sys.stderr)
    return SweepResult(out_dir, table, data, files)


# The names a sweep writes (see run_sweep and the reports): only these are ever removed.
_OWN_FILES = re.compile(r"(table\.csv|grids\.npz|metrics\.png|table\.md|fig10\.png|heatmap_[A-Za-z0-9_.]+\.png)")


def _previous_files(out_dir: Path) -> set[str]:
    """Files an earlier sweep wrote into ``out_dir``, read from its manifest when that is a
    spacearm sweep manifest; limited to the names a sweep writes."""
    try:
        manifest = json.loads((out_dir / "manifest.json").read_text())
        listed = manifest["files"] if "spacearm" in manifest["packages"] and "config_sha256" in manifest else []
    except (OSError, ValueError, KeyError, TypeError):
        return set()
    return {name for name in listed if isinstance(name, str) and _OWN_FILES.fullmatch(name)}


def _check_output_dir(out_dir: Path) -> None:
    """ConfigError unless ``out_dir`` is, or can become, a writable folder (nothing is created)."""
    target = out_dir.absolute()
    existing = target
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise ConfigError(f"--out {out_dir}: {existing} is a file, not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise ConfigError(f"--out {out_dir}: cannot write into {existing} (permission denied)")


def _axis_label(axis: Axis) -> str:
    """The axis name with its unit: SI for absolute values, 'relative' otherwise."""
    if axis.relative:
        return f"{axis.name} (relative)"
    if axis.field in _SIMPLE_FIELDS:
        unit = _SIMPLE_FIELDS[axis.field][1].replace("_m2", " m^2")
    elif axis.field in _DERIVED_FIELDS:
        unit = _DERIVED_FIELDS[axis.field]
    else:
        unit = {"mass": "kg", "inertia": "kg m^2"}.get(axis.field.rsplit(".", 1)[1], "m")
    return axis.name if unit == "1" else f"{axis.name} [{unit}]"


def _sweep_figures(spec: SweepSpec, out_dir: Path, values: dict[str, np.ndarray]) -> list[Path]:
    """A heatmap per metric for 2-D product sweeps, line plots for 1-D and zipped sweeps
    (against the first axis); none for 3 or more product axes (grids.npz holds them).
    Columns that do not vary are left out of the figures."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    varying = {c: v for c, v in values.items() if np.ptp(v) > 1e-12 * max(1.0, float(np.max(np.abs(v))))} or values
    paths = []
    if spec.combine == "product" and len(spec.axes) == 2:
        ax0, ax1 = spec.axes
        for column, flat in varying.items():
            grid = flat.reshape(spec.shape)
            fig, ax = plt.subplots(figsize=(5.5, 4.2), constrained_layout=True)
            # Cells by index, labelled with the values, so uneven axes draw as even cells.
            mesh = ax.pcolormesh(np.arange(len(ax1.values)), np.arange(len(ax0.values)), grid, shading="nearest",
                                 cmap="viridis")
            fig.colorbar(mesh, ax=ax, label=column)
            if grid.size > 1 and np.ptp(grid) > 0 and min(grid.shape) > 1:
                contours = ax.contour(np.arange(len(ax1.values)), np.arange(len(ax0.values)), grid, colors="white",
                                      linewidths=0.6)
                ax.clabel(contours, fontsize=7, fmt="%.3g")
            for axis, set_ticks, set_labels in ((ax1, ax.set_xticks, ax.set_xticklabels),
                                                (ax0, ax.set_yticks, ax.set_yticklabels)):
                ticks = np.unique(np.linspace(0, len(axis.values) - 1, min(len(axis.values), 7)).round().astype(int))
                set_ticks(ticks)
                set_labels([f"{axis.values[t]:.3g}" for t in ticks])
            ax.set_xlabel(_axis_label(ax1))
            ax.set_ylabel(_axis_label(ax0))
            ax.set_title(f"{spec.name}: {column}")
            paths.append(results.save_figure(fig, out_dir / f"heatmap_{column}.png", dpi=130))
            plt.close(fig)
    elif len(spec.axes) == 1 or spec.combine == "zip":
        axis = spec.axes[0]
        fig, axes = plt.subplots(1, len(varying), figsize=(3.6 * len(varying), 3.2), constrained_layout=True,
                                 squeeze=False)
        for ax, (column, flat) in zip(axes[0], varying.items()):
            ax.plot(axis.values, flat, "o-")
            ax.set_xlabel(_axis_label(axis) + (" (axes zipped)" if len(spec.axes) > 1 else ""))
            ax.set_ylabel(column)
            ax.grid(alpha=0.3)
        fig.suptitle(spec.name)
        paths.append(results.save_figure(fig, out_dir / "metrics.png", dpi=130))
        plt.close(fig)
    else:
        print(f"no figures for a {len(spec.axes)}-axis product sweep; grids.npz holds the arrays", file=sys.stderr)
    return paths


# Command line ---------------------------------------------------------------------------


def _cmd_sweep(args) -> int:
    spec = load_sweep(args.file, overrides=args.set or [])
    out_dir = Path(args.out) if args.out else Path(spec.output)
    print(spec.summary(), file=sys.stderr)
    try:
        result = run_sweep(spec, out_dir, progress=not args.quiet, command=sys.argv)
    except OSError as error:  # e.g. a read-only file system under --out
        raise ConfigError(f"--out {out_dir}: cannot write the results ({error.strerror or error})") from None
    timings = result.manifest["timings_s"]
    print(f"wrote {out_dir}/ ({len(result.files)} files; compile {timings['compile']:.1f} s, "
          f"run {timings['run']:.1f} s, wall {timings['wall']:.1f} s)")
    return 0


def add_sweep_command(subparsers) -> None:
    parser = subparsers.add_parser(
        "sweep",
        help="run a YAML design sweep (e.g. sweeps/table2.yaml)",
        description=(
            "Evaluate every design of a sweep file in compiled, batched chunks and write table.csv,\n"
            "grids.npz, manifest.json and figures into results/<name>/ (or --out). An interrupted\n"
            "sweep resumes from the finished chunks when run again."
        ),
        epilog=(
            "examples:\n"
            "  spacearm sweep sweeps/table2.yaml\n"
            "  spacearm sweep sweeps/masses.yaml --set chunk_size=64 --out /tmp/quick\n"
            f"design fields for axes: {FIELD_HELP}\n"
            f"metrics: {', '.join(sorted(METRICS))}\n"
            f"wbar options ({{name: wbar, ...}}): {', '.join(_WBAR_OPTIONS)}; rule: product trades the\n"
            "  default's ~1e-13 for ~1e-4 and a fixed node grid that is many times faster for big sweeps"
        ),
        formatter_class=__import__("argparse").RawDescriptionHelpFormatter,
    )
    parser.add_argument("file", help="the sweep YAML file")
    parser.add_argument("--out", metavar="DIR", help="output folder (default: the file's 'output', or results/<name>)")
    parser.add_argument("--set", metavar="KEY=VALUE", action="append",
                        help="override a key of the sweep file (dotted path, YAML value); repeatable")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=_cmd_sweep)


def _cmd_figures(args) -> int:
    from tqdm.auto import tqdm

    from .figures import all_figures

    figures = all_figures()
    if args.only is not None and not args.only.strip(","):
        raise ConfigError(f"--only: no figure named; known: {', '.join(figures)}")
    wanted = [name for name in args.only.split(",") if name] if args.only is not None else list(figures)
    unknown = [name for name in wanted if name not in figures]
    if unknown:
        raise ConfigError(f"--only: unknown figure(s) {', '.join(unknown)}; known: {', '.join(figures)}")
    out_dir = Path(args.out)
    written: list[Path] = []
    for name in tqdm(wanted, desc="figures", unit="figure", file=sys.stderr, disable=args.quiet):
        written.extend(figures[name](out_dir))
    for path in written:
        print(path)
    return 0


def add_figures_command(subparsers) -> None:
    parser = subparsers.add_parser(
        "figures",
        help="regenerate every paper figure into results/figures/",
        description="Regenerate the paper's figures (and ours) as PNG files.",
    )
    parser.add_argument("--out", default="results/figures", metavar="DIR", help="output folder (default results/figures)")
    parser.add_argument("--only", metavar="NAMES", help="comma-separated figure names, e.g. fig2,fig7")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=_cmd_figures)
