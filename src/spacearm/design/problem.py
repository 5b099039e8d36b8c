"""A design problem: variables with bounds, the fixed quantities, the parametrization, and
its YAML file (see ``sweeps/pareto-attachment.yaml``).

`load_problem` checks everything a run uses (every section, every option of the
w-bar quadrature, the baselines), so ``spacearm validate`` refuses what a run would.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import os
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from .._core.schema import check_keys, check_memory, choice, integer, number, read_yaml
from ..analysis import check_average_options
from ..analysis.manipulability_average import average_manipulability as planar_average_manipulability
from ..models.planar import PlanarRobot
from .objectives import OBJECTIVES, objective

__all__ = [
    "Variable",
    "SearchSettings",
    "DesignProblem",
    "problem_from_mapping",
    "load_problem",
    "variable_names_for",
    "parse_search",
    "parse_baselines",
    "WBAR_OPTIONS",
]

# The options of analysis.average_manipulability a problem's ``wbar:`` section may set.
WBAR_OPTIONS = tuple(name for name in inspect.signature(planar_average_manipulability).parameters if name != "robot")


@dataclasses.dataclass(frozen=True)
class Variable:
    """A design variable with box bounds (SI units or a dimensionless ratio)."""

    name: str
    lower: float
    upper: float


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
    """Names and box bounds of a problem's ``variables`` (shared by planar and spatial problems)."""

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
    """A multi-objective design problem over a family of planar space robots.

    The parametrization holds the total reach L, the total mass w = m0 + m_arm and
    the base radius of gyration fixed; the variables are drawn from

    * ``b0``: attachment distance base centroid -> joint 1, m;
    * ``l{i}_over_L`` (i < n): link length share, the last link takes the rest;
    * ``m{i}_over_arm`` (i < n): share of the arm mass in link i, the last takes the rest;
    * ``a{i}_over_l{i}`` (i <= n): centroid position along link i;
    * ``arm_over_base``: m_arm / m0 at fixed total mass (I0 scales with m0).

    Links are rods with radius of gyration l_i / sqrt(12): I_i = m_i l_i^2 / 12 (a
    uniform rod when a_i = l_i / 2, Table 1's case; for other a_i we keep the rod's
    gyration and move the centroid, a modelling choice).

    Attributes:
        name: the problem name (results go to ``results/<name>/``).
        n_links: number of arm links (static).
        base_mass, base_inertia, arm_mass, reach: reference values (kg, kg m^2, kg, m).
        defaults: value of every variable name for this n (those not optimized stay here).
        variables: the optimized variables, in column order.
        objectives: objective names, all maximized.
        reference_point: hypervolume reference point, one value per objective.
        wbar_options: keyword arguments for `spacearm.analysis.average_manipulability`.
        clamp_guaranteed: see `guaranteed_area`.
    """

    name: str
    n_links: int
    base_mass: float
    base_inertia: float
    arm_mass: float
    reach: float
    defaults: Mapping[str, float]
    variables: tuple[Variable, ...]
    objectives: tuple[str, ...] = ("wbar", "S_G")
    reference_point: tuple[float, ...] = (0.0, 0.0)
    wbar_options: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    clamp_guaranteed: bool = True
    search: SearchSettings = dataclasses.field(default_factory=SearchSettings)
    grid_points: tuple[int, ...] | None = None
    grid_chunk: int = 2048
    nsga2: Mapping[str, Any] | None = None
    description: str = ""

    def robot(self, x: jax.Array) -> PlanarRobot:
        """The design for one variable vector.

        Args:
            x: ``(d,)`` variable values in `variables` order (physical units).

        Returns:
            A `PlanarRobot` built without validation (leaves may be tracers);
            vmap this method for a batch.
        """
        x = jnp.asarray(x)
        values: dict[str, jax.Array] = {k: jnp.asarray(v, dtype=x.dtype) for k, v in self.defaults.items()}
        for i, name in enumerate(self.variable_names):
            values[name] = x[i]
        n = self.n_links
        total_mass = self.base_mass + self.arm_mass
        ratio = values["arm_over_base"]
        base_mass = total_mass / (1.0 + ratio)
        arm_mass = total_mass - base_mass
        base_inertia = self.base_inertia * base_mass / self.base_mass
        length_share = [values[f"l{i}_over_L"] for i in range(1, n)]
        length_share.append(1.0 - sum(length_share))
        mass_share = [values[f"m{i}_over_arm"] for i in range(1, n)]
        mass_share.append(1.0 - sum(mass_share))
        lengths = self.reach * jnp.stack(length_share)
        masses = arm_mass * jnp.stack(mass_share)
        a = lengths * jnp.stack([values[f"a{i}_over_l{i}"] for i in range(1, n + 1)])
        robot = object.__new__(PlanarRobot)
        fields = dict(
            base_mass=base_mass,
            base_inertia=base_inertia,
            base_attach=values["b0"],
            link_mass=masses,
            link_inertia=masses * lengths**2 / 12.0,
            link_a=a,
            link_b=lengths - a,
            joint_lower=jnp.full((n,), -jnp.inf, dtype=x.dtype),
            joint_upper=jnp.full((n,), jnp.inf, dtype=x.dtype),
            name=self.name,
        )
        for key, value in fields.items():
            object.__setattr__(robot, key, value)
        return robot

    def fixed_summary(self) -> dict:
        """The fixed quantities, for the run's summary."""
        return dict(base_mass=self.base_mass, base_inertia=self.base_inertia, arm_mass=self.arm_mass,
                    reach=self.reach, links=self.n_links,
                    **{k: v for k, v in self.defaults.items() if k not in self.variable_names})

    def objective_function(self) -> Callable[[jax.Array], jax.Array]:
        """``f(x)``: ``(d,)`` variables -> ``(m,)`` objectives (maximized); pure, differentiable."""
        functions = [objective(name, wbar_options=self.wbar_options, clamp_guaranteed=self.clamp_guaranteed)
                     for name in self.objectives]

        def evaluate(x: jax.Array) -> jax.Array:
            robot = self.robot(x)
            return jnp.stack([fn(robot) for fn in functions])

        return evaluate

    def batch_function(self) -> Callable[[jax.Array], jax.Array]:
        """Jitted ``(B, d) -> (B, m)``, one per problem (memoized): the search, the grid
        and NSGA-II share it, so each batch size compiles once per process."""
        cached = self.__dict__.get("_batch_function")
        if cached is None:
            cached = jax.jit(jax.vmap(self.objective_function()))
            object.__setattr__(self, "_batch_function", cached)
        return cached


