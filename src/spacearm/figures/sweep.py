"""Figures of a sweep (``spacearm sweep``): heatmaps or metric curves, and a report's figure
(Fig. 10 beside the Table 2 report)."""

from __future__ import annotations

import re
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

__all__ = ["COLUMN_LABELS", "axis_label", "column_label", "report_figures", "sweep_figures", "write_figures"]

# Table columns in words, with their units: the labels of the figures.
COLUMN_LABELS: dict[str, str] = {
    "wbar": "w-bar, mean w*/L² over the reachable area (eq. 12)",
    "S_M": "S_M, Maximum Reachable area / πL²",
    "S_G": "S_G, Guaranteed Workspace area / πL²",
    "K0_m": "K0, m",
    "R_attitude_m": "Attitude-Constraint radius, m",
    "R_max_m": "Maximum Reachable radius, m",
    "R_guaranteed_m": "Guaranteed Workspace radius, m",
    "R_inner_m": "inner radius of the reachable shell, m",
    "R_path_independent_m": "path-independent workspace radius, m",
    "L_m": "reach L, m",
    "S_fixed_vehicle": "Fixed-Vehicle area / πL²",
    "S_attitude_constraint": "Attitude-Constraint area / πL²",
    "S_maximum_reachable": "Maximum Reachable area / πL²",
    "S_guaranteed": "Guaranteed area / πL²",
    "eq9_holds": "eq. 9 holds (1 yes, 0 no)",
    "S_straight": "Straight-Path area / πL²",
    "w_star_m3": "w* at the posture, m³",
    "inverse_condition": "1/κ(J*_v) at the posture",
    "C_w_fro": "‖C_w‖_F at the posture, rad/rad",
    "w_avg_m3": "mean w* over the joint box, m³",
    "gci": "global conditioning index, mean 1/κ(J*_v)",
    "C_w_avg": "base disturbance, mean ‖C_w‖_F, rad/rad",
    "w_d_avg": "mean dynamic manipulability w_d",
    "peak_joint_torque_Nm": "peak joint torque along the task, N m",
    "peak_held_force_N": "peak force holding the bus along the task, N",
    "peak_held_torque_Nm": "peak torque holding the bus along the task, N m",
    "peak_wheel_momentum_Nms": "peak reaction-wheel momentum along the task, N m s",
    "peak_wheel_torque_Nm": "peak reaction-wheel torque along the task, N m",
    "virtual_mass_kg": "mean virtual mass of the tip, kg",
    "bus_rate_jump_radps_per_Ns": "mean bus rate jump per tip impulse, rad/s per N s",
    "capture_bus_rate_radps": "mean bus rate after the reference capture, rad/s",
}


def column_label(column: str) -> str:
    """A table column in words with its unit (the column name itself when it has no entry);
    a per-tip column (``w_avg_m3[left/tool0]``) names its tip, and an average's
    ``_samples`` column counts the postures behind it."""
    if column.endswith("_samples"):
        return f"postures averaged, {column_label(column[: -len('_samples')])}"
    match = re.fullmatch(r"(\w+)\[(.+)\]", column)
    if match and match.group(1) in COLUMN_LABELS:
        return f"{COLUMN_LABELS[match.group(1)]}, tip {match.group(2)}"
    return COLUMN_LABELS.get(column, column)


def _file_part(column: str) -> str:
    """A column as part of a file name: letters, digits, ``_`` and ``.`` (a tip's ``left/tool0``
    becomes ``left_tool0``)."""
    return re.sub(r"[^A-Za-z0-9_.]+", "_", column).strip("_")


def write_figures(spec: SweepSpec, out_dir: Path, table: Mapping[str, np.ndarray]) -> list[Path]:
    """Every figure of a sweep: `sweep_figures` and `report_figures`
    (a `spacearm.studies.runner.SweepOutput`)."""
    return sweep_figures(spec, out_dir, table) + report_figures(spec, out_dir, table)


def report_figures(spec: SweepSpec, out_dir: Path, table: Mapping[str, np.ndarray]) -> list[Path]:
    """The figure of the sweep's report: ``fig10.png`` for ``report: table2`` (b0/B0 = 0, 1, 2)."""
    if spec.report != "table2":
        return []
    return [
        draw_fig10(
            Path(out_dir) / "fig10.png",
            [spec.robot.replace(base_attach=np.float64(B0 * r)) for r in FIG10_RATIOS],
            [f"b0/B0 = {r:g}" for r in FIG10_RATIOS],
        )
    ]


def _fit_panel(label: str, width: int = 40) -> str:
    """An axis label on two lines (at its first ", ") when it is too long for a 3.6-inch panel,
    where it would run into the next panel's."""
    name, comma, rest = label.partition(", ")
    return f"{name},\n{rest}" if comma and len(label) > width else label


