"""The default design search: an evolutionary population refined by set-based
hypervolume-gradient steps on the whole front at once.

Pure gradient sets stall: dominated points have zero hypervolume gradient and single
runs settle on local Pareto sets. The methods that win are hybrids (HIGA-MO: Wang,
Deutz, Baeck & Emmerich, EMO 2017; Hypervolume Newton: Wang et al., MCA 28(1), 2023):

1. **Exploration.** A space-filling start (a Latin hypercube sample of the unit box, two
   populations' worth), then every generation an NSGA-II offspring batch (binary
   tournament on rank and crowding, simulated binary crossover, polynomial mutation;
   Deb et al., IEEE TEC 6(2), 2002) merged by non-dominated sorting and crowding.
2. **Refinement.** Every generation, a share of the population (``gradient_share``, the
   front first, at random within a layer) takes a step along the design-space gradient
   of the hypervolume of its own non-dominated layer: ``g_i = J_i^T dHV/df_i``
   (`spacearm.design.fronts.layer_face_areas`, the exact faces of the exclusive regions,
   in NumPy for 2 and 3 objectives; the autodiff of the exact hypervolume,
   `spacearm.design.hypervolume.layer_hypervolume_gradients`, for 4). ``J_i^T w`` comes
   from forward differences through the value program for up to 4 variables or
   closed-form objectives (d values, no other program to compile), else from one
   vmapped vector-Jacobian product; a member that has not moved since its last
   differences reuses their Jacobian (on pareto-6var 37 % of the differences had been
   such repeats); for two objectives, a variable at a bound where moving inward lowered
   both objectives at the last differences is not differenced (``bound_refresh``).
   Two objectives: every front member that is not Pareto-critical (its projected
   objective gradients not opposite) takes a Newton step onto the Pareto set
   (``newton``): on its free variables (those not held at a bound that the combination
   of the gradients pushes against) a critical point solves w g_0 + (1 - w) g_1 = 0 for
   a weight w; the step solves the linearization in the design and the weight, with
   Hessians from second differences (k (k + 1) / 2 values for k free variables), and
   takes the least step of its solutions. On pareto-6var, whose Pareto set in its steep
   end (w-bar above 0.161) is a curve in two free variables, 30 % of the archive front
   there had been dominated by a design 1e-6 away (NSGA-II's front after 17 s: 41 %);
   with the steps the search ends at 0.1577681358, 0.1577681337 and 0.1577681460
   (seeds 0-2) in 41,088-42,144 evaluations, against 0.1577680594, 0.1577680251 and
   0.1577680924 in 42,700-43,600 with the earlier trials along the direction raising
   both objectives (the min-norm convex combination of the normalized gradients:
   Fliege & Svaiter 2000, Desideri 2012; ``common_ascent``, now off by default).
   Dominated points follow their layer's gradient towards the front instead of
   freezing; on the front the hypervolume gradient itself spreads the points (a
   hypervolume-maximal set is spread by the front's slope). For joint-box averages over
   more than 4 variables (``step_rule: per_variable``) every member has a step length per
   variable in the unit box and moves each variable by its own step in the sign of its gradient (Rprop:
   Riedmiller & Braun, ICNN 1993): a step grows by 1.2 while its variable's gradient keeps
   its sign and halves (without a move) when the sign flips, so the weakly sensitive
   variables (a mount's position and angles beside link lengths and masses) converge as
   fast as the strong ones; the normalized gradient they replace moved them by a sliver of
   each step (pareto-ur5-arm: 99.68 % of the best known after 38 generations against
   99.2 %). A step that fails Armijo's sufficient-increase test on its layer's
   hypervolume (linearized at the old point) is refused and its lengths halved
   (``step_rule: armijo``, the default for fewer variables or closed-form objectives,
   where per-variable steps ended lower: one length per member along the normalized
   gradient, doubled after a passed test).
   Offspring fill the value batches of the stepped designs (and of the differences):
   with half of the population stepping (the default for joint-box averages; all of it
   for closed-form objectives, whose values are cheap), a generation of pareto-ur5-arm
   costs one batch of values and the vector-Jacobian products of half a batch, and
   reached a higher hypervolume per CPU second than a step for every member (two value
   batches and a full batch of products per generation) or for a quarter of them.
3. **Densification.** Every generation one more batch of designs interpolated between
   neighbouring archive-front designs (the Pareto set is a curve or a surface, and a chord
   between near optimal designs stays second-order close to it): along the front's curve
   where the gaps lose the most hypervolume for two objectives, 8 of them past the
   front's ends along its curve (`_end_designs`; these join the population: on
   pareto-6var the w-bar end lies on a curved ridge that the gradient steps crept up,
   and 2.2e-6 of the archive's 2.4e-6 relative shortfall after 100 generations lay
   there); for three or more, on chords from front designs drawn by the size of
   their gap to near neighbours (`_neighbour_designs`; archive only, as in the population
   they crowd the refined members out). The archive's hypervolume counts every evaluated
   design, and once the population sits on the front it grows by filling the front in.
   So, for three or more objectives, once the search has settled (the population's
   hypervolume rose no higher in ``population_patience`` generations, and over them the
   densified designs gained the archive more per evaluation than the steps, differences
   and offspring, in geometric mean) the steps stop, and each generation evaluates
   half a population of offspring and ``settled_fill`` populations at the centroids of
   the largest triangles of the archive front (`_simplex_designs`). On pareto-mount-ur5
   (its Pareto set a patch of the face pitch = 0.8 rad) this settled after 14
   generations (31 with seed 1) and left a third of the shortfall after 19,000
   evaluations (2.2e-5 against 7.2e-5 of the best known; seed 1: 2.0e-5 against 6.5e-5);
   on pareto-ur5-arm, whose population keeps refining weak variables, the fill gained
   0.25-0.57 of the rest per evaluation (5-generation geometric means) and the search
   never switched in 100 generations.
4. **Stopping** from the front's own convergence: the archive's hypervolume gained less
   than ``tolerance`` (relative) over the last ``patience`` generations; or, without
   densification, the population's own hypervolume rose no higher in the last
   ``population_patience`` generations while the archive's gained less than
   ``population_tolerance``; or a budget of generations, evaluations or seconds ran out.
   (The population rule stopped three-objective runs while their archive still gained
   fast: pareto-ur5-arm after 38 generations at 99.68 % of the best known, where 100
   reach 99.94 %.)

Every design is evaluated by the problem's own ``batch_function()`` in batches of the
population (compiled once; the differences and the offspring are archived, being designs
evaluated like any other) and, for more than 4 variables and joint-box averages, a
vmapped VJP of ``objective_function()`` (compiled once for the stepping share); the
hypervolume gradients of 4 objectives compile one more program; compile seconds are
reported apart and counted in every comparison.
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
        population_patience: without densification (``densify: false``), also stop when the population's own hypervolume has not
            risen above its best by more than ``tolerance`` (relative) for this many
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
            (pareto-6var's Pareto set lies on a face of the box: 4 or 5 of its 6
            variables at a bound; this saved 11,000 of 26,000 differences.)
        common_ascent: two objectives, forward differences: each generation, from every
            front member whose Jacobian is current and whose projected objective
            gradients are not opposite (so it is not Pareto-critical), designs at
            `COMMON_ASCENT_LENGTHS` along the direction that raises both objectives (the
            min-norm convex combination of the normalized gradients), evaluated in the
            steps' batch; they join the union. Off by default: beside the Newton steps
            they cost pareto-6var 13,000 more evaluations (55,000 against 42,000) for
            5e-9 to 1.2e-8 more hypervolume.
        newton: two objectives, forward differences: each generation the same members
            (front, current Jacobian, not Pareto-critical) take a Newton step onto the
            Pareto set (`_newton_probes`, `_newton_designs`): second differences on their
            free variables (k (k + 1) / 2 values for k free, none for one), evaluated in
            the steps' batch, then the step, evaluated with the densified designs; both
            join the union.
        step_rule: ``"per_variable"`` (a step length per variable, Rprop),
            ``"armijo"`` (one length per member along the normalized gradient) or
            ``"auto"`` (per variable for joint-box averages over more than 4 variables,
            where weak and strong variables mix; Armijo otherwise: on pareto-attachment,
            pareto-6var and pareto-mount-ur5 per-variable steps ended lower).
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
# joint-box averages costs about 4 (measured on pareto-mount-ur5) and compiles a program
# about 2.5 times as long as the values'.
DIFFERENCES_UP_TO = 4
# Above DIFFERENCES_UP_TO variables, differences still win when every objective is a
# closed form (no joint-box average): the product's compile then buys more values than
# the differences spend in a run (pareto-6var: compile 1.6 s instead of 17.5 s).
# Forward-difference step in the unit box (the objectives are smooth float64 averages on a
# fixed rule: truncation ~1e-6 relative, rounding ~1e-10).
DIFFERENCE_STEP = 1e-6
# Common-ascent trials (two objectives): unit-box lengths along the direction that raises
# both objectives, tried from each front member with a current Jacobian whose projected,
# normalized objective gradients are not opposite (the norm of their min-norm convex
# combination above COMMON_ASCENT_LEAST). On pareto-6var other ladders, (1e-5, 1e-4, 1e-3),
# (3e-5, 3e-4, 3e-3), (1e-4, 1e-3), (3e-4, 3e-3), ended within one seed's noise of it.
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
    pareto-mount-ur5) the centroid of three designs on it lies on it exactly. On
    pareto-mount-ur5, switched by `HybridSettings.settled_fill` at the same generation,
    this fill ended 3.5e-5 (relative) short of the best known hypervolume after 19,296
    evaluations, the same budget of random chords 17.5e-5 (docs/explanation/pareto.md).

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
    if reference is None:
        reference = getattr(problem, "reference_point", None)
    d, m = len(problem.variables), len(problem.objectives)
    if m > 4:
        raise ConfigError(f"objectives: the hybrid search handles 2 to 4 objectives, got {m}; use --method scalarized")
    population = settings.population
    lower, width = problem.lower, problem.upper - problem.lower
    evaluate = problem.batch_function()
    rng = np.random.default_rng(settings.seed)
    jacobian = settings.jacobian
    # Closed-form objectives (no joint-box average) make values cheap: a batch costs
    # 0.1-0.2 % of the value program's compile, against 3-4 % for the averages.
    # The radius (a search per value) is no closed form either.
    closed_forms = problem.closed_form
    share = settings.gradient_share if settings.gradient_share is not None else (1.0 if closed_forms else 0.5)
    stepping = min(population, round(share * population))
    densifying = settings.densify

    # Compile every program once, for the population's shapes, before the timed run:
    # the value program (every evaluation goes through it in batches of the population),
    # the vector-Jacobian product of `stepping` designs (reverse Jacobians only) and, for
    # four objectives, the layer hypervolume gradients.
    compile_seconds = {}
    tic = time.perf_counter()
    jax.block_until_ready(evaluate(jnp.asarray(np.tile(problem.lower, (population, 1)))))
    compile_seconds["value"] = time.perf_counter() - tic
    if jacobian == "auto":
        jacobian = "differences" if d <= DIFFERENCES_UP_TO or closed_forms else "reverse"
    pulls = None
    if jacobian == "reverse" and stepping > 0:
        pulls = _pull_program(problem)
        tic = time.perf_counter()
        jax.block_until_ready(pulls(jnp.asarray(np.full((stepping, d), 0.5)), jnp.asarray(np.ones((stepping, m)))))
        compile_seconds["gradient"] = time.perf_counter() - tic
    if m == 4:
        tic = time.perf_counter()
        dummy_k = jnp.asarray(np.zeros(population, dtype=np.int64))
        jax.block_until_ready(_layer_gradients_jax(jnp.ones((population, m)), jnp.zeros(m), dummy_k))
        compile_seconds["hypervolume"] = time.perf_counter() - tic

    start = time.perf_counter()
    designs, values, checkpoints = [], [], []
    unit_designs = []  # parallel to values: the unit-box designs
    counts = dict(value=0, value_and_gradient=0)
    spent = np.zeros(len(SOURCES))  # evaluations each source took

    def value_of(z, source):
        """Values of any number of unit-box designs, in batches of the compiled size (the
        last one padded with copies, which are not archived)."""
        rows = z.shape[0]
        padded = np.concatenate([z, np.repeat(z[-1:], -rows % population, axis=0)]) if rows else z
        x = lower + width * padded
        f = np.concatenate(
            [np.asarray(evaluate(jnp.asarray(x[i : i + population]))) for i in range(0, x.shape[0], population)]
        )[:rows]
        unit_designs.append(z)
        np.add.at(spent, np.broadcast_to(np.asarray(source), (rows,)), 1)
        designs.append(x[:rows])
        values.append(f)
        counts["value"] += padded.shape[0]
        return f

    # 1. Space-filling start: two populations of a Latin hypercube sample.
    start_designs = qmc.LatinHypercube(d, seed=settings.seed).random(2 * population)
    f_start = value_of(start_designs, _START)
    if reference is None:
        reference = reference_from_population(f_start, settings.reference_margin)
        reference_from = (
            f"nadir of the first {2 * population} designs' front minus {settings.reference_margin} of its range"
        )
    else:
        reference_from = "problem"
    reference = np.asarray(reference, dtype=np.float64)
    keep = _survivors(f_start, population)
    z, f = start_designs[keep], f_start[keep]
    step_rule = settings.step_rule
    if step_rule == "auto":
        step_rule = "per_variable" if d > DIFFERENCES_UP_TO and not closed_forms else "armijo"
    per_variable = step_rule == "per_variable"
    steps = np.full((population, d) if per_variable else population, settings.initial_step)
    signs = np.zeros((population, d))  # the last gradient's sign per variable (per_variable)
    # Forward differences: each member's Jacobian dF_j/dz_k, kept while it does not move.
    jacobians, jacobian_known = np.zeros((population, d, m)), np.zeros(population, dtype=bool)
    blocked = np.zeros((d, 2), dtype=bool)  # (variable, lower/upper bound): inward lowers every objective
    skipped_differences = 0
    bound_refresh = settings.bound_refresh if m == 2 else 0  # measured on two objectives only
    # Three or more objectives: once settled (see `HybridSettings.settled_fill`), the
    # steps stop and the fill takes the evaluations; the log ratios of the fill's archive
    # gain per evaluation to the rest's decide when.
    settled_at, gain_ratios, tried = None, [], set()
    first_front = nondominated_mask(f_start)
    front_f, front_z = f_start[first_front], start_designs[first_front]

    recorded = [len(values)]

    def record():
        nonlocal front_f, front_z
        merged = np.concatenate([front_f, *values[recorded[0] :]])
        merged_z = np.concatenate([front_z, *unit_designs[recorded[0] :]])
        recorded[0] = len(values)
        keep = nondominated_mask(merged)
        front_f, front_z = merged[keep], merged_z[keep]
        checkpoints.append(
            dict(
                evaluations=counts["value"] + counts["value_and_gradient"],
                seconds=time.perf_counter() - start,
                hypervolume=hypervolume(front_f, reference),
                population_hypervolume=hypervolume(f, reference),
            )
        )

    def offspring(count):
        """``count`` NSGA-II offspring of the current population."""
        batches = [_variation(rng, z, f, settings) for _ in range(-(-count // population))]
        return np.concatenate(batches)[:count] if batches else np.zeros((0, d))

    def filled(count, least=0):
        """Offspring that fill a batch of ``count`` designs up to a multiple of the
        population, at least ``least`` of them."""
        return offspring(-(count + least) % population + least)

    record()
    accepted_total, generation = 0, 0
    stop_reason = "generations"
    for generation in range(1, settings.generations + 1):
        new_z, new_f = [], []
        ranks = nondominated_ranks(f)
        stepping_now = 0 if settled_at is not None else stepping
        # 2a. Refinement: a hypervolume-gradient step for `stepping` members (the front
        # first, at random within a layer), each along its own layer's gradient.
        chosen = np.lexsort((rng.random(population), ranks))[:stepping_now]
        weights = np.nan_to_num(_layer_gradients(f, reference, ranks)[chosen], nan=0.0, posinf=0.0, neginf=0.0)
        flat = ~np.any(weights != 0, axis=1)
        if flat.any():
            # Below the reference or a duplicate: climb every objective, each by its spread.
            spread = np.ptp(f, axis=0)
            weights[flat] = 1.0 / np.where(spread > 0, spread, 1.0)
        z_step = z[chosen]
        if stepping_now == 0:
            grad = np.zeros((0, d))
        elif jacobian == "reverse":
            grad = np.asarray(pulls(jnp.asarray(z_step), jnp.asarray(weights)))
            counts["value_and_gradient"] += stepping_now
        else:
            # Forward differences, inward at the upper bound, evaluated with offspring
            # filling the batch (they join the union below). A member that has not moved
            # since its last differences reuses their Jacobian (the values are
            # deterministic): on pareto-6var 37 % of the differences were such repeats.
            need = ~jacobian_known[chosen]
            z_need = z_step[need]
            h = np.where(z_need > 0.5, -DIFFERENCE_STEP, DIFFERENCE_STEP)  # (needed, d), inward at a bound
            # A variable at a bound where, at the last differences, moving inward lowered
            # every objective (for every member there) has no inward projected gradient
            # for any weights: its difference is skipped (row zero) until the next refresh.
            at_bound = np.stack([z_need <= 0.0, z_need >= 1.0], axis=-1)  # (needed, d, 2)
            refresh = not bound_refresh or (generation - 1) % bound_refresh == 0
            skip = np.zeros(z_need.shape, dtype=bool) if refresh else np.any(at_bound & blocked[None], axis=-1)
            take = ~skip  # (needed, d)
            rows = int(take.sum())
            shifted = z_need[:, None, :] + h[:, :, None] * np.eye(d)[None]  # (needed, d, d)
            children = filled(rows)
            if rows + children.shape[0]:
                f_both = value_of(
                    np.concatenate([shifted[take], children]),
                    np.repeat([_DIFFERENCES, _OFFSPRING], [rows, children.shape[0]]),
                )
                new_z.append(children)
                new_f.append(f_both[rows:])
                f_shifted = np.repeat(f[chosen[need]][:, None, :], d, axis=1)  # skipped: zero difference
                f_shifted[take] = f_both[:rows]
                # (needed, d, m): dF_j/dz_k
                jacobians[chosen[need]] = (f_shifted - f[chosen[need]][:, None, :]) / h[:, :, None]
                jacobian_known[chosen[need]] = True
                if bound_refresh:
                    lowered = np.all(f_shifted <= f[chosen[need]][:, None, :], axis=-1) & take  # (needed, d)
                    for side in range(2):
                        seen = at_bound[..., side] & take
                        counted = seen.any(axis=0)
                        blocked[counted, side] = np.all(lowered | ~seen, axis=0)[counted]
                    skipped_differences += int(skip.sum())
            jac = jacobians[chosen]
            grad = np.einsum("skj,sj->sk", jac, weights)
        grad = np.nan_to_num(grad, nan=0.0, posinf=0.0, neginf=0.0)
        grad = _projected(grad, z_step)
        norm = np.linalg.norm(grad, axis=1, keepdims=True)
        if per_variable:
            # Each variable its own step (Rprop: Riedmiller & Braun, ICNN 1993): longer while
            # its gradient keeps its sign, halved (and no move this time) when it flips, so
            # weakly sensitive variables move as fast as strong ones.
            sign = np.sign(grad)
            agree = sign * signs[chosen]
            step_c = np.clip(
                np.where(agree > 0, 1.2 * steps[chosen], np.where(agree < 0, 0.5 * steps[chosen], steps[chosen])),
                settings.min_step,
                settings.max_step,
            )
            move = np.where(agree < 0, 0.0, sign * step_c)
            signs[chosen] = np.where(agree < 0, 0.0, sign)
        else:
            direction = np.where(norm > 0, grad / np.where(norm > 0, norm, 1.0), 0.0)
            move = steps[chosen][:, None] * direction
        z_stepped = np.clip(z_step + move, 0.0, 1.0)
        trials = probed = z_newton = np.zeros((0, d))
        newton = None
        # Two objectives with forward differences only (three or more, or reverse
        # Jacobians, take neither 2b nor 2b').
        if jacobian != "reverse" and m == 2 and (settings.common_ascent or settings.newton):
            on = np.flatnonzero(jacobian_known & nondominated_mask(f))
            if settings.common_ascent:
                # 2b. Common ascent (Fliege & Svaiter 2000; Desideri 2012): an unmoved front
                # member whose projected objective gradients are not opposite is not
                # Pareto-critical; along the min-norm convex combination of the normalized
                # gradients both objectives rise. Its Jacobian is the one its differences
                # gave, so each trial costs one value (in the steps' batch); the trials join
                # the union.
                trials = _common_ascent_designs(z[on], jacobians[on])
            if settings.newton:
                # 2b'. Pareto-Newton: the same members' second differences on their free
                # variables (in the steps' batch), then a Newton step onto the Pareto set
                # (evaluated with the densified designs, 2d); probes and steps join the union.
                newton = _newton_probes(z[on], jacobians[on])
                probed = newton["probes"][newton["taken"]]
        # 2c. Exploration: NSGA-II offspring fill the batch of the stepped designs, trials and probes.
        tried_count, probed_count = trials.shape[0], probed.shape[0]
        children = filled(stepping_now + tried_count + probed_count, least=population // 2)
        f_both = value_of(
            np.concatenate([z_stepped, trials, probed, children]),
            np.repeat(
                [_STEPS, _ASCENT, _PROBES, _OFFSPRING], [stepping_now, tried_count, probed_count, children.shape[0]]
            ),
        )
        f_stepped = f_both[:stepping_now]
        new_z.extend([trials, probed, children])
        new_f.append(f_both[stepping_now:])
        if newton is not None and newton["members"].size:
            members = on[newton["members"]]
            probe_values = np.zeros((*newton["taken"].shape, m))
            probe_values[newton["taken"]] = f_both[stepping_now + tried_count :][:probed_count]
            z_newton = _newton_designs(z[members], f[members], jacobians[members], newton, probe_values)
        if z_newton.shape[0] and not (densifying and front_f.shape[0] >= 2):
            # No densified batch to join: offspring fill the Newton steps' batch.
            children = filled(z_newton.shape[0])
            new_z.extend([z_newton, children])
            new_f.append(
                value_of(
                    np.concatenate([z_newton, children]),
                    np.repeat([_NEWTON, _OFFSPRING], [z_newton.shape[0], children.shape[0]]),
                )
            )
            z_newton = np.zeros((0, d))
        # Armijo's test on the layer hypervolume, linearized at the old point: the step's
        # gain w . (f_new - f) must reach a tenth of what the gradient promised (step |g|).
        gain = np.sum(weights * (f_stepped - f[chosen]), axis=1)
        # (per variable: what the gradient promised for the move actually made)
        promised = np.sum(grad * (z_stepped - z_step), axis=1) if per_variable else steps[chosen] * norm[:, 0]
        better = (gain >= 0.1 * promised) & (promised > 0) & np.all(np.isfinite(f_stepped), axis=1)
        z[chosen] = np.where(better[:, None], z_stepped, z_step)
        f[chosen] = np.where(better[:, None], f_stepped, f[chosen])
        if per_variable:
            steps[chosen] = np.where(better[:, None], step_c, np.maximum(0.5 * step_c, settings.min_step))
        else:
            steps[chosen] = np.clip(
                np.where(better, 2.0 * steps[chosen], 0.5 * steps[chosen]), settings.min_step, settings.max_step
            )
        accepted_total += int(better.sum())
        jacobian_known[chosen[better]] = False  # moved
        if densifying and front_f.shape[0] >= 2:
            # 2d. Designs interpolated between neighbouring archive-front designs, where the
            # gaps lose the most hypervolume: along the front's curve for two objectives,
            # on chords to near neighbours for more.
            if m == 2:
                order = np.argsort(front_f[:, 0])
                # A quarter of them at most past the front's ends, the rest in its gaps.
                z_ends = _end_designs(front_z[order])[: population // 4]
                # The Newton steps (2b') go first; densified designs fill the batch to a
                # multiple of the population, at least one population of them.
                dense = -(-(population + z_newton.shape[0]) // population) * population - z_newton.shape[0]
                z_dense = np.clip(_densify(front_f[order], front_z[order], dense - z_ends.shape[0]), 0.0, 1.0)
                z_dense = np.concatenate([z_ends, z_dense])
                z_dense = np.concatenate([z_dense, z_dense[-1:].repeat(dense - z_dense.shape[0], axis=0)])
                new_z.extend([z_newton, z_dense])
                new_f.append(
                    value_of(
                        np.concatenate([z_newton, z_dense]),
                        np.repeat([_NEWTON, _DENSIFIED], [z_newton.shape[0], dense]),
                    )
                )
            elif settled_at is None:
                # Archive only: in the population these near-front designs would crowd
                # the members being refined out (pareto-ur5-arm ended lower with them).
                fill_at = len(values)
                f_fill = value_of(_neighbour_designs(rng, front_f, front_z, population), _DENSIFIED)
                wait = settings.population_patience
                if settings.settled_fill and wait:
                    # What each evaluation gained the archive this generation: the fill's
                    # designs against the rest (offspring, steps, differences), each
                    # added alone to the front as it stood before the generation.
                    f_rest = np.concatenate(values[recorded[0] : fill_at])
                    old = hypervolume(front_f, reference)
                    fill_gain = (hypervolume(np.concatenate([front_f, f_fill]), reference) - old) / f_fill.shape[0]
                    rest_gain = (hypervolume(np.concatenate([front_f, f_rest]), reference) - old) / f_rest.shape[0]
                    gain_ratios.append(np.log(np.clip(fill_gain / max(rest_gain, 1e-300), 1e-12, 1e12)))
                    population_hv = [c["population_hypervolume"] for c in checkpoints]
                    if len(gain_ratios) >= wait and len(population_hv) > wait and np.mean(gain_ratios[-wait:]) > 0:
                        best_before = max(population_hv[:-wait])
                        if max(population_hv[-wait:]) <= best_before + settings.tolerance * abs(best_before):
                            settled_at = generation
            else:
                # Settled: the population sits on the front; the archive grows by filling
                # the front's largest gaps (chords make up any shortfall of simplices).
                count = settings.settled_fill * population
                z_fill = _simplex_designs(front_f, front_z, count, tried) if front_f.shape[0] > m else np.zeros((0, d))
                if z_fill.shape[0] < count:
                    z_fill = np.concatenate(
                        [z_fill, _neighbour_designs(rng, front_f, front_z, count - z_fill.shape[0])]
                    )
                value_of(z_fill, _DENSIFIED)
        z_all, f_all = np.concatenate([z, *new_z]), np.concatenate([f, *new_f])
        fresh = z_all.shape[0] - population
        steps_all = np.concatenate([steps, np.full((fresh, *steps.shape[1:]), settings.initial_step)])
        signs_all = np.concatenate([signs, np.zeros((fresh, d))])
        jacobians_all = np.concatenate([jacobians, np.zeros((fresh, d, m))])
        known_all = np.concatenate([jacobian_known, np.zeros(fresh, dtype=bool)])
        keep = _survivors(np.where(np.isfinite(f_all), f_all, -np.inf), population)
        z, f, steps, signs = z_all[keep], f_all[keep], steps_all[keep], signs_all[keep]
        jacobians, jacobian_known = jacobians_all[keep], known_all[keep]
        record()
        # 3. Stopping from the front's own convergence, or a budget.
        hv = [c["hypervolume"] for c in checkpoints]
        if len(hv) > settings.patience and hv[-1] - hv[-1 - settings.patience] <= settings.tolerance * abs(hv[-1]):
            stop_reason = f"converged: hypervolume gained < {settings.tolerance:g} in {settings.patience} generations"
            break
        # Without densification the population is the front the search refines: once its
        # own hypervolume stops rising (a set near the hypervolume-optimal distribution of
        # its size; what remains are crowding fluctuations) and the archive barely gains,
        # later generations only add designs near the same front. (The population alone
        # settles early on pareto-ur5-arm, at 98.9 % of the best known, while its archive
        # still gained 6e-3 in 5 generations; on pareto-mount-ur5, 5e-4.)
        population_hv = [c["population_hypervolume"] for c in checkpoints]
        wait = settings.population_patience
        if not densifying and wait and len(population_hv) > wait:
            best_before = max(population_hv[:-wait])
            settled = max(population_hv[-wait:]) <= best_before + settings.tolerance * abs(best_before)
            if settled and hv[-1] - hv[-1 - wait] <= settings.population_tolerance * abs(hv[-1]):
                stop_reason = (
                    f"converged: the population's hypervolume rose no higher in {wait} generations, "
                    f"the archive's by less than {settings.population_tolerance:g}"
                )
                break
        evaluations = counts["value"] + counts["value_and_gradient"]
        if settings.max_evaluations is not None and evaluations >= settings.max_evaluations:
            stop_reason = "max_evaluations"
            break
        if settings.max_seconds is not None and time.perf_counter() - start >= settings.max_seconds:
            stop_reason = "max_seconds"
            break
    run_seconds = time.perf_counter() - start
    return SearchResult(
        method="hybrid",
        designs=np.concatenate(designs),
        objectives=np.concatenate(values),
        checkpoints=checkpoints,
        evaluations=counts["value"] + counts["value_and_gradient"],
        compile_seconds=float(sum(compile_seconds.values())),
        run_seconds=run_seconds,
        extra=dict(
            reference_point=[float(r) for r in reference],
            reference_point_from=reference_from,
            population=population,
            generations=generation,
            stop_reason=stop_reason,
            jacobian=jacobian,
            step_rule=step_rule,
            gradient_steps_per_generation=stepping,
            value_evaluations=counts["value"],
            value_and_gradient_evaluations=counts["value_and_gradient"],
            accepted_gradient_steps=accepted_total,
            settled_at_generation=settled_at,
            evaluations_by_source={name: int(n) for name, n in zip(SOURCES, spent, strict=True)},
            compile_seconds_by_program={k: float(v) for k, v in compile_seconds.items()},
            settings=dataclasses.asdict(settings),
            skipped_differences=skipped_differences,
        ),
    )