# YAML ---------------------------------------------------------------------------------

_TOP_KEYS = {"name", "description", "fixed", "variables", "objectives", "reference_point", "wbar",
             "guaranteed", "search", "baselines", "hybrid"}  # hybrid: read by spacearm.design.hybrid.parse_hybrid
_FIXED_KEYS = {"base_mass", "base_inertia", "arm_mass", "reach", "links"}
_SEARCH_KEYS = {f.name for f in dataclasses.fields(SearchSettings)}
_NSGA_KEYS = {"population", "evaluations", "seed", "time_limit"}
_SEARCH_CHOICES = {"gradient": ("forward", "reverse"), "schedule": ("geometric", "cosine")}


def variable_names_for(n_links: int) -> tuple[str, ...]:
    """All variable names the parametrization knows for an n-link arm."""
    names = ["b0", "arm_over_base"]
    names += [f"l{i}_over_L" for i in range(1, n_links)]
    names += [f"m{i}_over_arm" for i in range(1, n_links)]
    names += [f"a{i}_over_l{i}" for i in range(1, n_links + 1)]
    return tuple(names)


def problem_from_mapping(config: Mapping[str, Any], *, source: str = "problem") -> DesignProblem:
    """Build a `DesignProblem` from its YAML mapping (see ``sweeps/pareto-attachment.yaml``).

    Checks every section a run uses, so a problem that loads also runs.

    Raises:
        ConfigError: naming the field and the reason.
    """
    if not isinstance(config, Mapping):
        raise ConfigError(f"{source}: an optimization problem must be a mapping")
    check_keys(f"{source}: ", config, _TOP_KEYS)
    name = config.get("name")
    if not isinstance(name, str) or not name:
        raise ConfigError(f"{source}: name: a non-empty string is required")
    description = str(config.get("description", ""))
    fixed = config.get("fixed")
    if not isinstance(fixed, Mapping):
        raise ConfigError(f"{source}: fixed: a mapping with base_mass, base_inertia, arm_mass, reach is required")
    links = integer(f"{source}: fixed.links", fixed.get("links", 2), least=2)
    known = variable_names_for(links)
    check_keys(f"{source}: fixed: ", fixed, _FIXED_KEYS | set(known))
    physical = {}
    for key in ("base_mass", "base_inertia", "arm_mass", "reach"):
        if key not in fixed:
            raise ConfigError(f"{source}: fixed.{key}: missing required key")
        physical[key] = number(f"{source}: fixed.{key}", fixed[key])
        if physical[key] <= 0:
            raise ConfigError(f"{source}: fixed.{key}: must be positive, got {physical[key]}")
    defaults = {"arm_over_base": physical["arm_mass"] / physical["base_mass"]}
    defaults.update({f"l{i}_over_L": 1.0 / links for i in range(1, links)})
    defaults.update({f"m{i}_over_arm": 1.0 / links for i in range(1, links)})
    defaults.update({f"a{i}_over_l{i}": 0.5 for i in range(1, links + 1)})
    for key in known:
        if key in fixed:
            defaults[key] = number(f"{source}: fixed.{key}", fixed[key])

    raw_variables = config.get("variables")
    if not isinstance(raw_variables, Mapping) or not raw_variables:
        raise ConfigError(f"{source}: variables: a mapping name: [lower, upper] with at least one entry is required")
    check_keys(f"{source}: variables: ", raw_variables, known)
    variables = []
    for key, bounds in raw_variables.items():
        where = f"{source}: variables.{key}"
        if not isinstance(bounds, (list, tuple)) or len(bounds) != 2:
            raise ConfigError(f"{where}: must be a list [lower, upper]")
        lower, upper = number(f"{where}[0]", bounds[0]), number(f"{where}[1]", bounds[1])
        if not lower < upper:
            raise ConfigError(f"{where}: the lower bound must be below the upper bound, got [{lower}, {upper}]")
        variables.append(Variable(key, lower, upper))
        defaults.setdefault(key, 0.5 * (lower + upper))
    if "b0" not in defaults:
        raise ConfigError(f"{source}: b0: give it in fixed (a value) or in variables (bounds)")
    _check_ranges(source, defaults, variables, links)

    raw_objectives = config.get("objectives", ["wbar", "S_G"])
    if not isinstance(raw_objectives, (list, tuple)):
        raise ConfigError(f"{source}: objectives: must be a list of objective names ({', '.join(OBJECTIVES)})")
    objectives = tuple(choice(f"{source}: objectives[{i}]", value, OBJECTIVES) for i, value in enumerate(raw_objectives))
    if len(objectives) < 2 or len(set(objectives)) != len(objectives):
        raise ConfigError(f"{source}: objectives: at least two distinct objectives are required")
    reference = config.get("reference_point", [0.0] * len(objectives))
    if not isinstance(reference, (list, tuple)) or len(reference) != len(objectives):
        raise ConfigError(f"{source}: reference_point: one number per objective is required")
    reference = tuple(number(f"{source}: reference_point[{i}]", r) for i, r in enumerate(reference))

    wbar = config.get("wbar", {}) or {}
    if not isinstance(wbar, Mapping):
        raise ConfigError(f"{source}: wbar: must be a mapping of options for analysis.average_manipulability")
    check_keys(f"{source}: wbar: ", wbar, WBAR_OPTIONS)
    check_average_options(where=f"{source}: wbar.", **wbar)
    if "wbar" in objectives and links != 2 and wbar.get("measure", "area") == "area":
        raise ConfigError(
            f"{source}: wbar: the area average (eq. 12) is defined for 2 links, fixed.links is {links}; "
            "set wbar: {measure: joint}"
        )
    guaranteed = choice(f"{source}: guaranteed", config.get("guaranteed", "clamped"), ("clamped", "paper"))

    search = parse_search(source, config.get("search", {}))
    grid_points, grid_chunk, nsga2 = parse_baselines(source, config.get("baselines", {}), len(variables),
                                                     len(OBJECTIVES))
    return DesignProblem(
        name=name,
        n_links=links,
        base_mass=physical["base_mass"],
        base_inertia=physical["base_inertia"],
        arm_mass=physical["arm_mass"],
        reach=physical["reach"],
        defaults=defaults,
        variables=tuple(variables),
        objectives=objectives,
        reference_point=reference,
        wbar_options=dict(wbar),
        clamp_guaranteed=guaranteed == "clamped",
        search=search,
        grid_points=grid_points,
        grid_chunk=grid_chunk,
        nsga2=nsga2,
        description=description,
    )


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
        if (not isinstance(points, (list, tuple)) or len(points) != n_variables
                or not all(isinstance(p, int) and not isinstance(p, bool) and p >= 2 for p in points)):
            raise ConfigError(f"{source}: baselines.grid.points: one integer >= 2 per variable is required")
        grid_points = tuple(points)
        _check_grid_size(f"{source}: baselines.grid.points", grid_points, n_objectives)
        grid_chunk = integer(f"{source}: baselines.grid.chunk", grid.get("chunk", 2048), least=1)
    nsga2 = None
    if baselines.get("nsga2") is not None:
        raw = baselines["nsga2"]
        if not isinstance(raw, Mapping):
            raise ConfigError(f"{source}: baselines.nsga2: must be a mapping (population, evaluations, seed, time_limit)")
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


