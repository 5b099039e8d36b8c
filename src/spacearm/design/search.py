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
from typing import Any

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


def _step_sizes(settings: SearchSettings) -> np.ndarray:
    """``(steps,)`` step sizes from ``learning_rate`` to ``final_learning_rate``: cosine,
    or geometric (travel early, precision soon after)."""
    progress = np.arange(settings.steps) / max(settings.steps - 1, 1)
    final = settings.final_learning_rate
    if settings.schedule == "cosine":
        return final + 0.5 * (settings.learning_rate - final) * (1.0 + np.cos(np.pi * progress))
    return settings.learning_rate * (final / settings.learning_rate) ** progress


def _chunk_function(objective: Callable, settings: SearchSettings, lower: np.ndarray, width: np.ndarray, adam):
    """``run_chunk(z, state, step_sizes, weights, utopia, nadir, scale)``: a scan of
    projected Adam steps of every run, vmapped, returning each visited design and its
    objectives (which come with the gradient)."""
    scalar = _scalarization_builder(objective, settings.smoothing, settings.augmentation)
    if settings.gradient == "forward":
        # d forward tangents instead of one reverse pass; slower on the joint-box
        # quadratures, kept as an option.
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

    return run_chunk


def _compile_both(evaluate_batch, run_chunk, x_first: np.ndarray, chunk_arguments: tuple, dtype):
    """Compile the value program and the chunk program on the real shapes, side by side:
    XLA compiles outside the GIL, so the value program compiles while the gradient
    program is traced and compiled. Returns the compiled chunk program."""
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        value_ready = pool.submit(
            lambda: jax.block_until_ready(evaluate_batch(x_first))
        )  # compiles (or hits the cache)
        shapes = jax.tree_util.tree_map(
            lambda x: jax.ShapeDtypeStruct(np.shape(x), dtype) if not isinstance(x, jax.ShapeDtypeStruct) else x,
            chunk_arguments,
        )
        compiled = jax.jit(run_chunk).lower(*shapes).compile()
        value_ready.result()
    return compiled


@dataclasses.dataclass
class _Archive:
    """Every design the scalarized search evaluated, in order, and the front of them all."""

    started: float
    reference: list
    designs: list = dataclasses.field(default_factory=list)
    values: list = dataclasses.field(default_factory=list)
    checkpoints: list = dataclasses.field(default_factory=list)
    evaluations: int = 0
    front_f: np.ndarray | None = None
    front_x: np.ndarray | None = None

    def add(self, x: np.ndarray, f: np.ndarray) -> None:
        """Archive ``(k, d)`` designs and their ``(k, m)`` objectives; update the front."""
        self.designs.append(x)
        self.values.append(f)
        self.evaluations += f.shape[0]
        if self.front_f is None:
            merged_f, merged_x = f, x
        else:
            merged_f, merged_x = np.concatenate([self.front_f, f]), np.concatenate([self.front_x, x])
        keep = nondominated_mask(merged_f)
        self.front_f, self.front_x = merged_f[keep], merged_x[keep]

    def checkpoint(self) -> None:
        self.checkpoints.append(
            dict(
                evaluations=self.evaluations,
                seconds=time.perf_counter() - self.started,
                hypervolume=hypervolume(self.front_f, self.reference),
            )
        )

    def normalization(self, spread: np.ndarray, utopia_margin: float):
        """The nadir and scales of the front (never below ``spread``) and the utopia point."""
        ideal, nadir = self.front_f.max(axis=0), self.front_f.min(axis=0)
        scale = np.maximum(np.maximum(ideal - nadir, spread), 1e-12)
        return nadir, scale, (ideal - nadir) / scale + utopia_margin


@dataclasses.dataclass
class _Search:
    """What the chunks of one scalarized search share."""

    settings: SearchSettings
    lower: np.ndarray  # (d,) the variables' bounds
    width: np.ndarray
    dtype: Any
    evaluate_batch: Callable
    run_chunk: Callable  # compiled (`_chunk_function`)
    state_shapes: Any  # Adam's state of every run
    step_sizes: np.ndarray
    spread: np.ndarray  # (m,) the least objective scales
    archive: _Archive
    value_seconds: list  # per design, of each value call
    gradient_seconds: list = dataclasses.field(default_factory=list)  # per design, of each chunk
    densified: int = 0


def _run_weights(targets: np.ndarray, utopia: np.ndarray, starts: int) -> np.ndarray:
    """``(runs, m)`` the Chebyshev weights of every run (each direction's, per start)."""
    weights = _ray_weights(targets, utopia) if targets.shape[1] == 2 else 1.0 / (utopia - targets)
    return np.repeat(weights, starts, axis=0)


