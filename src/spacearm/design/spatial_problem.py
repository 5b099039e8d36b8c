"""A design problem over a spatial robot: design fields with bounds (the mount pose, masses,
the arm's scale), objectives averaged over the joint box (see ``sweeps/pareto-mount-ur5.yaml``).

```yaml
name: pareto-mount-ur5
robot: ../configs/ur5-smallsat.yaml     # relative to this file
variables:                              # design fields (spacearm.models.spatial.fields): [lower, upper]
  mount.xyz[0]: [-0.4, 0.4]
  mount.rpy[1]: [-0.6, 0.6]
objectives: [w_avg, gci, low_disturbance]   # all maximized
reference_point: [0.0, 0.0, -1.0]
average: {samples: 2048, randomizations: 8, seed: 0}   # one fixed QMC rule for every design
```

The averages are `spacearm.analysis.averages.joint_average` with a fixed sample
count (``min_samples = max_samples``): the same randomized-QMC points for every design,
so each objective is a smooth, deterministic function of the design and its gradient is
exact for that rule (an adaptive sample count would make it jump where the count changes).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Mapping
from typing import Any

import jax
import jax.numpy as jnp

from .._core.errors import ConfigError
from .._core.schema import check_keys, choice, integer, number
from ..analysis.averages import joint_average
from ..analysis.joint_box import check_joint_box
from ..models import load_robot
from ..models.spatial import SpatialRobot
from ..models.spatial import fields as spatial_fields
from .problem import DesignProblem, SearchSettings, Variable, VariableBounds, parse_baselines, parse_search, problem_from_mapping
from .._core.schema import read_yaml

__all__ = ["SpatialDesignProblem", "SPATIAL_OBJECTIVES", "spatial_problem_from_mapping", "load_design_problem",
           "load_problem"]

# Objective name -> (joint_average metric, sign): all maximized.
SPATIAL_OBJECTIVES = {
    "w_avg": ("manipulability", 1.0),              # mean translational w*, m^3
    "gci": ("conditioning", 1.0),                   # global conditioning index, mean 1/kappa(J*_v)
    "low_disturbance": ("base_disturbance", -1.0),  # minus the mean ||C_w||_F, rad/rad
    "w_d_avg": ("dynamic_manipulability", 1.0),     # mean dynamic manipulability
    "low_total_mass": ("total_mass", -1.0),         # minus the bus mass plus every arm mass, kg
}
# Metrics of the design itself, not averaged over postures: name -> f(robot).
_DESIGN_METRICS = {"total_mass": lambda robot: robot.base_mass + spatial_fields.arm_mass(robot)}
_TOP_KEYS = {"name", "description", "robot", "variables", "objectives", "reference_point", "average", "search",
             "baselines", "hybrid"}  # hybrid: read by spacearm.design.hybrid.parse_hybrid
_AVERAGE_KEYS = {"samples", "randomizations", "seed"}


@dataclasses.dataclass(frozen=True)
class SpatialDesignProblem(VariableBounds):
    """A multi-objective design problem over one spatial robot's design fields.

    Attributes:
        name: the problem name (results go to ``results/<name>/``).
        base: the robot file's design; variables not optimized keep its values.
        robot_file: the robot file, as named in the problem file.
        variables: design fields with bounds (field units: m, rad, kg or a factor).
        objectives: names from `SPATIAL_OBJECTIVES`, all maximized.
        reference_point: hypervolume reference point, one value per objective, or None
            (the search then takes one below the nadir of its first population).
        samples, randomizations, seed: the fixed QMC rule of every average.
    """

    name: str
    base: SpatialRobot
    robot_file: str
    variables: tuple[Variable, ...]
    objectives: tuple[str, ...]
    reference_point: tuple[float, ...] | None
    samples: int = 2048
    randomizations: int = 8
    seed: int = 0
    search: SearchSettings = dataclasses.field(default_factory=SearchSettings)
    grid_points: tuple[int, ...] | None = None
    grid_chunk: int = 2048
    nsga2: Mapping[str, Any] | None = None
    description: str = ""

    def fixed_summary(self) -> dict:
        return dict(robot=self.robot_file, samples=self.samples, randomizations=self.randomizations, seed=self.seed)

    def robot(self, x: jax.Array) -> SpatialRobot:
        """The design for one ``(d,)`` variable vector (leaves may be tracers; unvalidated)."""
        x = jnp.asarray(x)
        robot = jax.tree_util.tree_map(lambda leaf: jnp.asarray(leaf, dtype=x.dtype), self.base)
        for i, variable in sorted(enumerate(self.variables), key=lambda p: spatial_fields.field_stage(p[1].name)):
            robot = spatial_fields.set_field(robot, variable.name, x[i])
        return robot

    def objective_function(self) -> Callable[[jax.Array], jax.Array]:
        """``f(x)``: ``(d,)`` variables -> ``(m,)`` objectives (maximized); pure, differentiable."""
        block = max(1, self.samples // self.randomizations)
        options = dict(rtol=1e-12, randomizations=self.randomizations, block=block, min_samples=self.samples,
                       max_samples=self.samples, seed=self.seed, designs_per_chunk=1)

        def evaluate(x: jax.Array) -> jax.Array:
            robot = self.robot(x)
            values = []
            for name in self.objectives:
                metric, sign = SPATIAL_OBJECTIVES[name]
                if metric in _DESIGN_METRICS:
                    values.append(sign * _DESIGN_METRICS[metric](robot))
                else:
                    values.append(sign * joint_average(robot, metric, **options).value)
            return jnp.stack(values)

        return evaluate

    def batch_function(self) -> Callable[[jax.Array], jax.Array]:
        """Jitted ``(B, d) -> (B, m)``, memoized (the search and the baselines share it)."""
        cached = self.__dict__.get("_batch_function")
        if cached is None:
            cached = jax.jit(jax.vmap(self.objective_function()))
            object.__setattr__(self, "_batch_function", cached)
        return cached


def spatial_problem_from_mapping(config: Mapping[str, Any], *, source: str = "problem",
                                 base_dir: str | os.PathLike = ".") -> SpatialDesignProblem:
    """Build a `SpatialDesignProblem` from its YAML mapping; checks every section.

    Raises:
        ConfigError: naming the field and the reason.
    """
    check_keys(f"{source}: ", config, _TOP_KEYS)
    name = config.get("name")
    if not isinstance(name, str) or not name:
        raise ConfigError(f"{source}: name: a non-empty string is required")
    robot_entry = config.get("robot")
    if not isinstance(robot_entry, str):
        raise ConfigError(f"{source}: robot: a spatial robot file path is required")
    path = robot_entry if os.path.isabs(robot_entry) else os.path.join(os.fspath(base_dir), robot_entry)
    if not os.path.exists(path):
        raise ConfigError(f"{source}: robot: no such robot file '{robot_entry}' (looked in {base_dir})")
    base = load_robot(path)
    if not isinstance(base, SpatialRobot):
        raise ConfigError(f"{source}: robot: '{robot_entry}' is a planar robot; a planar problem gives 'fixed:' "
                          "instead (see sweeps/pareto-attachment.yaml)")
    check_joint_box(base)

    raw = config.get("variables")
    if not isinstance(raw, Mapping) or not raw:
        raise ConfigError(f"{source}: variables: a mapping field: [lower, upper] with at least one entry is required")
    variables = []
    for key, bounds in raw.items():
        where = f"{source}: variables.{key}"
        field = spatial_fields.check_field(where, key, base)
        if not isinstance(bounds, (list, tuple)) or len(bounds) != 2:
            raise ConfigError(f"{where}: must be a list [lower, upper]")
        lower, upper = number(f"{where}[0]", bounds[0]), number(f"{where}[1]", bounds[1])
        if not lower < upper:
            raise ConfigError(f"{where}: the lower bound must be below the upper bound, got [{lower}, {upper}]")
        if (field in ("base.mass", "base.inertia", "arm.mass", "arm.mass_ratio", "arm.length")
                or field.endswith(".length")) and lower <= 0:
            raise ConfigError(f"{where}: must stay positive, got lower bound {lower}")
        variables.append(Variable(field, lower, upper))
    for i, first in enumerate(variables):
        for second in variables[i + 1:]:
            if spatial_fields.field_writes(first.name, base) & spatial_fields.field_writes(second.name, base):
                raise ConfigError(f"{source}: variables: {first.name} and {second.name} set the same design number")

    raw_objectives = config.get("objectives", ["w_avg", "low_disturbance"])
    if not isinstance(raw_objectives, (list, tuple)):
        raise ConfigError(f"{source}: objectives: must be a list ({', '.join(SPATIAL_OBJECTIVES)})")
    objectives = tuple(choice(f"{source}: objectives[{i}]", v, tuple(SPATIAL_OBJECTIVES))
                       for i, v in enumerate(raw_objectives))
    if len(objectives) < 2 or len(set(objectives)) != len(objectives):
        raise ConfigError(f"{source}: objectives: at least two distinct objectives are required")
    # Optional: when absent, the search takes it below the nadir of its first population.
    reference = config.get("reference_point")
    if reference is not None:
        if not isinstance(reference, (list, tuple)) or len(reference) != len(objectives):
            raise ConfigError(f"{source}: reference_point: one number per objective, or none (objectives "
                              "maximized; low_disturbance is minus the mean ||C_w||_F)")
        reference = tuple(number(f"{source}: reference_point[{i}]", r) for i, r in enumerate(reference))

    average = config.get("average", {}) or {}
    if not isinstance(average, Mapping):
        raise ConfigError(f"{source}: average: must be a mapping (samples, randomizations, seed)")
    check_keys(f"{source}: average: ", average, _AVERAGE_KEYS)
    randomizations = integer(f"{source}: average.randomizations", average.get("randomizations", 8), least=2)
    samples = integer(f"{source}: average.samples", average.get("samples", 2048), least=randomizations)
    per = samples // randomizations
    if samples % randomizations or per & (per - 1):
        raise ConfigError(f"{source}: average.samples: must be randomizations x a power of two, got {samples}")
    seed = integer(f"{source}: average.seed", average.get("seed", 0), least=0)

    search = parse_search(source, config.get("search", {}))
    grid_points, grid_chunk, nsga2 = parse_baselines(source, config.get("baselines", {}), len(variables),
                                                     len(objectives))
    return SpatialDesignProblem(
        name=name, base=base, robot_file=robot_entry, variables=tuple(variables), objectives=objectives,
        reference_point=reference, samples=samples, randomizations=randomizations, seed=seed, search=search,
        grid_points=grid_points, grid_chunk=grid_chunk, nsga2=nsga2, description=str(config.get("description", "")),
    )


def load_design_problem(source: str | os.PathLike | Mapping[str, Any], *, name: str | None = None,
                        base_dir: str | os.PathLike | None = None) -> DesignProblem | SpatialDesignProblem:
    """A planar (``fixed:``) or spatial (``robot:``) design problem from a file or its mapping.

    Args:
        source: the problem file or its parsed mapping.
        name: a label for messages (default: the file name).
        base_dir: where a relative ``robot:`` path starts (default: the file's folder, or
            the current folder for a mapping).
    """
    if isinstance(source, Mapping):
        config, label, folder = source, name or "problem", base_dir or "."
    else:
        path = os.fspath(source)
        config = read_yaml(path, what="design problem file")
        label, folder = name or path, base_dir or (os.path.dirname(os.path.abspath(path)))
    if isinstance(config, Mapping) and "robot" in config:
        return spatial_problem_from_mapping(config, source=label, base_dir=folder)
    return problem_from_mapping(config, source=label)


def load_problem(source: str | os.PathLike | Mapping[str, Any]) -> DesignProblem | SpatialDesignProblem:
    """A design problem of either family from its YAML file or mapping (``spacearm.load_problem``).

    The same as `load_design_problem` with its defaults: a ``robot:`` key makes a spatial
    problem, ``fixed:`` a planar one.

    Raises:
        ConfigError: for a missing or malformed file and any invalid field.
    """
    return load_design_problem(source)
