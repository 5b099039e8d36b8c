"""Design optimization: the Pareto front of average manipulability vs guaranteed workspace.

Umetani & Yoshida (1990, section 5, Table 2) end on a trade-off: a longer attachment
distance b0 raises the average manipulability w-bar (eq. 12) and shrinks the Guaranteed
Workspace (eq. 8), so "careful trade-off is necessary". This module makes the
trade-off computable.

* A :class:`DesignProblem` declares design variables with bounds (YAML), holds the
  fixed quantities (total reach L, total mass, base radius of gyration) through its
  parametrization :meth:`DesignProblem.robot`, and maps a variable vector to a
  :class:`~spacearm.robot.PlanarRobot` whose leaves are all traced, so every objective
  is differentiable with respect to every variable.
* Objectives (all maximized): ``wbar`` (eq. 12, from
  :func:`spacearm.metrics.average_manipulability`), ``S_G`` (eq. 8 normalized by
  pi L^2, see :func:`guaranteed_area`) and ``S_M`` (maximum reachable space).
* :func:`pareto_search` optimizes many smoothed Chebyshev scalarizations at once: one
  optax optimizer (projected Adam on the unit box) vmapped over directions x starts,
  jitted in chunks of steps. Every evaluated design is archived; the front is the
  non-dominated subset of the archive (:func:`nondominated`) and its quality is the
  exact 2-D hypervolume (:func:`hypervolume_2d`).
* Baselines measured with the same objective code: a dense grid
  (:func:`grid_search`) and NSGA-II from pymoo (:func:`nsga2_search`).
* ``spacearm optimize FILE [--out DIR]`` runs the problem and its baselines and writes
  ``pareto.csv``, ``summary.json`` and three figures (:func:`run_problem`).

Counting evaluations: one *evaluation* is one design's objective vector. The
gradient search evaluates value and gradient together; each counts as one
evaluation in ``evaluations`` and the run also reports the measured cost of a
value-and-gradient relative to a value (``value_and_grad_cost_ratio``) and the
resulting ``equivalent_value_evaluations``, so the counts compare honestly with the
value-only baselines.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .kinematics import tip_coefficients
from .robot import ConfigError, PlanarRobot

__all__ = [
    "Variable",
    "DesignProblem",
    "SearchSettings",
    "SearchResult",
    "load_problem",
    "problem_from_mapping",
    "guaranteed_area",
    "maximum_reachable_area",
    "nondominated",
    "nondominated_mask",
    "hypervolume_2d",
    "hypervolume_history",
    "pareto_search",
    "grid_search",
    "nsga2_search",
    "run_problem",
    "add_optimize_command",
]

OBJECTIVES = ("wbar", "S_G", "S_M")


# Objectives ----------------------------------------------------------------------------


def guaranteed_area(robot: PlanarRobot, *, clamp: bool = True) -> jax.Array:
    """Normalized area of the Guaranteed Workspace, S_G = r_G^2 / L^2 (eq. 8, Table 2).

    The paper's radius is r_G = |K0 - (K1 + ... + Kn)| (eq. 8). Its absolute value has
    a kink where K0 = K1 + ... + Kn, and past it the formula grows again although the
    disc is then not a workspace at all: with K0 > K1 + ... + Kn the tip stays at
    least K0 - (K1 + ... + Kn) away from the system centroid (triangle inequality on
    eq. 1), so nothing inside that circle is reachable. The honest area is therefore
    max(K1 + ... + Kn - K0, 0)^2 / L^2 (``clamp=True``): equal to the paper's formula
    wherever the disc exists, zero where it does not, and continuously differentiable
    everywhere (the square of a ramp has a zero slope at the crossing, so no kink is
    left for the optimizer). ``clamp=False`` gives the paper's (K0 - sum K)^2 / L^2.

    Args:
        robot: a design or a batch of designs.

    Returns:
        ``(...)`` dimensionless area normalized by pi L^2.
    """
    K = tip_coefficients(robot)
    margin = jnp.sum(K[..., 1:], axis=-1) - K[..., 0]
    if clamp:
        margin = jnp.maximum(margin, 0.0)
    return margin**2 / robot.reach**2


def maximum_reachable_area(robot: PlanarRobot) -> jax.Array:
    """``(...)`` S_M = (K0 + K1 + ... + Kn)^2 / L^2, the Maximum Reachable Space over pi L^2 (Table 2)."""
    K = tip_coefficients(robot)
    return jnp.sum(K, axis=-1) ** 2 / robot.reach**2


# The problem: variables, fixed quantities, parametrization -----------------------------


@dataclasses.dataclass(frozen=True)
class Variable:
    """A design variable with box bounds (SI units or a dimensionless ratio)."""

    name: str
    lower: float
    upper: float


@dataclasses.dataclass(frozen=True)
class SearchSettings:
    """Settings of :func:`pareto_search` (see its docstring)."""

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


@dataclasses.dataclass(frozen=True)
class DesignProblem:
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
        wbar_options: keyword arguments for :func:`spacearm.metrics.average_manipulability`.
        clamp_guaranteed: see :func:`guaranteed_area`.
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

    def robot(self, x: jax.Array) -> PlanarRobot:
        """The design for one variable vector.

        Args:
            x: ``(d,)`` variable values in :attr:`variables` order (physical units).

        Returns:
            A :class:`PlanarRobot` built without validation (leaves may be tracers);
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

    def objective_function(self) -> Callable[[jax.Array], jax.Array]:
        """``f(x)``: ``(d,)`` variables -> ``(m,)`` objectives (maximized); pure, differentiable."""
        functions = [_objective(name, self) for name in self.objectives]

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


def _objective(name: str, problem: DesignProblem) -> Callable[[PlanarRobot], jax.Array]:
    if name == "wbar":
        from . import metrics  # the table-2 helper's eq. 12; imported on first use

        import inspect

        options = dict(problem.wbar_options)
        accepted = inspect.signature(metrics.average_manipulability).parameters
        for key in options:
            if key not in accepted or key == "robot":
                known = ", ".join(k for k in accepted if k != "robot")
                raise ConfigError(f"wbar.{key}: not an option of metrics.average_manipulability; known: {known}")
        return lambda robot: metrics.average_manipulability(robot, **options)
    if name == "S_G":
        clamp = problem.clamp_guaranteed
        return lambda robot: guaranteed_area(robot, clamp=clamp)
    if name == "S_M":
        return maximum_reachable_area
    raise ConfigError(f"objectives: unknown objective '{name}'; known: {', '.join(OBJECTIVES)}")


# YAML ---------------------------------------------------------------------------------

_TOP_KEYS = {"name", "description", "fixed", "variables", "objectives", "reference_point", "wbar",
             "guaranteed", "search", "baselines"}
_FIXED_KEYS = {"base_mass", "base_inertia", "arm_mass", "reach", "links"}
_SEARCH_KEYS = {f.name for f in dataclasses.fields(SearchSettings)}
_NSGA_KEYS = {"population", "evaluations", "seed", "time_limit"}


def variable_names_for(n_links: int) -> tuple[str, ...]:
    """All variable names the parametrization knows for an n-link arm."""
    names = ["b0", "arm_over_base"]
    names += [f"l{i}_over_L" for i in range(1, n_links)]
    names += [f"m{i}_over_arm" for i in range(1, n_links)]
    names += [f"a{i}_over_l{i}" for i in range(1, n_links + 1)]
    return tuple(names)