def _warm_starts(search, ray_targets, z_samples, f_samples, z_runs, first) -> np.ndarray:
    """The runs' start designs: each direction's first start at the initial sample that
    scores best on its own scalarization; further starts stay random (multi-start)."""
    settings = search.settings
    nadir, scale, utopia = search.archive.normalization(search.spread, settings.utopia_margin)
    fhat = (f_samples - nadir) / scale
    weights = _run_weights(ray_targets, utopia, settings.starts)
    shortfall = utopia - fhat[None, :, :]
    score = np.max(weights[:, None, :] * shortfall, axis=-1) + settings.augmentation * shortfall.sum(-1)
    return np.where(first[:, None], z_samples[np.argmin(score, axis=1)], z_runs)


def _densify_front(search: _Search) -> int:
    """Two objectives: value-only designs interpolated between neighbouring front
    designs (`_densify`), padded to the initial batch so the compiled value program
    serves every call. Returns how many were evaluated."""
    settings, archive = search.settings, search.archive
    order = np.argsort(archive.front_f[:, 0])
    x_new = _densify(archive.front_f[order], archive.front_x[order], settings.initial_samples)
    tic = time.perf_counter()
    f_new = np.asarray(search.evaluate_batch(pad_leading(x_new, settings.initial_samples)))[: x_new.shape[0]]
    search.value_seconds.append((time.perf_counter() - tic) / settings.initial_samples)
    archive.add(x_new, f_new)
    return x_new.shape[0]


