"""The whole optimization run: the design search (the hybrid by default, or the
scalarized gradient search) and the declared baselines, compared, with the fronts, a
summary, a printed table and the manifest written atomically through `spacearm.io`.

Figures are drawn by the caller (``spacearm optimize`` passes
`spacearm.figures.design.plot_results` as an output); this layer draws nothing.
"""

from __future__ import annotations

import json
import os
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .._core.errors import ConfigError, RunError
from .._core.numeric import x64_enabled
from ..io import build_manifest, manifest as provenance, write_csv, write_json
from ..io.folders import check_output_folder, claimed_folder, replacing_folder
from .baselines import grid_search, nsga2_search
from .fronts import hypervolume
from .hybrid import HybridSettings, hybrid_search
from .problem import DesignProblem
from .search import SearchResult, pareto_search, value_and_grad_cost_ratio

__all__ = ["METHODS", "NSGA2_TIME_FACTOR", "TARGET_FRACTION", "ProblemOutput", "run_problem", "summary_table"]

METHODS = ("hybrid", "scalarized")
# NSGA-II runs this many times the main search's wall time (compile included on both sides).
NSGA2_TIME_FACTOR = 3.0

# An extra writer run after the searches, before the summary: (problem, results by
# method, summary, out_dir) -> the paths it wrote (listed in summary.json and the manifest).
ProblemOutput = Callable[[DesignProblem, Mapping[str, SearchResult], Mapping[str, Any], Path], "list[Path]"]

TARGET_FRACTION = 0.999

# A test hook: called with the staging folder once every file is written, right before the
# swap (the fault-injection tests kill the run there).
_BEFORE_SWAP: Callable[[Path], None] | None = None


