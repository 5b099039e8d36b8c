"""Sweep files: the schema, ``--set`` overrides and the validated `SweepSpec`.

A sweep file names a base robot (a file in ``configs/`` or an inline mapping), the
design axes to vary, how to combine them, and the metrics to compute::

    name: table2
    robot: ../configs/umetani1990.yaml
    axes:
      b0_over_B0: {field: base.attach, relative: true, values: [0, 0.5, 1.0, 1.5, 2.0]}
    metrics: [wbar, S_M, S_G]

Metrics taken along a timed task (``peak_joint_torque``, ``peak_held_wrench``) read the
file's ``task: {waypoints: [[...], ...], duration: 4.0}`` (joints in rad, or
``waypoints_deg``; `spacearm.motion.tasks`).

`load_sweep` checks everything a run uses, down to every sweep point's design, so
an invalid sweep fails before anything is written.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import jax
import numpy as np
import yaml

from .._core.errors import ConfigError
from .._core.schema import (
    check_keys,
    check_memory,
    describe_yaml_error,
    integer,
    is_number,
    number,
    quote,
    read_yaml,
)
from ..models import load_robot, robot_from_file_mapping
from ..models.family import family_of
from ..motion.tasks import task_from_mapping
from .designs import Axis, axis_points, build_designs, check_axes_compatible, check_field, field_axis_unit
from .metrics import METRICS, MetricSpec, attach_task, metric_specs, resolve_tips
from .table2 import REPORT_CHECKS, REPORTS

__all__ = ["Axis", "MetricSpec", "SweepSpec", "apply_overrides", "axis_points", "load_sweep"]

_TOP_KEYS = {
    "name",
    "description",
    "robot",
    "axes",
    "combine",
    "metrics",
    "output",
    "chunk_size",
    "report",
    "task",
}
_AXIS_KEYS = {"field", "values", "range", "relative"}
_RANGE_KEYS = {"start", "stop", "num", "step"}


@dataclasses.dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: the resolved config, the base robot, axes and metrics."""

    name: str
    config: dict
    robot: Any  # a robot of any family (`spacearm.models.family_of` gives its record)
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
        names = ", ".join(
            m.name + (f"[{m.options['tip']}]" if m.options.get("tip") is not None else "") for m in self.metrics
        )
        count = f"{self.n_designs} design" + ("s" if self.n_designs != 1 else "")
        return f"{self.name}: {count} over {axes} [{self.combine}]; metrics {names}"


