"""Workspace figures: Fig. 3, 4, 5 of Umetani & Yoshida 1990 and the dynamic singularities."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .. import analysis, paper
from ..io import save_figure
from ..kinematics import generalized_jacobian, tip_position
from ..motion import straight_tip_path_history
from ..paper import tip_coefficients, umetani1990
from . import figure
from .robot import draw_planar_robot

FIG3_POSTURE_DEG = (0.0, -60.0, 120.0)


def _setup():
    """pyplot (the command line picks the Agg backend and the precision)."""
    return plt


def _save(fig, path: Path) -> Path:
    return save_figure(fig, Path(path), dpi=130, bbox_inches="tight")


def _circle(ax, center, radius, **style):
    angle = np.linspace(0.0, 2.0 * np.pi, 361)
    ax.plot(center[0] + radius * np.cos(angle), center[1] + radius * np.sin(angle), **style)


def _fig3_posture():
    return np.radians(np.array(FIG3_POSTURE_DEG))


@figure("fig3")
def fig3(out_dir: Path) -> list[Path]:
    """Fig. 3: (a) one straight path along X_A, (b) the Straight-Path Workspace, phi = (0, -60, 120) deg."""
    plt = _setup()
    robot = umetani1990()
    phi = _fig3_posture()
    postures, tips = straight_tip_path_history(robot, phi, np.array([1.0, 0.0]), n_samples=121)
    postures, tips = np.asarray(postures), np.asarray(tips)
    ends = paper.straight_path_ends(robot, phi, 360)
    boundary = np.asarray(ends.end_tip)
    start = np.asarray(tip_position(robot, phi))

    fig, axes = plt.subplots(1, 2, figsize=(12, 6))
    ax = axes[0]
    for k in np.linspace(0, len(postures) - 1, 5).astype(int):
        draw_planar_robot(ax, robot, postures[k], color=plt.cm.viridis(k / (len(postures) - 1)))
    ax.plot(tips[:, 0], tips[:, 1], "r-", lw=1.5, label="tip path (straight along $X_A$)")
    end = postures[-1]
    ax.plot(*tips[-1], "rx", ms=9, label=f"end: $\\phi$ = ({', '.join(f'{v:.1f}' for v in np.degrees(end))}) deg")
    ax.plot(0, 0, "k*", ms=8, label="system centroid")
    ax.set_title("(a) one straight path along $X_A$ (dark: start, yellow: end)")
    ax.legend(loc="lower left", fontsize=8)

    ax = axes[1]
    closed = np.vstack([boundary, boundary[:1]])
    ax.fill(closed[:, 0], closed[:, 1], color="tab:blue", alpha=0.25, label="Straight-Path Workspace (360 directions)")
    ax.plot(closed[:, 0], closed[:, 1], "tab:blue", lw=1)
    folded = np.abs(np.asarray(ends.end_posture)[:, 2]) > np.pi / 2
    ax.plot(
        boundary[folded, 0], boundary[folded, 1], ".", color="tab:red", ms=3, label="ends at the folded-arm singularity"
    )
    _circle(
        ax,
        (0, 0),
        float(analysis.maximum_reachable_radius(robot)),
        color="k",
        ls="--",
        lw=1,
        label="Area 3, $K_0+K_1+K_2$",
    )
    _circle(ax, (0, 0), float(paper.guaranteed_radius(robot)), color="tab:green", ls="--", lw=1, label="eq. (8) radius")
    draw_planar_robot(ax, robot, phi, color="0.3")
    ax.plot(*start, "ko", ms=5, label="start tip")
    ax.plot(0, 0, "k*", ms=8, ls="none", label="system centroid")
    ax.set_title("(b) Straight-Path Workspace from $\\phi$ = (0, -60, 120) deg")
    ax.legend(loc="lower left", fontsize=8)
    for ax in axes:
        ax.set_aspect("equal")
        ax.set_xlabel("$X_A$ [m]")
        ax.set_ylabel("$Y_A$ [m]")
        ax.grid(alpha=0.3)
    return [_save(fig, Path(out_dir) / "fig3_straight_path.png")]


def _fig4_panel(ax, robot, title):

    K = np.asarray(tip_coefficients(robot))
    c1, r1 = np.asarray(paper.fixed_vehicle_center(robot)), float(paper.fixed_vehicle_radius(robot))
    c2, r2 = (np.asarray(x) for x in paper.attitude_constraint(robot))
    r3, r5 = float(analysis.maximum_reachable_radius(robot)), float(paper.guaranteed_radius(robot))
    hole2 = float(paper.attitude_constraint_inner_radius(robot))
    _circle(ax, c1, r1, color="tab:orange", lw=2, label=f"Area 1 Fixed-Vehicle, L = {r1:.2f} m about joint 1")
    _circle(ax, c2, r2, color="tab:blue", lw=2, label=f"Area 2 Attitude-Constraint, {r2:.2f} m about ($K_0$, 0)")
    if hole2 > 1e-9:
        _circle(ax, c2, hole2, color="tab:blue", lw=1, ls=":", label=f"Area 2 hole, |$K_1-K_2$| = {hole2:.3f} m")
    _circle(ax, (0, 0), r3, color="k", lw=2, label=f"Area 3 Maximum Reachable, {r3:.2f} m")
    _circle(ax, (0, 0), r5, color="tab:green", lw=2, label=f"Area 5 Guaranteed (eq. 8), {r5:.2f} m")
    draw_planar_robot(ax, robot, np.zeros(robot.n_links + 1), color="0.4")
    ax.plot(0, 0, "k*", ms=8, ls="none", label="system centroid")
    ok = bool(paper.attachment_condition(robot))
    bound = float(robot.total_mass / robot.base_mass * (robot.reach - K[1:].sum()))
    ax.set_title(
        f"{title}\nb0 = {float(robot.base_attach):.2f} m; eq. (9) needs b0 >= {bound:.2f} m: {'holds' if ok else 'fails'}"
    )
    ax.legend(loc="lower left", fontsize=7)
    ax.set_aspect("equal")
    ax.set_xlabel("$X_A$ [m]")
    ax.set_ylabel("$Y_A$ [m]")
    ax.grid(alpha=0.3)


@figure("fig4")
def fig4(out_dir: Path) -> list[Path]:
    """Fig. 4: Areas 1, 2, 3, 5 for Table 1 (eq. 9 holds) and for b0 = 0.2 m (it fails)."""
    plt = _setup()
    robot = umetani1990()
    fig, axes = plt.subplots(1, 2, figsize=(13, 6.5))
    _fig4_panel(axes[0], robot, "(a) Table 1: Area 3 >= Area 1 >= Area 2 >= Area 5")
    _fig4_panel(axes[1], robot.replace(base_attach=np.float64(0.2)), "(b) short attachment: Area 1 leaves Area 3")
    for ax in axes:
        ax.text(
            0.01,
            0.99,
            "robot drawn at $\\phi$ = 0 (Area 1 placed about its joint 1)",
            transform=ax.transAxes,
            va="top",
            fontsize=8,
        )
    return [_save(fig, Path(out_dir) / "fig4_workspaces.png")]


@figure("fig5")
def fig5(out_dir: Path) -> list[Path]:
    """Fig. 5: Areas 3, 4, 5 with points A, B, C (posture of Fig. 3)."""
    plt = _setup()
    robot = umetani1990()
    phi = _fig3_posture()
    ends = np.asarray(paper.straight_path_workspace(robot, phi, 360))
    start = np.asarray(tip_position(robot, phi))
    r3, r5 = float(analysis.maximum_reachable_radius(robot)), float(paper.guaranteed_radius(robot))
    r_piw = float(analysis.path_independent_radius(robot))
    study = paper.straight_path_study(robot, n_postures=200, n_directions=90, seed=1)

    # A: inside the singularity-free disk; B: in Area 4; C: in Area 3, outside Area 4, but
    # inside Area 4 turned about the centroid by some base reorientation delta.
    A = np.array([-0.5, 0.4])
    B = start + 0.6 * (ends[60] - start)
    ring = 0.25 * np.stack([np.cos(np.arange(8) * np.pi / 4), np.sin(np.arange(8) * np.pi / 4)], -1)

    def inside_with_margin(points):
        """(P,) -1 outside by 0.25 m, +1 inside by 0.25 m, 0 near the boundary."""
        near = np.asarray(paper.inside_straight_path_workspace(start, ends, points[:, None, :] + ring))
        return np.where(near.all(-1), 1, np.where(~near.any(-1), -1, 0))

    grid = np.stack(np.meshgrid(np.linspace(-4.5, 4.5, 61), np.linspace(-4.5, 4.5, 61)), -1).reshape(-1, 2)
    grid = grid[np.linalg.norm(grid, axis=-1) < 0.85 * r3]
    outside = grid[inside_with_margin(grid) == -1]
    # The smallest base turn delta after which some clearly outside point is clearly inside.
    best = None
    for delta in np.radians(np.arange(5.0, 181.0, 5.0)):
        for signed in (delta, -delta):
            c, s = np.cos(signed), np.sin(signed)
            ok = inside_with_margin(outside @ np.array([[c, -s], [s, c]])) == 1
            if ok.any():
                options = outside[ok]
                best = (signed, options[np.argmax(np.linalg.norm(options - start, axis=-1))])
                break
        if best is not None:
            break
    fig, ax = plt.subplots(figsize=(7.5, 7.5))
    _circle(
        ax,
        (0, 0),
        r3,
        color="k",
        lw=2,
        label=f"Area 3 Maximum Reachable ({r3:.2f} m; straight-path union {study['union_radius']:.3f} m)",
    )
    closed = np.vstack([ends, ends[:1]])
    ax.fill(
        closed[:, 0],
        closed[:, 1],
        color="tab:blue",
        alpha=0.25,
        label="Area 4 Straight-Path, $\\phi$ = (0, -60, 120) deg",
    )
    _circle(ax, (0, 0), r5, color="tab:green", lw=2, label=f"Area 5 by eq. (8), {r5:.2f} m")
    _circle(
        ax, (0, 0), r_piw, color="tab:red", lw=2, ls="--", label=f"singularity-free disk (det J* != 0), {r_piw:.2f} m"
    )
    if best is not None:
        delta, C = best
        c, s = np.cos(delta), np.sin(delta)
        turned = np.vstack([ends, ends[:1]]) @ np.array([[c, s], [-s, c]])
        ax.plot(
            turned[:, 0],
            turned[:, 1],
            color="tab:purple",
            ls=":",
            lw=1.5,
            label=f"Area 4 after a cyclic maneuver turns the base by {np.degrees(delta):.0f} deg",
        )
        draw_planar_robot(ax, robot, phi + np.array([delta, 0.0, 0.0]), color="tab:purple", alpha=0.4)
        ax.plot(*C, "s", color="tab:purple", ms=8)
        ax.annotate("C", C, xytext=(6, 6), textcoords="offset points", fontsize=12)
    draw_planar_robot(ax, robot, phi, color="0.3")
    for name, point, color in (("A", A, "tab:red"), ("B", B, "tab:blue")):
        ax.plot(*point, "o", color=color, ms=8)
        ax.annotate(name, point, xytext=(6, 6), textcoords="offset points", fontsize=12)
    ax.plot(0, 0, "k*", ms=8, ls="none", label="system centroid")
    ax.text(
        0.01,
        0.01,
        f"Straight paths from {study['n_postures']} random postures x {study['n_directions']} directions:\n"
        f"intersection radius {study['intersection_radius']:.3f} m (all starts), "
        f"{study['intersection_radius_inside_path_independent']:.3f} m (starts inside the red disk)",
        transform=ax.transAxes,
        fontsize=7.5,
    )
    ax.set_aspect("equal")
    ax.set_xlabel("$X_A$ [m]")
    ax.set_ylabel("$Y_A$ [m]")
    ax.set_xlim(-5.6, 5.6)
    ax.set_ylim(-5.6, 5.6)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=7)
    ax.set_title("Fig. 5: free workspaces; A guaranteed, B by a straight path, C after reorienting the base")
    return [_save(fig, Path(out_dir) / "fig5_free_workspaces.png")]


@figure("singularities")
def singularities(out_dir: Path) -> list[Path]:
    """Where det J* vanishes (Table 1) against phi2 = 0 and eq. (8)."""
    plt = _setup()
    robot = umetani1990()
    s = paper.dynamic_singularities(robot)
    phi1, phi2 = np.degrees(np.asarray(s.phi1)), np.degrees(np.asarray(s.phi2))
    folded = np.asarray(s.folded)
    radius = np.asarray(s.radius)
    found = np.isfinite(phi2)
    grid = np.radians(np.linspace(-180, 180, 361))
    Q1, Q2 = np.meshgrid(grid, grid, indexing="ij")
    J = np.asarray(generalized_jacobian(robot, np.stack([0 * Q1, Q1, Q2], -1)))
    det = (J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]) / float(robot.reach) ** 2

    fig, axes = plt.subplots(2, 2, figsize=(13, 11.5), layout="constrained")
    fig.get_layout_engine().set(wspace=0.1)  # room between (a)'s colour bar and (b)'s axis label
    ax = axes[0, 0]
    levels = np.linspace(-np.abs(det).max(), np.abs(det).max(), 21)
    mesh = ax.contourf(np.degrees(Q1), np.degrees(Q2), det, levels=levels, cmap="RdBu_r")
    fig.colorbar(mesh, ax=ax, label="det J* / L$^2$")
    ax.plot(phi1[found & ~folded], phi2[found & ~folded], "k.", ms=1.5, label="det J* = 0, stretched branch")
    ax.plot(
        phi1[found & folded], phi2[found & folded], ".", color="tab:purple", ms=1.5, label="det J* = 0, folded branch"
    )
    for level in (-180, 0, 180):
        ax.axhline(level, color="tab:green", ls="--", lw=1)
    ax.plot([], [], color="tab:green", ls="--", label="kinematic: $\\phi_2$ = 0, $\\pm$180 deg")
    ax.set_xlabel("$\\phi_1$ [deg]")
    ax.set_ylabel("$\\phi_2$ [deg]")
    ax.set_title("(a) joint space (det J* does not depend on $\\phi_0$)")
    ax.legend(loc="upper left", fontsize=7, markerscale=4)

    ax = axes[0, 1]
    tr = np.asarray(s.tip_robot)
    ax.plot(tr[found & ~folded, 0], tr[found & ~folded, 1], "k.", ms=1.5, label="tip at det J* = 0, stretched branch")
    ax.plot(
        tr[found & folded, 0],
        tr[found & folded, 1],
        ".",
        color="tab:purple",
        ms=1.5,
        label="tip at det J* = 0, folded branch",
    )
    L = float(robot.reach)
    _circle(ax, (0, 0), L, color="tab:green", ls="--", lw=1, label=f"fixed base singular: |p| = L = {L:.1f} m")
    ax.plot(0, 0, "x", color="tab:green", ms=8, label="fixed base singular: folded, tip at joint 1")
    ax.set_aspect("equal")
    ax.set_xlabel("$X_R$ [m]")
    ax.set_ylabel("$Y_R$ [m]")
    ax.set_title("(b) robot frame $\\Sigma_R$ (origin at joint 1)")
    ax.legend(loc="lower left", fontsize=7, markerscale=4)

    ax = axes[1, 0]
    ax.plot(phi1[found & ~folded], radius[found & ~folded], "k.", ms=1.5, label="stretched branch")
    ax.plot(phi1[found & folded], radius[found & folded], ".", color="tab:purple", ms=1.5, label="folded branch")
    r3, r5 = float(analysis.maximum_reachable_radius(robot)), float(paper.guaranteed_radius(robot))
    r_piw = float(np.nanmin(radius))
    ax.axhline(r5, color="tab:green", ls="--", label=f"eq. (8): {r5:.3f} m")
    ax.axhline(r_piw, color="tab:red", ls="--", label=f"smallest singular radius: {r_piw:.3f} m")
    ax.axhline(r3, color="k", ls=":", label=f"Area 3: {r3:.3f} m")
    ax.set_xlabel("$\\phi_1$ [deg]")
    ax.set_ylabel("distance of the tip from the system centroid [m]")
    ax.set_title("(c) inertial radius of the singular postures")
    ax.legend(loc="upper left", fontsize=7, markerscale=4)

    ax = axes[1, 1]
    bands = [
        (np.nanmin(radius[folded]), np.nanmax(radius[folded]), "tab:purple"),
        (np.nanmin(radius[found & ~folded]), np.nanmax(radius[found & ~folded]), "0.5"),
    ]
    angle = np.linspace(0, 2 * np.pi, 361)
    for low, high, color in bands:
        ring_x = np.concatenate([high * np.cos(angle), low * np.cos(angle[::-1])])
        ring_y = np.concatenate([high * np.sin(angle), low * np.sin(angle[::-1])])
        ax.fill(
            ring_x,
            ring_y,
            color=color,
            alpha=0.35,
            lw=0,
            label=f"singular tips (all $\\phi_0$): {low:.2f}-{high:.2f} m",
        )
    _circle(ax, (0, 0), r5, color="tab:green", ls="--", lw=2, label=f"Guaranteed, eq. (8): {r5:.2f} m")
    _circle(ax, (0, 0), r_piw, color="tab:red", lw=2, label=f"path-independent disk: {r_piw:.2f} m")
    _circle(ax, (0, 0), r3, color="k", lw=1, label=f"Area 3: {r3:.2f} m")
    ax.plot(0, 0, "k*", ms=8, ls="none", label="system centroid")
    ax.set_aspect("equal")
    ax.set_xlabel("$X_A$ [m]")
    ax.set_ylabel("$Y_A$ [m]")
    ax.set_title("(d) inertial frame: the singular annuli")
    ax.legend(loc="lower left", fontsize=7)
    for a in axes.flat:
        a.grid(alpha=0.3)
    fig.suptitle("Table 1 robot: where the free-floating arm is singular (det J* = 0) vs the paper's $\\phi_2$ = 0")
    return [_save(fig, Path(out_dir) / "singularities.png")]