def _check_keys(where: str, mapping: Mapping, allowed: set[str] | Sequence[str]) -> None:
    for key in mapping:
        if key not in allowed:
            hint = difflib.get_close_matches(str(key), sorted(allowed), n=1)
            extra = f" (did you mean '{hint[0]}'?)" if hint else ""
            raise ConfigError(f"{where}unknown key '{key}'{extra}; allowed: {', '.join(sorted(allowed))}")


def _as_number(where: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ConfigError(f"{where}: must be a finite number, got {value!r}")
    return float(value)


def problem_from_mapping(config: Mapping[str, Any], *, source: str = "problem") -> DesignProblem:
    """Build a :class:`DesignProblem` from its YAML mapping (see ``sweeps/pareto-attachment.yaml``).

    Raises:
        ConfigError: naming the field and the reason.
    """
    if not isinstance(config, Mapping):
        raise ConfigError(f"{source}: an optimization problem must be a mapping")
    _check_keys(f"{source}: ", config, _TOP_KEYS)
    name = config.get("name")
    if not isinstance(name, str) or not name:
        raise ConfigError(f"{source}: name: a non-empty string is required")
    fixed = config.get("fixed")
    if not isinstance(fixed, Mapping):
        raise ConfigError(f"{source}: fixed: a mapping with base_mass, base_inertia, arm_mass, reach is required")
    links = fixed.get("links", 2)
    if isinstance(links, bool) or not isinstance(links, int) or links < 2:
        raise ConfigError(f"{source}: fixed.links: an integer >= 2 is required, got {links!r}")
    known = variable_names_for(links)
    _check_keys(f"{source}: fixed: ", fixed, _FIXED_KEYS | set(known))
    physical = {}
    for key in ("base_mass", "base_inertia", "arm_mass", "reach"):
        if key not in fixed:
            raise ConfigError(f"{source}: fixed.{key}: missing required key")
        physical[key] = _as_number(f"{source}: fixed.{key}", fixed[key])
        if physical[key] <= 0:
            raise ConfigError(f"{source}: fixed.{key}: must be positive, got {physical[key]}")
    defaults = {"arm_over_base": physical["arm_mass"] / physical["base_mass"]}
    defaults.update({f"l{i}_over_L": 1.0 / links for i in range(1, links)})
    defaults.update({f"m{i}_over_arm": 1.0 / links for i in range(1, links)})
    defaults.update({f"a{i}_over_l{i}": 0.5 for i in range(1, links + 1)})
    for key in known:
        if key in fixed:
            defaults[key] = _as_number(f"{source}: fixed.{key}", fixed[key])

    raw_variables = config.get("variables")
    if not isinstance(raw_variables, Mapping) or not raw_variables:
        raise ConfigError(f"{source}: variables: a mapping name: [lower, upper] with at least one entry is required")
    _check_keys(f"{source}: variables: ", raw_variables, known)
    variables = []
    for key, bounds in raw_variables.items():
        where = f"{source}: variables.{key}"
        if not isinstance(bounds, (list, tuple)) or len(bounds) != 2:
            raise ConfigError(f"{where}: must be a list [lower, upper]")
        lower, upper = _as_number(where, bounds[0]), _as_number(where, bounds[1])
        if not lower < upper:
            raise ConfigError(f"{where}: the lower bound must be below the upper bound, got [{lower}, {upper}]")
        variables.append(Variable(key, lower, upper))
        defaults.setdefault(key, 0.5 * (lower + upper))
    if "b0" not in defaults:
        raise ConfigError(f"{source}: b0: give it in fixed (a value) or in variables (bounds)")
    _check_ranges(source, defaults, variables, links)

    objectives = tuple(config.get("objectives", ("wbar", "S_G")))
    for objective in objectives:
        if objective not in OBJECTIVES:
            raise ConfigError(f"{source}: objectives: unknown objective {objective!r}; known: {', '.join(OBJECTIVES)}")
    if len(objectives) < 2 or len(set(objectives)) != len(objectives):
        raise ConfigError(f"{source}: objectives: at least two distinct objectives are required")
    reference = config.get("reference_point", [0.0] * len(objectives))
    if not isinstance(reference, (list, tuple)) or len(reference) != len(objectives):
        raise ConfigError(f"{source}: reference_point: one number per objective is required")
    reference = tuple(_as_number(f"{source}: reference_point", r) for r in reference)
    wbar = config.get("wbar", {}) or {}
    if not isinstance(wbar, Mapping):
        raise ConfigError(f"{source}: wbar: must be a mapping of options for metrics.average_manipulability")
    guaranteed = config.get("guaranteed", "clamped")
    if guaranteed not in ("clamped", "paper"):
        raise ConfigError(f"{source}: guaranteed: must be 'clamped' or 'paper', got {guaranteed!r}")

    search_map = config.get("search", {}) or {}
    if not isinstance(search_map, Mapping):
        raise ConfigError(f"{source}: search: must be a mapping")
    _check_keys(f"{source}: search: ", search_map, _SEARCH_KEYS)
    search = SearchSettings()
    for key, value in search_map.items():
        default = getattr(search, key)
        if isinstance(default, bool):
            if not isinstance(value, bool):
                raise ConfigError(f"{source}: search.{key}: must be true or false, got {value!r}")
        elif isinstance(default, str):
            allowed = {"gradient": ("forward", "reverse"), "schedule": ("geometric", "cosine")}[key]
            if value not in allowed:
                raise ConfigError(f"{source}: search.{key}: must be one of {', '.join(allowed)}, got {value!r}")
        elif isinstance(default, int):
            if isinstance(value, bool) or not isinstance(value, int) or value < (0 if key == "seed" else 1):
                raise ConfigError(f"{source}: search.{key}: must be a positive integer, got {value!r}")
        else:
            value = _as_number(f"{source}: search.{key}", value)
            if value <= 0:
                raise ConfigError(f"{source}: search.{key}: must be positive, got {value}")
        search = dataclasses.replace(search, **{key: value})

    baselines = config.get("baselines", {}) or {}
    if not isinstance(baselines, Mapping):
        raise ConfigError(f"{source}: baselines: must be a mapping with optional keys grid, nsga2")
    _check_keys(f"{source}: baselines: ", baselines, {"grid", "nsga2"})
    grid_points = None
    grid_chunk = 2048
    if baselines.get("grid") is not None:
        grid = baselines["grid"]
        if not isinstance(grid, Mapping) or "points" not in grid:
            raise ConfigError(f"{source}: baselines.grid: a mapping with points: [n1, ..., nd] is required")
        _check_keys(f"{source}: baselines.grid: ", grid, {"points", "chunk"})
        points = grid["points"]
        if isinstance(points, int):
            points = [points] * len(variables)
        if (not isinstance(points, (list, tuple)) or len(points) != len(variables)
                or not all(isinstance(p, int) and not isinstance(p, bool) and p >= 2 for p in points)):
            raise ConfigError(f"{source}: baselines.grid.points: one integer >= 2 per variable is required")
        grid_points = tuple(points)
        grid_chunk = int(grid.get("chunk", 2048))
    nsga2 = None
    if baselines.get("nsga2") is not None:
        nsga2 = baselines["nsga2"]
        if not isinstance(nsga2, Mapping):
            raise ConfigError(f"{source}: baselines.nsga2: must be a mapping (population, evaluations, seed, time_limit)")
        _check_keys(f"{source}: baselines.nsga2: ", nsga2, _NSGA_KEYS)
        nsga2 = dict(nsga2)
    description = config.get("description", "")
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
        description=str(description),
    )


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


