"""Design optimization: the Pareto front of average manipulability vs guaranteed workspace.

Umetani & Yoshida (1990, section 5, Table 2) end on a trade-off: a longer attachment
distance b0 raises the average manipulability w-bar (eq. 12) and shrinks the Guaranteed
Workspace (eq. 8), so "careful trade-off is necessary". This package makes the
trade-off computable.

* A `DesignProblem` declares design variables with bounds (YAML): the design fields
  of its robot family (`RobotFamily.fields`, the names sweep axes use) set on a base
  design, a robot file (``robot:``) or, for planar arms, the reference values of
  ``fixed:`` (total reach L, total mass, base radius of gyration held by the fields
  chosen). `DesignProblem.robot` maps a variable vector to a robot whose leaves are all
  traced, so every objective is differentiable with respect to every variable.
  `load_problem` reads either family.
* Objectives (all maximized): planar ``wbar`` (eq. 12, from
  `spacearm.paper.normalized_wbar`), ``S_G`` (eq. 8 normalized by
  pi L^2, see `guaranteed_area`) and ``S_M`` (maximum reachable space); joint-box
  averages ``w_avg``, ``gci``, ``low_disturbance``, ``w_d_avg`` and the impact averages
  ``low_virtual_mass``, ``low_bus_rate_jump``, ``low_capture_bus_rate``
  (`AVERAGE_OBJECTIVES`), all from one fixed QMC rule; the task peaks (``low_peak_*``,
  `TASK_OBJECTIVES`); ``low_total_mass``; and
  ``reach_radius`` (the path-independent workspace radius, single-arm robots of either
  family, with its envelope-theorem gradient; `spacearm.design.objectives.reach_radius`).
* `hybrid_search` (the default of ``spacearm optimize``): an NSGA-II population refined
  by set-based hypervolume-gradient steps on the whole front at once (each
  non-dominated-sorting layer climbs its own hypervolume, computed exactly in JAX by
  `exact_hypervolume` and differentiated by autodiff), stopping when the archive's
  hypervolume stops growing; any problem, 2 to 4 objectives.
* `pareto_search` (``--method scalarized``) optimizes many smoothed Chebyshev scalarizations at once: one
  optax optimizer (projected Adam on the unit box) vmapped over directions x starts,
  jitted in chunks of steps. Every evaluated design is archived; the front is the
  non-dominated subset of the archive (`nondominated`) and its quality is the
  exact 2-D hypervolume (`hypervolume_2d`).
* Baselines measured with the same objective code: a dense grid
  (`grid_search`) and NSGA-II from pymoo (`nsga2_search`).
* `run_problem` runs the problem and its baselines and writes ``pareto.csv``,
  ``summary.json`` and the manifest; ``spacearm optimize FILE [--out DIR]`` adds three
  figures (`spacearm.figures.design`).

Modules: ``problem`` (variables, parametrization, YAML), ``objectives``, ``fronts``
(non-dominated sets, hypervolume), ``hypervolume`` (the exact hypervolume in JAX and its
gradient), ``hybrid`` (the default search), ``search`` (the scalarized gradient search),
``baselines`` (grid, NSGA-II), ``run`` (the whole run and its files).

Counting evaluations: one *evaluation* is one design's objective vector. The
gradient search evaluates value and gradient together; each counts as one
evaluation in ``evaluations`` and the run also reports the measured cost of a
value-and-gradient relative to a value (``value_and_grad_cost_ratio``) and the
resulting ``equivalent_value_evaluations``, so the counts compare honestly with the
value-only baselines.
"""

from .baselines import grid_search as grid_search, nsga2_search as nsga2_search
from .fronts import (
    hypervolume_2d as hypervolume_2d,
    hypervolume_history as hypervolume_history,
    nondominated as nondominated,
    nondominated_mask as nondominated_mask,
)
from .hybrid import HybridSettings as HybridSettings, hybrid_search as hybrid_search
from .hypervolume import exact_hypervolume as exact_hypervolume, hypervolume_gradient as hypervolume_gradient
from .objectives import (
    AVERAGE_OBJECTIVES as AVERAGE_OBJECTIVES,
    OBJECTIVES as OBJECTIVES,
    guaranteed_area as guaranteed_area,
    maximum_reachable_area as maximum_reachable_area,
)

# load_problem reads planar (fixed:) and spatial (robot:) problem files alike.
from .problem import (
    DesignProblem as DesignProblem,
    SearchSettings as SearchSettings,
    Variable as Variable,
    load_problem as load_problem,
    problem_from_mapping as problem_from_mapping,
    variable_names_for as variable_names_for,
)
from .run import TARGET_FRACTION as TARGET_FRACTION, run_problem as run_problem
from .search import (
    SearchResult as SearchResult,
    pareto_search as pareto_search,
    value_and_grad_cost_ratio as value_and_grad_cost_ratio,
)

__all__ = [
    "AVERAGE_OBJECTIVES",
    "OBJECTIVES",
    "TARGET_FRACTION",
    "DesignProblem",
    "HybridSettings",
    "SearchResult",
    "SearchSettings",
    "Variable",
    "exact_hypervolume",
    "grid_search",
    "guaranteed_area",
    "hybrid_search",
    "hypervolume_2d",
    "hypervolume_gradient",
    "hypervolume_history",
    "load_problem",
    "maximum_reachable_area",
    "nondominated",
    "nondominated_mask",
    "nsga2_search",
    "pareto_search",
    "problem_from_mapping",
    "run_problem",
    "value_and_grad_cost_ratio",
    "variable_names_for",
]
