"""Figures of the nonholonomic base motion (Umetani & Yoshida 1990, Fig. 2, 3a, 8, 9).

- "fig2": a cyclic joint loop from (phi1, phi2) = (-60, 120) deg, run both ways: the
  loop in joint space and the robot before and after in the inertial frame.
- "fig3a": one straight tip path along X_A from the Fig. 3 posture to its singular end.
- "fig9": two postures reaching the same point, elbow-down and elbow-up, with their
  manipulability ellipses (Fig. 8), and the base attitude during the same small
  go-and-back tip motion along Y_R (Fig. 9).

The paper prints neither the corners of its Fig. 2 loop nor the point of Fig. 8; the
values below are ours and are stated in the figures.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..io import save_figure
from ..kinematics import fixed_base_manipulability, manipulability
from ..motion import go_and_back, joint_path_history, straight_tip_path, straight_tip_path_history
from ..paper import manipulability_ellipse, umetani1990
from . import figure
from .robot import base_square, draw_planar_robot, robot_outline

DEG = np.pi / 180.0
FIG2_LOOP_DEG = np.array([[-60.0, 120.0], [30.0, 120.0], [30.0, 30.0], [-60.0, 30.0], [-60.0, 120.0]])
FIG3_START = np.array([0.0, -60.0, 120.0]) * DEG
FIG8_POINT = np.array([2.0, 2.0])  # robot frame, m (first quadrant)
FIG9_DISTANCE = 0.2  # m, each way


def _save(fig, path: Path) -> Path:
    return save_figure(fig, Path(path), dpi=130, bbox_inches="tight")


def _pyplot():
    return plt


def _outline(robot, phi):
    """Base square corners and the chain [base centroid, joint 1, ..., tip], inertial, m."""
    base, chain = robot_outline(robot, phi)
    box = base_square(base, np.asarray(phi, float)[0], max(0.5 * float(robot.base_attach), 0.3))
    return box, np.vstack([base, chain])


def _ellipse(ax, robot, phi, color, scale=0.5):
    """The manipulability ellipse of J* (axes x ``scale``) about the tip, robot frame."""
    major, minor, angle = (float(x) for x in manipulability_ellipse(robot, phi))
    t = np.linspace(0, 2 * np.pi, 200)
    c, s = np.cos(angle), np.sin(angle)
    x, y = scale * major * np.cos(t), scale * minor * np.sin(t)
    _, chain = _outline(robot, phi)
    tip = chain[-1] - chain[1]
    ax.plot(tip[0] + c * x - s * y, tip[1] + s * x + c * y, color=color, lw=1.2)
    return major, minor


def fig2_study(robot=None):
    """The Fig. 2 numbers: base rotation and tips before/after for both loop directions.

    Returns:
        dict with "loop" (k, 2) rad, and for "forward" / "reverse": "phi_end" (3,) rad,
        "postures" (S, 3), "tips" (S, 2) m.
    """

    robot = umetani1990() if robot is None else robot
    loop = FIG2_LOOP_DEG * DEG
    loops = np.stack([loop, loop[::-1]])
    phi_start = np.r_[0.0, loop[0]]
    phi0, joints, tips = joint_path_history(robot, phi_start, loops, 64)
    postures, tips = np.concatenate([np.asarray(phi0)[..., None], np.asarray(joints)], axis=-1), np.asarray(tips)
    out = {"loop": loop, "robot": robot}
    for i, name in enumerate(("forward", "reverse")):
        out[name] = {"phi_end": postures[i, -1], "postures": postures[i], "tips": tips[i]}
    return out


@figure("fig2")
def fig2(out_dir: Path) -> list[Path]:
    """Fig. 2: base attitude change by a cyclic joint motion, both loop directions."""
    plt = _pyplot()
    study = fig2_study()
    robot, loop = study["robot"], study["loop"]
    fig, (ax_joint, ax_inertial) = plt.subplots(1, 2, figsize=(12.5, 5.6))
    colors = {"forward": "tab:red", "reverse": "tab:blue"}
    for name, label in (("forward", "loop 1-2-3-4-1"), ("reverse", "reversed 1-4-3-2-1")):
        corners = loop if name == "forward" else loop[::-1]
        offset = 1.5 if name == "forward" else -1.5
        pts = corners / DEG + offset
        ax_joint.plot(pts[:, 0], pts[:, 1], "-", color=colors[name], lw=1.8, label=label)
        for a, b in itertools.pairwise(pts):
            mid = 0.5 * (a + b)
            ax_joint.annotate(
                "",
                xy=mid + 0.08 * (b - a),
                xytext=mid - 0.08 * (b - a),
                arrowprops=dict(arrowstyle="->", color=colors[name], lw=1.8),
            )
    for k, corner in enumerate(loop[:-1] / DEG):
        ax_joint.annotate(str(k + 1), corner, textcoords="offset points", xytext=(6, 6), fontsize=11)
    ax_joint.set_xlabel(r"$\phi_1$ [deg]")
    ax_joint.set_ylabel(r"$\phi_2$ [deg]")
    ax_joint.set_title("(a) cyclic operation in joint space (loops drawn 3 deg apart)")
    ax_joint.set_aspect("equal")
    ax_joint.grid(alpha=0.3)
    ax_joint.legend(loc="center")

    phi_start = np.r_[0.0, loop[0]]
    draw_planar_robot(ax_inertial, robot, phi_start, "black", "start (both)", lw=2.4)
    for name, label in (("forward", "after loop 1-2-3-4-1"), ("reverse", "after reversed loop")):
        result = study[name]
        tips = result["tips"]
        ax_inertial.plot(tips[:, 0], tips[:, 1], ":", color=colors[name], lw=1.2)
        for posture in result["postures"][64:-1:64]:
            draw_planar_robot(ax_inertial, robot, posture, colors[name], alpha=0.25, lw=1.2)
        rotation = result["phi_end"][0] / DEG
        draw_planar_robot(
            ax_inertial, robot, result["phi_end"], colors[name], f"{label}: $\\Delta\\phi_0$ = {rotation:+.3f} deg"
        )
        moved = np.linalg.norm(tips[-1] - tips[0])
        ax_inertial.plot(*tips[-1], "*", color=colors[name], ms=12)
        ax_inertial.annotate(
            f"tip moved {moved:.3f} m",
            tips[-1],
            textcoords="offset points",
            xytext=(8, -14 if name == "forward" else 8),
            color=colors[name],
            fontsize=9,
        )
    ax_inertial.plot(0, 0, "k+", ms=12)
    ax_inertial.set_xlabel(r"$X_A$ [m] (origin: system centroid)")
    ax_inertial.set_ylabel(r"$Y_A$ [m]")
    ax_inertial.set_title("(b) course of postural change (inertial frame)")
    ax_inertial.set_aspect("equal")
    ax_inertial.grid(alpha=0.3)
    ax_inertial.legend(loc="lower left", fontsize=8.5)
    fig.suptitle(
        "Fig. 2: base attitude change by a cyclic joint motion (Table 1 robot; loop corners are our choice)",
        fontsize=11,
    )
    fig.tight_layout()
    path = _save(fig, Path(out_dir) / "fig2_cyclic_loop.png")
    plt.close(fig)
    return [path]


@figure("fig3a")
def fig3a(out_dir: Path) -> list[Path]:
    """Fig. 3a: one straight tip path along X_A from (0, -60, 120) deg to its singular end."""
    plt = _pyplot()
    robot = umetani1990()
    direction = np.array([1.0, 0.0])
    path = straight_tip_path(robot, FIG3_START, direction)
    postures, tips = straight_tip_path_history(robot, FIG3_START, direction, 41)
    postures, tips = np.asarray(postures), np.asarray(tips)
    end = np.asarray(path.end_posture)
    fig, (ax, ax_w) = plt.subplots(1, 2, figsize=(12.5, 5.2), gridspec_kw={"width_ratios": [1.35, 1]})
    for posture in postures[8:-1:8]:
        draw_planar_robot(ax, robot, posture, "tab:gray", alpha=0.35, lw=1.2)
    draw_planar_robot(ax, robot, FIG3_START, "black", "start (0, -60, 120) deg")
    kind = "kinematic" if bool(path.kinematic) else "dynamic"
    draw_planar_robot(
        ax,
        robot,
        end,
        "tab:red",
        f"end: ({end[0] / DEG:.2f}, {end[1] / DEG:.2f}, {end[2] / DEG:.2f}) deg, det J* = 0 ({kind})",
    )
    ax.plot(tips[:, 0], tips[:, 1], "-", color="tab:red", lw=2.5, alpha=0.6)
    ax.annotate(f"length {float(path.length):.4f} m", tips[-1], textcoords="offset points", xytext=(-40, 12))
    ax.plot(0, 0, "k+", ms=12)
    ax.set_xlabel(r"$X_A$ [m]")
    ax.set_ylabel(r"$Y_A$ [m]")
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", fontsize=8.5)
    ax.set_title("(a) straight path along $X_A$ to the singular end")
    travelled = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(tips, axis=0), axis=1))]
    L2 = float(robot.reach) ** 2
    ax_w.plot(travelled, np.asarray(manipulability(robot, postures)) / L2, label=r"$w^*/L^2$ (free-floating, eq. 11)")
    ax_w.plot(
        travelled,
        np.asarray(fixed_base_manipulability(robot, postures[:, 1:])) / L2,
        "--",
        label=r"fixed-base $w/L^2$ ($\propto |\sin\phi_2|$)",
    )
    ax_w.axhline(0, color="k", lw=0.8)
    ax_att = ax_w.twinx()
    ax_att.plot(travelled, postures[:, 0] / DEG, ":", color="tab:green", label=r"base attitude $\phi_0$")
    ax_att.set_ylabel(r"base attitude $\phi_0$ [deg]", color="tab:green")
    ax_att.legend(loc="lower right", fontsize=8.5)
    ax_w.set_xlabel("tip distance travelled [m]")
    ax_w.set_ylabel("normalized manipulability [-]")
    ax_w.set_title(r"(b) $w^*$ reaches 0 while $\phi_2$ = %.1f deg" % (end[2] / DEG))
    ax_w.grid(alpha=0.3)
    ax_w.legend(loc="lower left", fontsize=8.5)
    fig.suptitle("Fig. 3(a): straight tip path until J* loses rank (Table 1 robot, b0 = 1.4 m)", fontsize=11)
    fig.tight_layout()
    out = _save(fig, Path(out_dir) / "fig3a_straight_path.png")
    plt.close(fig)
    return [out]


def fig9_study(robot=None, point=FIG8_POINT, distance=FIG9_DISTANCE, n_samples=81):
    """Elbow-down and elbow-up postures reaching ``point`` (robot frame, phi0 = 0) and the
    base attitude during a go-and-back tip motion of ``distance`` along Y_R.

    Returns:
        dict: "postures" (2, 3) rad [elbow-down, elbow-up]; "history" (2, S, 3) rad;
        "travelled" (2, S) m; "peak" (2,) largest |phi0 - phi0_start|, rad.
    """

    robot = umetani1990() if robot is None else robot
    l1, l2 = (float(x) for x in np.asarray(robot.link_length))
    x, y = point
    c2 = (x * x + y * y - l1 * l1 - l2 * l2) / (2 * l1 * l2)
    postures = []
    for sign in (1.0, -1.0):  # elbow-down (phi2 >= 0), then elbow-up
        s2 = sign * np.sqrt(max(0.0, 1.0 - c2 * c2))
        q2 = np.arctan2(s2, c2)
        q1 = np.arctan2(y, x) - np.arctan2(l2 * s2, l1 + l2 * c2)
        postures.append([0.0, q1, q2])
    postures = np.array(postures)
    history, _, travelled = go_and_back(robot, postures, np.array([0.0, 1.0]), distance, n_samples)
    history, travelled = np.asarray(history), np.asarray(travelled)
    peak = np.max(np.abs(history[..., 0] - postures[:, None, 0]), axis=-1)
    return {"robot": robot, "postures": postures, "history": history, "travelled": travelled, "peak": peak}


@figure("fig9")
def fig9(out_dir: Path) -> list[Path]:
    """Fig. 8 and 9: same point, two postures, base attitude during a go-and-back along Y_R."""
    plt = _pyplot()
    study = fig9_study()
    robot = study["robot"]
    fig, (ax, ax_att) = plt.subplots(1, 2, figsize=(12.5, 5.2))
    colors = ("tab:red", "tab:blue")
    names = ("posture 1 (elbow-down)", "posture 2 (elbow-up)")
    for k in range(2):
        phi = study["postures"][k]
        major, minor = _ellipse(ax, robot, phi, colors[k])
        draw_planar_robot(
            ax,
            robot,
            phi,
            colors[k],
            f"{names[k]}: ({phi[1] / DEG:.0f}, {phi[2] / DEG:.0f}) deg; J* axes {major:.2f}, {minor:.2f} m/rad",
            robot_frame=True,
        )
    tip = np.asarray(FIG8_POINT)
    ax.annotate("", xy=tip + [0, 0.5], xytext=tip - [0, 0.5], arrowprops=dict(arrowstyle="<->", color="k"))
    ax.annotate("go-and-back\nalong $Y_R$", tip + [0.08, 0.25], fontsize=8.5)
    ax.set_xlabel(r"$X_R$ [m] (robot frame, origin at joint 1)")
    ax.set_ylabel(r"$Y_R$ [m]")
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", fontsize=8.5)
    ax.set_title("(Fig. 8) two postures, same tip; ellipses of J* (x0.5)")
    for k in range(2):
        ax_att.plot(
            study["travelled"][k],
            (study["history"][k, :, 0] - study["postures"][k, 0]) / DEG,
            color=colors[k],
            lw=2,
            label=f"{names[k]}: peak {study['peak'][k] / DEG:.2f} deg",
        )
    ax_att.axvline(FIG9_DISTANCE, color="k", lw=0.8, ls=":")
    ax_att.set_xlabel(f"tip path length travelled [m] (out {FIG9_DISTANCE} m along $Y_R$, then back)")
    ax_att.set_ylabel(r"base attitude $\phi_0$ [deg]")
    ax_att.set_title("(Fig. 9) base attitude during the same go-and-back tip motion")
    ax_att.grid(alpha=0.3)
    ax_att.legend(fontsize=9)
    fig.suptitle(
        f"Fig. 8/9: tip at ({FIG8_POINT[0]:.1f}, {FIG8_POINT[1]:.1f}) m in the robot frame (our choice); Table 1 robot",
        fontsize=11,
    )
    fig.tight_layout()
    out = _save(fig, Path(out_dir) / "fig9_go_and_back.png")
    plt.close(fig)
    return [out]