def load_problem(path: str | os.PathLike | Mapping[str, Any]) -> DesignProblem:
    """Load an optimization problem from a YAML file (or its parsed mapping)."""
    if isinstance(path, Mapping):
        return problem_from_mapping(path)
    from .validate import read_yaml

    return problem_from_mapping(read_yaml(path), source=os.fspath(path))


# Fronts and hypervolume ---------------------------------------------------------------


def nondominated_mask(objectives: np.ndarray) -> np.ndarray:
    """``(N,)`` bool: True for points no other point dominates (all objectives maximized).

    Duplicates keep their first occurrence only. Two objectives: O(N log N) sweep;
    more: pairwise comparison.

    Args:
        objectives: ``(N, m)`` objective values.
    """
    f = np.asarray(objectives, dtype=np.float64)
    count = f.shape[0]
    mask = np.zeros(count, dtype=bool)
    if count == 0:
        return mask
    finite = np.all(np.isfinite(f), axis=1)
    if f.shape[1] == 2:
        # Sort by f1 descending, then f2 descending; a point survives when its f2 beats
        # every f2 before it (an equal f2 with a larger-or-equal f1 dominates it).
        order = np.lexsort((-f[:, 1], -f[:, 0]))
        order = order[finite[order]]
        f2 = f[order, 1]
        best_before = np.concatenate([[-np.inf], np.maximum.accumulate(f2)[:-1]])
        mask[order[f2 > best_before]] = True
        return mask
    for i in np.flatnonzero(finite):
        others = f[finite]
        dominated = np.any(np.all(others >= f[i], axis=1) & np.any(others > f[i], axis=1))
        mask[i] = not dominated
    # Drop exact duplicates after the first.
    _, first = np.unique(f[mask], axis=0, return_index=True)
    keep = np.flatnonzero(mask)[np.sort(first)]
    mask[:] = False
    mask[keep] = True
    return mask


def nondominated(objectives: np.ndarray) -> np.ndarray:
    """Indices of the non-dominated points, sorted by the first objective ascending."""
    f = np.asarray(objectives)
    index = np.flatnonzero(nondominated_mask(f))
    return index[np.argsort(f[index, 0], kind="stable")]


def hypervolume_2d(objectives: np.ndarray, reference: Sequence[float] = (0.0, 0.0)) -> float:
    """Exact hypervolume of a 2-D point set (both objectives maximized).

    The area of the union of the boxes [r1, f1] x [r2, f2] over the points that beat
    the reference point in both objectives: a sweep in f1 descending adds one strip
    per front point, (f1 - r1)(f2 - best f2 so far).

    Args:
        objectives: ``(N, 2)`` points (any order, dominated ones allowed).
        reference: ``(2,)`` the reference point.
    """
    f = np.asarray(objectives, dtype=np.float64).reshape(-1, 2)
    r1, r2 = float(reference[0]), float(reference[1])
    f = f[np.all(np.isfinite(f), axis=1) & (f[:, 0] > r1) & (f[:, 1] > r2)]
    if f.size == 0:
        return 0.0
    front = f[nondominated_mask(f)]
    front = front[np.argsort(-front[:, 0])]  # f1 descending, so f2 ascending
    below = np.concatenate([[r2], front[:-1, 1]])
    return float(np.sum((front[:, 0] - r1) * (front[:, 1] - below)))


def hypervolume_history(batches: Sequence[np.ndarray], reference: Sequence[float]) -> np.ndarray:
    """Hypervolume of the growing archive after each batch of evaluated points.

    Args:
        batches: a sequence of ``(B_k, 2)`` objective arrays, in evaluation order.

    Returns:
        ``(len(batches),)`` hypervolume of the union of the first k+1 batches.
    """
    front = np.zeros((0, 2))
    values = []
    for batch in batches:
        merged = np.concatenate([front, np.asarray(batch, dtype=np.float64).reshape(-1, 2)])
        front = merged[nondominated_mask(merged)]
        values.append(hypervolume_2d(front, reference))
    return np.array(values)


# The gradient search ------------------------------------------------------------------


@dataclasses.dataclass
class SearchResult:
    """Everything a search evaluated, in order, with timings.

    Attributes:
        method: ``"gradient"``, ``"grid"`` or ``"nsga2"``.
        designs: ``(N, d)`` every evaluated variable vector.
        objectives: ``(N, m)`` their objective values.
        checkpoints: list of dicts (``evaluations``, ``seconds``, ``hypervolume``) after each batch.
        evaluations: total objective evaluations (value+gradient counts as one for ``gradient``).
        compile_seconds: time spent compiling (measured apart).
        run_seconds: wall time of the search itself, compile excluded.
        extra: method-specific numbers.
    """

    method: str
    designs: np.ndarray
    objectives: np.ndarray
    checkpoints: list[dict]
    evaluations: int
    compile_seconds: float
    run_seconds: float
    extra: dict = dataclasses.field(default_factory=dict)

    def front(self) -> np.ndarray:
        """Indices of the non-dominated evaluated designs, by the first objective."""
        return nondominated(self.objectives)

    def seconds_to(self, hypervolume: float) -> float | None:
        """Run seconds until the archive first reached ``hypervolume`` (None if never)."""
        for point in self.checkpoints:
            if point["hypervolume"] >= hypervolume:
                return point["seconds"]
        return None

    def evaluations_to(self, hypervolume: float) -> int | None:
        for point in self.checkpoints:
            if point["hypervolume"] >= hypervolume:
                return point["evaluations"]
        return None

    def hypervolume_at(self, seconds: float) -> float:
        """Archive hypervolume at a given run time (the last checkpoint not after it)."""
        value = 0.0
        for point in self.checkpoints:
            if point["seconds"] <= seconds:
                value = point["hypervolume"]
        return value


def _direction_targets(count: int, objectives: int) -> np.ndarray:
    """``(count, m)`` points on the simplex of normalized anchors, evenly spread.

    For two objectives: (s, 1 - s) with s evenly in [0, 1] (from the max-f2 anchor to
    the max-f1 anchor, the order of a front sorted by f1), so each Chebyshev ray from
    the utopia point aims at an even share of the front's projection (as in normal
    boundary intersection). More objectives: a seeded random simplex sample.
    """
    if objectives == 2:
        s = np.linspace(0.0, 1.0, count)
        return np.stack([s, 1.0 - s], axis=1)
    rng = np.random.default_rng(0)
    return rng.dirichlet(np.ones(objectives), size=count)


def _scalarization_builder(objective: Callable, smoothing: float, augmentation: float):
    """Smoothed, augmented Chebyshev scalarization of one design, to be minimized.

    g(x) = mu log sum_i exp(lambda_i (u_i - fhat_i) / mu) + rho sum_i (u_i - fhat_i),
    fhat = (f - nadir) / scale, u the utopia point. g is smooth and strictly decreasing
    in every objective, so each minimizer is Pareto-optimal (the rho term breaks ties
    of one-hot weights); a small mu keeps Chebyshev's reach into non-convex parts of
    the front, where weighted sums fail.
    """

    def scalar(z, lower, width, weights, utopia, nadir, scale):
        x = lower + width * z
        f = objective(x)
        shortfall = utopia - (f - nadir) / scale
        g = smoothing * jax.nn.logsumexp(weights * shortfall / smoothing) + augmentation * jnp.sum(shortfall)
        return g, f

    return scalar


