"""The default design search: an evolutionary population refined by set-based
hypervolume-gradient steps on the whole front at once.

Pure gradient sets stall: dominated points have zero hypervolume gradient and single
runs settle on local Pareto sets. The methods that win are hybrids (HIGA-MO: Wang,
Deutz, Baeck & Emmerich, EMO 2017; Hypervolume Newton: Wang et al., MCA 28(1), 2023):

1. **Exploration.** A space-filling start (a Latin hypercube sample of the unit box, two
   populations' worth), then every generation an NSGA-II offspring batch (binary
   tournament on rank and crowding, simulated binary crossover, polynomial mutation;
   Deb et al., IEEE TEC 6(2), 2002) merged by non-dominated sorting and crowding.
2. **Refinement.** Every generation, each member of the population takes a step along
   the design-space gradient of the hypervolume of its own non-dominated layer:
   ``g_i = J_i^T dHV/df_i`` (`spacearm.design.hypervolume.layer_hypervolume_gradients`,
   the exact sort-based hypervolume by autodiff, one vector-Jacobian product per design,
   vmapped). Dominated points follow their layer's gradient towards the front instead of
   freezing; on the front the hypervolume gradient itself spreads the points (a
   hypervolume-maximal set is spread by the front's slope). Each step has its own
   length in the unit box, doubled after a step that passed Armijo's sufficient-increase
   test on its layer's hypervolume (linearized at the old point) and halved after one that
   did not (the step is then refused), so steps shrink to the precision the front needs.
3. **Stopping** from the front's own convergence: the archive's hypervolume gained less
   than ``tolerance`` (relative) over the last ``patience`` generations, or a budget of
   generations, evaluations or seconds ran out.

Every design is evaluated by the problem's own ``batch_function()`` (values) or a vmapped
VJP of ``objective_function()`` (gradient steps; their values are not archived, the
designs being archived already), each compiled once for the population's shape before
the timed run; compile seconds are reported apart and counted in every comparison.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping, Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from scipy.stats import qmc

from .._core.errors import ConfigError
from .._core.schema import check_keys, integer, number
from .fronts import hypervolume, nondominated_mask, reference_from_population
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
        initial_step, min_step, max_step: gradient step lengths in the unit box.
        reference_margin: the reference point, when the problem gives none, lies this
            share of the first population's front range below its nadir.
        densify: with two objectives, also evaluate a population of designs interpolated
            between neighbouring archive-front designs every generation.
        crossover_eta, mutation_eta: distribution indices of SBX and polynomial mutation.
        seed: random seed (Latin hypercube, variation).
    """

    population: int = 48
    generations: int = 100
    max_evaluations: int | None = None
    max_seconds: float | None = None
    patience: int = 10
    tolerance: float = 1e-9
    initial_step: float = 0.05
    min_step: float = 1e-5
    max_step: float = 0.3
    reference_margin: float = 0.1
    densify: bool = True
    crossover_eta: float = 15.0
    mutation_eta: float = 20.0
    seed: int = 0


_INTEGER_KEYS = {"population": 4, "generations": 1, "max_evaluations": 1, "patience": 1, "seed": 0}


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
        if value is None and key in ("max_evaluations", "max_seconds"):
            changes[key] = None
        elif key == "densify":
            if not isinstance(value, bool):
                raise ConfigError(f"{where}: must be true or false, got {value!r}")
            changes[key] = value
        elif key in _INTEGER_KEYS:
            changes[key] = integer(where, value, least=_INTEGER_KEYS[key])
        else:
            changes[key] = number(where, value)
            if changes[key] < 0 or (changes[key] == 0 and key != "tolerance"):
                raise ConfigError(f"{where}: must be positive, got {value}")
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