def _check_ranges(source: str, defaults: Mapping[str, float], variables: Sequence[Variable], n: int) -> None:
    """Every design inside the box must be physical: positive shares, 0 <= a/l <= 1, b0 >= 0."""
    box = {k: (v, v) for k, v in defaults.items()}
    box.update({v.name: (v.lower, v.upper) for v in variables})
    for prefix in ("l", "m"):
        suffix = "_over_L" if prefix == "l" else "_over_arm"
        names = [f"{prefix}{i}{suffix}" for i in range(1, n)]
        for key in names:
            if box[key][0] <= 0:
                raise ConfigError(f"{source}: {key}: must stay above 0, got lower value {box[key][0]}")
        if sum(box[key][1] for key in names) >= 1:
            raise ConfigError(f"{source}: {', '.join(names)}: the upper values must sum below 1 so the last link keeps a share")
    for i in range(1, n + 1):
        key = f"a{i}_over_l{i}"
        if box[key][0] < 0 or box[key][1] > 1:
            raise ConfigError(f"{source}: {key}: must stay within [0, 1]")
    if box["b0"][0] < 0:
        raise ConfigError(f"{source}: b0: must not be negative")
    if box["arm_over_base"][0] <= 0:
        raise ConfigError(f"{source}: arm_over_base: must stay above 0")


def _check_grid_size(where: str, points: Sequence[int], n_objectives: int) -> None:
    """Refuse a grid baseline whose designs would not fit in memory (the grid is built at once)."""
    count = math.prod(points)
    need = count * 8 * (2 * len(points) + n_objectives)  # the mesh, its meshgrid, the objective values
    check_memory(where, need, f"{count:,} grid designs ({' x '.join(map(str, points))})", "use fewer points")


def load_problem(path: str | os.PathLike | Mapping[str, Any]) -> DesignProblem:
    """Load an optimization problem from a YAML file (or its parsed mapping).

    Raises:
        ConfigError: for a missing or malformed file and any invalid field.
    """
    if isinstance(path, Mapping):
        return problem_from_mapping(path)
    return problem_from_mapping(read_yaml(path, what="design problem file"), source=os.fspath(path))