def _ray_weights(targets: np.ndarray, utopia: np.ndarray) -> np.ndarray:
    """Chebyshev weights 1/(u - t) of rays from the utopia point through ``targets``,
    scaled to sum 1; the first and last rays become one-hot anchors (max f2, max f1)."""
    weights = 1.0 / np.maximum(utopia - targets, 1e-9)
    weights = weights / weights.sum(axis=1, keepdims=True)
    if targets.shape[1] == 2 and targets.shape[0] >= 2:
        weights[0] = (0.0, 1.0)
        weights[-1] = (1.0, 0.0)
    return weights


def _front_rays(front_f: np.ndarray, front_x: np.ndarray, count: int, nadir, scale, utopia,
                blend: float = 0.25):
    """Re-aim ``count`` rays at points spread along the current front.

    The front (sorted by f1) is a polyline in normalized objective space. Its points
    are spread evenly in the measure sqrt(|df1 df2|) + blend * |df|: the first term is
    the hypervolume-optimal density of a large point set on a 2-D front (proportional
    to sqrt(|slope|), Auger, Bader, Brockhoff & Zitzler 2009), which puts the points
    where the gaps lose hypervolume; the second, Euclidean arc length, keeps some rays
    on flat stretches too. The k-th run restarts from the archived design nearest to
    its target. A ray from the utopia point through a front point p has weights
    1/(u - p); if p is already Pareto-optimal it is that ray's Chebyshev optimum,
    otherwise the run improves on it.
    """
    normalized = (front_f - nadir) / scale
    if normalized.shape[0] == 1:
        return np.repeat(normalized, count, axis=0), np.repeat(front_x, count, axis=0)
    delta = np.diff(normalized, axis=0)
    steps = np.sqrt(np.abs(delta[:, 0] * delta[:, 1])) + blend * np.linalg.norm(delta, axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    wanted = np.linspace(0.0, arc[-1], count)
    targets = np.stack([np.interp(wanted, arc, normalized[:, i]) for i in range(normalized.shape[1])], axis=1)
    nearest = np.clip(np.searchsorted(arc, wanted), 0, arc.size - 1)
    previous = np.clip(nearest - 1, 0, arc.size - 1)
    nearest = np.where(np.abs(arc[previous] - wanted) < np.abs(arc[nearest] - wanted), previous, nearest)
    return targets, front_x[nearest]


def _densify(front_f: np.ndarray, front_x: np.ndarray, count: int) -> np.ndarray:
    """``count`` designs interpolated between neighbouring front designs, ``(count, d)``.

    The Pareto set of a 2-objective problem is a curve in design space; between two
    neighbouring optimal designs its chord is second-order close to it. The gaps
    between neighbouring front points (sorted by f1) lose the hypervolume
    Delta f1 * Delta f2 / 2, and k evenly spaced new points cut that by (k + 1); points
    go greedily to the gap whose loss is largest after the points it already has.
    """
    gap = np.abs(np.diff(front_f[:, 0])) * np.abs(np.diff(front_f[:, 1]))
    allotted = np.zeros(gap.size, dtype=int)
    for _ in range(count):
        allotted[np.argmax(gap / (allotted + 1) ** 2)] += 1
    rows = []
    for i in np.flatnonzero(allotted):
        t = np.arange(1, allotted[i] + 1)[:, None] / (allotted[i] + 1)
        rows.append(front_x[i] + t * (front_x[i + 1] - front_x[i]))
    return np.concatenate(rows)[:count]


def pareto_search(problem: DesignProblem, settings: SearchSettings | None = None) -> SearchResult:
    """Gradient-based Pareto search: vmapped projected Adam over Chebyshev scalarizations.

    1. ``initial_samples`` random designs (value only) give a first front, ideal
       point and objective scales.
    2. ``directions`` x ``starts`` smoothed Chebyshev scalarizations run in parallel:
       the variables are mapped to the unit box, one Adam state per run is vmapped
       (``optax.scale_by_adam``), each update is projected back onto the box (so
       bounds that are active at the optimum are reached exactly, which a sigmoid
       reparametrization cannot do), and the step size decays from ``learning_rate``
       to ``final_learning_rate`` (cosine). The first start of each direction begins
       at the initial sample that scores best on its scalarization (``warm_start``),
       the other starts at random designs.
    3. The steps run in jitted chunks of ``chunk`` steps (compiled once, same shapes
       every call). After each chunk the ideal point and scales are re-read from the
       archive and, with ``reaim``, the rays are re-aimed at points evenly spaced by
       arc length along the current front (:func:`_front_rays`); the first start of
       each direction restarts from the archived design nearest its new target, the
       other starts continue their own trajectories. Rays then follow the front's
       shape, so a flat or a steep stretch of the front gets its share of points, and
       the free starts keep exploring (on the 6-variable problem the w-bar anchor at
       b0 = 0 is a stationary point of w-bar in b0: only a free start finds the
       steep part of the front beyond it).
    4. The first and last rays are one-hot anchors (each objective alone, the other
       breaking ties through the augmentation term); objective scales never fall
       below the spread of the initial samples, so a front first seen as a flat
       stretch does not freeze the anchors.

    Every design the optimizer visits is archived (the objective values come with the
    gradient for free); the front is the non-dominated part of the archive.

    Returns:
        A :class:`SearchResult` with every evaluated design in order.
    """
    import optax

    settings = settings or problem.search
    objective = problem.objective_function()
    lower_np, width_np = problem.lower, problem.upper - problem.lower
    lower, width = jnp.asarray(lower_np), jnp.asarray(width_np)
    d, m = len(problem.variables), len(problem.objectives)
    runs = settings.directions * settings.starts
    rng = np.random.default_rng(settings.seed)
    ray_targets = _direction_targets(settings.directions, m)  # (directions, m)
    first = np.arange(runs) % settings.starts == 0  # the first start of each direction

    progress = np.arange(settings.steps) / max(settings.steps - 1, 1)
    final = settings.final_learning_rate
    if settings.schedule == "cosine":
        step_sizes = final + 0.5 * (settings.learning_rate - final) * (1.0 + np.cos(np.pi * progress))
    else:  # geometric: travel early, precision soon after
        step_sizes = settings.learning_rate * (final / settings.learning_rate) ** progress
    adam = optax.scale_by_adam()
    scalar = _scalarization_builder(objective, settings.smoothing, settings.augmentation)
    if settings.gradient == "forward":
        # d forward tangents instead of one reverse pass; measured slower on eq. 12's
        # quadrature (about 1.7x a value vs 1.2x for reverse), kept as an option.
        gradient_and_objectives = jax.jacfwd(scalar, has_aux=True)
    elif settings.gradient == "reverse":
        gradient_and_objectives = jax.grad(scalar, has_aux=True)
    else:
        raise ConfigError(f"search.gradient: must be 'forward' or 'reverse', got {settings.gradient!r}")

    def one_step(z, state, step_size, weights, utopia, nadir, scale):
        grad, f = gradient_and_objectives(z, lower, width, weights, utopia, nadir, scale)
        grad = jnp.where(jnp.isfinite(grad), grad, 0.0)
        direction, state = adam.update(grad, state)
        z_new = jnp.clip(z - step_size * direction, 0.0, 1.0)
        return z_new, state, z, f

    batched_step = jax.vmap(one_step, in_axes=(0, 0, None, 0, None, None, None))

    def run_chunk(z, state, step_sizes, weights, utopia, nadir, scale):
        def body(carry, step_size):
            z, state = carry
            z, state, z_seen, f_seen = batched_step(z, state, step_size, weights, utopia, nadir, scale)
            return (z, state), (z_seen, f_seen)

        (z, state), (zs, fs) = jax.lax.scan(body, (z, state), step_sizes)
        return z, state, zs, fs

    evaluate_batch = problem.batch_function()
    z_samples = rng.uniform(size=(settings.initial_samples, d))
    z_runs = rng.uniform(size=(runs, d))

    # Compile both programs first, on the real shapes (timed apart from the run).
    start = time.perf_counter()
    jax.block_until_ready(evaluate_batch(jnp.asarray(lower_np + width_np * z_samples)))  # compiles (or hits the cache)
    chunk_shapes = (jnp.asarray(z_runs), jax.vmap(adam.init)(jnp.asarray(z_runs)),
                    jnp.asarray(step_sizes[: settings.chunk]), jnp.ones((runs, m)),
                    jnp.ones(m), jnp.zeros(m), jnp.ones(m))
    run_chunk = jax.jit(run_chunk).lower(*chunk_shapes).compile()
    compile_seconds = time.perf_counter() - start

    reference = problem.reference_point
    two = m == 2
    designs, values, checkpoints = [], [], []
    start = time.perf_counter()
    x_samples = lower_np + width_np * z_samples
    f_samples = np.asarray(evaluate_batch(jnp.asarray(x_samples)))
    designs.append(x_samples)
    values.append(f_samples)
    evaluations = settings.initial_samples
    keep = nondominated_mask(f_samples)
    front_f, front_x = f_samples[keep], x_samples[keep]
    checkpoints.append(dict(evaluations=evaluations, seconds=time.perf_counter() - start,
                            hypervolume=hypervolume_2d(front_f, reference) if two else float("nan")))

    # Objective scales never fall below the spread (10th-90th percentile) of the initial
    # samples: while the archive front covers only a flat stretch (a range near zero in
    # one objective), the front's own range would blow that objective's scale up, and
    # the anchors would refuse to trade it for the other (the fronts here are L-shaped).
    spread = np.percentile(f_samples, 90, axis=0) - np.percentile(f_samples, 10, axis=0)

    def normalization():
        ideal, nadir = front_f.max(axis=0), front_f.min(axis=0)
        scale = np.maximum(np.maximum(ideal - nadir, spread), 1e-12)
        return nadir, scale, (ideal - nadir) / scale + settings.utopia_margin

    if settings.warm_start:
        # Each direction's first start begins at the initial sample that scores best on
        # its own scalarization; further starts stay random (multi-start).
        nadir, scale, utopia = normalization()
        fhat = (f_samples - nadir) / scale
        weights = _ray_weights(ray_targets, utopia) if m == 2 else 1.0 / (utopia - ray_targets)
        weights = np.repeat(weights, settings.starts, axis=0)  # (runs, m)
        shortfall = utopia - fhat[None, :, :]
        score = np.max(weights[:, None, :] * shortfall, axis=-1) + settings.augmentation * shortfall.sum(-1)
        z_runs = np.where(first[:, None], z_samples[np.argmin(score, axis=1)], z_runs)

    steps_done = densified = 0
    state = None
    while steps_done < settings.steps:
        nadir, scale, utopia = normalization()
        if settings.reaim and steps_done > 0 and m == 2:
            # The first start of each direction restarts from the front; the others keep
            # their own trajectories (multi-start survives re-aiming: a start elsewhere
            # can still find a part of the front the archive has not seen).
            order = np.argsort(front_f[:, 0])
            ray_targets, x_start = _front_rays(front_f[order], front_x[order], settings.directions,
                                               nadir, scale, utopia)
            z_runs[first] = (x_start - lower_np) / width_np
        weights = np.repeat(_ray_weights(ray_targets, utopia) if m == 2 else 1.0 / (utopia - ray_targets),
                            settings.starts, axis=0)
        sizes = step_sizes[steps_done: steps_done + settings.chunk]
        sizes = np.concatenate([sizes, np.full(settings.chunk - sizes.size, final)])
        if state is None or settings.reset_adam:
            state = jax.vmap(adam.init)(jnp.asarray(z_runs))
        z, state, zs, fs = run_chunk(jnp.asarray(z_runs), state, jnp.asarray(sizes), jnp.asarray(weights),
                              jnp.asarray(utopia), jnp.asarray(nadir), jnp.asarray(scale))
        z_runs = np.array(z)
        fs = np.asarray(fs).reshape(-1, m)
        xs = lower_np + width_np * np.asarray(zs).reshape(-1, d)
        designs.append(xs)
        values.append(fs)
        steps_done += settings.chunk
        evaluations += fs.shape[0]
        merged_f, merged_x = np.concatenate([front_f, fs]), np.concatenate([front_x, xs])
        keep = nondominated_mask(merged_f)
        front_f, front_x = merged_f[keep], merged_x[keep]
        if settings.densify and two and front_f.shape[0] >= 2:
            # Densify: value-only designs interpolated between neighbouring front designs.
            order = np.argsort(front_f[:, 0])
            x_new = _densify(front_f[order], front_x[order], settings.initial_samples)
            f_new = np.asarray(evaluate_batch(jnp.asarray(x_new)))
            designs.append(x_new)
            values.append(f_new)
            evaluations += x_new.shape[0]
            densified += x_new.shape[0]
            merged_f, merged_x = np.concatenate([front_f, f_new]), np.concatenate([front_x, x_new])
            keep = nondominated_mask(merged_f)
            front_f, front_x = merged_f[keep], merged_x[keep]
        checkpoints.append(dict(evaluations=evaluations, seconds=time.perf_counter() - start,
                                hypervolume=hypervolume_2d(front_f, reference) if two else float("nan")))
    run_seconds = time.perf_counter() - start
    return SearchResult(
        method="gradient",
        designs=np.concatenate(designs),
        objectives=np.concatenate(values),
        checkpoints=checkpoints,
        evaluations=evaluations,
        compile_seconds=compile_seconds,
        run_seconds=run_seconds,
        extra=dict(directions=settings.directions, starts=settings.starts, steps=steps_done,
                   gradient=settings.gradient, value_evaluations=settings.initial_samples + densified,
                   densify_evaluations=densified,
                   value_and_gradient_evaluations=evaluations - settings.initial_samples - densified),
    )


def value_and_grad_cost_ratio(problem: DesignProblem, *, gradient: str = "reverse", batch: int = 64,
                              repeats: int = 5) -> float:
    """Measured wall time of a batched value-and-gradient over a batched value (same batch).

    Used to convert the gradient search's evaluation count into value-only
    equivalents. Best of ``repeats`` timings of each, compiled beforehand.
    """
    objective = problem.objective_function()
    value = problem.batch_function()
    differentiate = jax.jacfwd if gradient == "forward" else jax.grad

    def summed(y):
        f = objective(y)
        return jnp.sum(f), f

    both = jax.jit(jax.vmap(differentiate(summed, has_aux=True)))  # as in the search: gradient + values
    rng = np.random.default_rng(1)
    x = jnp.asarray(problem.lower + (problem.upper - problem.lower) * rng.uniform(size=(batch, len(problem.variables))))
    jax.block_until_ready(value(x))
    jax.block_until_ready(both(x))

    def best(fn):
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            jax.block_until_ready(fn(x))
            times.append(time.perf_counter() - start)
        return min(times)

    return best(both) / best(value)


# Baselines ----------------------------------------------------------------------------


def grid_search(problem: DesignProblem, points: Sequence[int] | None = None, chunk: int | None = None) -> SearchResult:
    """Dense grid baseline: every design of the outer-product grid over the bounds.

    Evaluated in fixed-size chunks (the last one padded) with one compiled program.
    """
    points = tuple(points or problem.grid_points or (21,) * len(problem.variables))
    chunk = int(chunk or problem.grid_chunk)
    axes = [np.linspace(v.lower, v.upper, p) for v, p in zip(problem.variables, points)]
    mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(axes))
    total = mesh.shape[0]
    chunk = min(chunk, total)
    evaluate = problem.batch_function()
    start = time.perf_counter()
    compiled = evaluate
    jax.block_until_ready(evaluate(jnp.asarray(np.tile(problem.lower, (chunk, 1)))))  # compiles (or hits the cache)
    compile_seconds = time.perf_counter() - start
    start = time.perf_counter()
    values = []
    for begin in range(0, total, chunk):
        block = mesh[begin:begin + chunk]
        padded = np.concatenate([block, np.repeat(block[-1:], chunk - block.shape[0], axis=0)])
        values.append(np.asarray(compiled(jnp.asarray(padded)))[: block.shape[0]])
    run_seconds = time.perf_counter() - start
    objectives = np.concatenate(values)
    hv = hypervolume_2d(objectives, problem.reference_point) if objectives.shape[1] == 2 else float("nan")
    return SearchResult(
        method="grid",
        designs=mesh,
        objectives=objectives,
        checkpoints=[dict(evaluations=total, seconds=run_seconds, hypervolume=hv)],
        evaluations=total,
        compile_seconds=compile_seconds,
        run_seconds=run_seconds,
        extra=dict(points=list(points)),
    )