def _axis_values(where: str, spec: Mapping, numbers: int) -> np.ndarray:
    if ("values" in spec) == ("range" in spec):
        raise ConfigError(f"{where}: give exactly one of 'values' (a list) or 'range' (start, stop, num | step)")
    if "values" in spec:
        values = spec["values"]
        if not isinstance(values, (list, tuple)):
            raise ConfigError(f"{where}.values: must be a list of numbers, got {type(values).__name__} {quote(values)}")
        if not values:
            raise ConfigError(f"{where}.values: is empty; an axis needs at least one value")
        for i, value in enumerate(values):
            if not is_number(value) or not math.isfinite(value):
                raise ConfigError(f"{where}.values[{i}]: must be a finite number, got {quote(value)}")
            number(f"{where}.values[{i}]", value)  # not huge either (MAX_MAGNITUDE)
        return np.asarray(values, dtype=np.float64)
    rng = spec["range"]
    if not isinstance(rng, Mapping):
        raise ConfigError(f"{where}.range: must be a mapping with start, stop and num or step")
    check_keys(f"{where}.range: ", rng, _RANGE_KEYS)
    for key in ("start", "stop"):
        if key not in rng:
            raise ConfigError(f"{where}.range.{key}: missing required key")
        if not is_number(rng[key]) or not math.isfinite(rng[key]):
            raise ConfigError(f"{where}.range.{key}: must be a finite number, got {quote(rng[key])}")
        number(f"{where}.range.{key}", rng[key])  # not huge either (MAX_MAGNITUDE)
    if ("num" in rng) == ("step" in rng):
        raise ConfigError(f"{where}.range: give exactly one of 'num' or 'step'")
    start, stop = float(rng["start"]), float(rng["stop"])
    if not math.isfinite(stop - start):
        raise ConfigError(f"{where}.range: stop - start overflows ({start:g} to {stop:g})")
    if "num" in rng:
        num = rng["num"]
        if not isinstance(num, int) or isinstance(num, bool) or num < 1:
            raise ConfigError(f"{where}.range.num: must be a positive integer, got {num!r}")
        _check_size(f"{where}.range", num, f"num: {num}", numbers)
        return np.linspace(start, stop, num)
    step = rng["step"]
    if not is_number(step) or step == 0 or not math.isfinite(step):
        raise ConfigError(
            f"{where}.range.step: must be a nonzero number (negative for a descending axis), got {step!r}"
        )
    steps = (stop - start) / step
    if not math.isfinite(steps) or steps > 2**53:
        raise ConfigError(f"{where}.range.step: {step:g} from {start:g} to {stop:g} gives too many values")
    count = int(math.floor(steps + 1e-9)) + 1
    if count < 1:
        raise ConfigError(
            f"{where}.range: stepping by {step:g} from {start:g} never reaches {stop:g}; the axis is empty"
        )
    _check_size(f"{where}.range", count, f"{count} steps", numbers)
    return start + step * np.arange(count)


def apply_overrides(config: dict, overrides: Sequence[str]) -> dict:
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
        check_keys(f"--set {key}: ", {parts[0]: None}, _TOP_KEYS)
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
    config, where, base_dir = _read_sweep(source)
    config = apply_overrides(config, overrides)
    check_keys(f"{where}: ", config, _TOP_KEYS)
    name = config.get("name", Path(where).stem if where != "sweep" else "sweep")
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_.-]+", name):
        raise ConfigError(f"{where}: name: must be a plain name (letters, digits, _ . -), got {name!r}")
    robot, robot_source, robot_mapping = _base_robot(where, config, base_dir)
    axes = _parse_axes(where, config.get("axes"), robot)
    combine = _check_combine(where, config, axes, robot)
    metrics = metric_specs(f"{where}: metrics", config.get("metrics"))
    chunk_size, output, report = _run_settings(where, config, name)
    metrics = _check_metrics(where, metrics, robot)
    task = config.get("task")
    task = None if task is None else task_from_mapping(where, task, family_of(robot).joint_kinds(robot))
    written, metrics = metrics, attach_task(where, metrics, task, robot)
    resolved = {
        "name": name,
        "description": config.get("description", ""),
        "robot": robot_mapping,  # inline, so the resolved config is itself a sweep file
        "axes": {a.name: {"field": a.field, "relative": a.relative, "values": a.values.tolist()} for a in axes},
        "combine": combine,
        "metrics": [{"name": m.name, **m.options} for m in written],
        **({} if task is None else {"task": task.to_mapping()}),
        "chunk_size": chunk_size,
        "output": output,
        "report": report,
    }
    spec = SweepSpec(
        name=name,
        config=resolved,
        robot=robot,
        axes=tuple(axes),
        combine=combine,
        metrics=metrics,
        chunk_size=chunk_size,
        output=output,
        report=report,
        source=where,
        robot_source=robot_source,
    )
    if report is not None:
        REPORT_CHECKS[report](spec)
    build_designs(spec)  # validates every sweep point before anything is written
    return spec


def _read_sweep(source: str | os.PathLike | Mapping) -> tuple[dict, str, Path]:
    """The sweep's mapping, its label for messages and the folder relative paths start from."""
    if isinstance(source, Mapping):
        return dict(source), "sweep", Path.cwd()
    path = Path(source)
    config, where = read_yaml(path, what="sweep file"), str(path)
    if not isinstance(config, dict):
        raise ConfigError(f"{where}: a sweep file must be a mapping with robot, axes and metrics")
    return config, where, path.resolve().parent