def axis_label(axis: Axis) -> str:
    """The axis name, the design field it sets and its unit: SI for absolute values,
    'relative to the base design' otherwise (``x = mount.xyz[0], m``)."""
    unit = axis_unit(axis)
    name = axis.name if axis.name == axis.field else f"{axis.name} = {axis.field}"
    if unit == "relative":
        return f"{name}, relative to the base design"
    return name if unit == "1" else f"{name}, {unit}"


def sweep_figures(spec: SweepSpec, out_dir: Path, table: Mapping[str, np.ndarray]) -> list[Path]:
    """A heatmap per metric for 2-D product sweeps, line plots for 1-D and zipped sweeps
    (against the first axis); none for 3 or more product axes (grids.npz holds them).
    Columns that do not vary are left out of the figures."""
    columns = metric_columns(spec.metrics)
    # An `_error` column is drawn with its value (bars, a band, or its largest value in the
    # title), not as a metric of its own: a change within the errors then looks like one.
    # (A `_samples` column, the postures an average used, is in the table, not drawn.)
    errors = {c[: -len("_error")]: np.asarray(table[c]) for c in columns if c.endswith("_error")}
    values = {column: np.asarray(table[column]) for column in columns if not column.endswith(("_error", "_samples"))}
    varying = {c: v for c, v in values.items() if np.ptp(v) > 1e-12 * max(1.0, float(np.max(np.abs(v))))} or values
    paths = []
    if spec.combine == "product" and len(spec.axes) == 2:
        ax0, ax1 = spec.axes
        for column, flat in varying.items():
            grid = flat.reshape(spec.shape)
            fig, ax = plt.subplots(figsize=(5.5, 4.2), constrained_layout=True)
            # Cells by index, labelled with the values, so uneven axes draw as even cells.
            mesh = ax.pcolormesh(
                np.arange(len(ax1.values)), np.arange(len(ax0.values)), grid, shading="nearest", cmap="viridis"
            )
            fig.colorbar(mesh, ax=ax, label=column_label(column))
            if grid.size > 1 and np.ptp(grid) > 0 and min(grid.shape) > 1:
                contours = ax.contour(
                    np.arange(len(ax1.values)), np.arange(len(ax0.values)), grid, colors="white", linewidths=0.6
                )
                ax.clabel(contours, fontsize=7, fmt="%.3g")
            for axis, set_ticks, set_labels in (
                (ax1, ax.set_xticks, ax.set_xticklabels),
                (ax0, ax.set_yticks, ax.set_yticklabels),
            ):
                ticks = np.unique(np.linspace(0, len(axis.values) - 1, min(len(axis.values), 7)).round().astype(int))
                set_ticks(ticks)
                set_labels([f"{axis.values[t]:.3g}" for t in ticks])
            ax.set_xlabel(axis_label(ax1))
            ax.set_ylabel(axis_label(ax0))
            title = f"{spec.name}: {column_label(column)}"
            if column in errors:
                title += f"\nstandard error ≤ {np.max(errors[column]):.2g} (the colour range spans {np.ptp(grid):.2g})"
            ax.set_title(title, fontsize=9)
            paths.append(save_figure(fig, out_dir / f"heatmap_{_file_part(column)}.png", dpi=130))
            plt.close(fig)
    elif len(spec.axes) == 1 or spec.combine == "zip":
        axis = spec.axes[0]
        fig, axes = plt.subplots(
            1, len(varying), figsize=(3.6 * len(varying), 3.2), constrained_layout=True, squeeze=False
        )
        x = np.asarray(axis.values, float)
        for ax, (column, flat) in zip(axes[0], varying.items(), strict=False):
            if column in errors:
                error = errors[column]
                ax.fill_between(
                    x, flat - 2 * error, flat + 2 * error, color="C0", alpha=0.25, lw=0, label="± 2 standard errors"
                )
                ax.errorbar(x, flat, yerr=2 * error, fmt="o-", color="C0", ms=4, capsize=3, label="estimate")
                ax.legend(fontsize=7)
            else:
                ax.plot(x, flat, "o-", ms=4)
            ax.set_xlabel(_fit_panel(axis_label(axis) + (" (axes zipped)" if len(spec.axes) > 1 else "")))
            ax.set_ylabel(column_label(column), fontsize=8)
            ax.grid(alpha=0.3)
        fig.suptitle(spec.name)
        paths.append(save_figure(fig, out_dir / "metrics.png", dpi=130))
        plt.close(fig)
    else:
        print(f"no figures for a {len(spec.axes)}-axis product sweep; grids.npz holds the arrays", file=sys.stderr)
    return paths