def pareto_search(problem: DesignProblem, settings: SearchSettings | None = None, reference=None) -> SearchResult:
    """Gradient-based Pareto search: vmapped projected Adam over Chebyshev scalarizations.

    1. ``initial_samples`` random designs (value only) give a first front, ideal
       point and objective scales.
    2. ``directions`` x ``starts`` smoothed Chebyshev scalarizations run in parallel:
       the variables are mapped to the unit box, one Adam state per run is vmapped
       (``optax.scale_by_adam``), each update is projected back onto the box (so
       bounds that are active at the optimum are reached exactly, which a sigmoid
       reparametrization cannot do), and the step size decays from ``learning_rate``
       to ``final_learning_rate``. The first start of each direction begins at the
       initial sample that scores best on its scalarization (``warm_start``), the other
       starts at random designs.
    3. The steps run in jitted chunks of ``chunk`` steps (compiled once, same shapes
       every call). After each chunk the ideal point and scales are re-read from the
       archive and, with ``reaim``, the rays are re-aimed at points spread along the
       current front (`_front_rays`); the first start of each direction restarts from
       the archived design nearest its new target, the other starts continue their own
       trajectories, so a flat or a steep stretch of the front gets its share of points
       and the free starts keep exploring (a stationary point of one objective can hide
       a part of the front that only a free start finds).
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
    lower, width = problem.lower, problem.upper - problem.lower
    dtype = jnp.result_type(float)
    d, m = len(problem.variables), len(problem.objectives)
    runs = settings.directions * settings.starts
    rng = np.random.default_rng(settings.seed)
    adam = optax.scale_by_adam()
    run_chunk = _chunk_function(objective, settings, np.asarray(lower, dtype), np.asarray(width, dtype), adam)
    evaluate_batch = problem.batch_function()
    z_samples = rng.uniform(size=(settings.initial_samples, d))
    z_runs = rng.uniform(size=(runs, d))
    # Adam's state starts at zeros (count, first and second moments): built in NumPy from
    # its shapes, so no small program compiles for it.
    state_shapes = jax.eval_shape(jax.vmap(adam.init), jax.ShapeDtypeStruct(z_runs.shape, dtype))
    step_sizes = _step_sizes(settings)
    arguments = (
        z_runs,
        state_shapes,
        step_sizes[: settings.chunk],
        np.ones((runs, m)),
        np.ones(m),
        np.zeros(m),
        np.ones(m),
    )
    start = time.perf_counter()
    run_chunk = _compile_both(evaluate_batch, run_chunk, lower + width * z_samples, arguments, dtype)
    compile_seconds = time.perf_counter() - start

    if reference is None:
        reference = getattr(problem, "reference_point", None)
    archive, value_seconds = _sample(evaluate_batch, lower + width * z_samples, reference)
    f_samples = archive.values[0]
    # Objective scales never fall below the spread (10th-90th percentile) of the initial
    # samples: while the archive front covers only a flat stretch (a range near zero in
    # one objective), the front's own range would blow that objective's scale up, and
    # the anchors would refuse to trade it for the other (the fronts here are L-shaped).
    spread = np.percentile(f_samples, 90, axis=0) - np.percentile(f_samples, 10, axis=0)
    search = _Search(
        settings=settings,
        lower=lower,
        width=width,
        dtype=dtype,
        evaluate_batch=evaluate_batch,
        run_chunk=run_chunk,
        state_shapes=state_shapes,
        step_sizes=step_sizes,
        spread=spread,
        archive=archive,
        value_seconds=value_seconds,
    )
    ray_targets = _direction_targets(settings.directions, m)  # (directions, m)
    first = np.arange(runs) % settings.starts == 0  # the first start of each direction
    if settings.warm_start:
        z_runs = _warm_starts(search, ray_targets, z_samples, f_samples, z_runs, first)
    steps_done = _descend(search, ray_targets, z_runs, first)
    return _result(search, compile_seconds, steps_done)


def _sample(evaluate_batch, x_samples: np.ndarray, reference) -> tuple[_Archive, list]:
    """1. The initial samples' values: the archive (its reference point from them when
    None is given) and the seconds per design of the value call."""
    started = time.perf_counter()
    tic = time.perf_counter()
    f_samples = np.asarray(evaluate_batch(x_samples))
    value_seconds = [(time.perf_counter() - tic) / x_samples.shape[0]]
    if reference is None:
        reference = reference_from_population(f_samples, 0.1)
    archive = _Archive(started, [float(r) for r in reference])
    archive.add(x_samples, f_samples)
    archive.checkpoint()
    return archive, value_seconds


def _descend(search: _Search, ray_targets: np.ndarray, z_runs: np.ndarray, first: np.ndarray) -> int:
    """2-3. The chunks of steps, each followed by re-aiming and densification; returns
    the steps taken."""
    settings, archive = search.settings, search.archive
    two = ray_targets.shape[1] == 2
    steps_done, state = 0, None
    while steps_done < settings.steps:
        nadir, scale, utopia = archive.normalization(search.spread, settings.utopia_margin)
        if settings.reaim and steps_done > 0 and two:
            # The first start of each direction restarts from the front; the others keep
            # their own trajectories (a start elsewhere can still find a part of the
            # front the archive has not seen).
            order = np.argsort(archive.front_f[:, 0])
            ray_targets, x_start = _front_rays(
                archive.front_f[order], archive.front_x[order], settings.directions, nadir, scale, utopia
            )
            z_runs[first] = (x_start - search.lower) / search.width
        if state is None or settings.reset_adam:
            state = jax.tree_util.tree_map(lambda leaf: np.zeros(leaf.shape, leaf.dtype), search.state_shapes)
        weights = _run_weights(ray_targets, utopia, settings.starts)
        z_runs, state = _run_chunk(search, steps_done, z_runs, state, (weights, utopia, nadir, scale))
        steps_done += settings.chunk
        if settings.densify and two and archive.front_f.shape[0] >= 2:
            search.densified += _densify_front(search)
        archive.checkpoint()
    return steps_done


def _run_chunk(search: _Search, steps_done: int, z_runs: np.ndarray, state, aim: tuple) -> tuple[np.ndarray, Any]:
    """One compiled chunk of steps from ``z_runs`` ``(runs, d)``; ``aim``: the weights,
    utopia, nadir and scales. Archives every visited design; returns the runs' designs
    and Adam's state after it."""
    settings, dtype = search.settings, search.dtype
    sizes = search.step_sizes[steps_done : steps_done + settings.chunk]
    sizes = np.concatenate([sizes, np.full(settings.chunk - sizes.size, settings.final_learning_rate)])
    tic = time.perf_counter()
    # NumPy arguments go straight to the compiled program (jnp.asarray would compile a
    # staging program per shape).
    z, state, zs, fs = search.run_chunk(
        np.asarray(z_runs, dtype), state, *(np.asarray(x, dtype) for x in (sizes, *aim))
    )
    z_runs = np.array(z)
    search.gradient_seconds.append((time.perf_counter() - tic) / (settings.chunk * z_runs.shape[0]))
    zs, fs = np.asarray(zs), np.asarray(fs)  # (chunk, runs, d), (chunk, runs, m)
    search.archive.add(search.lower + search.width * zs.reshape(-1, zs.shape[-1]), fs.reshape(-1, fs.shape[-1]))
    return z_runs, state


def _result(search: _Search, compile_seconds: float, steps_done: int) -> SearchResult:
    settings, archive = search.settings, search.archive
    densified = search.densified
    return SearchResult(
        method="gradient",
        designs=np.concatenate(archive.designs),
        objectives=np.concatenate(archive.values),
        checkpoints=archive.checkpoints,
        evaluations=archive.evaluations,
        compile_seconds=compile_seconds,
        run_seconds=time.perf_counter() - archive.started,
        extra=dict(
            reference_point=archive.reference,
            directions=settings.directions,
            starts=settings.starts,
            steps=steps_done,
            gradient=settings.gradient,
            value_evaluations=settings.initial_samples + densified,
            densify_evaluations=densified,
            value_and_gradient_evaluations=archive.evaluations - settings.initial_samples - densified,
            # Seconds per design of the fastest value call and the fastest chunk of
            # value-and-gradient steps of this run: their quotient is the cost ratio,
            # read off the compiled programs the search runs anyway.
            value_seconds_per_design=min(search.value_seconds),
            value_and_gradient_seconds_per_design=(
                min(search.gradient_seconds) if search.gradient_seconds else float("nan")
            ),
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
