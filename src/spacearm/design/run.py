"""The whole optimization run: the gradient search and the declared baselines, compared,
with the fronts, a summary and the manifest written atomically through `spacearm.io`.

Figures are drawn by the caller (``spacearm optimize`` passes
`spacearm.figures.design.plot_results` as an output); this layer draws nothing.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from .._core.errors import ConfigError
from ..io import build_manifest, write_csv, write_json
from ..io import manifest as provenance
from .baselines import grid_search, nsga2_search
import numpy as np

from .fronts import hypervolume
from .problem import DesignProblem
from .search import SearchResult, pareto_search, value_and_grad_cost_ratio

__all__ = ["run_problem", "TARGET_FRACTION", "ProblemOutput"]

# An extra writer run after the searches, before the summary: (problem, results by
# method, summary, out_dir) -> the paths it wrote (listed in summary.json and the manifest).
ProblemOutput = Callable[[DesignProblem, Mapping[str, SearchResult], Mapping[str, Any], Path], "list[Path]"]

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
                         hypervolume=hypervolume(sub, problem.reference_point)))
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
                config: Mapping | None = None, log: Callable[[str], None] = print,
                outputs: Sequence[ProblemOutput] = (), command: Sequence[str] | None = None,
                cost_ratio: str = "search") -> dict:
    """Run the gradient search and the declared baselines; write results atomically.

    Writes into ``out_dir``: ``pareto.csv`` (the gradient search's front: the
    variables by name, then the objectives), ``pareto_grid.csv`` and
    ``pareto_nsga2.csv`` for the baselines, whatever each of ``outputs`` writes (the
    command line passes the figures ``front.png``, ``designs.png``, ``convergence.png``),
    ``summary.json`` and ``manifest.json``.

    Comparisons. With a grid: the target is ``TARGET_FRACTION`` of the dense grid's
    hypervolume, and each method's run time to reach it is reported. Without a grid,
    NSGA-II is compared at the gradient search's run time (read off its archive's
    hypervolume curve). Compile time is measured apart and reported, never mixed
    into the run times.

    Cost of a value-and-gradient in values (``value_and_gradient_cost_ratio``): with
    ``cost_ratio="search"`` (default) the quotient of the per-design times of the
    fastest value call and the fastest chunk of gradient steps the search ran anyway;
    with ``"measured"``, `value_and_grad_cost_ratio` times both on one batch
    (best of 5), at the price of compiling a gradient program of its own.

    Returns:
        The summary dictionary also written to ``summary.json``.
    """
    if cost_ratio not in ("search", "measured"):
        raise ConfigError(f"cost_ratio: must be 'search' or 'measured', got {cost_ratio!r}")
    code_state = provenance.git_state()  # before anything under out_dir (perhaps tracked) changes
    started = time.perf_counter()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    log(f"optimize {problem.name}: {len(problem.variables)} variables ({', '.join(problem.variable_names)}), "
        f"objectives {', '.join(problem.objectives)}")
    gradient = pareto_search(problem)
    log(f"  gradient: {gradient.evaluations} evaluations, compile {gradient.compile_seconds:.1f} s, "
        f"run {gradient.run_seconds:.2f} s, hypervolume {gradient.checkpoints[-1]['hypervolume']:.6g}")
    if cost_ratio == "measured":
        ratio = value_and_grad_cost_ratio(problem, gradient=problem.search.gradient,
                                          batch=problem.search.initial_samples)
    else:
        ratio = gradient.extra["value_and_gradient_seconds_per_design"] / gradient.extra["value_seconds_per_design"]
    gradient.extra["value_and_gradient_cost_ratio"] = ratio
    gradient.extra["value_and_gradient_cost_ratio_from"] = cost_ratio
    gradient.extra["equivalent_value_evaluations"] = (
        gradient.extra["value_evaluations"] + ratio * gradient.extra["value_and_gradient_evaluations"])

    results = {"gradient": gradient}
    grid_rows = None
    if baselines and problem.grid_points is not None:
        grid = grid_search(problem)
        results["grid"] = grid
        grid_rows = _grid_convergence(problem, grid)
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

    grid_hv = results["grid"].checkpoints[-1]["hypervolume"] if "grid" in results else None
    # The best-known hypervolume: every design any method evaluated, together.
    best_known = hypervolume(np.concatenate([r.objectives for r in results.values()]), problem.reference_point)
    summary: dict[str, Any] = dict(
        name=problem.name,
        description=problem.description,
        variables={v.name: [v.lower, v.upper] for v in problem.variables},
        fixed=problem.fixed_summary(),
        objectives=list(problem.objectives),
        objectives_maximized=True,
        reference_point=list(problem.reference_point),
        hypervolume=gradient.checkpoints[-1]["hypervolume"],
        best_known_hypervolume=best_known,
        fraction_of_best_known={name: r.checkpoints[-1]["hypervolume"] / best_known if best_known > 0 else None
                                for name, r in results.items()},
        evaluation_counting=(
            "one evaluation = the objective vector of one design. The gradient search gets value and gradient "
            "together (reverse or forward mode) and counts that as one evaluation; "
            "value_and_gradient_cost_ratio is its measured wall-time cost in value evaluations (from the "
            "search's own timed calls, or timed apart with --cost-ratio: value_and_gradient_cost_ratio_from) and "
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
    elif "nsga2" in results:
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
    if "nsga2" in results:
        # Always: NSGA-II's archive at the gradient search's run time (compile excluded for both).
        nsga = results["nsga2"]
        budget = gradient.run_seconds
        summary["equal_time"] = dict(
            seconds=budget,
            gradient_hypervolume=gradient.checkpoints[-1]["hypervolume"],
            nsga2_hypervolume=nsga.hypervolume_at(budget),
            nsga2_ran_seconds=nsga.run_seconds,
            nsga2_ran_long_enough=bool(nsga.run_seconds >= budget),
            gradient_more=bool(gradient.checkpoints[-1]["hypervolume"] > nsga.hypervolume_at(budget)),
        )
        log("  equal time: " + ", ".join(f"{k} {v:.6g}" if isinstance(v, float) else f"{k} {v}"
                                        for k, v in summary["equal_time"].items()))
    if "comparison" in summary:
        log("  comparison: " + ", ".join(f"{k} {v:.6g}" if isinstance(v, float) else f"{k} {v}"
                                         for k, v in summary["comparison"].items()))

    written = [write_csv(out_dir / "pareto.csv", _front_table(problem, gradient))]
    for name in ("grid", "nsga2"):
        if name in results:
            written.append(write_csv(out_dir / f"pareto_{name}.csv", _front_table(problem, results[name])))
    for output in outputs:
        written += output(problem, results, summary, out_dir)
    summary["files"] = [p.name for p in written] + ["summary.json", "manifest.json"]
    if config is not None:
        summary["config"] = dict(config)
    write_json(out_dir / "summary.json", summary)
    timings = {"wall": time.perf_counter() - started}
    data = build_manifest(dict(config) if config is not None else {"problem": problem.name},
                          command=list(command) if command is not None else sys.argv, timings=timings,
                          git=code_state, extra={"files": summary["files"]})
    write_json(out_dir / "manifest.json", data)
    log(f"  wrote {out_dir}: {', '.join(summary['files'])}")
    return summary
