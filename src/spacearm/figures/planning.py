"""Reaching point C (Umetani & Yoshida 1990, sec. 3.2, Fig. 5): base, arm and tip path.

``draw_reach`` draws a `ReachPlan` in the inertial frame (left:
the Maximum Reachable circle, the Straight-Path workspace before and after the
reorientation, the tip path by phase, the robot at the start, after the loop and at
the end; right: the base attitude and joint angles along the plan).
``animate_reach`` writes the same motion as a GIF. The registered figure "reach"
plans point C for the Table 1 robot from the Fig. 3 posture.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.animation import FuncAnimation, PillowWriter

from ..io import atomic_path, save_figure
from ..paper import straight_path_workspace, umetani1990
from ..planning import PHASE_LOOP, PHASE_REPOSITION, PHASE_STRAIGHT, plan_reach, reachable_bounds
from . import figure
from .robot import base_square, draw_planar_robot, robot_outline

DEG = np.pi / 180.0
# Fig. 3/5 initial posture and a point C for the Table 1 robot (our choice of point: the
# paper does not print coordinates for it).
FIG5_START = np.array([0.0, -60.0, 120.0]) * DEG
FIG5_POINT_C = np.array([-2.5, -3.0])


def _base_box(robot, base, phi0):
    """Corners of a square base drawn about its centroid, side b0 (at least 0.6 m)."""
    return base_square(base, phi0, max(0.5 * float(robot.base_attach), 0.3))


def draw_reach(robot, phi_start, plan, path: Path, *, n_directions: int = 180) -> Path:
    """Draw a reach plan (PNG, written atomically).

    Args:
        robot: the design.
        phi_start: ``(n+1,)`` start posture, rad.
        plan: a `ReachPlan` from ``plan_reach(robot, phi_start, ...)``.
        path: output PNG.
        n_directions: directions of the Straight-Path workspace boundaries drawn.
    """
    phi_start = np.asarray(phi_start, float)
    inner, outer = reachable_bounds(robot)
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13.0, 7.4), gridspec_kw={"width_ratios": [1.15, 1.0]})

    circle = np.linspace(0.0, 2.0 * np.pi, 361)
    ring = np.stack([np.cos(circle), np.sin(circle)], axis=-1)
    ax.plot(outer * ring[:, 0], outer * ring[:, 1], "k--", lw=1.0, label=f"Maximum Reachable (r = {outer:.3g} m)")
    if inner > 0:
        ax.plot(inner * ring[:, 0], inner * ring[:, 1], "k--", lw=1.0)

    boundary = np.asarray(straight_path_workspace(robot, phi_start, n_directions=n_directions))
    closed = np.vstack([boundary, boundary[:1]])
    ax.fill(closed[:, 0], closed[:, 1], color="0.6", alpha=0.18)
    ax.plot(closed[:, 0], closed[:, 1], color="0.45", lw=1.0, label="Straight-Path workspace at the start")
    loop_rows = np.flatnonzero(plan.phase == PHASE_LOOP)
    phi_after = plan.postures[loop_rows[-1]] if loop_rows.size else None
    if phi_after is not None:
        after = np.asarray(straight_path_workspace(robot, phi_after, n_directions=n_directions))
        after = np.vstack([after, after[:1]])
        ax.fill(after[:, 0], after[:, 1], color="tab:blue", alpha=0.08)
        ax.plot(
            after[:, 0], after[:, 1], color="tab:blue", lw=1.0, ls=":", label="Straight-Path workspace after the loop"
        )

    styles = {
        PHASE_REPOSITION: ("tab:purple", "tip: joint repositioning"),
        PHASE_LOOP: ("tab:orange", f"tip: reorientation loop ({plan.loops}x)"),
        PHASE_STRAIGHT: ("tab:green", "tip: straight path"),
    }
    for phase, (color, label) in styles.items():
        rows = np.flatnonzero(plan.phase == phase)
        if rows.size > 1:
            ax.plot(plan.tips[rows, 0], plan.tips[rows, 1], color=color, lw=1.2, label=label)

    draw_planar_robot(ax, robot, phi_start, "0.3", "robot at the start")
    if phi_after is not None:
        draw_planar_robot(ax, robot, phi_after, "tab:blue", "after the loop", alpha=0.8)
    draw_planar_robot(ax, robot, plan.end_posture, "tab:green", "at the end")
    ax.plot(*plan.target, marker="*", color="tab:red", ms=15, ls="none", label="target (point C)")
    ax.plot(0.0, 0.0, "k+", ms=10)
    ax.annotate("system centroid", (0.0, 0.0), xytext=(4, 4), textcoords="offset points", fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m), inertial frame")
    ax.set_ylabel("y (m)")
    title = {
        "straight": "straight tip path",
        "reorient": "reorientation loop, then straight path",
        "reposition": "joint repositioning, reorientation loop, straight path",
    }[plan.mode]
    ax.set_title(
        f"{robot.name}: {title}\nbase turned {np.degrees(plan.delta_phi0):.1f} deg, "
        f"joint travel {plan.joint_travel:.1f} rad, tip error {plan.error:.1e} m",
        fontsize=10,
    )
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=3, fontsize=7.5, frameon=False)
    lim = outer * 1.08
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.grid(alpha=0.25)

    sample = np.arange(len(plan.postures))
    ax2.plot(sample, np.degrees(plan.postures[:, 0]), color="k", lw=1.6, label="base attitude phi0")
    for j in range(1, plan.postures.shape[1]):
        ax2.plot(sample, np.degrees(plan.postures[:, j]), lw=1.0, label=f"joint phi{j}")
    for phase, (color, _) in styles.items():
        rows = np.flatnonzero(plan.phase == phase)
        if rows.size:
            ax2.axvspan(rows[0], rows[-1], color=color, alpha=0.08)
    ax2.set_xlabel("sample along the plan (loop samples, then straight-path samples)")
    ax2.set_ylabel("angle (deg)")
    ax2.set_title("attitude and joint history (shaded: phase)", fontsize=10)
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.25)
    fig.tight_layout()
    try:
        return save_figure(fig, Path(path), dpi=130, bbox_inches="tight")
    finally:
        plt.close(fig)


def animate_reach(robot, plan, path: Path, *, frames: int = 120, fps: int = 20) -> Path:
    """The plan as a GIF (Pillow writer): the robot and the tip trace in the inertial frame."""
    _, outer = reachable_bounds(robot)
    rows = np.unique(np.linspace(0, len(plan.postures) - 1, frames).round().astype(int))
    fig, ax = plt.subplots(figsize=(5.5, 5.5))
    circle = np.linspace(0.0, 2.0 * np.pi, 361)
    ax.plot(outer * np.cos(circle), outer * np.sin(circle), "k--", lw=0.8)
    ax.plot(*plan.target, marker="*", color="tab:red", ms=13, ls="none")
    (trace,) = ax.plot([], [], color="tab:orange", lw=1.0)
    (arm,) = ax.plot([], [], "-o", color="tab:blue", lw=2.2, ms=3)
    (box,) = ax.plot([], [], color="tab:blue", lw=1.0)
    ax.set_aspect("equal")
    lim = outer * 1.08
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_xlabel("x (m), inertial frame")
    ax.set_ylabel("y (m)")

    def update(index):
        row = rows[index]
        base, chain = robot_outline(robot, plan.postures[row])
        points = np.vstack([base, chain])
        arm.set_data(points[:, 0], points[:, 1])
        corners = _base_box(robot, base, plan.postures[row, 0])
        box.set_data(corners[:, 0], corners[:, 1])
        trace.set_data(plan.tips[: row + 1, 0], plan.tips[: row + 1, 1])
        ax.set_title(f"phi0 = {np.degrees(plan.postures[row, 0]):.1f} deg", fontsize=10)
        return arm, box, trace

    animation = FuncAnimation(fig, update, frames=len(rows), blit=False)
    path = Path(path)
    try:
        # Pillow picks the format from the name: the temporary keeps the .gif suffix.
        with atomic_path(path, keep_suffix=True) as temporary:
            animation.save(temporary, writer=PillowWriter(fps=fps))
    finally:
        plt.close(fig)
    return path


@figure("reach")
def reach_figure(out_dir: Path) -> list[Path]:
    """Point C of Fig. 5 for the Table 1 robot: reorientation loop, then a straight path."""
    robot = umetani1990()
    plan = plan_reach(robot, FIG5_START, FIG5_POINT_C)
    return [draw_reach(robot, FIG5_START, plan, Path(out_dir) / "reach.png")]
