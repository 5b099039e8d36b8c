"""A design problem: design variables with bounds, the objectives, and its YAML file, for
any robot family (see ``sweeps/pareto-attachment.yaml`` and ``sweeps/pareto-mount-ur5.yaml``).

The design variables are the family's design fields (`RobotFamily.fields`, the names
sweep axes use): a base design (``robot:`` a robot file, or for planar arms ``fixed:``,
the reference values of a uniform-rod arm) with the variables set on it in the
family's field order. `load_problem` checks everything a run uses (every section,
every option of the w-bar quadrature, the baselines), so ``spacearm validate`` refuses
what a run would.

```yaml
name: pareto-mount-ur5
robot: ../configs/ur5-smallsat.yaml     # relative to this file
variables:                              # design fields: [lower, upper]
  mount.xyz[0]: [-0.4, 0.4]
  mount.rpy[1]: [-0.6, 0.6]
objectives: [w_avg, gci, low_disturbance]   # all maximized
reference_point: [0.0, 0.0, -1.0]
average: {samples: 2048, randomizations: 8, seed: 0}   # one fixed QMC rule for every design
```

The objective ``reach_radius`` (the path-independent workspace radius, m; single-arm
robots) takes its search's options from an optional ``radius:`` section
(`spacearm.design.objectives.RADIUS_OPTIONS`: samples, keep, candidates, descent_steps,
newton_steps, seed).

The task objectives (`spacearm.design.objectives.TASK_OBJECTIVES`, every family:
``low_peak_joint_torque``, ``low_peak_held_force``, ``low_peak_held_torque``,
``low_peak_wheel_momentum``, ``low_peak_wheel_torque``) are taken along the file's timed
task, ``task: {waypoints: [[...], ...], duration: 4.0}`` (joints in rad, or
``waypoints_deg``; `spacearm.motion.tasks`).

The impact objectives (`spacearm.design.objectives.IMPACT_OBJECTIVES`, every family:
``low_virtual_mass``, ``low_bus_rate_jump``, ``low_capture_bus_rate``) are joint-box
averages on the same rule as the others, set by an optional ``impact:`` section
(`spacearm.analysis.impacts.impact_setup`)::

    impact:
      direction: [1, 0, 0]        # the tip impulse's direction, bus axes (default the bus x axis)
      joints: free                # or locked, during the impact
      target: {mass: 50, inertia: [[4, 0, 0], [0, 5, 0], [0, 0, 6]], offset: [0, 0, 0.3],
               velocity: [0.05, 0, 0, 0, 0, 0.1]}   # the reference target (low_capture_bus_rate)

On a robot with several arms (a tree) the variables are its fields
(``arms.right.mount.xyz[0]``, ``links.left/forearm_link.length``;
`spacearm.models.tree.fields`) and a per-tip objective names its tip, as
``{name: w_avg, tip: left/tool0}`` or ``w_avg[left/tool0]`` (the name it then carries in
``pareto.csv``); ``low_disturbance`` and ``low_total_mass`` are of the whole system
(see ``sweeps/pareto-dual-ur5.yaml``).

Joint-box averages use one fixed randomized-QMC rule (`joint_averages` with
``min_samples = max_samples``): the same points for every design, so each objective is a
smooth, deterministic function of the design with an exact gradient for that rule, and
all of them come from one chain pass per posture.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import math
import os
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from .._core.schema import (
    MAX_OBJECTIVES,
    check_keys,
    check_memory,
    check_name,
    choice,
    did_you_mean,
    integer,
    number,
    read_yaml,
)
from ..analysis.averages import joint_averages
from ..analysis.impacts import ImpactSetup, impact_setup
from ..analysis.joint_box import check_joint_box
from ..models import load_robot
from ..models.family import family_of
from ..motion.tasks import TimedTask, task_from_mapping
from ..paper import PlanarRobot, check_average_options, normalized_wbar
from ..paper.planar_parts import design_field_aliases
from .objectives import (
    AVERAGE_OBJECTIVES,
    IMPACT_OBJECTIVES,
    RADIUS_OBJECTIVES,
    RADIUS_OPTIONS,
    TASK_OBJECTIVES,
    average_objective,
    objective,
    objective_name,
    objectives_for,
    split_objective,
    task_objectives,
)

__all__ = [
    "WBAR_OPTIONS",
    "DesignProblem",
    "SearchSettings",
    "Variable",
    "VariableBounds",
    "load_problem",
    "parse_baselines",
    "parse_search",
    "problem_from_mapping",
    "variable_names_for",
]

# The options of spacearm.paper.normalized_wbar a problem's ``wbar:`` section may set.
WBAR_OPTIONS = tuple(name for name in inspect.signature(normalized_wbar).parameters if name != "robot")


@dataclasses.dataclass(frozen=True)
class Variable:
    """A design variable with box bounds, in its field's unit.

    Attributes:
        name: the name as the problem file gives it (table columns use it).
        lower, upper: the bounds.
        field: the design field it sets (the name itself unless the file used an alias).
    """

    name: str
    lower: float
    upper: float
    field: str = ""

    def __post_init__(self):
        if not self.field:
            object.__setattr__(self, "field", self.name)


@dataclasses.dataclass(frozen=True)
class SearchSettings:
    """Settings of `pareto_search` (see its docstring)."""

    directions: int = 64
    starts: int = 2
    steps: int = 120
    chunk: int = 10
    learning_rate: float = 0.03
    final_learning_rate: float = 0.001
    schedule: str = "geometric"
    reset_adam: bool = True
    smoothing: float = 0.01
    augmentation: float = 0.001
    utopia_margin: float = 0.05
    initial_samples: int = 64
    warm_start: bool = True
    reaim: bool = True
    densify: bool = True
    gradient: str = "reverse"
    seed: int = 0


class VariableBounds:
    """Names and box bounds of a problem's ``variables``."""

    variables: tuple[Variable, ...]

    @property
    def variable_names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self.variables)

    @property
    def lower(self) -> np.ndarray:
        """``(d,)`` lower bounds."""
        return np.array([v.lower for v in self.variables], dtype=np.float64)

    @property
    def upper(self) -> np.ndarray:
        """``(d,)`` upper bounds."""
        return np.array([v.upper for v in self.variables], dtype=np.float64)


