"""The gradient Pareto search: many smoothed Chebyshev scalarizations, one vmapped
projected Adam (optax), every evaluated design archived.

Counting evaluations: one *evaluation* is one design's objective vector. The
gradient search evaluates value and gradient together; each counts as one
evaluation in ``evaluations``, and `value_and_grad_cost_ratio` measures the cost
of a value-and-gradient relative to a value, so the counts compare honestly with the
value-only baselines.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import time
from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from .._core.batching import pad_leading
from .._core.errors import ConfigError
from .fronts import hypervolume, nondominated, nondominated_mask, reference_from_population
from .problem import DesignProblem, SearchSettings

__all__ = ["SearchResult", "pareto_search", "value_and_grad_cost_ratio"]


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


def _front_rays(front_f: np.ndarray, front_x: np.ndarray, count: int, nadir, scale, utopia, blend: float = 0.25):
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


def pareto_search(problem: DesignProblem, settings: SearchSettings | None = None, reference=None) -> SearchResult:
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
       arc length along the current front (`_front_rays`); the first start of
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

    Args:
        reference: the hypervolume reference point of the checkpoints; None takes the
            problem's, or, when it gives none, `reference_from_population` of the initial
            samples (margin 0.1).

    Returns:
        A `SearchResult` with every evaluated design in order.
    """
    settings = settings or problem.search
    objective = problem.objective_function()
    lower_np, width_np = problem.lower, problem.upper - problem.lower
    dtype = jnp.result_type(float)
    lower, width = np.asarray(lower_np, dtype), np.asarray(width_np, dtype)
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

    # Adam's state starts at zeros (count, first and second moments): built in NumPy from
    # its shapes, so no small program compiles for it.
    state_shapes = jax.eval_shape(jax.vmap(adam.init), jax.ShapeDtypeStruct(z_runs.shape, dtype))

    def initial_state():
        return jax.tree_util.tree_map(lambda leaf: np.zeros(leaf.shape, leaf.dtype), state_shapes)

    # Compile both programs first, on the real shapes (timed apart from the run), side by
    # side: XLA compiles outside the GIL, so on two cores the value program compiles
    # while the gradient program is traced and compiled.
    start = time.perf_counter()
    x_first = lower_np + width_np * z_samples
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        value_ready = pool.submit(
            lambda: jax.block_until_ready(evaluate_batch(x_first))
        )  # compiles (or hits the cache)
        chunk_shapes = (
            z_runs,
            state_shapes,
            step_sizes[: settings.chunk],
            np.ones((runs, m)),
            np.ones(m),
            np.zeros(m),
            np.ones(m),
        )
        chunk_shapes = jax.tree_util.tree_map(
            lambda x: jax.ShapeDtypeStruct(np.shape(x), dtype) if not isinstance(x, jax.ShapeDtypeStruct) else x,
            chunk_shapes,
        )
        run_chunk = jax.jit(run_chunk).lower(*chunk_shapes).compile()
        value_ready.result()
    compile_seconds = time.perf_counter() - start

    if reference is None:
        reference = getattr(problem, "reference_point", None)
    two = m == 2
    designs, values, checkpoints = [], [], []
    start = time.perf_counter()
    x_samples = lower_np + width_np * z_samples
    tic = time.perf_counter()
    f_samples = np.asarray(evaluate_batch(x_samples))
    value_seconds = [(time.perf_counter() - tic) / settings.initial_samples]
    designs.append(x_samples)
    values.append(f_samples)
    evaluations = settings.initial_samples
    if reference is None:
        reference = reference_from_population(f_samples, 0.1)
    reference = [float(r) for r in reference]
    keep = nondominated_mask(f_samples)
    front_f, front_x = f_samples[keep], x_samples[keep]
    checkpoints.append(
        dict(evaluations=evaluations, seconds=time.perf_counter() - start, hypervolume=hypervolume(front_f, reference))
    )

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
    gradient_seconds = []
    while steps_done < settings.steps:
        nadir, scale, utopia = normalization()
        if settings.reaim and steps_done > 0 and m == 2:
            # The first start of each direction restarts from the front; the others keep
            # their own trajectories (multi-start survives re-aiming: a start elsewhere
            # can still find a part of the front the archive has not seen).
            order = np.argsort(front_f[:, 0])
            ray_targets, x_start = _front_rays(
                front_f[order], front_x[order], settings.directions, nadir, scale, utopia
            )
            z_runs[first] = (x_start - lower_np) / width_np
        weights = np.repeat(
            _ray_weights(ray_targets, utopia) if m == 2 else 1.0 / (utopia - ray_targets), settings.starts, axis=0
        )
        sizes = step_sizes[steps_done : steps_done + settings.chunk]
        sizes = np.concatenate([sizes, np.full(settings.chunk - sizes.size, final)])
        if state is None or settings.reset_adam:
            state = initial_state()
        tic = time.perf_counter()
        # NumPy arguments go straight to the compiled program (jnp.asarray would compile
        # a staging program per shape).
        z, state, zs, fs = run_chunk(
            *(np.asarray(x, dtype) for x in (z_runs,)),
            state,
            *(np.asarray(x, dtype) for x in (sizes, weights, utopia, nadir, scale)),
        )
        z_runs = np.array(z)
        gradient_seconds.append((time.perf_counter() - tic) / (settings.chunk * runs))
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
            # Padded to the initial batch: the value program compiled above serves every call.
            tic = time.perf_counter()
            f_new = np.asarray(evaluate_batch(pad_leading(x_new, settings.initial_samples)))
            f_new = f_new[: x_new.shape[0]]
            value_seconds.append((time.perf_counter() - tic) / settings.initial_samples)
            designs.append(x_new)
            values.append(f_new)
            evaluations += x_new.shape[0]
            densified += x_new.shape[0]
            merged_f, merged_x = np.concatenate([front_f, f_new]), np.concatenate([front_x, x_new])
            keep = nondominated_mask(merged_f)
            front_f, front_x = merged_f[keep], merged_x[keep]
        checkpoints.append(
            dict(
                evaluations=evaluations,
                seconds=time.perf_counter() - start,
                hypervolume=hypervolume(front_f, reference),
            )
        )
    run_seconds = time.perf_counter() - start
    return SearchResult(
        method="gradient",
        designs=np.concatenate(designs),
        objectives=np.concatenate(values),
        checkpoints=checkpoints,
        evaluations=evaluations,
        compile_seconds=compile_seconds,
        run_seconds=run_seconds,
        extra=dict(
            reference_point=reference,
            directions=settings.directions,
            starts=settings.starts,
            steps=steps_done,
            gradient=settings.gradient,
            value_evaluations=settings.initial_samples + densified,
            densify_evaluations=densified,
            value_and_gradient_evaluations=evaluations - settings.initial_samples - densified,
            # Seconds per design of the fastest value call and the fastest chunk of
            # value-and-gradient steps of this run: their quotient is the cost ratio,
            # read off the compiled programs the search runs anyway.
            value_seconds_per_design=min(value_seconds),
            value_and_gradient_seconds_per_design=min(gradient_seconds) if gradient_seconds else float("nan"),
        ),
    )


def value_and_grad_cost_ratio(
    problem: DesignProblem, *, gradient: str = "reverse", batch: int = 64, repeats: int = 5
) -> float:
    """Measured wall time of a batched value-and-gradient over a batched value (same batch).

    Used to convert the gradient search's evaluation count into value-only
    equivalents. Best of ``repeats`` timings of each, compiled beforehand: this compiles
    a gradient program of its own, so ``run_problem`` calls it only when asked
    (``cost_ratio="measured"``, ``spacearm optimize --cost-ratio``); by default the ratio
    is read off the search's own timed calls.
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
