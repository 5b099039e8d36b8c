"""Manipulability figures of section 4.2 and 5: Fig. 6, 7, 8 and 10.

All maps are drawn in the robot frame Sigma_R (origin at joint 1, x along the base),
with the base attitude phi0 = 0, so the inertial axes of the ellipses coincide with
the robot frame's. Contour labels are w*/L^2 x 40, as printed in the paper.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Ellipse

from ..io import save_figure
from ..kinematics import manipulability
from ..paper import inverse_kinematics, manipulability_ellipse, robot_frame_tip_position, umetani1990, workspace_map
from ..studies.table2_readings import Derivation, derivation_coefficients
from . import figure

ELLIPSE_SCALE = 0.2  # drawn semi-axis per unit singular value of J*, m / (m/rad)
CONTOUR_LEVELS_X40 = np.arange(1, 11)  # w*/L^2 x 40 = 1 .. 10


def _plt():
    return plt


def _save(fig, path: Path, *, tight: bool = True) -> Path:
    """Save at 130 dpi; ``tight`` crops to the drawn content, at the price of a second draw."""
    save_figure(fig, Path(path), dpi=130, bbox_inches="tight" if tight else None)
    _plt().close(fig)
    return path


def _reach(robot) -> float:
    """L = the sum of the arm link lengths, on the host (``robot.reach`` of a concrete
    design would compile an eager program that the compile cache never keeps)."""
    return float(np.sum(np.asarray(robot.link_length)))


def _table1(ratio: float = 1.0):
    robot = umetani1990()
    return robot.replace(base_attach=np.float64(1.4 * ratio))


def contour_map(ax, robot, *, ground: bool = False, n_cells: int = 241, elbow: str = "down", title: str = ""):
    """Contours of w*/L^2 x 40 (eq. 11) over the reachable disk, robot frame."""
    x, y, w = workspace_map(robot, n_cells, elbow=elbow, ground=ground)
    x, y, w = np.asarray(x), np.asarray(y), np.asarray(w) * 40.0
    reach = _reach(robot)
    filled = ax.contourf(x, y, w, levels=np.arange(0, 11), cmap="viridis", extend="max")
    lines = ax.contour(x, y, w, levels=CONTOUR_LEVELS_X40, colors="k", linewidths=0.6)
    ax.clabel(lines, fmt="%d", fontsize=7)
    ax.add_patch(_plt().Circle((0, 0), reach, fill=False, color="0.4", lw=0.8, label="reach |x| = L"))
    ax.plot(0, 0, "k+", ms=8, ls="none", label="joint 1 (robot-frame origin)")
    ax.set_aspect("equal")
    ax.set_xlim(-1.05 * reach, 1.05 * reach)
    ax.set_ylim(-1.05 * reach, 1.05 * reach)
    ax.set_xlabel("x_R [m]")
    ax.set_ylabel("y_R [m]")
    ax.set_title(title, fontsize=10)
    return filled


def _ellipse(ax, robot, phi_arm, color="C3", scale=ELLIPSE_SCALE):

    phi = np.concatenate([[0.0], phi_arm])
    major, minor, angle = (float(v) for v in manipulability_ellipse(robot, phi))
    tip = np.asarray(robot_frame_tip_position(robot, np.asarray(phi_arm)))
    ax.add_patch(
        Ellipse(tip, 2 * scale * major, 2 * scale * minor, angle=np.degrees(angle), fill=False, color=color, lw=1.0)
    )
    return tip


def _draw_arm(ax, robot, phi_arm, color="k"):
    lengths = np.asarray(robot.link_length)
    theta = np.cumsum(phi_arm)
    points = [np.zeros(2)]
    for length, angle in zip(lengths, theta, strict=False):
        points.append(points[-1] + length * np.array([np.cos(angle), np.sin(angle)]))
    points = np.array(points)
    ax.plot(points[:, 0], points[:, 1], "-o", color=color, lw=2, ms=4, label="arm (dots: joints and tip)")


def _draw_base(ax, robot, color="0.5"):
    """The base as a box around its centroid at (-b0, 0) in the robot frame (Table 1: 2.6 m wide),
    labelled for a legend."""
    b0 = float(robot.base_attach)
    ax.add_patch(
        _plt().Rectangle(
            (-b0 - 1.2, -1.2), 2.4 + 0.2, 2.4, fill=True, alpha=0.25, color=color, label="base (drawn as a 2.6 m box)"
        )
    )
    ax.plot(-b0, 0, "kx", ms=6, ls="none", label="base centroid")


@figure("fig6")
def fig6(out_dir: Path) -> list[Path]:
    """Fig. 6: manipulability ellipses over the elbow-down workspace (Table 1 robot)."""
    plt = _plt()
    robot = _table1()
    fig, ax = plt.subplots(figsize=(6, 6))
    reach = _reach(robot)
    axis = np.arange(-3.5, 3.51, 1.0)
    gx, gy = np.meshgrid(axis, axis)
    points = np.stack([gx.ravel(), gy.ravel()], -1)
    radius = np.hypot(points[:, 0], points[:, 1])
    points = points[(radius < reach - 0.2) & (radius > 0.3)]
    phi_arm, _ = inverse_kinematics(robot, points)
    for q in np.asarray(phi_arm):
        _ellipse(ax, robot, q)
    ax.add_patch(plt.Circle((0, 0), reach, fill=False, color="0.4", lw=0.8, label="|x| = L"))
    _draw_base(ax, robot)
    ax.set_aspect("equal")
    ax.set_xlim(-4.5, 4.5)
    ax.set_ylim(-4.5, 4.5)
    ax.set_xlabel("x_R [m]")
    ax.set_ylabel("y_R [m]")
    ax.set_title(f"Fig. 6: ellipses of J* (elbow-down), semi-axes x {ELLIPSE_SCALE} m per m/rad", fontsize=9)
    ax.plot([], [], color="C3", label="manipulability ellipse")
    ax.legend(loc="lower left", fontsize=8)
    return [_save(fig, Path(out_dir) / "fig6.png")]


@figure("fig7")
def fig7(out_dir: Path) -> list[Path]:
    """Fig. 7: contour maps of w*/L^2 x 40, space robot (a) beside the ground robot (b)."""
    plt = _plt()
    robot = _table1()
    fig, axes = plt.subplots(1, 2, figsize=(11, 5))
    filled = contour_map(axes[0], robot, title="(a) space robot, w*/L^2 x 40 (elbow-down)")
    contour_map(axes[1], robot, ground=True, title="(b) ground robot, w/L^2 x 40")
    _draw_base(axes[0], robot)
    axes[0].legend(loc="lower left", fontsize=7, framealpha=0.9)
    fig.colorbar(filled, ax=axes, shrink=0.8, label="w/L^2 x 40")
    return [_save(fig, Path(out_dir) / "fig7.png")]


# Posture 1 (elbow-down) and posture 2 (elbow-up) reaching the same tip, first quadrant.
FIG8_TIP = np.array([2.0, 2.0])


@figure("fig8")
def fig8(out_dir: Path) -> list[Path]:
    """Fig. 8: the same tip reached elbow-down (posture 1) and elbow-up (posture 2), with ellipses."""
    plt = _plt()
    robot = _table1()
    fig, axes = plt.subplots(1, 2, figsize=(10, 5))
    for ax, elbow, label in zip(
        axes, ("down", "up"), ("(a) posture 1, elbow-down", "(b) posture 2, elbow-up"), strict=False
    ):
        phi_arm, _ = inverse_kinematics(robot, FIG8_TIP, elbow=elbow)
        phi_arm = np.asarray(phi_arm)
        _draw_base(ax, robot)
        _draw_arm(ax, robot, phi_arm)
        _ellipse(ax, robot, phi_arm, scale=0.6)
        w = float(manipulability(robot, np.concatenate([[0.0], phi_arm]))) / _reach(robot) ** 2
        deg = np.degrees(phi_arm)
        ax.set_title(
            f"{label}\nphi1 = {deg[0]:.1f} deg, phi2 = {deg[1]:.1f} deg, w*/L^2 x 40 = {40 * w:.2f}", fontsize=9
        )
        ax.set_aspect("equal")
        ax.set_xlim(-3.5, 4.0)
        ax.set_ylim(-2.5, 4.0)
        ax.set_xlabel("x_R [m]")
        ax.set_ylabel("y_R [m]")
        ax.grid(alpha=0.3)
        ax.plot([], [], color="C3", label="manipulability ellipse (x 0.6 m per m/rad)")
        ax.legend(loc="lower left", fontsize=7, framealpha=0.9)
    return [_save(fig, Path(out_dir) / "fig8.png")]


def draw_fig10(path: Path, robots: list, labels: list[str]) -> Path:
    """Fig. 10: workspaces (inertial frame, top) and w*/L^2 x 40 maps (robot frame, bottom)."""
    plt = _plt()
    # A fixed layout, in inches, in place of a tight crop (which draws the figure twice): the
    # plotting area of each column, then margins that hold the tick and axis labels.
    columns, area, margins = len(robots), (3.255, 6.468), dict(left=0.72, right=0.12, bottom=0.17, top=0.18)
    size = (area[0] * columns + margins["left"] + margins["right"], area[1] + margins["bottom"] + margins["top"])
    fig, axes = plt.subplots(2, columns, figsize=size)
    axes = np.atleast_2d(axes).reshape(2, -1)
    filled = None
    for column, (robot, label) in enumerate(zip(robots, labels, strict=False)):
        ax = axes[0, column]
        K = derivation_coefficients(Derivation(), robot).tip  # eq. 1 as printed, in NumPy on the host
        arm, reach = K[1:].sum(), _reach(robot)
        circles = [
            ((0, 0), K[0] + arm, "C0", "Maximum Reachable (S_M)"),
            ((K[0], 0), arm, "C2", "Attitude Constraint"),
            ((0, 0), abs(K[0] - arm), "C3", "Guaranteed (S_G)"),
        ]
        for centre, radius, color, name in circles:
            ax.add_patch(plt.Circle(centre, radius, fill=False, color=color, lw=1.4, label=name))
        # Fixed-Vehicle workspace drawn as in the paper's Fig. 4: radius L about the origin
        # (that placement gives eq. 9's condition for Area 3 to contain Area 1).
        ax.add_patch(
            plt.Circle((0, 0), reach, fill=False, color="0.5", ls="--", lw=1.0, label="Fixed Vehicle (radius L)")
        )
        ax.plot(0, 0, "k+", ms=8, ls="none", label="system centroid (origin)")
        limit = 6.8
        ax.set_xlim(-limit, limit)
        ax.set_ylim(-limit, limit)
        ax.set_aspect("equal")
        ax.set_xlabel("x_A [m]")
        ax.set_ylabel("y_A [m]")
        ax.set_title(f"{label}: workspaces (inertial frame)", fontsize=9)
        if column == 0:
            ax.legend(loc="lower left", fontsize=7)
        filled = contour_map(axes[1, column], robot, title=f"{label}: w*/L^2 x 40 (robot frame)")
        _draw_base(axes[1, column], robot)
        if column == 0:
            axes[1, column].legend(loc="lower left", fontsize=6, framealpha=0.9)
    fig.subplots_adjust(
        left=margins["left"] / size[0],
        right=1 - margins["right"] / size[0],
        bottom=margins["bottom"] / size[1],
        top=1 - margins["top"] / size[1],
        wspace=0.4,
        hspace=0.3,
    )
    fig.colorbar(filled, ax=axes[1, :].tolist(), shrink=0.8, label="w*/L^2 x 40")
    return _save(fig, Path(path), tight=False)


@figure("fig10")
def fig10(out_dir: Path) -> list[Path]:
    """Fig. 10 for b0/B0 = 0, 1, 2 (Table 1 otherwise)."""
    ratios = (0.0, 1.0, 2.0)
    return [draw_fig10(Path(out_dir) / "fig10.png", [_table1(r) for r in ratios], [f"b0/B0 = {r:g}" for r in ratios])]
