"""Figures of a sweep (``spacearm sweep``): heatmaps or metric curves, and a report's figure
(Fig. 10 beside the Table 2 report)."""

from __future__ import annotations

import sys
from collections.abc import Mapping
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..io import save_figure
from ..studies.designs import Axis, axis_unit
from ..studies.metrics import metric_columns
from ..studies.spec import SweepSpec
from ..studies.table2 import B0, FIG10_RATIOS
from .maps import draw_fig10

__all__ = ["write_figures", "sweep_figures", "report_figures", "axis_label"]


def write_figures(spec: SweepSpec, out_dir: Path, table: Mapping[str, np.ndarray]) -> list[Path]:
    """Every figure of a sweep: :func:`sweep_figures` and :func:`report_figures`
    (a :data:`spacearm.studies.runner.SweepOutput`)."""
    return sweep_figures(spec, out_dir, table) + report_figures(spec, out_dir, table)


def report_figures(spec: SweepSpec, out_dir: Path, table: Mapping[str, np.ndarray]) -> list[Path]:
    """The figure of the sweep's report: ``fig10.png`` for ``report: table2`` (b0/B0 = 0, 1, 2)."""
    if spec.report != "table2":
        return []
    return [draw_fig10(
        Path(out_dir) / "fig10.png",
        [spec.robot.replace(base_attach=np.float64(B0 * r)) for r in FIG10_RATIOS],
        [f"b0/B0 = {r:g}" for r in FIG10_RATIOS],
    )]


def axis_label(axis: Axis) -> str:
    """The axis name with its unit: SI for absolute values, 'relative' otherwise."""
    unit = axis_unit(axis)
    if unit == "relative":
        return f"{axis.name} (relative)"
    return axis.name if unit == "1" else f"{axis.name} [{unit}]"


def sweep_figures(spec: SweepSpec, out_dir: Path, table: Mapping[str, np.ndarray]) -> list[Path]:
    """A heatmap per metric for 2-D product sweeps, line plots for 1-D and zipped sweeps
    (against the first axis); none for 3 or more product axes (grids.npz holds them).
    Columns that do not vary are left out of the figures."""
    values = {column: np.asarray(table[column]) for column in metric_columns(spec.metrics)}
    varying = {c: v for c, v in values.items() if np.ptp(v) > 1e-12 * max(1.0, float(np.max(np.abs(v))))} or values
    paths = []
    if spec.combine == "product" and len(spec.axes) == 2:
        ax0, ax1 = spec.axes
        for column, flat in varying.items():
            grid = flat.reshape(spec.shape)
            fig, ax = plt.subplots(figsize=(5.5, 4.2), constrained_layout=True)
            # Cells by index, labelled with the values, so uneven axes draw as even cells.
            mesh = ax.pcolormesh(np.arange(len(ax1.values)), np.arange(len(ax0.values)), grid, shading="nearest",
                                 cmap="viridis")
            fig.colorbar(mesh, ax=ax, label=column)
            if grid.size > 1 and np.ptp(grid) > 0 and min(grid.shape) > 1:
                contours = ax.contour(np.arange(len(ax1.values)), np.arange(len(ax0.values)), grid, colors="white",
                                      linewidths=0.6)
                ax.clabel(contours, fontsize=7, fmt="%.3g")
            for axis, set_ticks, set_labels in ((ax1, ax.set_xticks, ax.set_xticklabels),
                                                (ax0, ax.set_yticks, ax.set_yticklabels)):
                ticks = np.unique(np.linspace(0, len(axis.values) - 1, min(len(axis.values), 7)).round().astype(int))
                set_ticks(ticks)
                set_labels([f"{axis.values[t]:.3g}" for t in ticks])
            ax.set_xlabel(axis_label(ax1))
            ax.set_ylabel(axis_label(ax0))
            ax.set_title(f"{spec.name}: {column}")
            paths.append(save_figure(fig, out_dir / f"heatmap_{column}.png", dpi=130))
            plt.close(fig)
    elif len(spec.axes) == 1 or spec.combine == "zip":
        axis = spec.axes[0]
        fig, axes = plt.subplots(1, len(varying), figsize=(3.6 * len(varying), 3.2), constrained_layout=True,
                                 squeeze=False)
        for ax, (column, flat) in zip(axes[0], varying.items()):
            ax.plot(axis.values, flat, "o-")
            ax.set_xlabel(axis_label(axis) + (" (axes zipped)" if len(spec.axes) > 1 else ""))
            ax.set_ylabel(column)
            ax.grid(alpha=0.3)
        fig.suptitle(spec.name)
        paths.append(save_figure(fig, out_dir / "metrics.png", dpi=130))
        plt.close(fig)
    else:
        print(f"no figures for a {len(spec.axes)}-axis product sweep; grids.npz holds the arrays", file=sys.stderr)
    return paths