def _base_robot(where: str, config: Mapping, base_dir: Path) -> tuple[Any, str, dict]:
    """The base robot: a path (relative to the sweep file) or an inline mapping. Returns
    the robot, where it came from (the path, or "inline") and its resolved mapping."""
    if "robot" not in config:
        raise ConfigError(f"{where}: robot: missing required key (a robot file path or an inline robot)")
    robot_entry = config["robot"]
    if isinstance(robot_entry, Mapping):
        robot = robot_from_file_mapping(robot_entry, source=f"{where}: robot", base_dir=base_dir)
        return robot, "inline", _resolved_robot(robot, base_dir / "robot.yaml", lambda: robot_entry)
    if not isinstance(robot_entry, str):
        raise ConfigError(f"{where}: robot: must be a file path or an inline robot mapping")
    robot_path = Path(robot_entry)
    if not robot_path.is_absolute():
        candidate = base_dir / robot_path
        robot_path = candidate if candidate.exists() or not robot_path.exists() else robot_path
    if not robot_path.exists():
        raise ConfigError(f"{where}: robot: no such robot file '{robot_entry}' (looked in {base_dir})")
    if robot_path.is_dir():
        raise ConfigError(f"{where}: robot: '{robot_entry}' is a folder, not a robot file")
    robot = load_robot(robot_path)
    return robot, str(robot_entry), _resolved_robot(robot, robot_path, lambda: read_yaml(robot_path, what="robot file"))


def _design_size(robot) -> int:
    """Numbers per design (float64 leaves), for the memory check of the batched designs."""
    return sum(int(np.size(leaf)) for leaf in jax.tree_util.tree_leaves(robot))


def _parse_axes(where: str, axes_entry: Any, robot) -> list[Axis]:
    """The ``axes:`` mapping: each axis's design field, values and whether they are relative."""
    size = _design_size(robot)
    if not isinstance(axes_entry, Mapping) or not axes_entry:
        raise ConfigError(f"{where}: axes: must be a non-empty mapping of axis name -> {{field, values | range}}")
    axes = []
    for axis_name, spec in axes_entry.items():
        at = f"{where}: axes.{axis_name}"
        if not isinstance(axis_name, str) or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", axis_name):
            raise ConfigError(f"{at}: axis names must be identifiers (letters, digits, _)")
        if not isinstance(spec, Mapping):
            raise ConfigError(f"{at}: must be a mapping with field and values or range")
        check_keys(f"{at}: ", spec, _AXIS_KEYS)
        if "field" not in spec:
            raise ConfigError(f"{at}.field: missing required key; fields: {family_of(robot).fields.FIELD_HELP}")
        field = check_field(at, spec["field"], robot)
        relative = spec.get("relative", False)
        if not isinstance(relative, bool):
            raise ConfigError(f"{at}.relative: must be true or false, got {relative!r}")
        unit = field_axis_unit(robot, field, relative)
        axes.append(Axis(axis_name, field, _axis_values(at, spec, size), relative, unit))
    return axes


def _check_combine(where: str, config: Mapping, axes: list[Axis], robot) -> str:
    """How the axes combine (``product``: every combination, within the size limit;
    ``zip``: axes of equal length, side by side)."""
    check_axes_compatible(where, axes, robot)
    if config.get("combine", "product") == "product":
        count = math.prod(len(a.values) for a in axes)
        _check_size(f"{where}: axes", count, " x ".join(str(len(a.values)) for a in axes), _design_size(robot))
    combine = config.get("combine", "product")
    if combine not in ("product", "zip"):
        raise ConfigError(f"{where}: combine: must be 'product' or 'zip', got {combine!r}")
    if combine == "zip" and len({len(a.values) for a in axes}) > 1:
        sizes = ", ".join(f"{a.name}: {len(a.values)}" for a in axes)
        raise ConfigError(f"{where}: combine: zip needs axes of equal length ({sizes})")
    return combine