@dataclasses.dataclass(frozen=True)
class DesignProblem(VariableBounds):
    """A multi-objective design problem over the design fields of one base design (any family).

    Attributes:
        name: the problem name (results go to ``results/<name>/``).
        base: the base design; fields not optimized keep its values.
        variables: the optimized design fields, in column order.
        objectives: objective names (`objectives_for` the family), all maximized.
        reference_point: hypervolume reference point, one value per objective, or None
            (the search then takes one below the nadir of its first population).
        robot_file: the robot file as the problem names it ("" for a planar ``fixed:`` base).
        fixed: the fixed quantities, for the run's summary.
        wbar_options: keyword arguments of the planar w-bar (objective ``wbar``).
        clamp_guaranteed: see `guaranteed_area` (objective ``S_G``).
        samples, randomizations, seed: the fixed QMC rule of the joint-box averages.
        radius_options: options of the ``reach_radius`` search (`RADIUS_OPTIONS`), as given.
        task: the timed task of the task objectives (`TASK_OBJECTIVES`), or None.
        impact: the settings of the impact objectives (`IMPACT_OBJECTIVES`), or None.
    """

    name: str
    base: Any
    variables: tuple[Variable, ...]
    objectives: tuple[str, ...]
    reference_point: tuple[float, ...] | None
    robot_file: str = ""
    fixed: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    wbar_options: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    clamp_guaranteed: bool = True
    samples: int = 2048
    randomizations: int = 8
    seed: int = 0
    search: SearchSettings = dataclasses.field(default_factory=SearchSettings)
    grid_points: tuple[int, ...] | None = None
    grid_chunk: int = 2048
    nsga2: Mapping[str, Any] | None = None
    description: str = ""
    radius_options: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    task: TimedTask | None = None
    impact: ImpactSetup | None = None

    @property
    def family(self):
        """The base design's `RobotFamily`."""
        return family_of(self.base)

    @property
    def n_links(self) -> int:
        """Joints of the arm (planar: links)."""
        return self.family.joint_count(self.base)

    @property
    def closed_form(self) -> bool:
        """True when every objective is a closed form of the design: no joint-box average
        (of any tip) and no radius search, so a value costs next to nothing against the
        value program's compile."""
        return not any(
            split_objective(name)[0] in AVERAGE_OBJECTIVES or name in RADIUS_OBJECTIVES or name in TASK_OBJECTIVES
            for name in self.objectives
        )

    def fixed_summary(self) -> dict:
        """The fixed quantities, for the run's summary."""
        return dict(self.fixed)

    def robot(self, x: jax.Array):
        """The design for one ``(d,)`` variable vector (physical units, `variables` order).

        Built without validation (leaves may be tracers); vmap this method for a batch.
        """
        return _design(self.base, tuple(v.field for v in self.variables), jnp.asarray(x))

    def _program(self) -> _Program:
        return _Program(
            tuple(v.field for v in self.variables),
            self.objectives,
            tuple(sorted(self.wbar_options.items())),
            self.clamp_guaranteed,
            self.samples,
            self.randomizations,
            tuple(sorted(self.radius_options.items())),
        )

    def objective_function(self) -> Callable[[jax.Array], jax.Array]:
        """``f(x)``: ``(d,)`` variables -> ``(m,)`` objectives (maximized); pure, differentiable.

        Every joint-box average comes from one `joint_averages` call on the fixed rule
        (one chain pass per posture for all of them)."""
        program, base, seed, task, impact = self._program(), self.base, self.seed, self.task, self.impact
        return lambda x: _evaluate(program, base, jnp.asarray(x), seed, task, impact)

    def batch_function(self) -> Callable[[jax.Array], jax.Array]:
        """``(B, d) -> (B, m)``, jitted once per process for every problem of the same shape:
        the base design and the seed are traced arguments, so the search, the grid and
        NSGA-II (and other problems differing only in numbers) share one program per batch size
        (the task and the impact target too are traced arguments: their shapes, not their
        values, are compiled)."""
        program, base, seed, task, impact = self._program(), self.base, self.seed, self.task, self.impact
        return lambda xs: _evaluate_batch(program, base, jnp.asarray(xs), seed, task, impact)