def _nested_grid_levels(points: Sequence[int]) -> list[tuple[int, ...]]:
    """Coarser grids nested in the dense one: (p - 1) / 2^k + 1 points per axis."""
    levels = [tuple(points)]
    while True:
        coarser = tuple((p - 1) // 2 + 1 if (p - 1) % 2 == 0 else None for p in levels[-1])
        if any(c is None or c < 3 for c in coarser):
            break
        levels.append(coarser)
    return levels[::-1]


def _grid_convergence(problem: DesignProblem, grid: SearchResult, reference: Sequence[float]) -> list[dict]:
    """Hypervolume of the nested coarser grids, read off the dense grid's values.

    Their times are the dense grid's run time per design times their size (an
    estimate: the coarse grids are not re-evaluated).
    """
    points = grid.extra["points"]
    values = grid.objectives.reshape(*points, -1)
    seconds_per_design = grid.run_seconds / grid.evaluations
    rows = []
    for level in _nested_grid_levels(points):
        strides = [(p - 1) // (q - 1) for p, q in zip(points, level, strict=False)]
        sub = values[tuple(slice(None, None, s) for s in strides)].reshape(-1, values.shape[-1])
        rows.append(
            dict(
                points=list(level),
                evaluations=int(sub.shape[0]),
                seconds=seconds_per_design * sub.shape[0],
                hypervolume=hypervolume(sub, reference),
            )
        )
    return rows


def _wall_to(result: SearchResult, hypervolume: float) -> float | None:
    """Wall seconds, compile included, until the archive first reached ``hypervolume``."""
    seconds = result.seconds_to(hypervolume)
    return None if seconds is None else result.compile_seconds + seconds


def _method_summary(result: SearchResult, reference_hv: float | None) -> dict:
    front = result.front()
    final_hv = result.checkpoints[-1]["hypervolume"] if result.checkpoints else float("nan")
    summary = dict(
        hypervolume=final_hv,
        evaluations=result.evaluations,
        compile_seconds=result.compile_seconds,
        run_seconds=result.run_seconds,
        wall_seconds=result.compile_seconds + result.run_seconds,
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


def summary_table(summary: Mapping[str, Any]) -> str:
    """The run's summary as a short table: one row per method (hypervolume, share of the
    best known when there is more than one method, evaluations, run and compile seconds),
    the reference point, which baseline beat the search if one did, then the comparison
    with NSGA-II in one line."""
    best = summary["best_known_hypervolume"]
    methods = summary["methods"]
    shared = len(methods) > 1  # a share of the best known, when others were measured
    lines = [
        f"{'method':<11}{'hypervolume':>14}"
        + (f"{'of best':>10}" if shared else "")
        + f"{'evaluations':>13}{'run s':>9}{'compile s':>11}"
    ]
    for name, row in methods.items():
        share = f"{row['hypervolume'] / best if best else float('nan'):>10.4%}" if shared else ""
        lines.append(
            f"{name:<11}{row['hypervolume']:>14.7g}{share}{row['evaluations']:>13d}"
            f"{row['run_seconds']:>9.2f}{row['compile_seconds']:>11.2f}"
        )
    reference = ", ".join(f"{r:.6g}" for r in summary["reference_point"])
    lines.append(
        f"reference point {reference} ({summary['reference_point_from']}); "
        + (f"best known hypervolume {best:.7g} (all methods' designs)" if shared else f"hypervolume {best:.7g}")
    )
    if not best > 0:
        lines.append(
            "no design dominates the reference point, so every hypervolume is 0: set reference_point below the front"
        )
    main = summary["method"]
    winners = [
        name for name, row in methods.items() if name != main and row["hypervolume"] > methods[main]["hypervolume"]
    ]
    for name in winners:
        lines.append(
            f"the {name} baseline beat the {main} search: {methods[name]['hypervolume']:.7g} against "
            f"{methods[main]['hypervolume']:.7g}; its designs are in pareto_{name}.csv"
        )
    against = summary.get("against_nsga2")
    if against:
        reached = against["main_wall_seconds_to_nsga2_final"]
        lines.append(
            f"NSGA-II ran {against['nsga2_wall_seconds']:.1f} s wall ({against['nsga2_wall_factor']:.3g}x {main}'s "
            f"{against['main_wall_seconds']:.1f} s, compile included) to {against['nsga2_final_hypervolume']:.7g}; "
            + (
                f"{main} reached it at {reached:.1f} s wall (NSGA-II at {against['nsga2_wall_seconds_to_own_final']:.1f}"
                f" s: ratio {against['wall_time_ratio']:.3g})"
                if reached is not None
                else f"{main} did not reach it"
            )
        )
    return "\n".join(lines)


def run_problem(
    problem: DesignProblem,
    out_dir: str | os.PathLike,
    *,
    method: str = "hybrid",
    hybrid: HybridSettings | None = None,
    baselines: bool = True,
    config: Mapping | None = None,
    log: Callable[[str], None] = print,
    outputs: Sequence[ProblemOutput] = (),
    command: Sequence[str] | None = None,
    cost_ratio: str = "search",
    nsga2_time_factor: float = NSGA2_TIME_FACTOR,
) -> dict:
    """Run the design search and the declared baselines; write results atomically.

    Writes into ``out_dir``: ``pareto.csv`` (the main search's front: the variables by
    name, then the objectives, as the problem's ``batch_function()`` computed them),
    ``pareto_grid.csv`` and ``pareto_nsga2.csv`` for the baselines, whatever each of
    ``outputs`` writes (the command line passes the figures), ``summary.json`` and
    ``manifest.json``; prints `summary_table`.

    Args:
        method: ``"hybrid"`` (`spacearm.design.hybrid.hybrid_search`, results key
            ``hybrid``) or ``"scalarized"`` (the Chebyshev search `pareto_search`, results
            key ``gradient``).
        hybrid: the hybrid's settings (default `HybridSettings()`).
        nsga2_time_factor: NSGA-II, when declared, runs until its wall time (its compile
            included) is this many times the main search's (compile included), or until a
            ``time_limit`` given in the file; its evaluation cap is not applied.
        cost_ratio: for the scalarized search, how its value-and-gradient cost ratio is
            read (``"search"``: off its own timed calls; ``"measured"``: timed apart).

    Comparisons: the reference point is the problem's, or the main search's choice when
    the problem gives none (written to the summary). ``best_known_hypervolume`` is that
    of every design any method evaluated. ``against_nsga2``: NSGA-II's final hypervolume
    and the wall time (compile included) each method took to reach it. With a grid, the
    target is ``TARGET_FRACTION`` of the grid's hypervolume, as before.

    The files are written into a staging folder beside ``out_dir`` that replaces it as a
    whole (`spacearm.io.folders`), under the folder's lock, taken before the search;
    files in ``out_dir`` that the previous run's manifest does not list are kept.

    Returns:
        The summary dictionary also written to ``summary.json``.

    Raises:
        ConfigError: another process holds ``out_dir``'s lock (its PID is named), or
            ``out_dir`` cannot be a results folder of its own.
        RunError: an objective came out non-finite for an evaluated design
            (`check_finite_objectives`); nothing is written.
    """
    if method not in METHODS:
        raise ConfigError(f"method: must be one of {', '.join(METHODS)}, got {method!r}")
    if cost_ratio not in ("search", "measured"):
        raise ConfigError(f"cost_ratio: must be 'search' or 'measured', got {cost_ratio!r}")
    out_dir = Path(out_dir)
    check_output_folder(out_dir)
    # One writer at a time (a second one is refused naming the holder's PID), taken before
    # the search so that a refused run costs nothing.
    with claimed_folder(out_dir, "optimize", label=f"--out {out_dir}"):
        code_state = provenance.git_state()  # before anything under out_dir (perhaps tracked) changes
        started = time.perf_counter()
        log(
            f"optimize {problem.name} ({method}): {len(problem.variables)} variables "
            f"({', '.join(problem.variable_names)}), objectives {', '.join(problem.objectives)}"
        )
        main_key, main = _main_search(problem, method, hybrid, cost_ratio, log)
        results = {main_key: main}
        grid_rows = _baselines(problem, results, main, baselines, nsga2_time_factor, log)
        summary = _summary(problem, main_key, results, grid_rows)
        for name, result in results.items():
            check_finite_objectives(problem, name, result)
        run = dict(config=config, command=command, git=code_state, started=started)
        _write_results(problem, out_dir, results, summary, outputs, run)
        log(summary_table(summary))
        log(f"  wrote {out_dir}: {', '.join(summary['files'])}")
    return summary


def _main_search(problem: DesignProblem, method: str, hybrid: HybridSettings | None, cost_ratio: str, log):
    """The main search's results key and result; the scalarized search's value-and-gradient
    cost ratio (read off its own timed calls, or ``"measured"`` apart) in its ``extra``."""
    if method == "hybrid":
        main_key, main = "hybrid", hybrid_search(problem, hybrid)
    else:
        main_key, main = "gradient", pareto_search(problem)
        if cost_ratio == "measured":
            ratio = value_and_grad_cost_ratio(
                problem, gradient=problem.search.gradient, batch=problem.search.initial_samples
            )
        else:
            ratio = main.extra["value_and_gradient_seconds_per_design"] / main.extra["value_seconds_per_design"]
        main.extra["value_and_gradient_cost_ratio"] = ratio
        main.extra["value_and_gradient_cost_ratio_from"] = cost_ratio
        main.extra["equivalent_value_evaluations"] = (
            main.extra["value_evaluations"] + ratio * main.extra["value_and_gradient_evaluations"]
        )
    log(
        f"  {main_key}: {main.evaluations} evaluations, compile {main.compile_seconds:.1f} s, "
        f"run {main.run_seconds:.2f} s, hypervolume {main.checkpoints[-1]['hypervolume']:.7g}"
    )
    return main_key, main


def _baselines(problem, results: dict, main: SearchResult, baselines: bool, nsga2_time_factor: float, log):
    """Run the declared baselines into ``results`` (``grid``, ``nsga2``) at the main
    search's reference point; returns the grid's nested-grid rows (None without a grid)."""
    reference = [float(r) for r in main.extra["reference_point"]]
    grid_rows = None
    if baselines and problem.grid_points is not None:
        grid = grid_search(problem, reference=reference)
        results["grid"] = grid
        grid_rows = _grid_convergence(problem, grid, reference)
        log(
            f"  grid {'x'.join(map(str, problem.grid_points))}: {grid.evaluations} evaluations, "
            f"run {grid.run_seconds:.2f} s, hypervolume {grid.checkpoints[-1]['hypervolume']:.7g}"
        )
    if baselines and problem.nsga2 is not None:
        results["nsga2"] = _nsga2(problem, main, reference, nsga2_time_factor, log)
    return grid_rows


def _nsga2(problem, main: SearchResult, reference: list[float], nsga2_time_factor: float, log) -> SearchResult:
    """NSGA-II until its wall time (compile included) is ``nsga2_time_factor`` times the
    main search's, or the file's ``time_limit``."""
    options = dict(problem.nsga2)
    population = int(options.get("population", 40))
    # NSGA-II needs the value program too: when the main search compiled it for the
    # same shape (a cache hit here), NSGA-II is charged the main search's compile of it.
    value_compile = main.extra.get("compile_seconds_by_program", {}).get("value", 0.0)
    charged = value_compile if population == main.extra.get("population") else 0.0
    limit = nsga2_time_factor * (main.compile_seconds + main.run_seconds) - charged
    if options.get("time_limit") is not None:
        limit = min(limit, float(options["time_limit"]))
    nsga = nsga2_search(
        problem,
        population=population,
        evaluations=10**12,
        seed=int(options.get("seed", 0)),
        time_limit=max(limit, 1e-3),
        reference=reference,
    )
    nsga.compile_seconds = max(nsga.compile_seconds, charged)
    log(
        f"  nsga2 (population {population}): {nsga.evaluations} evaluations, "
        f"run {nsga.run_seconds:.2f} s, hypervolume {nsga.checkpoints[-1]['hypervolume']:.7g}"
    )
    return nsga


# How summary.json explains its counts and timings.
_EVALUATION_COUNTING = (
    "one evaluation = the objective vector of one design. A value-and-gradient (the hybrid's "
    "vector-Jacobian products, the scalarized search's steps) counts as one evaluation; the hybrid reports "
    "value_evaluations (its forward differences included: each is a design's values) and "
    "value_and_gradient_evaluations apart, the scalarized search its measured value_and_gradient_cost_"
    "ratio. Grid and NSGA-II evaluate values only."
)
_TIMING = (
    "run_seconds exclude compilation (compile_seconds, measured apart); wall_seconds = both. Every "
    "comparison against NSGA-II counts compile on both sides. Checkpoints include each method's own "
    "bookkeeping (pymoo's overhead for NSGA-II); archive hypervolumes are computed after the run for "
    "NSGA-II and the grid, inside the run for the main search"
)


def _summary(problem: DesignProblem, main_key: str, results: Mapping[str, SearchResult], grid_rows) -> dict:
    """The summary of every search (written to ``summary.json``)."""
    main = results[main_key]
    reference = [float(r) for r in main.extra["reference_point"]]
    reference_from = (
        "problem"
        if getattr(problem, "reference_point", None) is not None
        else (main.extra.get("reference_point_from", "the main search's first designs"))
    )
    grid_hv = results["grid"].checkpoints[-1]["hypervolume"] if "grid" in results else None
    # The best-known hypervolume: every design any method evaluated, together.
    best_known = hypervolume(np.concatenate([r.objectives for r in results.values()]), reference)
    summary: dict[str, Any] = dict(
        name=problem.name,
        description=problem.description,
        method=main_key,
        variables={v.name: [v.lower, v.upper] for v in problem.variables},
        fixed=problem.fixed_summary(),
        objectives=list(problem.objectives),
        objectives_maximized=True,
        reference_point=reference,
        reference_point_from=reference_from,
        hypervolume=main.checkpoints[-1]["hypervolume"],
        best_known_hypervolume=best_known,
        fraction_of_best_known={
            name: r.checkpoints[-1]["hypervolume"] / best_known if best_known > 0 else None
            for name, r in results.items()
        },
        evaluation_counting=_EVALUATION_COUNTING,
        timing=_TIMING,
        methods={name: _method_summary(result, grid_hv) for name, result in results.items()},
    )
    if grid_rows is not None:
        summary["methods"]["grid"]["nested_grids"] = grid_rows
    if grid_hv is not None:
        summary["comparison"] = _grid_comparison(main, results.get("nsga2"), grid_hv)
    if "nsga2" in results:
        summary["against_nsga2"] = _against_nsga2(main, results["nsga2"], best_known)
    return summary


def _grid_comparison(main: SearchResult, nsga: SearchResult | None, grid_hv: float) -> dict:
    """The time and evaluations each method took to reach ``TARGET_FRACTION`` of the grid's hypervolume."""
    target = TARGET_FRACTION * grid_hv
    comparison = dict(
        kind="time to reach the target hypervolume",
        grid_hypervolume=grid_hv,
        target_fraction=TARGET_FRACTION,
        target_hypervolume=target,
        main_seconds=main.seconds_to(target),
        main_evaluations=main.evaluations_to(target),
    )
    if nsga is not None:
        comparison.update(nsga2_seconds=nsga.seconds_to(target), nsga2_evaluations=nsga.evaluations_to(target))
    return comparison


def _against_nsga2(main: SearchResult, nsga: SearchResult, best_known: float) -> dict:
    """NSGA-II's final hypervolume and the wall time (compile included) each method took to reach it."""
    main_wall = main.compile_seconds + main.run_seconds
    nsga_final = nsga.checkpoints[-1]["hypervolume"]
    main_to = _wall_to(main, nsga_final)
    nsga_to = _wall_to(nsga, nsga_final)
    main_hv = main.checkpoints[-1]["hypervolume"]
    return dict(
        kind="NSGA-II's final hypervolume and the wall time (compile included) each method took to reach it",
        main_wall_seconds=main_wall,
        nsga2_wall_seconds=nsga.compile_seconds + nsga.run_seconds,
        nsga2_wall_factor=(nsga.compile_seconds + nsga.run_seconds) / main_wall,
        nsga2_final_hypervolume=nsga_final,
        nsga2_hypervolume_at_main_wall=nsga.hypervolume_at(main_wall - nsga.compile_seconds),
        main_hypervolume=main_hv,
        main_wall_seconds_to_nsga2_final=main_to,
        nsga2_wall_seconds_to_own_final=nsga_to,
        wall_time_ratio=None if main_to is None or not nsga_to else main_to / nsga_to,
        main_share_of_best_known=main_hv / best_known if best_known > 0 else None,
        met=bool(main_hv >= nsga_final and best_known > 0 and main_hv >= 0.995 * best_known),
    )


def _write_results(
    problem: DesignProblem,
    out_dir: Path,
    results: Mapping[str, SearchResult],
    summary: dict,
    outputs: Sequence[ProblemOutput],
    run: Mapping[str, Any],
) -> None:
    """Write the fronts, the outputs, ``summary.json`` and ``manifest.json`` into a folder
    that replaces ``out_dir`` as a whole; files an earlier run did not write are kept.
    ``run``: the ``config``, ``command``, ``git`` state and ``started`` time of the run."""
    config = run["config"]
    previous = _previous_files(out_dir)
    with replacing_folder(out_dir, keep=lambda name: name not in previous, before_swap=_BEFORE_SWAP) as staging:
        main = results[summary["method"]]
        written = [write_csv(staging / "pareto.csv", _front_table(problem, main))]
        for name in ("grid", "nsga2"):
            if name in results:
                written.append(write_csv(staging / f"pareto_{name}.csv", _front_table(problem, results[name])))
        for output in outputs:
            written += output(problem, results, summary, staging)
        summary["files"] = [p.name for p in written] + ["summary.json", "manifest.json"]
        if config is not None:
            summary["config"] = dict(config)
        write_json(staging / "summary.json", summary)
        data = build_manifest(
            dict(config) if config is not None else {"problem": problem.name},
            command=list(run["command"]) if run["command"] is not None else sys.argv,
            timings={"wall": time.perf_counter() - run["started"]},
            git=run["git"],
            extra={"kind": "optimize", "files": summary["files"]},
        )
        write_json(staging / "manifest.json", data)


def check_finite_objectives(problem: DesignProblem, method: str, result: SearchResult) -> None:
    """Refuse a search in which a design's objective came out non-finite (NaN or inf):
    `RunError` naming the method, the objective and the design. The front leaves such
    designs out (`spacearm.design.fronts.nondominated_mask`), so without this check they
    would vanish silently; no shipped problem has one anywhere in its box."""
    values = np.asarray(result.objectives, dtype=float)
    bad = np.argwhere(~np.isfinite(values))
    if bad.size:
        row, column = (int(i) for i in bad[0])
        design = np.asarray(result.designs, dtype=float)[row]
        where = ", ".join(f"{name} = {float(v):g}" for name, v in zip(problem.variable_names, design, strict=True))
        raise RunError(
            f"{problem.name}: objective '{problem.objectives[column]}' is {float(values[row, column])} for the "
            f"design {where} ({method} search; {len(bad)} non-finite values in {values.shape[0]} evaluated designs); "
            "nothing was written (check the problem's numbers" + ("" if x64_enabled() else ", or drop --float32") + ")"
        )


def _previous_files(out_dir: Path) -> set[str]:
    """The files an earlier ``spacearm optimize`` run listed in its manifest (top-level names)."""
    try:
        listed = json.loads((out_dir / "manifest.json").read_text())["files"]
    except (OSError, ValueError, KeyError, TypeError):
        return set()
    if not isinstance(listed, list):
        return set()
    return {name for name in listed if isinstance(name, str) and "/" not in name and not name.startswith(".")}
