"""Baselines measured with the same objective code as the search: a dense grid and NSGA-II (pymoo)."""

from __future__ import annotations

import time
from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np

from .._core.batching import pad_leading
from .._core.errors import ConfigError
from .fronts import hypervolume, hypervolume_history
from .problem import DesignProblem
from .search import SearchResult

__all__ = ["grid_search", "nsga2_search"]


def grid_search(
    problem: DesignProblem,
    points: Sequence[int] | None = None,
    chunk: int | None = None,
    reference: Sequence[float] | None = None,
) -> SearchResult:
    """Dense grid baseline: every design of the outer-product grid over the bounds.

    Evaluated in fixed-size chunks (the last one padded) with one compiled program.
    ``reference``: the hypervolume reference point (default: the problem's).
    """
    reference = problem.reference_point if reference is None else reference
    points = tuple(points or problem.grid_points or (21,) * len(problem.variables))
    chunk = int(chunk or problem.grid_chunk)
    axes = [np.linspace(v.lower, v.upper, p) for v, p in zip(problem.variables, points, strict=False)]
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
        block = mesh[begin : begin + chunk]
        padded = np.concatenate([block, np.repeat(block[-1:], chunk - block.shape[0], axis=0)])
        values.append(np.asarray(compiled(jnp.asarray(padded)))[: block.shape[0]])
    run_seconds = time.perf_counter() - start
    objectives = np.concatenate(values)
    hv = hypervolume(objectives, reference)
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
    reference: Sequence[float] | None = None,
) -> SearchResult:
    """NSGA-II baseline (pymoo) on the same objective code, vectorized per generation.

    pymoo minimizes, so it sees -f. Every evaluated design is archived with a time
    stamp; the archive hypervolume is computed after the run (not timed).

    Args:
        population: NSGA-II population size.
        evaluations: stop after this many objective evaluations.
        time_limit: optional wall-time limit, s (stops at the next generation).
        reference: the hypervolume reference point (default: the problem's).
    """
    reference = problem.reference_point if reference is None else reference
    try:  # pymoo is the optional extra "optimize": imported when this baseline runs
        from pymoo.algorithms.moo.nsga2 import NSGA2  # noqa: PLC0415
        from pymoo.core.problem import Problem  # noqa: PLC0415
        from pymoo.core.termination import Termination  # noqa: PLC0415
        from pymoo.optimize import minimize  # noqa: PLC0415
    except ImportError as error:  # pragma: no cover - optional extra
        raise ConfigError("baselines.nsga2: needs pymoo (pip install 'spacearm[optimize]')") from error

    evaluate = problem.batch_function()
    d, m = len(problem.variables), len(problem.objectives)
    start = time.perf_counter()
    # Compile for the population size; pymoo may send a smaller batch after removing
    # duplicates, which is padded to it (one program, never compiled inside the timed run).
    jax.block_until_ready(evaluate(jnp.asarray(np.tile(problem.lower, (population, 1)))))
    compile_seconds = time.perf_counter() - start
    log: list[tuple[np.ndarray, np.ndarray, float]] = []
    clock = {"start": 0.0}

    class _Problem(Problem):
        def __init__(self):
            super().__init__(n_var=d, n_obj=m, xl=problem.lower, xu=problem.upper)

        def _evaluate(self, x, out, *args, **kwargs):
            x = np.asarray(x, dtype=np.float64)
            rows = max(population, x.shape[0])
            f = np.asarray(evaluate(jnp.asarray(pad_leading(x, rows))))[: x.shape[0]]
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
    hv = hypervolume_history([entry[1] for entry in log], reference)
    checkpoints, count = [], 0
    for k, entry in enumerate(log):
        count += entry[1].shape[0]
        checkpoints.append(
            dict(evaluations=count, seconds=entry[2], hypervolume=float(hv[k]) if hv is not None else float("nan"))
        )
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