def nsga2_search(
    problem: DesignProblem,
    *,
    population: int = 40,
    evaluations: int = 4000,
    seed: int = 0,
    time_limit: float | None = None,
) -> SearchResult:
    """NSGA-II baseline (pymoo) on the same objective code, vectorized per generation.

    pymoo minimizes, so it sees -f. Every evaluated design is archived with a time
    stamp; the archive hypervolume is computed after the run (not timed).

    Args:
        population: NSGA-II population size.
        evaluations: stop after this many objective evaluations.
        time_limit: optional wall-time limit, s (stops at the next generation).
    """
    try:
        from pymoo.algorithms.moo.nsga2 import NSGA2
        from pymoo.core.problem import Problem
        from pymoo.core.termination import Termination
        from pymoo.optimize import minimize
    except ImportError as error:  # pragma: no cover - optional extra
        raise ConfigError("baselines.nsga2: needs pymoo (pip install 'spacearm[optimize]')") from error

    evaluate = problem.batch_function()
    d, m = len(problem.variables), len(problem.objectives)
    start = time.perf_counter()
    # Compile for the population size (pymoo may send a smaller batch after removing
    # duplicates; such a batch compiles once more, inside the timed run).
    jax.block_until_ready(evaluate(jnp.asarray(np.tile(problem.lower, (population, 1)))))
    compile_seconds = time.perf_counter() - start
    log: list[tuple[np.ndarray, np.ndarray, float]] = []
    clock = {"start": 0.0}

    class _Problem(Problem):
        def __init__(self):
            super().__init__(n_var=d, n_obj=m, xl=problem.lower, xu=problem.upper)

        def _evaluate(self, x, out, *args, **kwargs):
            f = np.asarray(evaluate(jnp.asarray(x, dtype=jnp.float64)))
            out["F"] = -f
            log.append((np.array(x, dtype=np.float64), f, time.perf_counter() - clock["start"]))

    class _Budget(Termination):
        def _update(self, algorithm):
            done = algorithm.evaluator.n_eval / evaluations
            if time_limit is not None:
                done = max(done, (time.perf_counter() - clock["start"]) / time_limit)
            return min(done, 1.0)

    algorithm = NSGA2(pop_size=population)
    clock["start"] = time.perf_counter()
    minimize(_Problem(), algorithm, _Budget(), seed=seed, verbose=False)
    run_seconds = time.perf_counter() - clock["start"]
    designs = np.concatenate([entry[0] for entry in log])
    objectives = np.concatenate([entry[1] for entry in log])
    hv = hypervolume_history([entry[1] for entry in log], problem.reference_point) if m == 2 else None
    checkpoints, count = [], 0
    for k, entry in enumerate(log):
        count += entry[1].shape[0]
        checkpoints.append(dict(evaluations=count, seconds=entry[2],
                                hypervolume=float(hv[k]) if hv is not None else float("nan")))
    return SearchResult(
        method="nsga2",
        designs=designs,
        objectives=objectives,
        checkpoints=checkpoints,
        evaluations=count,
        compile_seconds=compile_seconds,
        run_seconds=run_seconds,
        extra=dict(population=population, seed=seed),
    )