def _programs(problem, population: int, m: int):
    """The compiled programs of one problem and population size."""
    objective = problem.objective_function()
    lower = jnp.asarray(problem.lower)
    width = jnp.asarray(problem.upper - problem.lower)

    def pull(z, weight):
        # The design-space gradient of sum_j weight_j f_j, in unit-box coordinates.
        _, vjp = jax.vjp(lambda zz: objective(lower + width * zz), z)
        return vjp(weight)[0]

    pulls = jax.jit(jax.vmap(pull))

    @jax.jit
    def layer_gradients(f, reference, ranks):
        return layer_hypervolume_gradients(f, reference, ranks)

    return pulls, layer_gradients


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
        order; ``extra`` holds the reference point used, the evaluation counts and the
        compile seconds of each program.
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

    # Compile every program once, for the population's shapes, before the timed run.
    compile_seconds = {}
    tic = time.perf_counter()
    jax.block_until_ready(evaluate(jnp.asarray(np.tile(problem.lower, (population, 1)))))
    compile_seconds["value"] = time.perf_counter() - tic
    pulls, layer_gradients = _programs(problem, population, m)
    tic = time.perf_counter()
    jax.block_until_ready(pulls(jnp.asarray(np.full((population, d), 0.5)), jnp.asarray(np.ones((population, m)))))
    compile_seconds["gradient"] = time.perf_counter() - tic
    tic = time.perf_counter()
    dummy_f, dummy_r = jnp.asarray(np.ones((population, m))), jnp.asarray(np.zeros(m))
    dummy_k = jnp.asarray(np.zeros(population, dtype=np.int64))
    jax.block_until_ready(layer_gradients(dummy_f, dummy_r, dummy_k))
    compile_seconds["hypervolume"] = time.perf_counter() - tic

    start = time.perf_counter()
    designs, values, checkpoints = [], [], []
    unit_designs = []  # parallel to values: the unit-box designs
    counts = dict(value=0, value_and_gradient=0)

    def value_of(z):
        unit_designs.append(z)
        x = lower + width * z
        f = np.asarray(evaluate(jnp.asarray(x)))
        designs.append(x)
        values.append(f)
        counts["value"] += z.shape[0]
        return f

    # 1. Space-filling start: two populations of a Latin hypercube sample.
    start_designs = qmc.LatinHypercube(d, seed=settings.seed).random(2 * population)
    f_start = np.concatenate([value_of(start_designs[:population]), value_of(start_designs[population:])])
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
    steps = np.full(population, settings.initial_step)
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
            )
        )

    record()
    accepted_total, generation = 0, 0
    stop_reason = "generations"
    for generation in range(1, settings.generations + 1):  # noqa: B007 (the count is reported after the loop)
        # 2a. Refinement: one hypervolume-gradient step per member, its own layer's gradient.
        ranks = nondominated_ranks(f)
        weights = np.array(layer_gradients(jnp.asarray(f), jnp.asarray(reference), jnp.asarray(ranks)))
        weights = np.nan_to_num(weights, nan=0.0, posinf=0.0, neginf=0.0)
        flat = ~np.any(weights != 0, axis=1)
        if flat.any():
            # Below the reference or a duplicate: climb every objective, each by its spread.
            spread = np.ptp(f, axis=0)
            weights[flat] = 1.0 / np.where(spread > 0, spread, 1.0)
        grad = np.nan_to_num(np.asarray(pulls(jnp.asarray(z), jnp.asarray(weights))), nan=0.0, posinf=0.0, neginf=0.0)
        counts["value_and_gradient"] += population
        grad = np.where(((z <= 0.0) & (grad < 0)) | ((z >= 1.0) & (grad > 0)), 0.0, grad)  # projected
        norm = np.linalg.norm(grad, axis=1, keepdims=True)
        direction = np.where(norm > 0, grad / np.where(norm > 0, norm, 1.0), 0.0)
        z_new = np.clip(z + steps[:, None] * direction, 0.0, 1.0)
        f_new = value_of(z_new)
        # Armijo's test on the layer hypervolume, linearized at the old point: the step's
        # gain w . (f_new - f) must reach a tenth of what the gradient promised (step |g|).
        gain = np.sum(weights * (f_new - f), axis=1)
        better = (gain >= 0.1 * steps * norm[:, 0]) & (norm[:, 0] > 0) & np.all(np.isfinite(f_new), axis=1)
        z, f = np.where(better[:, None], z_new, z), np.where(better[:, None], f_new, f)
        steps = np.clip(np.where(better, 2.0 * steps, 0.5 * steps), settings.min_step, settings.max_step)
        accepted_total += int(better.sum())
        # 2b. Exploration: NSGA-II offspring, merged by non-dominated sorting and crowding.
        z_child = _variation(rng, z, f, settings)
        f_child = value_of(z_child)
        z_all, f_all = np.concatenate([z, z_child]), np.concatenate([f, f_child])
        if settings.densify and m == 2 and front_f.shape[0] >= 2:
            # 2c. Two objectives: designs interpolated between neighbouring archive-front
            # designs, where the gaps lose the most hypervolume (the Pareto set is a curve).
            order = np.argsort(front_f[:, 0])
            z_dense = np.clip(_densify(front_f[order], front_z[order], population), 0.0, 1.0)
            z_dense = np.concatenate([z_dense, z_dense[-1:].repeat(population - z_dense.shape[0], axis=0)])
            f_dense = value_of(z_dense)
            z_all, f_all = np.concatenate([z_all, z_dense]), np.concatenate([f_all, f_dense])
        steps_all = np.concatenate([steps, np.full(z_all.shape[0] - population, settings.initial_step)])
        keep = _survivors(np.where(np.isfinite(f_all), f_all, -np.inf), population)
        z, f, steps = z_all[keep], f_all[keep], steps_all[keep]
        record()
        # 3. Stopping from the front's own convergence, or a budget.
        hv = [c["hypervolume"] for c in checkpoints]
        if len(hv) > settings.patience and hv[-1] - hv[-1 - settings.patience] <= settings.tolerance * abs(hv[-1]):
            stop_reason = f"converged: hypervolume gained < {settings.tolerance:g} in {settings.patience} generations"
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
            value_evaluations=counts["value"],
            value_and_gradient_evaluations=counts["value_and_gradient"],
            accepted_gradient_steps=accepted_total,
            compile_seconds_by_program={k: float(v) for k, v in compile_seconds.items()},
            settings=dataclasses.asdict(settings),
        ),
    )
