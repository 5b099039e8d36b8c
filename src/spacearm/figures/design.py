"""Figures of a design optimization (``spacearm optimize``): the front, the designs, convergence.

Two objectives: the front in objective space and the designs in variable space. Three or
more: pairwise projections of the front, each colored by a third objective
(``front.png``), and a parallel-coordinates plot of the front's designs and objectives
(``designs.png``). Always: the archive hypervolume against evaluations and against wall
time, compile included (``convergence.png``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..design import TARGET_FRACTION, DesignProblem, SearchResult
from ..io import save_figure

__all__ = ["plot_results"]

_LABELS = {
    "wbar": r"$\bar{w}$, average manipulability (eq. 12, $w^*/L^2$)",
    "S_G": r"$\hat{S}_G$, guaranteed workspace ($/\pi L^2$)",
    "S_M": r"$\hat{S}_M$, maximum reachable space ($/\pi L^2$)",
}
_UNITS = {"b0": "b0 [m]"}
_STYLE = {
    "gradient": dict(color="tab:red", label="gradient (Chebyshev, vmapped Adam)"),
    "hybrid": dict(color="tab:red", label="hybrid (evolution + hypervolume gradient)"),
    "nsga2": dict(color="tab:blue", label="NSGA-II (pymoo)"),
    "grid": dict(color="0.35", label="dense grid"),
}


def plot_results(
    problem: DesignProblem, results: Mapping[str, SearchResult], summary: Mapping, out_dir: Path
) -> list[Path]:
    """The front in objective space, the front designs in variable space, convergence.

    ``front.png``, ``designs.png``, ``convergence.png`` (see the module docstring). Fits
    `spacearm.design.run.ProblemOutput`.
    """
    main = summary.get("method", "gradient")
    if len(problem.objectives) != 2:
        return [
            _pairwise_front(problem, results, summary, out_dir, main),
            _parallel_coordinates(problem, results[main], out_dir),
            _convergence(problem, results, summary, out_dir),
        ]
    return [
        _two_objective_front(problem, results, summary, out_dir, main),
        _front_designs(problem, results, out_dir, main),
        _convergence(problem, results, summary, out_dir),
    ]


def _two_objective_front(
    problem, results: Mapping[str, SearchResult], summary: Mapping, out_dir: Path, main: str
) -> Path:
    """Two objectives: every method's front (and a thinned cloud of the grid's designs)."""
    names = problem.objectives
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    if "grid" in results:
        grid = results["grid"]
        step = max(1, grid.objectives.shape[0] // 6000)
        ax.scatter(
            grid.objectives[::step, 0],
            grid.objectives[::step, 1],
            s=2,
            color="0.85",
            label=f"grid designs ({grid.evaluations}, every {step}th shown)",
            rasterized=True,
        )
    marker = {main: dict(fmt=".", ms=3), "grid": dict(fmt="-", lw=1.0), "nsga2": dict(fmt="x", ms=4)}
    for method in ("grid", "nsga2", main):
        if method in results:
            result = results[method]
            front = result.objectives[result.front()]
            hv = result.checkpoints[-1]["hypervolume"]
            style = dict(_STYLE[method])
            label = f"{style.pop('label')} front: {front.shape[0]} pts, HV {hv:.6f}"
            line = dict(marker[method])
            ax.plot(front[:, 0], front[:, 1], line.pop("fmt"), **line, label=label, **style)
    ax.set_xlabel(_LABELS.get(names[0], names[0]))
    ax.set_ylabel(_LABELS.get(names[1], names[1]))
    reference = tuple(round(r, 6) for r in summary["reference_point"])
    ax.set_title(f"{problem.name}: Pareto front (both maximized, reference point {reference})")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    path = save_figure(fig, out_dir / "front.png", dpi=130)
    plt.close(fig)
    return path


def _front_designs(problem, results: Mapping[str, SearchResult], out_dir: Path, main: str) -> Path:
    """Two objectives: the main search's front designs in variable space."""
    if len(problem.variables) == 2:
        fig = _designs_in_the_box(problem, results, main)
    else:
        fig = _designs_by_variable(problem, results, main)
    fig.tight_layout()
    path = save_figure(fig, out_dir / "designs.png", dpi=130)
    plt.close(fig)
    return path


