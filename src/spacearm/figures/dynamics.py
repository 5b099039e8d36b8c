"""Figures of a simulated run (`spacearm.simulate`, ``spacearm simulate``).

One figure, three panels over time: the joints, the bus attitude as the rotation from the
start (rotation-vector components, bus axes at the start: one angle about z for a planar
bus, three for a spatial one) and the bus angular velocity (bus axes) with its magnitude.
The caller passes plain arrays, so the figure serves every robot family.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..io import save_figure

__all__ = ["draw_simulation"]


def draw_simulation(
    path: str | Path,
    time,
    joints,
    attitude_change,
    bus_rate,
    *,
    joint_labels: Sequence[str],
    prismatic,
    axis_labels: Sequence[str],
    stop_time: float | None = None,
    stop_label: str = "",
    title: str = "",
) -> Path:
    """Write the three-panel figure of a run.

    Args:
        path: the image file (PNG or SVG by its suffix).
        time: ``(k,)`` sample times, s.
        joints: ``(k, n)`` joints, rad (m where ``prismatic``); drawn in degrees (m).
        attitude_change: ``(k, d)`` the bus rotation from the first sample as a rotation
            vector, rad, components about ``axis_labels``; drawn in degrees.
        bus_rate: ``(k, d)`` the bus angular velocity, rad/s, bus axes; drawn in deg/s.
        joint_labels: ``n`` names of the joints.
        prismatic: ``(n,)`` booleans, the joints in m.
        axis_labels: ``d`` names of the rotation axes (e.g. ``("x", "y", "z")``).
        stop_time: where an event stopped the run, s (a dashed line), or ``None``.
        stop_label: the event's name, shown beside the line.
        title: the figure's title.
    """
    time = np.asarray(time, float)
    joints = np.asarray(joints, float)
    prismatic = np.asarray(prismatic, bool)
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 8.0), sharex=True, constrained_layout=True)
    for j, label in enumerate(joint_labels):
        values = joints[:, j] if prismatic[j] else np.degrees(joints[:, j])
        axes[0].plot(time, values, lw=1.2, label=f"{label} (m)" if prismatic[j] else label)
    axes[0].set_ylabel("joints (deg; m prismatic)")
    axes[0].legend(fontsize=7, ncol=min(len(joint_labels), 4), loc="best")
    change = np.degrees(np.asarray(attitude_change, float))
    rate = np.degrees(np.asarray(bus_rate, float))
    for i, axis in enumerate(axis_labels):
        axes[1].plot(time, change[:, i], lw=1.2, label=f"about {axis}")
        axes[2].plot(time, rate[:, i], lw=1.2, label=f"w_{axis}")
    if len(axis_labels) > 1:
        axes[2].plot(time, np.linalg.norm(rate, axis=1), "k--", lw=1.0, label="|w|")
    axes[1].set_ylabel("bus rotation from start (deg)")
    axes[2].set_ylabel("bus angular velocity (deg/s, bus axes)")
    axes[2].set_xlabel("time (s)")
    for ax in axes[1:]:
        ax.legend(fontsize=7, loc="best")
    for ax in axes:
        ax.grid(True, lw=0.4, alpha=0.5)
        if stop_time is not None:
            ax.axvline(stop_time, color="C3", ls=":", lw=1.2)
    if stop_time is not None:
        axes[0].annotate(
            f"stopped: {stop_label}", (stop_time, 1.0), xycoords=("data", "axes fraction"), color="C3", fontsize=8
        )
    if title:
        fig.suptitle(title, fontsize=10)
    try:
        return save_figure(fig, Path(path), dpi=130)
    finally:
        plt.close(fig)