# The whole run: search, baselines, files --------------------------------------------

TARGET_FRACTION = 0.999


def _nested_grid_levels(points: Sequence[int]) -> list[tuple[int, ...]]:
    """Coarser grids nested in the dense one: (p - 1) / 2^k + 1 points per axis."""
    levels = [tuple(points)]
    while True:
        coarser = tuple((p - 1) // 2 + 1 if (p - 1) % 2 == 0 else None for p in levels[-1])
        if any(c is None or c < 3 for c in coarser):
            break
        levels.append(coarser)
    return levels[::-1]


def _grid_convergence(problem: DesignProblem, grid: SearchResult) -> list[dict]:
    """Hypervolume of the nested coarser grids, read off the dense grid's values.

    Their times are the dense grid's run time per design times their size (an
    estimate: the coarse grids are not re-evaluated).
    """
    points = grid.extra["points"]
    values = grid.objectives.reshape(*points, -1)
    seconds_per_design = grid.run_seconds / grid.evaluations
    rows = []
    for level in _nested_grid_levels(points):
        strides = [(p - 1) // (q - 1) for p, q in zip(points, level)]
        sub = values[tuple(slice(None, None, s) for s in strides)].reshape(-1, values.shape[-1])
        rows.append(dict(points=list(level), evaluations=int(sub.shape[0]),
                         seconds=seconds_per_design * sub.shape[0],
                         hypervolume=hypervolume_2d(sub, problem.reference_point)))
    return rows


def _method_summary(result: SearchResult, reference_hv: float | None) -> dict:
    front = result.front()
    final_hv = result.checkpoints[-1]["hypervolume"] if result.checkpoints else float("nan")
    summary = dict(
        hypervolume=final_hv,
        evaluations=result.evaluations,
        compile_seconds=result.compile_seconds,
        run_seconds=result.run_seconds,
        front_size=int(front.size),
        **result.extra,
    )
    if reference_hv:
        target = TARGET_FRACTION * reference_hv
        summary.update(
            fraction_of_grid_hypervolume=final_hv / reference_hv,
            seconds_to_target=result.seconds_to(target),
            evaluations_to_target=result.evaluations_to(target),
        )
    summary["checkpoints"] = result.checkpoints
    return summary


def _front_table(problem: DesignProblem, result: SearchResult) -> dict[str, list[float]]:
    index = result.front()
    columns: dict[str, list[float]] = {}
    for j, name in enumerate(problem.variable_names):
        columns[name] = [float(v) for v in result.designs[index, j]]
    for j, name in enumerate(problem.objectives):
        columns[name] = [float(v) for v in result.objectives[index, j]]
    return columns


def run_problem(problem: DesignProblem, out_dir: str | os.PathLike, *, baselines: bool = True,
                figures: bool = True, config: Mapping | None = None, log: Callable[[str], None] = print) -> dict:
    """Run the gradient search and the declared baselines; write results atomically.

    Writes into ``out_dir``: ``pareto.csv`` (the gradient search's front: the
    variables by name, then the objectives), ``pareto_grid.csv`` and
    ``pareto_nsga2.csv`` for the baselines, ``summary.json`` and the figures
    ``front.png``, ``designs.png``, ``convergence.png``.

    Comparisons. With a grid: the target is ``TARGET_FRACTION`` of the dense grid's
    hypervolume, and each method's run time to reach it is reported. Without a grid,
    NSGA-II is compared at the gradient search's run time (read off its archive's
    hypervolume curve). Compile time is measured apart and reported, never mixed
    into the run times.

    Returns:
        The summary dictionary also written to ``summary.json``.
    """
    from .results import git_state, manifest, write_csv, write_json

    code_state = git_state()  # before anything under out_dir (perhaps tracked) changes
    started = time.perf_counter()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    two = len(problem.objectives) == 2
    log(f"optimize {problem.name}: {len(problem.variables)} variables ({', '.join(problem.variable_names)}), "
        f"objectives {', '.join(problem.objectives)}")
    gradient = pareto_search(problem)
    log(f"  gradient: {gradient.evaluations} evaluations, compile {gradient.compile_seconds:.1f} s, "
        f"run {gradient.run_seconds:.2f} s, hypervolume {gradient.checkpoints[-1]['hypervolume']:.6g}")
    ratio = value_and_grad_cost_ratio(problem, gradient=problem.search.gradient, batch=problem.search.initial_samples)
    gradient.extra["value_and_gradient_cost_ratio"] = ratio
    gradient.extra["equivalent_value_evaluations"] = (
        gradient.extra["value_evaluations"] + ratio * gradient.extra["value_and_gradient_evaluations"])

    results = {"gradient": gradient}
    grid_rows = None
    if baselines and problem.grid_points is not None:
        grid = grid_search(problem)
        results["grid"] = grid
        grid_rows = _grid_convergence(problem, grid) if two else None
        log(f"  grid {'x'.join(map(str, problem.grid_points))}: {grid.evaluations} evaluations, "
            f"run {grid.run_seconds:.2f} s, hypervolume {grid.checkpoints[-1]['hypervolume']:.6g}")
    if baselines and problem.nsga2 is not None:
        options = dict(problem.nsga2)
        nsga = nsga2_search(problem, population=int(options.get("population", 40)),
                            evaluations=int(options.get("evaluations", 4000)), seed=int(options.get("seed", 0)),
                            time_limit=options.get("time_limit"))
        results["nsga2"] = nsga
        log(f"  nsga2 (population {nsga.extra['population']}): {nsga.evaluations} evaluations, "
            f"run {nsga.run_seconds:.2f} s, hypervolume {nsga.checkpoints[-1]['hypervolume']:.6g}")

    grid_hv = results["grid"].checkpoints[-1]["hypervolume"] if "grid" in results and two else None
    summary: dict[str, Any] = dict(
        name=problem.name,
        description=problem.description,
        variables={v.name: [v.lower, v.upper] for v in problem.variables},
        fixed=dict(base_mass=problem.base_mass, base_inertia=problem.base_inertia, arm_mass=problem.arm_mass,
                   reach=problem.reach, links=problem.n_links,
                   **{k: v for k, v in problem.defaults.items() if k not in problem.variable_names}),
        objectives=list(problem.objectives),
        objectives_maximized=True,
        reference_point=list(problem.reference_point),
        hypervolume=gradient.checkpoints[-1]["hypervolume"],
        evaluation_counting=(
            "one evaluation = the objective vector of one design. The gradient search gets value and gradient "
            "together (reverse or forward mode) and counts that as one evaluation; "
            "value_and_gradient_cost_ratio is its measured wall-time cost in value evaluations and "
            "equivalent_value_evaluations = value_evaluations + ratio * value_and_gradient_evaluations. "
            "Grid and NSGA-II evaluate values only."),
        timing=("run_seconds exclude compilation (compile_seconds, measured apart); the gradient search's "
                "checkpoints include its own bookkeeping (front update between chunks); NSGA-II's include pymoo's "
                "overhead; archive hypervolumes are computed after the run, untimed"),
        methods={name: _method_summary(result, grid_hv) for name, result in results.items()},
    )
    if grid_rows is not None:
        summary["methods"]["grid"]["nested_grids"] = grid_rows
    if grid_hv is not None:
        target = TARGET_FRACTION * grid_hv
        comparison = dict(
            kind="time to reach the target hypervolume",
            grid_hypervolume=grid_hv,
            target_fraction=TARGET_FRACTION,
            target_hypervolume=target,
            gradient_seconds=gradient.seconds_to(target),
            gradient_evaluations=gradient.evaluations_to(target),
        )
        if "nsga2" in results:
            nsga = results["nsga2"]
            comparison.update(nsga2_seconds=nsga.seconds_to(target), nsga2_evaluations=nsga.evaluations_to(target))
            comparison["met"] = bool(
                comparison["gradient_seconds"] is not None
                and (comparison["nsga2_seconds"] is None or comparison["gradient_seconds"] < comparison["nsga2_seconds"]))
        summary["comparison"] = comparison
    elif "nsga2" in results and two:
        nsga = results["nsga2"]
        budget = gradient.run_seconds
        summary["comparison"] = dict(
            kind="hypervolume at equal run time",
            seconds=budget,
            gradient_hypervolume=gradient.checkpoints[-1]["hypervolume"],
            nsga2_hypervolume_at_same_time=nsga.hypervolume_at(budget),
            nsga2_final_hypervolume=nsga.checkpoints[-1]["hypervolume"],
            nsga2_final_seconds=nsga.run_seconds,
            nsga2_seconds_to_gradient_hypervolume=nsga.seconds_to(gradient.checkpoints[-1]["hypervolume"]),
            met=bool(gradient.checkpoints[-1]["hypervolume"] > nsga.hypervolume_at(budget)),
        )
    if "comparison" in summary:
        log("  comparison: " + ", ".join(f"{k} {v:.6g}" if isinstance(v, float) else f"{k} {v}"
                                         for k, v in summary["comparison"].items()))

    written = [write_csv(out_dir / "pareto.csv", _front_table(problem, gradient))]
    for name in ("grid", "nsga2"):
        if name in results:
            written.append(write_csv(out_dir / f"pareto_{name}.csv", _front_table(problem, results[name])))
    if figures and two:
        written += plot_results(problem, results, summary, out_dir)
    summary["files"] = [p.name for p in written] + ["summary.json", "manifest.json"]
    if config is not None:
        summary["config"] = dict(config)
    write_json(out_dir / "summary.json", summary)
    timings = {"wall": time.perf_counter() - started}
    write_json(out_dir / "manifest.json", manifest(dict(config) if config is not None else {"problem": problem.name},
                                                   command=sys.argv, timings=timings, git=code_state,
                                                   extra={"files": summary["files"]}))
    log(f"  wrote {out_dir}: {', '.join(summary['files'])}")
    return summary


# Figures ------------------------------------------------------------------------------

_LABELS = {
    "wbar": r"$\bar{w}$, average manipulability (eq. 12, $w^*/L^2$)",
    "S_G": r"$\hat{S}_G$, guaranteed workspace ($/\pi L^2$)",
    "S_M": r"$\hat{S}_M$, maximum reachable space ($/\pi L^2$)",
}
_UNITS = {"b0": "b0 [m]"}
_STYLE = {
    "gradient": dict(color="tab:red", label="gradient (Chebyshev, vmapped Adam)"),
    "nsga2": dict(color="tab:blue", label="NSGA-II (pymoo)"),
    "grid": dict(color="0.35", label="dense grid"),
}


def plot_results(problem: DesignProblem, results: Mapping[str, SearchResult], summary: Mapping,
                 out_dir: Path) -> list[Path]:
    """The front in objective space, the front designs in variable space, convergence."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .results import save_figure

    written = []
    names = problem.objectives
    # 1. Objective space.
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    if "grid" in results:
        grid = results["grid"]
        step = max(1, grid.objectives.shape[0] // 6000)
        ax.scatter(grid.objectives[::step, 0], grid.objectives[::step, 1], s=2, color="0.85",
                   label=f"grid designs ({grid.evaluations}, every {step}th shown)", rasterized=True)
    for method in ("grid", "nsga2", "gradient"):
        if method in results:
            result = results[method]
            front = result.objectives[result.front()]
            hv = result.checkpoints[-1]["hypervolume"]
            style = dict(_STYLE[method])
            label = f"{style.pop('label')} front: {front.shape[0]} pts, HV {hv:.6f}"
            if method == "gradient":
                ax.plot(front[:, 0], front[:, 1], ".", ms=3, label=label, **style)
            elif method == "grid":
                ax.plot(front[:, 0], front[:, 1], "-", lw=1.0, label=label, **style)
            else:
                ax.plot(front[:, 0], front[:, 1], "x", ms=4, label=label, **style)
    ax.set_xlabel(_LABELS.get(names[0], names[0]))
    ax.set_ylabel(_LABELS.get(names[1], names[1]))
    ax.set_title(f"{problem.name}: Pareto front (both maximized, reference point {tuple(problem.reference_point)})")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    written.append(save_figure(fig, out_dir / "front.png", dpi=130))
    plt.close(fig)

    # 2. Variable space.
    gradient = results["gradient"]
    index = gradient.front()
    designs, objectives = gradient.designs[index], gradient.objectives[index]
    d = len(problem.variables)
    if d == 2:
        fig, ax = plt.subplots(figsize=(7.0, 5.5))
        if "grid" in results:
            gf = results["grid"].front()
            ax.plot(results["grid"].designs[gf, 0], results["grid"].designs[gf, 1], "s", ms=3, mfc="none",
                    color="0.6", label="grid front designs")
        points = ax.scatter(designs[:, 0], designs[:, 1], c=objectives[:, 1], s=8, cmap="viridis",
                            label="gradient front designs")
        fig.colorbar(points, ax=ax, label=_LABELS.get(names[1], names[1]))
        for v, set_limits in zip(problem.variables, (ax.set_xlim, ax.set_ylim)):
            pad = 0.02 * (v.upper - v.lower)  # designs on a bound stay visible
            set_limits(v.lower - pad, v.upper + pad)
        ax.set_xlabel(_UNITS.get(problem.variables[0].name, problem.variables[0].name))
        ax.set_ylabel(_UNITS.get(problem.variables[1].name, problem.variables[1].name))
        ax.legend(fontsize=8, loc="upper right")
        ax.grid(alpha=0.3)
        ax.set_title("Pareto-optimal designs in variable space (the whole box shown)")
    else:
        cols = 3
        rows = int(math.ceil(d / cols))
        fig, axes = plt.subplots(rows, cols, figsize=(4.0 * cols, 3.0 * rows), squeeze=False)
        for j, variable in enumerate(problem.variables):
            ax = axes[j // cols][j % cols]
            if "nsga2" in results:
                nf = results["nsga2"].front()
                ax.plot(results["nsga2"].objectives[nf, 1], results["nsga2"].designs[nf, j], "x", ms=3,
                        color=_STYLE["nsga2"]["color"], label="NSGA-II front")
            ax.plot(objectives[:, 1], designs[:, j], ".", ms=3, color=_STYLE["gradient"]["color"],
                    label="gradient front")
            ax.set_ylim(variable.lower, variable.upper)
            ax.set_xlabel(_LABELS.get(names[1], names[1]), fontsize=8)
            ax.set_ylabel(_UNITS.get(variable.name, variable.name))
            ax.grid(alpha=0.3)
            if j == 0:
                ax.legend(fontsize=7)
        for j in range(d, rows * cols):
            axes[j // cols][j % cols].axis("off")
        fig.suptitle("Pareto-optimal designs: each variable (full bound range) along the front")
    fig.tight_layout()
    written.append(save_figure(fig, out_dir / "designs.png", dpi=130))
    plt.close(fig)

    # 3. Convergence.
    fig, (ax_e, ax_t) = plt.subplots(1, 2, figsize=(12.0, 4.8))
    best = max(r.checkpoints[-1]["hypervolume"] for r in results.values())
    for method in ("nsga2", "gradient"):
        if method in results:
            cp = results[method].checkpoints
            ev = [c["evaluations"] for c in cp]
            sec = [c["seconds"] for c in cp]
            hv = [c["hypervolume"] / best for c in cp]
            ax_e.plot(ev, hv, "-", **_STYLE[method])
            ax_t.plot(sec, hv, "-", **_STYLE[method])
    if "grid" in results:
        nested = summary["methods"]["grid"].get("nested_grids", [])
        ev = [r["evaluations"] for r in nested]
        hv = [r["hypervolume"] / best for r in nested]
        sec = [r["seconds"] for r in nested]
        ax_e.plot(ev, hv, "o--", color="0.35", label="nested grids (coarse to dense)")
        ax_t.plot(sec, hv, "o--", color="0.35", label="nested grids (time per design x size)")
        target = TARGET_FRACTION * results["grid"].checkpoints[-1]["hypervolume"] / best
        for ax in (ax_e, ax_t):
            ax.axhline(target, color="k", lw=0.8, ls=":", label=f"target: {TARGET_FRACTION:.1%} of dense grid")
    for ax in (ax_e, ax_t):
        ax.set_xscale("log")
        ax.set_ylim(0.98, 1.0015)
        ax.set_ylabel("archive hypervolume / best final")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8, loc="lower right")
    ax_e.set_xlabel("objective evaluations (value + gradient counts as one)")
    ax_t.set_xlabel("run time [s] (compile excluded)")
    fig.suptitle(f"{problem.name}: convergence")
    fig.tight_layout()
    written.append(save_figure(fig, out_dir / "convergence.png", dpi=130))
    plt.close(fig)
    return written


# Command line -------------------------------------------------------------------------


def _cmd_optimize(args) -> int:
    from .validate import read_yaml

    config = read_yaml(args.file)
    problem = problem_from_mapping(config, source=os.fspath(args.file))
    out_dir = Path(args.out) if args.out else Path("results") / problem.name
    run_problem(problem, out_dir, baselines=not args.no_baselines, config=config)
    return 0


def add_optimize_command(subparsers) -> None:
    """``spacearm optimize FILE [--out DIR] [--no-baselines]``."""
    parser = subparsers.add_parser(
        "optimize",
        help="gradient-based Pareto search over designs (w-bar vs S_G), with grid and NSGA-II baselines",
        description=(
            "Search the Pareto front of the objectives declared in FILE (e.g. sweeps/pareto-attachment.yaml) "
            "and write pareto.csv, summary.json and figures into results/<name>/ or --out."),
    )
    parser.add_argument("file", help="problem YAML, e.g. sweeps/pareto-attachment.yaml")
    parser.add_argument("--out", help="output folder (default results/<name>/)")
    parser.add_argument("--no-baselines", action="store_true", help="skip the grid and NSGA-II baselines")
    parser.set_defaults(func=_cmd_optimize)