def _designs_in_the_box(problem, results: Mapping[str, SearchResult], main: str):
    """Two variables: the front designs in the whole box, colored by the second objective."""
    names = problem.objectives
    result = results[main]
    index = result.front()
    designs, objectives = result.designs[index], result.objectives[index]
    fig, ax = plt.subplots(figsize=(7.0, 5.5))
    if "grid" in results:
        gf = results["grid"].front()
        ax.plot(
            results["grid"].designs[gf, 0],
            results["grid"].designs[gf, 1],
            "s",
            ms=3,
            mfc="none",
            color="0.6",
            label="grid front designs",
        )
    points = ax.scatter(
        designs[:, 0], designs[:, 1], c=objectives[:, 1], s=8, cmap="viridis", label=f"{main} front designs"
    )
    fig.colorbar(points, ax=ax, label=_LABELS.get(names[1], names[1]))
    for v, set_limits in zip(problem.variables, (ax.set_xlim, ax.set_ylim), strict=False):
        pad = 0.02 * (v.upper - v.lower)  # designs on a bound stay visible
        set_limits(v.lower - pad, v.upper + pad)
    ax.set_xlabel(_UNITS.get(problem.variables[0].name, problem.variables[0].name))
    ax.set_ylabel(_UNITS.get(problem.variables[1].name, problem.variables[1].name))
    ax.legend(fontsize=8, loc="upper right")
    ax.grid(alpha=0.3)
    ax.set_title("Pareto-optimal designs in variable space (the whole box shown)")
    return fig


