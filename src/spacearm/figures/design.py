"""Figures of a design optimization (``spacearm optimize``): the front, the designs, convergence."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import matplotlib.pyplot as plt

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
    "nsga2": dict(color="tab:blue", label="NSGA-II (pymoo)"),
    "grid": dict(color="0.35", label="dense grid"),
}


def plot_results(problem: DesignProblem, results: Mapping[str, SearchResult], summary: Mapping,
                 out_dir: Path) -> list[Path]:
    """The front in objective space, the front designs in variable space, convergence.

    Drawn for two objectives (``front.png``, ``designs.png``, ``convergence.png``); for
    more, ``convergence.png`` only. Fits `spacearm.design.run.ProblemOutput`.
    """
    if len(problem.objectives) != 2:
        return [_convergence(problem, results, summary, out_dir)]
    written = []
    names = problem.objectives
    # 1. Objective space.
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    if "grid" in results:
        grid = results["grid"]
        step = max(1, grid.objectives.shape[0] // 6000)
        ax.scatter(grid.objectives[::step, 0], grid.objectives[::step, 1], s=2, color="0.85",
                   label=f"grid designs ({grid.evaluations}, every {step}th shown)", rasterized=True)
    for method in ("grid", "nsga2", "gradient"):
        if method in results:
            result = results[method]
            front = result.objectives[result.front()]
            hv = result.checkpoints[-1]["hypervolume"]
            style = dict(_STYLE[method])
            label = f"{style.pop('label')} front: {front.shape[0]} pts, HV {hv:.6f}"
            if method == "gradient":
                ax.plot(front[:, 0], front[:, 1], ".", ms=3, label=label, **style)
            elif method == "grid":
                ax.plot(front[:, 0], front[:, 1], "-", lw=1.0, label=label, **style)
            else:
                ax.plot(front[:, 0], front[:, 1], "x", ms=4, label=label, **style)
    ax.set_xlabel(_LABELS.get(names[0], names[0]))
    ax.set_ylabel(_LABELS.get(names[1], names[1]))
    ax.set_title(f"{problem.name}: Pareto front (both maximized, reference point {tuple(problem.reference_point)})")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    written.append(save_figure(fig, out_dir / "front.png", dpi=130))
    plt.close(fig)

    # 2. Variable space.
    gradient = results["gradient"]
    index = gradient.front()
    designs, objectives = gradient.designs[index], gradient.objectives[index]
    d = len(problem.variables)
    if d == 2:
        fig, ax = plt.subplots(figsize=(7.0, 5.5))
        if "grid" in results:
            gf = results["grid"].front()
            ax.plot(results["grid"].designs[gf, 0], results["grid"].designs[gf, 1], "s", ms=3, mfc="none",
                    color="0.6", label="grid front designs")
        points = ax.scatter(designs[:, 0], designs[:, 1], c=objectives[:, 1], s=8, cmap="viridis",
                            label="gradient front designs")
        fig.colorbar(points, ax=ax, label=_LABELS.get(names[1], names[1]))
        for v, set_limits in zip(problem.variables, (ax.set_xlim, ax.set_ylim)):
            pad = 0.02 * (v.upper - v.lower)  # designs on a bound stay visible
            set_limits(v.lower - pad, v.upper + pad)
        ax.set_xlabel(_UNITS.get(problem.variables[0].name, problem.variables[0].name))
        ax.set_ylabel(_UNITS.get(problem.variables[1].name, problem.variables[1].name))
        ax.legend(fontsize=8, loc="upper right")
        ax.grid(alpha=0.3)
        ax.set_title("Pareto-optimal designs in variable space (the whole box shown)")
    else:
        cols = 3
        rows = int(math.ceil(d / cols))
        fig, axes = plt.subplots(rows, cols, figsize=(4.0 * cols, 3.0 * rows), squeeze=False)
        for j, variable in enumerate(problem.variables):
            ax = axes[j // cols][j % cols]
            if "nsga2" in results:
                nf = results["nsga2"].front()
                ax.plot(results["nsga2"].objectives[nf, 1], results["nsga2"].designs[nf, j], "x", ms=3,
                        color=_STYLE["nsga2"]["color"], label="NSGA-II front")
            ax.plot(objectives[:, 1], designs[:, j], ".", ms=3, color=_STYLE["gradient"]["color"],
                    label="gradient front")
            ax.set_ylim(variable.lower, variable.upper)
            ax.set_xlabel(_LABELS.get(names[1], names[1]), fontsize=8)
            ax.set_ylabel(_UNITS.get(variable.name, variable.name))
            ax.grid(alpha=0.3)
            if j == 0:
                ax.legend(fontsize=7)
        for j in range(d, rows * cols):
            axes[j // cols][j % cols].axis("off")
        fig.suptitle("Pareto-optimal designs: each variable (full bound range) along the front")
    fig.tight_layout()
    written.append(save_figure(fig, out_dir / "designs.png", dpi=130))
    plt.close(fig)

    written.append(_convergence(problem, results, summary, out_dir))
    return written


def _convergence(problem, results: Mapping[str, SearchResult], summary: Mapping, out_dir: Path) -> Path:
    """Archive hypervolume against evaluations and run time, per method."""
    fig, (ax_e, ax_t) = plt.subplots(1, 2, figsize=(12.0, 4.8))
    best = max(r.checkpoints[-1]["hypervolume"] for r in results.values())
    for method in ("nsga2", "gradient"):
        if method in results:
            cp = results[method].checkpoints
            ev = [c["evaluations"] for c in cp]
            sec = [c["seconds"] for c in cp]
            hv = [c["hypervolume"] / best for c in cp]
            ax_e.plot(ev, hv, "-", **_STYLE[method])
            ax_t.plot(sec, hv, "-", **_STYLE[method])
    if "grid" in results:
        nested = summary["methods"]["grid"].get("nested_grids", [])
        ev = [r["evaluations"] for r in nested]
        hv = [r["hypervolume"] / best for r in nested]
        sec = [r["seconds"] for r in nested]
        ax_e.plot(ev, hv, "o--", color="0.35", label="nested grids (coarse to dense)")
        ax_t.plot(sec, hv, "o--", color="0.35", label="nested grids (time per design x size)")
        target = TARGET_FRACTION * results["grid"].checkpoints[-1]["hypervolume"] / best
        for ax in (ax_e, ax_t):
            ax.axhline(target, color="k", lw=0.8, ls=":", label=f"target: {TARGET_FRACTION:.1%} of dense grid")
    for ax in (ax_e, ax_t):
        ax.set_xscale("log")
        ax.set_ylim(0.98, 1.0015)
        ax.set_ylabel("archive hypervolume / best final")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8, loc="lower right")
    ax_e.set_xlabel("objective evaluations (value + gradient counts as one)")
    ax_t.set_xlabel("run time [s] (compile excluded)")
    fig.suptitle(f"{problem.name}: convergence")
    fig.tight_layout()
    path = save_figure(fig, out_dir / "convergence.png", dpi=130)
    plt.close(fig)
    return path