@dataclasses.dataclass(frozen=True)
class _Program:
    """What fixes the shapes of a problem's objective program (a static argument)."""

    fields: tuple[str, ...]
    objectives: tuple[str, ...]
    wbar_options: tuple[tuple[str, Any], ...]
    clamp_guaranteed: bool
    samples: int
    randomizations: int
    radius_options: tuple[tuple[str, int], ...] = ()


def _design(base, fields_set: tuple[str, ...], x: jax.Array):
    """``base`` with ``x[i]`` set on field ``fields_set[i]``, in the family's field order (unvalidated)."""
    fields = family_of(base).fields
    robot = jax.tree_util.tree_map(lambda leaf: jnp.asarray(leaf, dtype=x.dtype), base)
    for i, field in sorted(enumerate(fields_set), key=lambda p: fields.field_stage(p[1])):
        robot = fields.set_field(robot, field, x[i])
    return robot


def _evaluate(
    program: _Program, base, x: jax.Array, seed, task: TimedTask | None = None, impact: ImpactSetup | None = None
) -> jax.Array:
    """``(m,)`` objectives of one ``(d,)`` variable vector set on ``base``; the task objectives
    from one `task_objectives` call, the joint-box averages from one `joint_averages` call."""
    robot = _design(base, program.fields, x)
    values: list[Any] = [None] * len(program.objectives)
    kinds = [average_objective(name, robot) for name in program.objectives]  # per tip: manipulability[1]
    averaged = [(i, *kind) for i, kind in enumerate(kinds) if kind is not None]
    along = task_objectives(program.objectives, robot, task) if task is not None else {}
    for i, name in enumerate(program.objectives):
        if name in TASK_OBJECTIVES:
            values[i] = along[name]
        elif kinds[i] is None:
            values[i] = objective(
                name,
                wbar_options=dict(program.wbar_options),
                clamp_guaranteed=program.clamp_guaranteed,
                radius_options=dict(program.radius_options),
            )(robot)
    if averaged:
        means = joint_averages(
            robot,
            tuple(metric for _, metric, _ in averaged),
            randomizations=program.randomizations,
            block=max(1, program.samples // program.randomizations),
            min_samples=program.samples,
            max_samples=program.samples,
            seed=seed,
            designs_per_chunk=1,
            impact=impact,
        )
        for i, metric, sign in averaged:
            values[i] = sign * means[metric].value
    return jnp.stack(values)


@functools.partial(jax.jit, static_argnames=("program",))
def _evaluate_batch(
    program: _Program, base, xs: jax.Array, seed, task: TimedTask | None = None, impact: ImpactSetup | None = None
) -> jax.Array:
    return jax.vmap(lambda x: _evaluate(program, base, x, seed, task, impact))(xs)


# YAML ---------------------------------------------------------------------------------

_TOP_KEYS = {
    "name",
    "description",
    "robot",
    "fixed",
    "variables",
    "objectives",
    "reference_point",
    "wbar",
    "guaranteed",
    "average",
    "search",
    "baselines",
    "hybrid",
    "radius",
    "task",
    "impact",
}  # hybrid: read by spacearm.design.hybrid.parse_hybrid
_FIXED_KEYS = {"base_mass", "base_inertia", "arm_mass", "reach", "links"}
_AVERAGE_KEYS = {"samples", "randomizations", "seed"}
_SEARCH_KEYS = {f.name for f in dataclasses.fields(SearchSettings)}
_NSGA_KEYS = {"population", "evaluations", "seed", "time_limit"}
_SEARCH_CHOICES = {"gradient": ("forward", "reverse"), "schedule": ("geometric", "cosine")}
# Fields whose values must stay positive (a mass, a length, a factor on either).
_POSITIVE = ("base.mass", "base.inertia", "arm.mass", "arm.mass_ratio", "arm.mass_ratio_fixed_total", "arm.length")


def variable_names_for(n_links: int) -> tuple[str, ...]:
    """The names of the first planar problem files for an n-link arm (aliases of design fields)."""
    return design_field_aliases(n_links)


def _uniform_rod_arm(source: str, fixed: Mapping[str, Any]) -> tuple[PlanarRobot, dict]:
    """The planar base of a ``fixed:`` section: n equal uniform rods (a = b = l / 2,
    I = m l^2 / 12) sharing the reach and the arm mass, on the given base."""
    links = integer(f"{source}: fixed.links", fixed.get("links", 2), least=2)
    physical = {}
    for key in ("base_mass", "base_inertia", "arm_mass", "reach"):
        if key not in fixed:
            raise ConfigError(f"{source}: fixed.{key}: missing required key")
        physical[key] = number(f"{source}: fixed.{key}", fixed[key])
        if physical[key] <= 0:
            raise ConfigError(f"{source}: fixed.{key}: must be positive, got {physical[key]}")
    length, mass = physical["reach"] / links, physical["arm_mass"] / links
    base = PlanarRobot(
        base_mass=np.float64(physical["base_mass"]),
        base_inertia=np.float64(physical["base_inertia"]),
        base_attach=np.float64(0.0),
        link_mass=np.full(links, mass),
        link_inertia=np.full(links, mass * length**2 / 12.0),
        link_a=np.full(links, length / 2),
        link_b=np.full(links, length / 2),
        joint_lower=np.full(links, -np.inf),
        joint_upper=np.full(links, np.inf),
        name=source,
    )
    return base, dict(physical, links=links)


def _planar_fixed(source: str, config: Mapping[str, Any]) -> tuple[PlanarRobot, dict, dict]:
    """``fixed:``: the base design, the summary and the field values it sets (by name as written)."""
    fixed = config.get("fixed")
    if not isinstance(fixed, Mapping):
        raise ConfigError(f"{source}: fixed: a mapping with base_mass, base_inertia, arm_mass, reach is required")
    links = integer(f"{source}: fixed.links", fixed.get("links", 2), least=2)
    check_keys(f"{source}: fixed: ", fixed, _FIXED_KEYS | set(variable_names_for(links)))
    base, summary = _uniform_rod_arm(source, fixed)
    values = {key: number(f"{source}: fixed.{key}", value) for key, value in fixed.items() if key not in _FIXED_KEYS}
    return base, summary, values


def _check_planar_ranges(source: str, box: Mapping[str, tuple[float, float, str]], n: int) -> None:
    """Every design inside the box must be physical: positive shares summing below 1,
    centroids on their links, b0 >= 0. ``box``: field -> (lower, upper, name as written)."""
    for what, total in (("length_share", "L"), ("mass_share", "the arm mass")):
        keys = [f"links[{i}].{what}" for i in range(n - 1) if f"links[{i}].{what}" in box]
        for key in keys:
            if box[key][0] <= 0:
                raise ConfigError(f"{source}: {box[key][2]}: must stay above 0, got lower value {box[key][0]}")
        if keys and sum(box[key][1] for key in keys) + (n - 1 - len(keys)) / n >= 1:
            names = ", ".join(box[key][2] for key in keys)
            raise ConfigError(
                f"{source}: {names}: the upper values must sum below 1 so the last link keeps a share of {total}"
            )
    for i in range(n):
        key = f"links[{i}].centroid"
        if key in box and (box[key][0] < 0 or box[key][1] > 1):
            raise ConfigError(f"{source}: {box[key][2]}: must stay within [0, 1]")
    if "base.attach" in box and box["base.attach"][0] < 0:
        raise ConfigError(f"{source}: {box['base.attach'][2]}: must not be negative")


def problem_from_mapping(
    config: Mapping[str, Any], *, source: str = "problem", base_dir: str | os.PathLike | None = None
) -> DesignProblem:
    """Build a `DesignProblem` of either family from its YAML mapping; checks every section.

    Args:
        config: the parsed problem file.
        source: a label for messages (the file name).
        base_dir: where a relative ``robot:`` path starts (default: the current folder).

    Raises:
        ConfigError: naming the field and the reason.
    """
    if not isinstance(config, Mapping):
        raise ConfigError(f"{source}: an optimization problem must be a mapping")
    check_keys(f"{source}: ", config, _TOP_KEYS)
    if "name" not in config:
        raise ConfigError(f"{source}: name: missing required key (it names the result folder, results/<name>/)")
    name = check_name(f"{source}: name", config["name"])
    base, fixed_summary, fixed_values, robot_file = _base_design(source, config, base_dir)
    family = family_of(base)
    n = family.joint_count(base)
    variables = _parse_variables(source, config.get("variables"), family.fields, base)
    base = _fixed_base(source, base, n, variables, fixed_values)
    if "robot" in config:
        fixed_summary = {"robot": robot_file}
    objectives = _parse_objectives(source, config, family, base)
    averaged = any(split_objective(name)[0] in AVERAGE_OBJECTIVES for name in objectives)
    with_radius = any(name in RADIUS_OBJECTIVES for name in objectives)
    radius_options = _radius_options(source, config.get("radius"), with_radius)
    task = _task(source, config.get("task"), objectives, family.joint_kinds(base))
    impact = _impact(source, config.get("impact"), objectives, base)
    reference = _reference_point(source, config, objectives, averaged or with_radius or task is not None)
    wbar = _parse_wbar(source, config, objectives, n)
    guaranteed = choice(f"{source}: guaranteed", config.get("guaranteed", "clamped"), ("clamped", "paper"))
    samples, randomizations, seed = _parse_average(source, config.get("average", {}) or {})
    if averaged:
        check_joint_box(base)
        fixed_summary.update(samples=samples, randomizations=randomizations, seed=seed)
    if with_radius:
        check_joint_box(base)
        fixed_summary.update(radius={**RADIUS_OPTIONS, **radius_options})
    if task is not None:
        fixed_summary.update(task=task.to_mapping())
    if impact is not None:
        fixed_summary.update(impact=_impact_summary(impact))
    search = parse_search(source, config.get("search", {}))
    grid_points, grid_chunk, nsga2 = parse_baselines(
        source, config.get("baselines", {}), len(variables), len(objectives)
    )
    return DesignProblem(
        name=name,
        base=base,
        variables=tuple(variables),
        objectives=objectives,
        reference_point=reference,
        robot_file=robot_file,
        fixed=fixed_summary,
        wbar_options=dict(wbar),
        clamp_guaranteed=guaranteed == "clamped",
        samples=samples,
        randomizations=randomizations,
        seed=seed,
        search=search,
        grid_points=grid_points,
        grid_chunk=grid_chunk,
        nsga2=nsga2,
        description=str(config.get("description", "")),
        radius_options=radius_options,
        task=task,
        impact=impact,
    )


def _task(source: str, section: Any, objectives: tuple[str, ...], joint_kinds: tuple[str, ...]) -> TimedTask | None:
    """The ``task:`` section (`task_from_mapping`): required by a task objective, refused without one."""
    along = [name for name in objectives if name in TASK_OBJECTIVES]
    if section is None:
        if along:
            raise ConfigError(
                f"{source}: task: missing; {', '.join(along)} is taken along a timed task, e.g. "
                "task: {waypoints: [[...], [...]], duration: 4.0} (joints in rad, time in s)"
            )
        return None
    if not along:
        raise ConfigError(
            f"{source}: task: the timed task of the task objectives ({', '.join(TASK_OBJECTIVES)}), "
            "which objectives does not list"
        )
    return task_from_mapping(source, section, joint_kinds)


def _impact(source: str, section: Any, objectives: tuple[str, ...], base) -> ImpactSetup | None:
    """The ``impact:`` section (`impact_setup`): the defaults when an impact objective has none,
    refused without one; the reference target required by ``low_capture_bus_rate``."""
    used = [name for name in objectives if split_objective(name)[0] in IMPACT_OBJECTIVES]
    if not used:
        if section is not None:
            raise ConfigError(
                f"{source}: impact: the settings of the impact objectives ({', '.join(IMPACT_OBJECTIVES)}), "
                "which objectives does not list"
            )
        return None
    capture = any(split_objective(name)[0] == "low_capture_bus_rate" for name in used)
    return impact_setup(f"{source}: impact", section, base, need_target=capture)


def _impact_summary(impact: ImpactSetup) -> dict:
    """The impact settings as the run's summary writes them (lists of numbers)."""
    summary: dict[str, Any] = {"direction": np.asarray(impact.direction).tolist(), "joints": impact.joints}
    if impact.target is not None:
        summary["target"] = {key: np.asarray(value).tolist() for key, value in impact.target.items()}
    return summary


def _base_design(source: str, config: Mapping[str, Any], base_dir) -> tuple[Any, dict, dict, str]:
    """The base design: a robot file, or a planar ``fixed:`` section. Returns the robot,
    the fixed summary (planar), the ``fixed:`` field values and the robot file ("" for none)."""
    if ("robot" in config) == ("fixed" in config):
        raise ConfigError(f"{source}: give either robot: (a robot file) or fixed: (a planar arm's reference values)")
    if "fixed" in config:
        base, fixed_summary, fixed_values = _planar_fixed(source, config)
        return base, fixed_summary, fixed_values, ""
    robot_entry = config["robot"]
    if not isinstance(robot_entry, str):
        raise ConfigError(f"{source}: robot: a robot file path is required")
    folder = os.fspath(base_dir) if base_dir is not None else os.getcwd()
    path = robot_entry if os.path.isabs(robot_entry) else os.path.join(folder, robot_entry)
    if not os.path.isfile(path):
        raise ConfigError(f"{source}: robot: no such robot file '{robot_entry}' (looked in {folder})")
    return load_robot(path), {}, {}, robot_entry


def _parse_variables(source: str, raw: Any, fields, base) -> list[Variable]:
    """The ``variables:`` section: the family's design fields (first-generation planar
    names accepted) with their bounds, no two setting the same design number."""
    if not isinstance(raw, Mapping) or not raw:
        raise ConfigError(f"{source}: variables: a mapping field: [lower, upper] with at least one entry is required")
    variables = []
    for key, bounds in raw.items():
        where = f"{source}: variables.{key}"
        field = fields.check_field(where, fields.canonical_name(key), base)
        if not isinstance(bounds, (list, tuple)) or len(bounds) != 2:
            raise ConfigError(f"{where}: must be a list [lower, upper]")
        lower, upper = number(f"{where}[0]", bounds[0]), number(f"{where}[1]", bounds[1])
        if not lower < upper:
            raise ConfigError(f"{where}: the lower bound must be below the upper bound, got [{lower}, {upper}]")
        if (field in _POSITIVE or field in fields.FACTOR_FIELDS or field.endswith(".length")) and lower <= 0:
            raise ConfigError(f"{where}: must stay positive, got lower bound {lower}")
        variables.append(Variable(str(key), lower, upper, field))
    for i, first in enumerate(variables):
        for second in variables[i + 1 :]:
            if fields.conflicting_number(first.field, second.field, base):
                raise ConfigError(f"{source}: variables: {first.name} and {second.name} set the same design number")
    return variables


def _fixed_base(source: str, base, n: int, variables: list[Variable], fixed_values: dict):
    """The base design (``n`` joints) with its fixed field values (planar ``fixed:``
    extras such as b0) set, the planar box checked, validated."""
    family = family_of(base)
    fields = family.fields
    chosen = {v.field for v in variables}
    settings = []
    for key, value in fixed_values.items():
        field = fields.check_field(f"{source}: fixed.{key}", fields.canonical_name(key), base)
        if field not in chosen:
            settings.append((field, value))
    for field, value in sorted(settings, key=lambda p: fields.field_stage(p[0])):
        base = fields.set_field(base, field, value)
    if family.capabilities.virtual_manipulator:  # the paper's arm: b0 chosen, every box design physical
        box = {v.field: (v.lower, v.upper, v.name) for v in variables}
        if "base.attach" not in box and "b0" not in fixed_values:
            raise ConfigError(f"{source}: b0: give it in fixed (a value) or in variables (bounds)")
        _check_planar_ranges(source, box, n)
    try:
        return base.replace()  # validated
    except ConfigError as error:
        raise ConfigError(f"{source}: the base design is not a valid robot: {error}") from None


def _parse_objectives(source: str, config: Mapping[str, Any], family, base) -> tuple[str, ...]:
    """The ``objectives:`` list: at least two distinct objectives of the family (default: each
    tip's w_avg and the system's disturbance where the family has the joint-box averages, else
    its first two objectives, the paper's w-bar and S_G)."""
    allowed = objectives_for(family)
    raw = config.get("objectives")
    if "objectives" not in config:
        tips = family.tip_count(base)
        default = ["w_avg", "low_disturbance"]
        if tips is not None and tips > 1:  # several arms: each tip's w_avg, and the system's disturbance
            default = [{"name": "w_avg", "tip": t} for t in range(tips)] + ["low_disturbance"]
        raw = default if family.capabilities.joint_box_averages else list(allowed[:2])
    if not isinstance(raw, (list, tuple)):
        raise ConfigError(f"{source}: objectives: must be a list of objective names ({', '.join(allowed)})")
    if len(raw) > MAX_OBJECTIVES:
        raise ConfigError(
            f"{source}: objectives: {len(raw)} listed; at most {MAX_OBJECTIVES} (the hypervolume's "
            "cost grows exponentially with their number)"
        )
    objectives = tuple(_objective_entry(f"{source}: objectives[{i}]", v, allowed, base) for i, v in enumerate(raw))
    if len(objectives) < 2 or len(set(objectives)) != len(objectives):
        raise ConfigError(f"{source}: objectives: at least two distinct objectives are required")
    return objectives


def _reference_point(source: str, config: Mapping[str, Any], objectives: tuple[str, ...], no_zero: bool):
    """The ``reference_point:``, one number per objective. Optional where an objective
    has no natural zero (``no_zero``: averages and the radius): absent, the search takes it
    below the nadir of its first population. The radius is positive, but a few mm on a
    UR5: a zero reference would dwarf its differences."""
    reference = config.get("reference_point", None if no_zero else [0.0] * len(objectives))
    if reference is None:
        return None
    if not isinstance(reference, (list, tuple)) or len(reference) != len(objectives):
        raise ConfigError(
            f"{source}: reference_point: one number per objective, or none (objectives maximized; "
            "low_disturbance is minus the mean ||C_w||_F)"
        )
    return tuple(number(f"{source}: reference_point[{i}]", r) for i, r in enumerate(reference))


def _parse_wbar(source: str, config: Mapping[str, Any], objectives: tuple[str, ...], n: int) -> Mapping:
    """The ``wbar:`` options of `spacearm.paper.normalized_wbar` (the area
    average, eq. 12, is defined for 2 links only)."""
    wbar = config.get("wbar", {}) or {}
    if not isinstance(wbar, Mapping):
        raise ConfigError(f"{source}: wbar: must be a mapping of options for spacearm.paper.normalized_wbar")
    check_keys(f"{source}: wbar: ", wbar, WBAR_OPTIONS)
    check_average_options(where=f"{source}: wbar.", **wbar)
    if "wbar" in objectives and n != 2 and wbar.get("measure", "area") == "area":
        raise ConfigError(
            f"{source}: wbar: the area average (eq. 12) is defined for 2 links, "
            f"{'fixed.links is' if 'fixed' in config else 'the robot has'} {n}; "
            "set wbar: {measure: joint}"
        )
    return wbar


def _parse_average(source: str, average: Any) -> tuple[int, int, int]:
    """The ``average:`` section of the joint-box averages: samples (randomizations x a
    power of two), randomizations and seed."""
    if not isinstance(average, Mapping):
        raise ConfigError(f"{source}: average: must be a mapping (samples, randomizations, seed)")
    check_keys(f"{source}: average: ", average, _AVERAGE_KEYS)
    randomizations = integer(f"{source}: average.randomizations", average.get("randomizations", 8), least=2)
    samples = integer(f"{source}: average.samples", average.get("samples", 2048), least=randomizations)
    per = samples // randomizations
    if samples % randomizations or per & (per - 1):
        raise ConfigError(f"{source}: average.samples: must be randomizations x a power of two, got {samples}")
    seed = integer(f"{source}: average.seed", average.get("seed", 0), least=0)
    return samples, randomizations, seed


def _radius_options(source: str, section: Any, with_radius: bool) -> dict[str, int]:
    """The ``radius:`` section (options of the ``reach_radius`` search), checked; only with that objective."""
    if section is None:
        return {}
    if not with_radius:
        raise ConfigError(f"{source}: radius: options of the reach_radius objective, which objectives does not list")
    if not isinstance(section, Mapping):
        raise ConfigError(f"{source}: radius: must be a mapping ({', '.join(RADIUS_OPTIONS)})")
    check_keys(f"{source}: radius: ", section, set(RADIUS_OPTIONS))
    least = {"newton_steps": 0, "seed": 0}
    options = {
        key: integer(f"{source}: radius.{key}", value, least=least.get(key, 1)) for key, value in section.items()
    }
    merged = {**RADIUS_OPTIONS, **options}
    if merged["keep"] > merged["samples"]:
        raise ConfigError(
            f"{source}: radius.keep: at most radius.samples ({merged['samples']}) postures can be kept, "
            f"got {merged['keep']}"
        )
    return options


def _objective_entry(where: str, entry: Any, allowed: Sequence[str], base) -> str:
    """An entry of ``objectives``: a name (``w_avg``, or ``w_avg[left/tool0]`` for one tip of a
    robot with several) or a mapping ``{name: w_avg, tip: left/tool0}`` (a tip's name or
    index); the objective's canonical name (`objective_name`)."""
    tip = None
    if isinstance(entry, Mapping):
        check_keys(f"{where}: ", entry, {"name", "tip"})
        if "name" not in entry:
            raise ConfigError(f"{where}.name: missing required key (an objective name: {', '.join(allowed)})")
        entry, tip = entry["name"], entry.get("tip")
        if tip is not None and (isinstance(tip, bool) or not isinstance(tip, (str, int))):
            raise ConfigError(f"{where}.tip: a tip's name or index, got {tip!r}")
    name = split_objective(entry)[0] if isinstance(entry, str) else entry
    if name not in TASK_OBJECTIVES:  # the task objectives listed apart: they need the file's task
        try:
            choice(where, name, [a for a in allowed if a not in TASK_OBJECTIVES])
        except ConfigError as error:
            along = ", ".join(TASK_OBJECTIVES)
            hint = did_you_mean(name, TASK_OBJECTIVES) if isinstance(name, str) else ""
            raise ConfigError(f"{error}; along the file's timed task: {along}{hint}") from None
    return objective_name(where, base, entry, tip)


def parse_search(source: str, search_map: Any) -> SearchSettings:
    """The ``search:`` section of a problem file as `SearchSettings` (checked)."""
    search_map = search_map or {}
    if not isinstance(search_map, Mapping):
        raise ConfigError(f"{source}: search: must be a mapping")
    check_keys(f"{source}: search: ", search_map, _SEARCH_KEYS)
    search = SearchSettings()
    for key, value in search_map.items():
        where = f"{source}: search.{key}"
        default = getattr(search, key)
        if isinstance(default, bool):
            if not isinstance(value, bool):
                raise ConfigError(f"{where}: must be true or false, got {value!r}")
        elif isinstance(default, str):
            value = choice(where, value, _SEARCH_CHOICES[key])
        elif isinstance(default, int):
            value = integer(where, value, least=0 if key == "seed" else 1)
        else:
            value = number(where, value)
            if value <= 0:
                raise ConfigError(f"{where}: must be positive, got {value}")
        search = dataclasses.replace(search, **{key: value})

    return search


def parse_baselines(source: str, baselines: Any, n_variables: int, n_objectives: int):
    """The ``baselines:`` section: ``(grid_points or None, grid_chunk, nsga2 options or None)``."""
    baselines = baselines or {}
    if not isinstance(baselines, Mapping):
        raise ConfigError(f"{source}: baselines: must be a mapping with optional keys grid, nsga2")
    check_keys(f"{source}: baselines: ", baselines, {"grid", "nsga2"})
    grid_points = None
    grid_chunk = 2048
    if baselines.get("grid") is not None:
        grid = baselines["grid"]
        if not isinstance(grid, Mapping) or "points" not in grid:
            raise ConfigError(f"{source}: baselines.grid: a mapping with points: [n1, ..., nd] is required")
        check_keys(f"{source}: baselines.grid: ", grid, {"points", "chunk"})
        points = grid["points"]
        if isinstance(points, int) and not isinstance(points, bool):
            points = [points] * n_variables
        if (
            not isinstance(points, (list, tuple))
            or len(points) != n_variables
            or not all(isinstance(p, int) and not isinstance(p, bool) and p >= 2 for p in points)
        ):
            raise ConfigError(f"{source}: baselines.grid.points: one integer >= 2 per variable is required")
        grid_points = tuple(points)
        _check_grid_size(f"{source}: baselines.grid.points", grid_points, n_objectives)
        grid_chunk = integer(f"{source}: baselines.grid.chunk", grid.get("chunk", 2048), least=1)
    nsga2 = None
    if baselines.get("nsga2") is not None:
        raw = baselines["nsga2"]
        if not isinstance(raw, Mapping):
            raise ConfigError(
                f"{source}: baselines.nsga2: must be a mapping (population, evaluations, seed, time_limit)"
            )
        check_keys(f"{source}: baselines.nsga2: ", raw, _NSGA_KEYS)
        where = f"{source}: baselines.nsga2"
        nsga2 = {
            "population": integer(f"{where}.population", raw.get("population", 40), least=2),
            "evaluations": integer(f"{where}.evaluations", raw.get("evaluations", 4000), least=1),
            "seed": integer(f"{where}.seed", raw.get("seed", 0), least=0),
        }
        if raw.get("time_limit") is not None:
            nsga2["time_limit"] = number(f"{where}.time_limit", raw["time_limit"])
            if nsga2["time_limit"] <= 0:
                raise ConfigError(f"{where}.time_limit: must be positive (seconds), got {nsga2['time_limit']}")
    return grid_points, grid_chunk, nsga2


def _check_grid_size(where: str, points: Sequence[int], n_objectives: int) -> None:
    """Refuse a grid baseline whose designs would not fit in memory (the grid is built at once)."""
    count = math.prod(points)
    need = count * 8 * (2 * len(points) + n_objectives)  # the mesh, its meshgrid, the objective values
    check_memory(where, need, f"{count:,} grid designs ({' x '.join(map(str, points))})", "use fewer points")


def load_problem(
    source: str | os.PathLike | Mapping[str, Any], *, name: str | None = None, base_dir: str | os.PathLike | None = None
) -> DesignProblem:
    """Load a design problem of either family from a YAML file (or its parsed mapping).

    Args:
        source: the problem file or its parsed mapping.
        name: a label for messages (default: the file name).
        base_dir: where a relative ``robot:`` path starts (default: the file's folder,
            or the current folder for a mapping).

    Raises:
        ConfigError: for a missing or malformed file and any invalid field.
    """
    if isinstance(source, Mapping):
        return problem_from_mapping(source, source=name or "problem", base_dir=base_dir)
    path = os.fspath(source)
    folder = base_dir if base_dir is not None else os.path.dirname(os.path.abspath(path))
    return problem_from_mapping(read_yaml(path, what="design problem file"), source=name or path, base_dir=folder)