def _designs_by_variable(problem, results: Mapping[str, SearchResult], main: str):
    """More variables: each variable (its whole bound range) along the front, one panel each."""
    names = problem.objectives
    result = results[main]
    index = result.front()
    designs, objectives = result.designs[index], result.objectives[index]
    d, cols = len(problem.variables), 3
    rows = int(math.ceil(d / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4.0 * cols, 3.0 * rows), squeeze=False)
    for j, variable in enumerate(problem.variables):
        ax = axes[j // cols][j % cols]
        if "nsga2" in results:
            nf = results["nsga2"].front()
            ax.plot(
                results["nsga2"].objectives[nf, 1],
                results["nsga2"].designs[nf, j],
                "x",
                ms=3,
                color=_STYLE["nsga2"]["color"],
                label="NSGA-II front",
            )
        ax.plot(objectives[:, 1], designs[:, j], ".", ms=3, color=_STYLE[main]["color"], label=f"{main} front")
        ax.set_ylim(variable.lower, variable.upper)
        ax.set_xlabel(_LABELS.get(names[1], names[1]), fontsize=8)
        ax.set_ylabel(_UNITS.get(variable.name, variable.name))
        ax.grid(alpha=0.3)
        if j == 0:
            ax.legend(fontsize=7)
    for j in range(d, rows * cols):
        axes[j // cols][j % cols].axis("off")
    fig.suptitle("Pareto-optimal designs: each variable (full bound range) along the front")
    return fig


def _pairwise_front(problem, results: Mapping[str, SearchResult], summary: Mapping, out_dir: Path, main: str) -> Path:
    """Every pair of objectives, the main search's front colored by a third objective,
    NSGA-II's front as grey crosses."""
    names = problem.objectives
    m = len(names)
    pairs = [(i, j) for i in range(m) for j in range(i + 1, m)]
    fig, axes = plt.subplots(1, len(pairs), figsize=(5.0 * len(pairs), 4.4), squeeze=False)
    result = results[main]
    front = result.objectives[result.front()]
    for ax, (i, j) in zip(axes[0], pairs, strict=False):
        third = next(k for k in range(m) if k not in (i, j))
        if "nsga2" in results:
            other = results["nsga2"].objectives[results["nsga2"].front()]
            ax.plot(
                other[:, i], other[:, j], "x", ms=3, color="0.6", zorder=1, label=f"NSGA-II front ({other.shape[0]})"
            )
        points = ax.scatter(  # above the crosses (a line's default z-order is above a scatter's)
            front[:, i],
            front[:, j],
            c=front[:, third],
            s=9,
            cmap="viridis",
            zorder=2,
            label=f"{main} front ({front.shape[0]})",
        )
        ax.locator_params(nbins=4)  # a narrow front's long tick labels would overlap
        fig.colorbar(points, ax=ax, label=_LABELS.get(names[third], names[third]))
        ax.set_xlabel(_LABELS.get(names[i], names[i]))
        ax.set_ylabel(_LABELS.get(names[j], names[j]))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="lower left")
    fig.suptitle(f"{problem.name}: Pareto front, pairwise projections (all maximized)")
    fig.tight_layout()
    path = save_figure(fig, out_dir / "front.png", dpi=130)
    plt.close(fig)
    return path


def _parallel_coordinates(problem, result: SearchResult, out_dir: Path) -> Path:
    """The front's designs: every variable (scaled to its bounds) and objective (scaled to
    the front's range), one line per design, colored by the first objective."""
    index = result.front()
    designs, objectives = result.designs[index], result.objectives[index]
    scaled_x = (designs - problem.lower) / (problem.upper - problem.lower)
    span = np.ptp(objectives, axis=0)
    scaled_f = (objectives - objectives.min(axis=0)) / np.where(span > 0, span, 1.0)
    columns = np.concatenate([scaled_x, scaled_f], axis=1)
    labels = list(problem.variable_names) + list(problem.objectives)
    fig, ax = plt.subplots(figsize=(max(8.0, 1.1 * len(labels)), 4.8))
    colors = plt.get_cmap("viridis")(scaled_f[:, 0])
    order = np.argsort(scaled_f[:, 0])
    for k in order:
        ax.plot(np.arange(len(labels)), columns[k], "-", lw=0.7, alpha=0.6, color=colors[k])
    ax.axvline(len(problem.variable_names) - 0.5, color="k", lw=0.8)
    ax.set_xticks(np.arange(len(labels)))
    ax.set_xticklabels(labels, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel("variables: share of the bounds; objectives: share of the front's range")
    ax.set_title(f"{problem.name}: {index.size} Pareto-optimal designs, colored by {problem.objectives[0]}")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path = save_figure(fig, out_dir / "designs.png", dpi=130)
    plt.close(fig)
    return path


def _convergence(problem, results: Mapping[str, SearchResult], summary: Mapping, out_dir: Path) -> Path:
    """Archive hypervolume against evaluations and against wall time (compile included)."""
    fig, (ax_e, ax_t) = plt.subplots(1, 2, figsize=(12.0, 4.8))
    best = summary["best_known_hypervolume"] or max(r.checkpoints[-1]["hypervolume"] for r in results.values())
    if not best > 0:  # no design dominates the reference point: the ratios would be 0 / 0
        best = 1.0
    lowest = 1.0
    for method in ("nsga2", "gradient", "hybrid"):
        if method in results:
            result = results[method]
            cp = result.checkpoints
            ev = [c["evaluations"] for c in cp]
            sec = [result.compile_seconds + c["seconds"] for c in cp]
            hv = [c["hypervolume"] / best for c in cp]
            lowest = min(lowest, hv[len(hv) // 4] if hv else 1.0)
            ax_e.plot(ev, hv, "-", **_STYLE[method])
            ax_t.plot(sec, hv, "-", **_STYLE[method])
    if "grid" in results:
        grid = results["grid"]
        nested = summary["methods"]["grid"].get("nested_grids", [])
        ev = [r["evaluations"] for r in nested]
        hv = [r["hypervolume"] / best for r in nested]
        sec = [grid.compile_seconds + r["seconds"] for r in nested]
        ax_e.plot(ev, hv, "o--", color="0.35", label="nested grids (coarse to dense)")
        ax_t.plot(sec, hv, "o--", color="0.35", label="nested grids (time per design x size)")
        target = TARGET_FRACTION * grid.checkpoints[-1]["hypervolume"] / best
        for ax in (ax_e, ax_t):
            ax.axhline(target, color="k", lw=0.8, ls=":", label=f"target: {TARGET_FRACTION:.1%} of dense grid")
    against = summary.get("against_nsga2")
    if against:
        level = against["nsga2_final_hypervolume"] / best
        for ax in (ax_e, ax_t):
            ax.axhline(level, color="tab:blue", lw=0.8, ls=":", label="NSGA-II's final hypervolume")
    for ax in (ax_e, ax_t):
        ax.set_xscale("log")
        ax.set_ylim(max(0.9, min(lowest, 0.995)), 1.0005)
        ax.set_ylabel("archive hypervolume / best known")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8, loc="lower right")
    ax_e.set_xlabel("objective evaluations (value + gradient counts as one)")
    ax_t.set_xlabel("wall time [s], compile included")
    fig.suptitle(f"{problem.name}: convergence")
    fig.tight_layout()
    path = save_figure(fig, out_dir / "convergence.png", dpi=130)
    plt.close(fig)
    return path