def _run_settings(where: str, config: Mapping, name: str) -> tuple[int, str, str | None]:
    """``chunk_size``, ``output`` (default ``results/<name>``) and ``report``, checked."""
    chunk_size = config.get("chunk_size", 256)
    if not isinstance(chunk_size, int) or isinstance(chunk_size, bool) or chunk_size < 1:
        raise ConfigError(f"{where}: chunk_size: must be a positive integer, got {chunk_size!r}")
    integer(f"{where}: chunk_size", chunk_size, least=1)  # its upper bound (SIZE_LIMITS)
    output = config.get("output", f"results/{name}")
    if not isinstance(output, str) or not output or "\0" in output:
        raise ConfigError(f"{where}: output: must be a folder path (a non-empty string with no NUL byte)")
    report = config.get("report")
    if report is not None and report not in REPORTS:
        raise ConfigError(f"{where}: report: unknown report {report!r}; known: {', '.join(sorted(REPORTS))}")
    return chunk_size, output, report


def _check_metrics(where: str, metrics: tuple[MetricSpec, ...], robot) -> tuple[MetricSpec, ...]:
    """The metrics, each checked against the robot's family and the robot; a tip index
    becomes the tip's name."""
    family = family_of(robot)
    for i, metric in enumerate(metrics):
        entry = METRICS[metric.name]
        if not entry.offered(family.capabilities):
            others = ", ".join(sorted(name for name, m in METRICS.items() if m.offered(family.capabilities)))
            raise ConfigError(
                f"{where}: metrics[{i}]: '{metric.name}' is a metric of {' and '.join(entry.families)} "
                f"robots; the robot is {family.name}; its metrics: {others}"
            )
        entry.check_robot(f"{where}: metrics[{i}]", metric.options, robot)
    return resolve_tips(f"{where}: metrics", metrics, robot)


def _resolved_robot(robot, path: Path, mapping) -> dict:
    """The robot's mapping for the resolved config: a family's own normal form where it
    writes one (planar: `robot_to_mapping`), else the file's mapping (``mapping()``) with
    its URDF path made to work from the current folder."""
    form = family_of(robot).normal_form(robot)
    return _spatial_mapping(path, mapping()) if form is None else form


def _spatial_mapping(path: Path, config: Mapping) -> dict:
    """A spatial or tree robot file's mapping for the resolved config, its URDF paths made to work
    from the current folder (relative when below it), so the resolved config is itself a
    sweep file for a run from the same folder."""
    mapping = copy.deepcopy(dict(config))
    folder = Path(path).resolve().parent

    def moved(entry):
        if not isinstance(entry, Mapping) or not isinstance(entry.get("urdf"), str) or os.path.isabs(entry["urdf"]):
            return entry
        urdf = (folder / entry["urdf"]).resolve()
        try:
            return {**entry, "urdf": str(urdf.relative_to(Path.cwd().resolve()))}
        except ValueError:
            return {**entry, "urdf": str(urdf)}

    # One arm (``arm:``), arms on a bus (``arms:``, a list) or one whole-system URDF (``system:``).
    for key in ("arm", "system"):
        if key in mapping:
            mapping[key] = moved(mapping[key])
    if isinstance(mapping.get("arms"), list):
        mapping["arms"] = [moved(entry) for entry in mapping["arms"]]
    return mapping


def _check_size(where: str, count: int, sizes: str, numbers: int) -> None:
    """Refuse a sweep whose designs alone would not fit in memory (they are built at once),
    before anything that large is allocated; ``numbers``: float64 leaves per design."""
    need = count * 8 * numbers * 4  # with room for temporaries
    check_memory(where, need, f"{count:,} designs ({sizes})", "split the sweep into several files")
