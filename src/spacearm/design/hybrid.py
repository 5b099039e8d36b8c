"""The default design search: an evolutionary population refined by set-based
hypervolume-gradient steps on the whole front at once.

Pure gradient sets stall: dominated points have zero hypervolume gradient and single
runs settle on local Pareto sets. The methods that work are hybrids (HIGA-MO: Wang,
Deutz, Baeck & Emmerich, EMO 2017; Hypervolume Newton: Wang et al., MCA 28(1), 2023).
Each generation is a chain of small steps over one search state (`_GENERATION`, run by
`hybrid_search`):

1. **Exploration.** A space-filling start (a Latin hypercube of two populations), then
   NSGA-II offspring every generation (binary tournament on rank and crowding, simulated
   binary crossover, polynomial mutation; Deb et al., IEEE TEC 6(2), 2002), merged by
   non-dominated sorting and crowding. Offspring fill every value batch up to a multiple
   of the population, so the value program compiles once.
2. **Refinement.** A share of the population (``gradient_share``, the front first)
   steps along the design-space gradient of the hypervolume of its own non-dominated
   layer, ``g_i = J_i^T dHV/df_i`` (`spacearm.design.fronts.layer_face_areas` for 2 and 3
   objectives, `spacearm.design.hypervolume.layer_hypervolume_gradients` for 4), so
   dominated points move towards the front instead of freezing and the front spreads by
   its own slope. ``J^T w`` comes from forward differences through the value program
   (few variables, or closed-form objectives whose values are cheap; an unmoved member
   keeps its Jacobian, and a variable held at a bound where moving inward lowers both
   objectives is not differenced, ``bound_refresh``) or from a vmapped vector-Jacobian
   product. A step must pass Armijo's sufficient-increase test on the layer's
   hypervolume (``step_rule: armijo``); for joint-box averages over many variables each
   variable has its own length instead (Rprop: Riedmiller & Braun, ICNN 1993), so weakly
   sensitive variables converge as fast as strong ones.
   Two objectives: a front member that is not Pareto-critical (its projected objective
   gradients not opposite) also takes a Newton step onto the Pareto set (``newton``): on
   its free variables a critical point solves w g_0 + (1 - w) g_1 = 0, linearized in the
   design and the weight with Hessians from second differences (Hillermeier 2001), and
   the least step of its solutions is taken. Trials along the direction that raises
   both objectives (the min-norm convex combination of the normalized gradients:
   Fliege & Svaiter 2000; Desideri 2012) are an option (``common_ascent``).
3. **Densification.** Designs interpolated between neighbouring archive-front designs
   (the Pareto set is a curve or a surface, and a chord between near optimal designs
   stays second-order close to it): along the front's curve, where the gaps lose the
   most hypervolume, and past its ends for two objectives (`_end_designs`); on chords to
   near neighbours for more (`_neighbour_designs`, archive only, where they would crowd
   the refined members out of the population). Once a three-objective search has
   settled (the population's hypervolume stalls while the densified designs gain the
   archive more per evaluation than the rest) the steps stop and the archive fills the
   largest triangles of its front (`_simplex_designs`, ``settled_fill``).
4. **Stopping** from the front's own convergence: the archive's hypervolume gained less
   than ``tolerance`` over ``patience`` generations; or, without densification, the
   population's hypervolume stalled while the archive's gained less than
   ``population_tolerance``; or a budget of generations, evaluations or seconds ran out.

Every design is evaluated by the problem's ``batch_function()`` in batches of the
population and archived (differences, probes and offspring included); the
vector-Jacobian product and the 4-objective hypervolume gradients compile one program
each. Compile seconds are reported apart. docs/explanation/pareto-search.md compares the
search with the baselines.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping, Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from scipy.spatial import Delaunay, QhullError, cKDTree
from scipy.stats import qmc

from .._core.errors import ConfigError
from .._core.schema import check_keys, integer, number
from .fronts import hypervolume, layer_face_areas, nondominated_mask, reference_from_population
from .hypervolume import layer_hypervolume_gradients
from .search import SearchResult, _densify

__all__ = ["HybridSettings", "hybrid_search", "nondominated_ranks", "parse_hybrid", "reference_from_population"]


@dataclasses.dataclass(frozen=True)
class HybridSettings:
    """Settings of `hybrid_search` (YAML section ``hybrid:``).

    Attributes:
        population: designs per generation (the compiled batch size).
        generations: most generations.
        max_evaluations: stop past this many evaluations (None: no limit).
        max_seconds: stop past this run time, s (None: no limit).
        patience, tolerance: stop when the archive hypervolume gained less than
            ``tolerance`` (relative) over ``patience`` generations.
        population_patience: without densification (``densify: false``), also stop when
            the population's own hypervolume has not risen above its best by more than ``tolerance`` (relative) for this many
            generations (0: never) while the archive's hypervolume gained less than
            ``population_tolerance`` (relative) over them.
        gradient_share: share of the population that takes a gradient step each
            generation (the front first, at random within a layer); the rest of the
            evaluations go to offspring. None: all of it when every objective is a
            closed form (values cost little next to a generation's bookkeeping), half
            otherwise (joint-box averages).
        jacobian: how the design-space gradient J^T w is computed: ``"reverse"`` (a
            vmapped vector-Jacobian product, one more compiled program), ``"differences"``
            (forward differences through the value program: d values per design, no
            other program) or ``"auto"`` (differences for at most 4 variables, where they
            cost no more than a vector-Jacobian product, about 4 values, and save its
            compile, or when every objective is a closed form, not a joint-box average,
            so values are cheap; reverse otherwise).
        initial_step, min_step, max_step: gradient step lengths in the unit box.
        reference_margin: the reference point, when the problem gives none, lies this
            share of the first population's front range below its nadir.
        densify: also evaluate a population of designs interpolated between neighbouring
            archive-front designs every generation.
        settled_fill: three or more objectives, with densification: once the search has
            settled (the population's hypervolume rose no higher in
            ``population_patience`` generations, and over them the densified designs
            gained the archive more hypervolume per evaluation than the rest, in
            geometric mean), the gradient steps stop and every generation fills the
            front with this many populations of designs at the centroids of its largest
            simplices (`_simplex_designs`) beside half a population of offspring.
            0: never (chords and steps to the end).
        bound_refresh: two objectives, forward differences: a variable at a bound where,
            at the last differences taken there, moving inward lowered both objectives for
            every member at that bound is not differenced (its Jacobian row is zero: no
            weights give it an inward projected gradient) except every ``bound_refresh``-th
            generation, when every difference is taken again. 0: always difference.
            (Pareto sets on a face of the box leave many variables at a bound.)
        common_ascent: two objectives, forward differences: each generation, from every
            front member whose Jacobian is current and whose projected objective
            gradients are not opposite (so it is not Pareto-critical), designs at
            `COMMON_ASCENT_LENGTHS` along the direction that raises both objectives (the
            min-norm convex combination of the normalized gradients), evaluated in the
            steps' batch; they join the union. Off by default: beside the Newton steps
            they cost many evaluations for little hypervolume.
        newton: two objectives, forward differences: each generation the same members
            (front, current Jacobian, not Pareto-critical) take a Newton step onto the
            Pareto set (`_newton_probes`, `_newton_designs`): second differences on their
            free variables (k (k + 1) / 2 values for k free, none for one), evaluated in
            the steps' batch, then the step, evaluated with the densified designs; both
            join the union.
        step_rule: ``"per_variable"`` (a step length per variable, Rprop),
            ``"armijo"`` (one length per member along the normalized gradient) or
            ``"auto"`` (per variable for joint-box averages over more than 4 variables,
            where weak and strong variables mix; Armijo otherwise, where per-variable
            steps end lower).
        crossover_eta, mutation_eta: distribution indices of SBX and polynomial mutation.
        seed: random seed (Latin hypercube, variation).
    """

    population: int = 48
    generations: int = 100
    max_evaluations: int | None = None
    max_seconds: float | None = None
    patience: int = 10
    tolerance: float = 1e-9
    population_patience: int = 5
    population_tolerance: float = 1e-3
    gradient_share: float | None = None
    jacobian: str = "auto"
    step_rule: str = "auto"
    initial_step: float = 0.05
    min_step: float = 1e-5
    max_step: float = 0.3
    reference_margin: float = 0.1
    densify: bool = True
    settled_fill: int = 3
    bound_refresh: int = 10
    common_ascent: bool = False
    newton: bool = True
    crossover_eta: float = 15.0
    mutation_eta: float = 20.0
    seed: int = 0


JACOBIANS = ("auto", "reverse", "differences")
STEP_RULES = ("auto", "per_variable", "armijo")
# Where an evaluated design came from (the evaluations of each are reported).
SOURCES = ("start", "differences", "steps", "offspring", "densified", "common_ascent", "newton_probes", "newton")
_START, _DIFFERENCES, _STEPS, _OFFSPRING, _DENSIFIED, _ASCENT, _PROBES, _NEWTON = range(len(SOURCES))
# Forward differences cost d values per gradient; a vector-Jacobian product through the
# joint-box averages costs a few values and compiles a program of its own, longer than
# the values'. Above DIFFERENCES_UP_TO variables, differences still win when every
# objective is a closed form (no joint-box average): values are then cheap.
DIFFERENCES_UP_TO = 4
# Forward-difference step in the unit box (the objectives are smooth float64 averages on a
# fixed rule: truncation ~1e-6 relative, rounding ~1e-10).
DIFFERENCE_STEP = 1e-6
# Common-ascent trials (two objectives): unit-box lengths along the direction that raises
# both objectives, tried from each front member with a current Jacobian whose projected,
# normalized objective gradients are not opposite (the norm of their min-norm convex
# combination above COMMON_ASCENT_LEAST).
COMMON_ASCENT_LENGTHS = (1e-4, 1e-3, 1e-2)
COMMON_ASCENT_LEAST = 1e-3
# Pareto-Newton steps (two objectives): the unit-box step of the second differences, the
# distance to a bound within which a variable pushed out of the box is held at it, and the
# longest step (unit box).
NEWTON_HESSIAN_STEP = 1e-3
NEWTON_SNAP = 1e-3
NEWTON_LONGEST = 0.05

_INTEGER_KEYS = {
    "population": 4,
    "generations": 1,
    "max_evaluations": 1,
    "patience": 1,
    "population_patience": 0,
    "settled_fill": 0,
    "bound_refresh": 0,
    "seed": 0,
}


def parse_hybrid(source: str, section: Any) -> HybridSettings:
    """The ``hybrid:`` section of a problem file as `HybridSettings` (checked).

    Raises:
        ConfigError: naming the file, the key and the reason.
    """
    section = section or {}
    if not isinstance(section, Mapping):
        raise ConfigError(f"{source}: hybrid: must be a mapping")
    settings = HybridSettings()
    check_keys(f"{source}: hybrid: ", section, {f.name for f in dataclasses.fields(HybridSettings)})
    changes = {}
    for key, value in section.items():
        where = f"{source}: hybrid.{key}"
        if value is None and key in ("max_evaluations", "max_seconds", "gradient_share"):
            changes[key] = None
        elif key in ("jacobian", "step_rule"):
            allowed = JACOBIANS if key == "jacobian" else STEP_RULES
            if value not in allowed:
                raise ConfigError(f"{where}: must be one of {', '.join(allowed)}, got {value!r}")
            changes[key] = value
        elif key in ("densify", "common_ascent", "newton"):
            if not isinstance(value, bool):
                raise ConfigError(f"{where}: must be true or false, got {value!r}")
            changes[key] = value
        elif key in _INTEGER_KEYS:
            changes[key] = integer(where, value, least=_INTEGER_KEYS[key])
        else:
            changes[key] = number(where, value)
            if changes[key] < 0 or (changes[key] == 0 and key not in ("tolerance", "gradient_share")):
                raise ConfigError(f"{where}: must be positive, got {value}")
            if key == "gradient_share" and changes[key] > 1:
                raise ConfigError(f"{where}: must lie in [0, 1], got {value}")
    return dataclasses.replace(settings, **changes)


def nondominated_ranks(objectives: np.ndarray) -> np.ndarray:
    """``(N,)`` int: the non-dominated sorting layer of each point (0 = the front), all
    objectives maximized; non-finite rows get the last layer."""
    f = np.asarray(objectives, dtype=np.float64)
    finite = np.all(np.isfinite(f), axis=1)
    f = np.where(finite[:, None], f, -np.inf)
    # dominates[i, j]: i dominates j.
    dominates = np.all(f[:, None, :] >= f[None, :, :], axis=2) & np.any(f[:, None, :] > f[None, :, :], axis=2)
    ranks = np.full(f.shape[0], -1)
    remaining = np.ones(f.shape[0], dtype=bool)
    layer = 0
    while remaining.any():
        dominated = np.any(dominates[remaining][:, remaining], axis=0)
        current = np.flatnonzero(remaining)[~dominated]
        ranks[current] = layer
        remaining[current] = False
        layer += 1
    return ranks


def _crowding(objectives: np.ndarray, ranks: np.ndarray) -> np.ndarray:
    """Crowding distance within each layer (Deb et al. 2002); extremes get infinity."""
    distance = np.zeros(objectives.shape[0])
    for rank in np.unique(ranks):
        members = np.flatnonzero(ranks == rank)
        if members.size <= 2:
            distance[members] = np.inf
            continue
        for j in range(objectives.shape[1]):
            values = objectives[members, j]
            order = np.argsort(values)
            spread = values[order[-1]] - values[order[0]]
            distance[members[order[[0, -1]]]] = np.inf
            if spread > 0:
                distance[members[order[1:-1]]] += (values[order[2:]] - values[order[:-2]]) / spread
    return distance


def _survivors(objectives: np.ndarray, count: int) -> np.ndarray:
    """Indices of the ``count`` best rows by (rank, -crowding): NSGA-II's selection."""
    ranks = nondominated_ranks(objectives)
    crowding = _crowding(objectives, ranks)
    return np.lexsort((-crowding, ranks))[:count]


def _variation(rng: np.random.Generator, z: np.ndarray, f: np.ndarray, settings: HybridSettings) -> np.ndarray:
    """NSGA-II offspring of a population in the unit box: tournament, SBX, polynomial mutation."""
    count, d = z.shape
    ranks = nondominated_ranks(f)
    crowding = _crowding(f, ranks)
    a, b = rng.integers(count, size=(2, count))
    better = (ranks[a] < ranks[b]) | ((ranks[a] == ranks[b]) & (crowding[a] >= crowding[b]))
    parents = np.where(better, a, b)
    first, second = z[parents[0::2]], z[parents[1::2]]
    pairs = first.shape[0]
    # Simulated binary crossover, probability 0.9 per pair, 0.5 per variable.
    u = rng.uniform(size=(pairs, d))
    eta = settings.crossover_eta
    beta = np.where(u <= 0.5, (2 * u) ** (1 / (eta + 1)), (1 / (2 * (1 - u))) ** (1 / (eta + 1)))
    cross = (rng.uniform(size=(pairs, 1)) < 0.9) & (rng.uniform(size=(pairs, d)) < 0.5)
    beta = np.where(cross, beta, 1.0)
    mean, half = 0.5 * (first + second), 0.5 * (second - first)
    children = np.concatenate([mean - beta * half, mean + beta * half])[:count]
    if children.shape[0] < count:
        children = np.concatenate([children, z[rng.integers(count, size=count - children.shape[0])]])
    # Polynomial mutation, probability 1/d per variable.
    eta = settings.mutation_eta
    u = rng.uniform(size=children.shape)
    delta = np.where(u < 0.5, (2 * u) ** (1 / (eta + 1)) - 1, 1 - (2 * (1 - u)) ** (1 / (eta + 1)))
    mutate = rng.uniform(size=children.shape) < 1.0 / d
    return np.clip(children + np.where(mutate, delta, 0.0), 0.0, 1.0)


def _neighbour_designs(
    rng: np.random.Generator, front_f: np.ndarray, front_z: np.ndarray, count: int, neighbours: int = 4
) -> np.ndarray:
    """``count`` unit-box designs between archive-front designs and their neighbours on the front.

    The Pareto set of an m-objective problem is (piecewise) an (m-1)-manifold in design
    space; a chord between two neighbouring optimal designs stays second-order close to it.
    Each new design lies at a uniform place on the chord from a front design to one of its
    ``neighbours`` nearest front designs (in objectives scaled by the front's range); front
    designs are drawn with probability proportional to the (m-1)-volume of their gap (the
    distance to their nearest neighbour to the power m-1), so the sparse parts of the front
    fill first.
    """
    n, m = front_f.shape
    spread = np.ptp(front_f, axis=0)
    scaled = (front_f - front_f.min(axis=0)) / np.where(spread > 0, spread, 1.0)
    k = min(neighbours, n - 1)
    distance, index = cKDTree(scaled).query(scaled, k=k + 1)
    gap = distance[:, 1] ** (m - 1)
    total = gap.sum()
    chosen = rng.choice(n, size=count, p=gap / total) if total > 0 else rng.integers(n, size=count)
    mates = index[chosen, rng.integers(1, k + 1, size=count)]
    t = rng.uniform(size=(count, 1))
    return np.clip(front_z[chosen] + t * (front_z[mates] - front_z[chosen]), 0.0, 1.0)


def _simplex_designs(front_f: np.ndarray, front_z: np.ndarray, count: int, tried: set) -> np.ndarray:
    """Up to ``count`` unit-box designs at the centroids of the largest simplices of the front.

    A non-dominated set of m objectives meets each line along (1, ..., 1) at most once,
    so its projection on the hyperplane normal to that line (after scaling each
    objective by the front's range) is one-to-one: a Delaunay triangulation there is a
    triangulation of the front's surface (for three objectives; its (m-1)-simplices for
    more). Its simplices are ranked by their (m-1)-volume in the scaled objectives (the
    gap a missing design leaves grows with it) and the design-space centroid of each of
    the largest is returned, each simplex once (``tried`` holds the vertex designs of the
    simplices already filled, so one whose centroid fell off the front is not drawn
    again). Where the Pareto set is flat in design space (a face of the box, as on
    pareto-mount-ur5) the centroid of three designs on it lies on it exactly, and it
    lands in one of the front's largest gaps, where a random chord lands anywhere
    (docs/explanation/pareto.md).

    Args:
        front_f: ``(n, m)`` the archive front's objectives, n > m.
        front_z: ``(n, d)`` its designs in the unit box.
        count: most designs returned.
        tried: keys of the simplices filled before (updated in place).

    Returns:
        ``(k, d)`` designs, k <= count (fewer when fewer simplices are left untried or
        the triangulation fails, as for a degenerate front).
    """
    m = front_f.shape[1]
    spread = np.ptp(front_f, axis=0)
    scaled = (front_f - front_f.min(axis=0)) / np.where(spread > 0, spread, 1.0)
    basis = np.linalg.svd(np.ones((1, m)))[2][1:]  # (m-1, m): orthonormal, normal to (1, ..., 1)
    try:
        simplices = Delaunay(scaled @ basis.T).simplices  # (T, m)
    except QhullError:
        return np.zeros((0, front_z.shape[1]))
    edges = scaled[simplices[:, 1:]] - scaled[simplices[:, :1]]  # (T, m-1, m)
    volume = np.sqrt(np.maximum(np.linalg.det(np.einsum("tik,tjk->tij", edges, edges)), 0.0))
    chosen = []
    for index in np.argsort(-volume):
        if len(chosen) == count:
            break
        key = tuple(sorted(front_z[i].tobytes() for i in simplices[index]))
        if key not in tried:
            tried.add(key)
            chosen.append(index)
    return np.clip(front_z[simplices[np.asarray(chosen, dtype=np.int64)]].mean(axis=1), 0.0, 1.0)


# Unit-box lengths of the extrapolations past each end of a two-objective front.
END_LENGTHS = (1e-4, 1e-3, 1e-2, 1e-1)


def _end_designs(front_z: np.ndarray) -> np.ndarray:
    """Designs past both ends of a two-objective front, along its Pareto set's curve.

    ``front_z``: ``(n, d)`` the front's unit-box designs, sorted along the front.
    For each end and each length in `END_LENGTHS`, the design ``length`` beyond the end
    along the chord from the first front design at least ``length`` inward (the last
    one when none is that far). Returns ``(2 * len(END_LENGTHS), d)`` designs, clipped
    to the box, shortest length first, the two ends alternating.
    """
    rows = []
    for length in END_LENGTHS:
        for ordered in (front_z, front_z[::-1]):
            end = ordered[-1]
            far = np.flatnonzero(np.linalg.norm(ordered - end, axis=1) >= length)
            chord = end - (ordered[far[-1]] if far.size else ordered[0])
            norm = np.linalg.norm(chord)
            rows.append(end + (length / norm) * chord if norm > 0 else end)
    return np.clip(np.asarray(rows), 0.0, 1.0)


def _projected(gradient: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``gradient`` (ascent, unit box) with the components that would leave the box at ``z`` zeroed."""
    return np.where(((z <= 0.0) & (gradient < 0)) | ((z >= 1.0) & (gradient > 0)), 0.0, gradient)


def _common_combination(z: np.ndarray, jacobians: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two objectives: the min-norm convex combination of the projected, normalized gradients.

    ``z``: ``(k, d)`` unit-box designs; ``jacobians``: ``(k, d, 2)`` their dF_j/dz_k.
    Returns ``(direction, weight, scale)``: the ``(k, d)`` combination (both objectives
    rise along it; zero where the design is Pareto-critical: Fliege & Svaiter 2000;
    Desideri 2012), the ``(k,)`` weight of objective 0 in it, and the ``(k, 2)`` norms
    of the projected gradients it normalized by.
    """
    g = _projected(np.transpose(jacobians, (0, 2, 1)), z[:, None, :])  # (k, 2, d)
    scale = np.maximum(np.linalg.norm(g, axis=2), 1e-300)
    g = g / scale[:, :, None]
    between = g[:, 0] - g[:, 1]
    t = np.clip(np.sum(g[:, 0] * between, axis=1) / np.maximum(np.sum(between * between, axis=1), 1e-300), 0.0, 1.0)
    return g[:, 0] - t[:, None] * between, 1.0 - t, scale


def _common_ascent_designs(z: np.ndarray, jacobians: np.ndarray) -> np.ndarray:
    """Two objectives: designs along the direction that raises both, from each of ``z``.

    ``z``: ``(k, d)`` unit-box designs; ``jacobians``: ``(k, d, 2)`` their dF_j/dz_k.
    The direction is `_common_combination`; where its norm is at most
    `COMMON_ASCENT_LEAST` the gradients are (nearly) opposite and the design is
    Pareto-critical: no trial. Returns ``(k' * len(COMMON_ASCENT_LENGTHS), d)`` designs
    at those unit-box lengths along it, clipped to the box.
    """
    direction = _common_combination(z, jacobians)[0]
    length = np.linalg.norm(direction, axis=1)
    ascent = length > COMMON_ASCENT_LEAST
    lengths = np.asarray(COMMON_ASCENT_LENGTHS)[None, :, None]
    unit = direction[ascent] / length[ascent, None]
    return np.clip(z[ascent][:, None, :] + lengths * unit[:, None, :], 0.0, 1.0).reshape(-1, z.shape[1])


def _newton_probes(z: np.ndarray, jacobians: np.ndarray) -> dict:
    """Two objectives: the second-difference probes of the Pareto-Newton step (`_newton_designs`).

    ``z``: ``(k, d)`` unit-box designs; ``jacobians``: ``(k, d, 2)`` their dF_j/dz_k.
    A design is stepped when it is not Pareto-critical (its `_common_combination` longer
    than `COMMON_ASCENT_LEAST`). Its variables within `NEWTON_SNAP` of a bound where the
    combination q = w g_0 + (1 - w) g_1 of the normalized (unprojected) gradients points
    out of the box are held at that bound; the others are free. The probes are the
    designs ``z + h e_i`` for free i and ``z + h (e_i + e_j)`` for free i < j, when two or
    more are free (h = `NEWTON_HESSIAN_STEP`, inward past the middle of the box).

    Returns a dict: ``members`` ``(s,)`` the indices of the stepped designs into ``z``;
    ``free``, ``lower``, ``upper`` ``(s, d)`` bool; ``weight`` ``(s,)``; ``scale``
    ``(s, 2)`` (see `_common_combination`); ``h`` ``(s, d)``; ``probes``
    ``(s, d (d + 1) / 2, d)`` and ``taken`` ``(s, d (d + 1) / 2)``, the probes needed
    (both variables free), pairs in ``np.triu_indices(d)`` order.
    """
    d = z.shape[1]
    direction, weight, scale = _common_combination(z, jacobians)
    members = np.flatnonzero(np.linalg.norm(direction, axis=1) > COMMON_ASCENT_LEAST)
    z, jacobians, weight, scale = z[members], jacobians[members], weight[members], scale[members]
    q = np.einsum("skj,sj->sk", jacobians, np.stack([weight, 1.0 - weight], axis=1) / scale)  # (s, d)
    lower, upper = (z <= NEWTON_SNAP) & (q <= 0), (z >= 1.0 - NEWTON_SNAP) & (q >= 0)
    free = ~(lower | upper)
    # The weight and the scales again, of the free variables' gradients alone; where one
    # of them vanishes the design is critical there (that objective's optimum): no step.
    _, weight, scale = _common_combination(z, np.where(free[:, :, None], jacobians, 0.0))
    both = np.all(scale > 1e-300, axis=1)
    members, z, weight, scale, lower, upper, free = (a[both] for a in (members, z, weight, scale, lower, upper, free))
    h = np.where(z > 0.5, -NEWTON_HESSIAN_STEP, NEWTON_HESSIAN_STEP)
    first, second = np.triu_indices(d)
    unit = np.eye(d)
    probes = (
        z[:, None, :]
        + h[:, first, None] * unit[first]
        + np.where((first != second)[None, :, None], h[:, second, None] * unit[second], 0.0)
    )
    # One free variable: its gradients are opposite (or the design would not be stepped
    # without its held variables), so the step is zero: no probes.
    taken = free[:, first] & free[:, second] & (free.sum(axis=1) >= 2)[:, None]
    return dict(
        members=members,
        free=free,
        lower=lower,
        upper=upper,
        weight=weight,
        scale=scale,
        h=h,
        probes=probes,
        taken=taken,
    )


def _newton_designs(
    z: np.ndarray, f: np.ndarray, jacobians: np.ndarray, probes: dict, probe_values: np.ndarray
) -> np.ndarray:
    """Two objectives: each stepped design's Newton step onto the Pareto set.

    ``z``, ``f``, ``jacobians``: ``(s, d)``, ``(s, 2)``, ``(s, d, 2)`` the stepped designs
    (``probes["members"]`` of those `_newton_probes` took); ``probe_values``
    ``(s, d (d + 1) / 2, 2)`` the objectives at its probes (any value where not taken).
    On the free variables a Pareto-critical point solves q = w g_0 + (1 - w) g_1 = 0 for
    some weight w (normalized gradients; the Karush-Kuhn-Tucker system whose solutions
    Hillermeier's homotopy method follows, 2001). Linearized at the design, with the weight free
    too: ``H_w dz + (g_0 - g_1) dw = -q``, H_w the same combination of the Hessians (from
    the forward differences and the probes' second differences). Of its solutions the
    step takes the least ``|dz|`` (the system projected normal to g_0 - g_1, solved by
    pseudo-inverse), at most `NEWTON_LONGEST` long; the held variables go to their bound.
    With one free variable the design is critical already: only the bounds move it.
    Returns ``(s', d)`` the designs that differ from their start, clipped to the box.
    """
    s, d = z.shape
    if s == 0:
        return np.zeros((0, d))
    first, second = np.triu_indices(d)
    h, free, taken = probes["h"], probes["free"], probes["taken"]
    hi, hj = h[:, first, None], h[:, second, None]  # (s, P, 1)
    gi, gj = jacobians[:, first], jacobians[:, second]  # (s, P, 2)
    # Second differences along one variable (the probe z + h e_i), then across two (z + h e_i + h e_j).
    diagonal = 2.0 * (probe_values - f[:, None, :] - hi * gi) / hi**2  # (s, P, 2), valid where first == second
    pure = diagonal[:, first == second]  # (s, d, 2): d^2 F / dz_i^2
    across = (
        probe_values - f[:, None, :] - hi * gi - hj * gj - 0.5 * (hi**2 * pure[:, first] + hj**2 * pure[:, second])
    ) / (hi * hj)
    values = np.where(taken[:, :, None], np.where((first == second)[None, :, None], diagonal, across), 0.0)
    hessians = np.zeros((s, d, d, 2))
    hessians[:, first, second] = values
    hessians[:, second, first] = values
    combination = np.stack([probes["weight"], 1.0 - probes["weight"]], axis=1) / probes["scale"]  # (s, 2)
    mask = free[:, :, None] & free[:, None, :]
    hessian = np.where(mask, np.einsum("sklj,sj->skl", hessians, combination), 0.0)  # (s, d, d)
    q = np.where(free, np.einsum("skj,sj->sk", jacobians, combination), 0.0)
    between = np.where(
        free, (jacobians[:, :, 0] / probes["scale"][:, :1] - jacobians[:, :, 1] / probes["scale"][:, 1:]), 0.0
    )
    between /= np.maximum(np.linalg.norm(between, axis=1, keepdims=True), 1e-300)
    normal = np.where(mask, np.eye(d)[None] - between[:, :, None] * between[:, None, :], 0.0)  # (s, d, d)
    step = -np.einsum("skl,sl->sk", np.linalg.pinv(normal @ hessian, rcond=1e-10), np.einsum("skl,sl->sk", normal, q))
    step = np.where(free, step, 0.0)
    length = np.linalg.norm(step, axis=1, keepdims=True)
    step *= np.minimum(1.0, NEWTON_LONGEST / np.maximum(length, 1e-300))
    start = np.where(probes["lower"], 0.0, np.where(probes["upper"], 1.0, z))
    designs = np.clip(start + step, 0.0, 1.0)
    return designs[np.any(designs != z, axis=1)]


def _pull_program(problem):
    """The vmapped vector-Jacobian product: ``(z, w) -> J(z)^T w`` per design, unit box."""
    objective = problem.objective_function()
    lower = jnp.asarray(problem.lower)
    width = jnp.asarray(problem.upper - problem.lower)

    def pull(z, weight):
        # The design-space gradient of sum_j weight_j f_j, in unit-box coordinates.
        _, vjp = jax.vjp(lambda zz: objective(lower + width * zz), z)
        return vjp(weight)[0]

    return jax.jit(jax.vmap(pull))


@jax.jit
def _layer_gradients_jax(f, reference, ranks):
    return layer_hypervolume_gradients(f, reference, ranks)


def _layer_gradients(f: np.ndarray, reference: np.ndarray, ranks: np.ndarray) -> np.ndarray:
    """Each point's hypervolume gradient in its own layer: NumPy for 2 and 3 objectives
    (no compiled program), the autodiff of the exact hypervolume for 4."""
    if f.shape[1] <= 3:
        return layer_face_areas(f, reference, ranks)
    return np.array(_layer_gradients_jax(jnp.asarray(f), jnp.asarray(reference), jnp.asarray(ranks)))


@dataclasses.dataclass
class _Archive:
    """Every evaluated design in order, the front of them all, and the checkpoints.

    Values go through the problem's value program in batches of the compiled size
    (``batch``); the last batch is padded with copies, which count as evaluations but
    are not archived.
    """

    lower: np.ndarray
    width: np.ndarray
    evaluate: Any
    batch: int
    started: float
    designs: list = dataclasses.field(default_factory=list)
    unit_designs: list = dataclasses.field(default_factory=list)  # parallel to values: unit-box designs
    values: list = dataclasses.field(default_factory=list)
    spent: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(len(SOURCES)))  # by source
    value_evaluations: int = 0
    gradient_evaluations: int = 0
    checkpoints: list = dataclasses.field(default_factory=list)
    front_f: np.ndarray | None = None
    front_z: np.ndarray | None = None
    recorded: int = 0  # values[:recorded] are merged into the front

    @property
    def evaluations(self) -> int:
        return self.value_evaluations + self.gradient_evaluations

    def value_of(self, z: np.ndarray, source) -> np.ndarray:
        """``(k, m)`` values of ``(k, d)`` unit-box designs; ``source``: one of `SOURCES`'
        indices, or one per design."""
        rows = z.shape[0]
        padded = np.concatenate([z, np.repeat(z[-1:], -rows % self.batch, axis=0)]) if rows else z
        x = self.lower + self.width * padded
        f = np.concatenate(
            [np.asarray(self.evaluate(jnp.asarray(x[i : i + self.batch]))) for i in range(0, x.shape[0], self.batch)]
        )[:rows]
        self.unit_designs.append(z)
        np.add.at(self.spent, np.broadcast_to(np.asarray(source), (rows,)), 1)
        self.designs.append(x[:rows])
        self.values.append(f)
        self.value_evaluations += padded.shape[0]
        return f

    def record(self, population_f: np.ndarray, reference: np.ndarray) -> None:
        """Merge the values since the last record into the front; add a checkpoint."""
        merged = np.concatenate([self.front_f, *self.values[self.recorded :]])
        merged_z = np.concatenate([self.front_z, *self.unit_designs[self.recorded :]])
        self.recorded = len(self.values)
        keep = nondominated_mask(merged)
        self.front_f, self.front_z = merged[keep], merged_z[keep]
        self.checkpoints.append(
            dict(
                evaluations=self.evaluations,
                seconds=time.perf_counter() - self.started,
                hypervolume=hypervolume(self.front_f, reference),
                population_hypervolume=hypervolume(population_f, reference),
            )
        )


@dataclasses.dataclass
class _Members:
    """The population: unit-box designs ``z`` ``(n, d)``, values ``f`` ``(n, m)``, step
    lengths (``(n, d)`` per variable, else ``(n,)``), the last gradient signs ``(n, d)``
    (per variable), and each member's forward-difference Jacobian ``(n, d, m)``,
    ``known`` while it has not moved since."""

    z: np.ndarray
    f: np.ndarray
    steps: np.ndarray
    signs: np.ndarray
    jacobians: np.ndarray
    known: np.ndarray

    def joined(self, z: np.ndarray, f: np.ndarray, initial_step: float) -> _Members:
        """The members followed by new designs (fresh steps, no Jacobian)."""
        fresh = z.shape[0]
        return _Members(
            z=np.concatenate([self.z, z]),
            f=np.concatenate([self.f, f]),
            steps=np.concatenate([self.steps, np.full((fresh, *self.steps.shape[1:]), initial_step)]),
            signs=np.concatenate([self.signs, np.zeros((fresh, self.signs.shape[1]))]),
            jacobians=np.concatenate([self.jacobians, np.zeros((fresh, *self.jacobians.shape[1:]))]),
            known=np.concatenate([self.known, np.zeros(fresh, dtype=bool)]),
        )

    def taken(self, rows: np.ndarray) -> _Members:
        return _Members(*(getattr(self, field.name)[rows] for field in dataclasses.fields(self)))


@dataclasses.dataclass
class _Search:
    """The state of one hybrid run, changed by the generation's steps (`_GENERATION`)."""

    settings: HybridSettings
    d: int
    m: int
    stepping: int  # gradient steps per generation
    jacobian: str  # "reverse" or "differences"
    step_rule: str  # "per_variable" or "armijo"
    pulls: Any  # the vector-Jacobian program (reverse Jacobians)
    rng: np.random.Generator
    reference: np.ndarray
    reference_from: str
    archive: _Archive
    members: _Members
    # Two objectives, forward differences: (variable, lower/upper bound) where moving
    # inward lowered every objective at the last differences (`_skipped_differences`).
    blocked: np.ndarray
    bound_refresh: int
    skipped_differences: int = 0
    accepted: int = 0
    # Three or more objectives: the generation the search settled (`HybridSettings.settled_fill`),
    # the log ratios of the fill's archive gain per evaluation to the rest's, and the simplices filled.
    settled_at: int | None = None
    gain_ratios: list = dataclasses.field(default_factory=list)
    tried: set = dataclasses.field(default_factory=set)

    @property
    def population(self) -> int:
        return self.settings.population

    @property
    def per_variable(self) -> bool:
        return self.step_rule == "per_variable"

    @property
    def densifying(self) -> bool:
        """Whether this generation evaluates densified designs (a front of two or more)."""
        return self.settings.densify and self.archive.front_f.shape[0] >= 2

    def offspring(self, count: int) -> np.ndarray:
        """``count`` NSGA-II offspring of the current population."""
        batches = [
            _variation(self.rng, self.members.z, self.members.f, self.settings)
            for _ in range(-(-count // self.population))
        ]
        return np.concatenate(batches)[:count] if batches else np.zeros((0, self.d))

    def filled(self, count: int, least: int = 0) -> np.ndarray:
        """Offspring that fill a batch of ``count`` designs up to a multiple of the
        population, at least ``least`` of them."""
        return self.offspring(-(count + least) % self.population + least)

    def record(self) -> None:
        self.archive.record(self.members.f, self.reference)


@dataclasses.dataclass
class _Generation:
    """What the steps of one generation hand on to each other."""

    number: int
    new_z: list = dataclasses.field(default_factory=list)  # designs that join the union
    new_f: list = dataclasses.field(default_factory=list)
    count: int = 0  # members stepped
    chosen: np.ndarray | None = None  # (count,) their indices
    weights: np.ndarray | None = None  # (count, m) dHV/df of their layers
    z_from: np.ndarray | None = None  # (count, d)
    gradient: np.ndarray | None = None  # (count, d) projected J^T w
    norm: np.ndarray | None = None  # (count, 1)
    lengths: np.ndarray | None = None  # (count, d) the Rprop lengths (per variable)
    z_to: np.ndarray | None = None  # (count, d) the stepped designs
    f_to: np.ndarray | None = None
    on: np.ndarray | None = None  # front members with a current Jacobian (two objectives)
    trials: np.ndarray | None = None  # common-ascent designs
    probes: dict | None = None  # `_newton_probes`
    probed: np.ndarray | None = None  # the probes taken
    z_newton: np.ndarray | None = None  # Newton steps not yet evaluated


def _plan(problem, settings: HybridSettings) -> tuple[int, str, str]:
    """The gradient steps per generation, the Jacobian and the step rule a run takes.

    Closed-form objectives (no joint-box average) make values cheap: every member steps,
    by forward differences, along the normalized gradient. Joint-box averages over more
    than `DIFFERENCES_UP_TO` variables: half of them step, by vector-Jacobian products,
    each variable by its own length.
    """
    d, closed_forms = len(problem.variables), problem.closed_form
    share = settings.gradient_share if settings.gradient_share is not None else (1.0 if closed_forms else 0.5)
    stepping = min(settings.population, round(share * settings.population))
    jacobian = settings.jacobian
    if jacobian == "auto":
        jacobian = "differences" if d <= DIFFERENCES_UP_TO or closed_forms else "reverse"
    step_rule = settings.step_rule
    if step_rule == "auto":
        step_rule = "per_variable" if d > DIFFERENCES_UP_TO and not closed_forms else "armijo"
    return stepping, jacobian, step_rule


def _compile(problem, evaluate, population: int, stepping: int, jacobian: str) -> tuple[Any, dict]:
    """Compile every program once, for the population's shapes, before the timed run:
    the value program, the vector-Jacobian product of ``stepping`` designs (reverse
    Jacobians only) and, for four objectives, the layer hypervolume gradients. Returns
    the vector-Jacobian program (or None) and the compile seconds by program."""
    d, m = len(problem.variables), len(problem.objectives)
    compile_seconds = {}
    tic = time.perf_counter()
    jax.block_until_ready(evaluate(jnp.asarray(np.tile(problem.lower, (population, 1)))))
    compile_seconds["value"] = time.perf_counter() - tic
    pulls = None
    if jacobian == "reverse" and stepping > 0:
        pulls = _pull_program(problem)
        tic = time.perf_counter()
        jax.block_until_ready(pulls(jnp.asarray(np.full((stepping, d), 0.5)), jnp.asarray(np.ones((stepping, m)))))
        compile_seconds["gradient"] = time.perf_counter() - tic
    if m == 4:
        tic = time.perf_counter()
        dummy_ranks = jnp.asarray(np.zeros(population, dtype=np.int64))
        jax.block_until_ready(_layer_gradients_jax(jnp.ones((population, m)), jnp.zeros(m), dummy_ranks))
        compile_seconds["hypervolume"] = time.perf_counter() - tic
    return pulls, compile_seconds


def _start(
    problem, settings: HybridSettings, archive: _Archive, reference, per_variable: bool
) -> tuple[_Members, np.ndarray, str]:
    """1. The space-filling start: a Latin hypercube sample of two populations, of
    which NSGA-II's selection keeps one. Returns the members, the reference point and
    where it came from; the archive's front is the sample's."""
    d, m, population = len(problem.variables), len(problem.objectives), settings.population
    z_start = qmc.LatinHypercube(d, seed=settings.seed).random(2 * population)
    f_start = archive.value_of(z_start, _START)
    if reference is None:
        reference = reference_from_population(f_start, settings.reference_margin)
        reference_from = (
            f"nadir of the first {2 * population} designs' front minus {settings.reference_margin} of its range"
        )
    else:
        reference_from = "problem"
    keep = _survivors(f_start, population)
    members = _Members(
        z=z_start[keep],
        f=f_start[keep],
        steps=np.full((population, d) if per_variable else population, settings.initial_step),
        signs=np.zeros((population, d)),
        jacobians=np.zeros((population, d, m)),
        known=np.zeros(population, dtype=bool),
    )
    front = nondominated_mask(f_start)
    archive.front_f, archive.front_z = f_start[front], z_start[front]
    archive.recorded = len(archive.values)
    return members, np.asarray(reference, dtype=np.float64), reference_from


# The steps of a generation, run in this order by `hybrid_search` (each reads and
# changes the search and the generation).


def _choose_steppers(search: _Search, step: _Generation) -> None:
    """2a. The members that step (the front first, at random within a layer) and the
    hypervolume gradient of each one's layer."""
    members = search.members
    ranks = nondominated_ranks(members.f)
    step.count = 0 if search.settled_at is not None else search.stepping
    step.chosen = np.lexsort((search.rng.random(search.population), ranks))[: step.count]
    weights = _layer_gradients(members.f, search.reference, ranks)[step.chosen]
    weights = np.nan_to_num(weights, nan=0.0, posinf=0.0, neginf=0.0)
    flat = ~np.any(weights != 0, axis=1)
    if flat.any():
        # Below the reference or a duplicate: climb every objective, each by its spread.
        spread = np.ptp(members.f, axis=0)
        weights[flat] = 1.0 / np.where(spread > 0, spread, 1.0)
    step.weights = weights
    step.z_from = members.z[step.chosen]


def _design_gradients(search: _Search, step: _Generation) -> None:
    """2a. ``J^T w`` of each stepping member, projected onto the box."""
    if step.count == 0:
        gradient = np.zeros((0, search.d))
    elif search.jacobian == "reverse":
        gradient = np.asarray(search.pulls(jnp.asarray(step.z_from), jnp.asarray(step.weights)))
        search.archive.gradient_evaluations += step.count
    else:
        _difference_jacobians(search, step)
        gradient = np.einsum("skj,sj->sk", search.members.jacobians[step.chosen], step.weights)
    gradient = np.nan_to_num(gradient, nan=0.0, posinf=0.0, neginf=0.0)
    step.gradient = _projected(gradient, step.z_from)
    step.norm = np.linalg.norm(step.gradient, axis=1, keepdims=True)


def _difference_jacobians(search: _Search, step: _Generation) -> None:
    """Forward differences, inward at the upper bound, for the stepping members whose
    Jacobian is not current (the values are deterministic, so an unmoved member keeps
    its own), evaluated with offspring filling the batch (they join the union)."""
    members, d = search.members, search.d
    stale = step.chosen[~members.known[step.chosen]]
    z_stale, f_stale = members.z[stale], members.f[stale]
    h = np.where(z_stale > 0.5, -DIFFERENCE_STEP, DIFFERENCE_STEP)  # (stale, d)
    at_bound = np.stack([z_stale <= 0.0, z_stale >= 1.0], axis=-1)  # (stale, d, 2)
    skip = _skipped_differences(search, step.number, at_bound)
    take = ~skip
    rows = int(take.sum())
    shifted = z_stale[:, None, :] + h[:, :, None] * np.eye(d)[None]  # (stale, d, d)
    children = search.filled(rows)
    if rows + children.shape[0] == 0:
        return
    f_both = search.archive.value_of(
        np.concatenate([shifted[take], children]),
        np.repeat([_DIFFERENCES, _OFFSPRING], [rows, children.shape[0]]),
    )
    step.new_z.append(children)
    step.new_f.append(f_both[rows:])
    f_shifted = np.repeat(f_stale[:, None, :], d, axis=1)  # skipped: zero difference
    f_shifted[take] = f_both[:rows]
    members.jacobians[stale] = (f_shifted - f_stale[:, None, :]) / h[:, :, None]  # (stale, d, m): dF_j/dz_k
    members.known[stale] = True
    if search.bound_refresh:
        lowered = np.all(f_shifted <= f_stale[:, None, :], axis=-1) & take  # (stale, d)
        for side in range(2):
            seen = at_bound[..., side] & take
            counted = seen.any(axis=0)
            search.blocked[counted, side] = np.all(lowered | ~seen, axis=0)[counted]
        search.skipped_differences += int(skip.sum())


def _skipped_differences(search: _Search, generation: int, at_bound: np.ndarray) -> np.ndarray:
    """``(k, d)`` the differences not taken: a variable at a bound where, at the last
    differences, moving inward lowered every objective (for every member there) has no
    inward projected gradient for any weights; skipped (row zero) until the next refresh."""
    refresh = not search.bound_refresh or (generation - 1) % search.bound_refresh == 0
    if refresh:
        return np.zeros(at_bound.shape[:-1], dtype=bool)
    return np.any(at_bound & search.blocked[None], axis=-1)


def _gradient_steps(search: _Search, step: _Generation) -> None:
    """2a. The stepped designs: along the normalized gradient by each member's length
    (Armijo), or each variable by its own length in the sign of its gradient (Rprop:
    Riedmiller & Braun, ICNN 1993; longer while the sign holds, halved and no move when
    it flips, so weakly sensitive variables move as fast as strong ones)."""
    settings, members, chosen = search.settings, search.members, step.chosen
    if search.per_variable:
        sign = np.sign(step.gradient)
        agree = sign * members.signs[chosen]
        steps = members.steps[chosen]
        grown = np.where(agree > 0, 1.2 * steps, np.where(agree < 0, 0.5 * steps, steps))
        step.lengths = np.clip(grown, settings.min_step, settings.max_step)
        move = np.where(agree < 0, 0.0, sign * step.lengths)
        members.signs[chosen] = np.where(agree < 0, 0.0, sign)
    else:
        norm = step.norm
        direction = np.where(norm > 0, step.gradient / np.where(norm > 0, norm, 1.0), 0.0)
        move = members.steps[chosen][:, None] * direction
    step.z_to = np.clip(step.z_from + move, 0.0, 1.0)


def _pareto_probes(search: _Search, step: _Generation) -> None:
    """2b. Two objectives with forward differences: from each front member with a
    current Jacobian that is not Pareto-critical, the common-ascent trials (Fliege &
    Svaiter 2000; Desideri 2012) and the probes of a Pareto-Newton step, both evaluated
    in the steps' batch."""
    settings, members = search.settings, search.members
    step.trials = step.probed = step.z_newton = np.zeros((0, search.d))
    if search.jacobian == "reverse" or search.m != 2 or not (settings.common_ascent or settings.newton):
        return
    step.on = np.flatnonzero(members.known & nondominated_mask(members.f))
    if settings.common_ascent:
        step.trials = _common_ascent_designs(members.z[step.on], members.jacobians[step.on])
    if settings.newton:
        step.probes = _newton_probes(members.z[step.on], members.jacobians[step.on])
        step.probed = step.probes["probes"][step.probes["taken"]]


def _evaluate_steps(search: _Search, step: _Generation) -> None:
    """2c. The stepped designs, trials and probes in one batch that NSGA-II offspring
    fill (half a population at least); the Newton steps from the probes' values."""
    counts = [step.count, step.trials.shape[0], step.probed.shape[0]]
    children = search.filled(sum(counts), least=search.population // 2)
    f_all = search.archive.value_of(
        np.concatenate([step.z_to, step.trials, step.probed, children]),
        np.repeat([_STEPS, _ASCENT, _PROBES, _OFFSPRING], [*counts, children.shape[0]]),
    )
    step.f_to = f_all[: step.count]
    step.new_z.extend([step.trials, step.probed, children])
    step.new_f.append(f_all[step.count :])
    if step.probes is None or not step.probes["members"].size:
        return
    members, stepped = search.members, step.on[step.probes["members"]]
    probe_values = np.zeros((*step.probes["taken"].shape, search.m))
    probe_values[step.probes["taken"]] = f_all[counts[0] + counts[1] :][: counts[2]]
    step.z_newton = _newton_designs(
        members.z[stepped], members.f[stepped], members.jacobians[stepped], step.probes, probe_values
    )


def _evaluate_newton_alone(search: _Search, step: _Generation) -> None:
    """2b. The Newton steps, when no densified batch follows to carry them: offspring
    fill their batch."""
    if not step.z_newton.shape[0] or search.densifying:
        return
    children = search.filled(step.z_newton.shape[0])
    step.new_z.extend([step.z_newton, children])
    step.new_f.append(
        search.archive.value_of(
            np.concatenate([step.z_newton, children]),
            np.repeat([_NEWTON, _OFFSPRING], [step.z_newton.shape[0], children.shape[0]]),
        )
    )
    step.z_newton = np.zeros((0, search.d))


def _accept_steps(search: _Search, step: _Generation) -> None:
    """2a. Armijo's test on the layer hypervolume, linearized at the old point: a step's
    gain w . (f_new - f) must reach a tenth of what the gradient promised (per variable:
    for the move actually made). A passed step doubles the member's length (per
    variable: keeps the grown lengths), a refused one halves it."""
    settings, members, chosen = search.settings, search.members, step.chosen
    gain = np.sum(step.weights * (step.f_to - members.f[chosen]), axis=1)
    if search.per_variable:
        promised = np.sum(step.gradient * (step.z_to - step.z_from), axis=1)
    else:
        promised = members.steps[chosen] * step.norm[:, 0]
    better = (gain >= 0.1 * promised) & (promised > 0) & np.all(np.isfinite(step.f_to), axis=1)
    members.z[chosen] = np.where(better[:, None], step.z_to, step.z_from)
    members.f[chosen] = np.where(better[:, None], step.f_to, members.f[chosen])
    if search.per_variable:
        members.steps[chosen] = np.where(
            better[:, None], step.lengths, np.maximum(0.5 * step.lengths, settings.min_step)
        )
    else:
        lengths = np.where(better, 2.0 * members.steps[chosen], 0.5 * members.steps[chosen])
        members.steps[chosen] = np.clip(lengths, settings.min_step, settings.max_step)
    search.accepted += int(better.sum())
    members.known[chosen[better]] = False  # moved


def _densify_front(search: _Search, step: _Generation) -> None:
    """2d. Designs between neighbouring archive-front designs, where the gaps lose the
    most hypervolume: along the front's curve for two objectives, on chords to near
    neighbours for more, and, once settled, at the centroids of the largest simplices."""
    if not search.densifying:
        return
    if search.m == 2:
        _densify_curve(search, step)
    elif search.settled_at is None:
        _densify_chords(search, step)
    else:
        _fill_simplices(search)


def _densify_curve(search: _Search, step: _Generation) -> None:
    """Two objectives: the Newton steps first, then designs past the front's ends (a
    quarter of a population at most) and in its gaps, filling the batch to a multiple of
    the population (one population at least); all join the union."""
    archive, population, newton = search.archive, search.population, step.z_newton.shape[0]
    order = np.argsort(archive.front_f[:, 0])
    z_ends = _end_designs(archive.front_z[order])[: population // 4]
    dense = -(-(population + newton) // population) * population - newton
    z_gaps = _densify(archive.front_f[order], archive.front_z[order], dense - z_ends.shape[0])
    z_dense = np.concatenate([z_ends, np.clip(z_gaps, 0.0, 1.0)])
    z_dense = np.concatenate([z_dense, z_dense[-1:].repeat(dense - z_dense.shape[0], axis=0)])
    step.new_z.extend([step.z_newton, z_dense])
    step.new_f.append(
        archive.value_of(np.concatenate([step.z_newton, z_dense]), np.repeat([_NEWTON, _DENSIFIED], [newton, dense]))
    )


def _densify_chords(search: _Search, step: _Generation) -> None:
    """Three or more objectives: a population of chord designs for the archive only (in
    the population they would crowd out the members being refined), and whether the
    search has settled (`HybridSettings.settled_fill`)."""
    archive, settings = search.archive, search.settings
    fill_at = len(archive.values)
    f_fill = archive.value_of(
        _neighbour_designs(search.rng, archive.front_f, archive.front_z, search.population), _DENSIFIED
    )
    wait = settings.population_patience
    if not (settings.settled_fill and wait):
        return
    f_rest = np.concatenate(archive.values[archive.recorded : fill_at])
    search.gain_ratios.append(_fill_gain_ratio(archive, f_fill, f_rest, search.reference))
    ratios = search.gain_ratios
    if (
        len(ratios) >= wait
        and np.mean(ratios[-wait:]) > 0
        and _population_stalled(archive.checkpoints, wait, settings.tolerance)
    ):
        search.settled_at = step.number


def _fill_gain_ratio(archive: _Archive, f_fill: np.ndarray, f_rest: np.ndarray, reference: np.ndarray) -> float:
    """The log ratio of what each evaluation gained the archive this generation, the
    fill's designs against the rest (offspring, steps, differences), each set added alone
    to the front as it stood before the generation."""
    old = hypervolume(archive.front_f, reference)
    fill_gain = (hypervolume(np.concatenate([archive.front_f, f_fill]), reference) - old) / f_fill.shape[0]
    rest_gain = (hypervolume(np.concatenate([archive.front_f, f_rest]), reference) - old) / f_rest.shape[0]
    return np.log(np.clip(fill_gain / max(rest_gain, 1e-300), 1e-12, 1e12))


def _population_stalled(checkpoints: list, wait: int, tolerance: float) -> bool:
    """Whether the population's hypervolume rose no higher in the last ``wait``
    generations than ``tolerance`` (relative) above its best before them."""
    population_hv = [c["population_hypervolume"] for c in checkpoints]
    if len(population_hv) <= wait:
        return False
    best_before = max(population_hv[:-wait])
    return max(population_hv[-wait:]) <= best_before + tolerance * abs(best_before)


def _fill_simplices(search: _Search) -> None:
    """Settled: the population sits on the front; the archive grows by filling the
    front's largest gaps (chords make up any shortfall of simplices)."""
    archive, count = search.archive, search.settings.settled_fill * search.population
    front_f, front_z = archive.front_f, archive.front_z
    z_fill = (
        _simplex_designs(front_f, front_z, count, search.tried)
        if front_f.shape[0] > search.m
        else np.zeros((0, search.d))
    )
    if z_fill.shape[0] < count:
        z_fill = np.concatenate([z_fill, _neighbour_designs(search.rng, front_f, front_z, count - z_fill.shape[0])])
    archive.value_of(z_fill, _DENSIFIED)


def _select_survivors(search: _Search, step: _Generation) -> None:
    """NSGA-II's selection over the population and every design this generation added to it."""
    union = search.members.joined(np.concatenate(step.new_z), np.concatenate(step.new_f), search.settings.initial_step)
    keep = _survivors(np.where(np.isfinite(union.f), union.f, -np.inf), search.population)
    search.members = union.taken(keep)


_GENERATION = (
    _choose_steppers,
    _design_gradients,
    _gradient_steps,
    _pareto_probes,
    _evaluate_steps,
    _evaluate_newton_alone,
    _accept_steps,
    _densify_front,
    _select_survivors,
)


def _stop_reason(search: _Search) -> str | None:
    """3. Why the search stops after this generation (None: it goes on)."""
    settings, archive = search.settings, search.archive
    hv = [c["hypervolume"] for c in archive.checkpoints]
    if len(hv) > settings.patience and hv[-1] - hv[-1 - settings.patience] <= settings.tolerance * abs(hv[-1]):
        return f"converged: hypervolume gained < {settings.tolerance:g} in {settings.patience} generations"
    # Without densification the population is the front the search refines: once its own
    # hypervolume stops rising (what remains are crowding fluctuations) and the archive
    # barely gains, later generations only add designs near the same front.
    wait = settings.population_patience
    if (
        not settings.densify
        and wait
        and _population_stalled(archive.checkpoints, wait, settings.tolerance)
        and hv[-1] - hv[-1 - wait] <= settings.population_tolerance * abs(hv[-1])
    ):
        return (
            f"converged: the population's hypervolume rose no higher in {wait} generations, "
            f"the archive's by less than {settings.population_tolerance:g}"
        )
    if settings.max_evaluations is not None and archive.evaluations >= settings.max_evaluations:
        return "max_evaluations"
    if settings.max_seconds is not None and time.perf_counter() - archive.started >= settings.max_seconds:
        return "max_seconds"
    return None


def hybrid_search(
    problem, settings: HybridSettings | None = None, reference: Sequence[float] | None = None
) -> SearchResult:
    """The hybrid search (see the module docstring) on a design problem.

    Args:
        problem: a planar or spatial design problem (``objective_function``,
            ``batch_function``, ``lower``, ``upper``, ``objectives``).
        settings: `HybridSettings` (default: the defaults).
        reference: the hypervolume reference point; None takes the problem's, or, when
            the problem gives none, `reference_from_population` of the first population.

    Returns:
        A `SearchResult` (method ``"hybrid"``) with every value-evaluated design in
        order; ``extra`` holds the reference point used, the evaluation counts (also by
        source: `SOURCES`) and the compile seconds of each program.
    """
    settings = settings or HybridSettings()
    search, compile_seconds = _prepare(problem, settings, reference)
    generation, stop_reason = 0, None
    for generation in range(1, settings.generations + 1):
        step = _Generation(generation)
        for run_step in _GENERATION:
            run_step(search, step)
        search.record()
        stop_reason = _stop_reason(search)
        if stop_reason is not None:
            break
    return _result(search, compile_seconds, generation, stop_reason or "generations")


def _prepare(problem, settings: HybridSettings, reference) -> tuple[_Search, dict]:
    """Compile the programs, evaluate the start and record it: the search before its
    first generation, and the compile seconds by program."""
    if reference is None:
        reference = getattr(problem, "reference_point", None)
    d, m = len(problem.variables), len(problem.objectives)
    if m > 4:
        raise ConfigError(f"objectives: the hybrid search handles 2 to 4 objectives, got {m}; use --method scalarized")
    evaluate = problem.batch_function()
    rng = np.random.default_rng(settings.seed)
    stepping, jacobian, step_rule = _plan(problem, settings)
    pulls, compile_seconds = _compile(problem, evaluate, settings.population, stepping, jacobian)
    archive = _Archive(problem.lower, problem.upper - problem.lower, evaluate, settings.population, time.perf_counter())
    members, reference, reference_from = _start(problem, settings, archive, reference, step_rule == "per_variable")
    search = _Search(
        settings=settings,
        d=d,
        m=m,
        stepping=stepping,
        jacobian=jacobian,
        step_rule=step_rule,
        pulls=pulls,
        rng=rng,
        reference=reference,
        reference_from=reference_from,
        archive=archive,
        members=members,
        blocked=np.zeros((d, 2), dtype=bool),
        bound_refresh=settings.bound_refresh if m == 2 else 0,  # tried on two objectives only
    )
    search.record()
    return search, compile_seconds


def _result(search: _Search, compile_seconds: dict, generation: int, stop_reason: str) -> SearchResult:
    archive = search.archive
    return SearchResult(
        method="hybrid",
        designs=np.concatenate(archive.designs),
        objectives=np.concatenate(archive.values),
        checkpoints=archive.checkpoints,
        evaluations=archive.evaluations,
        compile_seconds=float(sum(compile_seconds.values())),
        run_seconds=time.perf_counter() - archive.started,
        extra=dict(
            reference_point=[float(r) for r in search.reference],
            reference_point_from=search.reference_from,
            population=search.population,
            generations=generation,
            stop_reason=stop_reason,
            jacobian=search.jacobian,
            step_rule=search.step_rule,
            gradient_steps_per_generation=search.stepping,
            value_evaluations=archive.value_evaluations,
            value_and_gradient_evaluations=archive.gradient_evaluations,
            accepted_gradient_steps=search.accepted,
            settled_at_generation=search.settled_at,
            evaluations_by_source={name: int(n) for name, n in zip(SOURCES, archive.spent, strict=True)},
            compile_seconds_by_program={k: float(v) for k, v in compile_seconds.items()},
            settings=dataclasses.asdict(search.settings),
            skipped_differences=search.skipped_differences,
        ),
    )
