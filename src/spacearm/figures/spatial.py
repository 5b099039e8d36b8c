"""Spatial arms on their bus in 3-D: a joint loop, the attitude history, a straight tip path.

Registered figures (``spacearm figures``), all for the UR5 on its 500 kg smallsat
(configs/ur5-smallsat.yaml):

- ``spatial-loop``: the arm and its bus drawn along a closed joint loop, inertial axes,
  about the system centroid; the tip trace; the bus turned by the loop.
- ``spatial-attitude``: the bus rotation vector log(R0^T R) and its angle along the loop.
- ``spatial-straight``: a straight tip path to its dynamic singularity (or 0.6 m), the
  arm at the start and the end, the bus attitude along the path.
- ``tree-arms``: several arms on one bus (configs/dual-ur5-servicer.yaml and
  configs/three-arm-servicer.yaml), each arm in its own colour, the mount frames and the tips.

One drawing helper serves one arm and many: `robot_drawing` gives the points of a
robot in one posture (from its view model, the tree walk the HTML views run), `draw_robot` draws them.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np

from ..io import save_figure
from ..models import load_robot
from ..models.view_model import view_model, view_pose
from ..motion.attitude import log, so3_joint_path_history
from ..motion.spatial_paths import spatial_straight_tip_path
from ..planning.spatial_reach import PHASE_LOOP, PHASE_STRAIGHT
from . import figure

CONFIGS = Path(__file__).resolve().parents[3] / "configs"
CONFIG = CONFIGS / "ur5-smallsat.yaml"
LOOP_START = np.array([0.3, -1.2, 1.6, -0.9, 1.2, 0.2])


def _robot():
    if not CONFIG.exists():
        raise FileNotFoundError(f"{CONFIG}: the spatial figures use the repository's configs/ur5-smallsat.yaml")
    return load_robot(os.fspath(CONFIG))


def arm_points(robot, q, rotation) -> tuple[np.ndarray, np.ndarray]:
    """Joint origins then tip ``(n + 1, 3)`` of a one-tip robot, and the bus centroid ``(3,)``,
    inertial axes about the system centroid, m, for one posture ``q`` and bus attitude ``rotation``."""
    pose = view_pose(view_model(robot), q, rotation)
    return np.vstack([pose["joints"], pose["tips"][:1]]), pose["bus"]


# The bus is drawn as its equivalent uniform box: same mass and principal moments.
BUS_LABEL = "bus (the uniform box of its mass and inertia)"


@dataclasses.dataclass(frozen=True)
class RobotDrawing:
    """A robot in one posture as drawn: inertial axes about the system centroid, m.

    Attributes:
        bus: ``(3,)`` bus centroid.
        bus_corners: ``(8, 3)`` corners of the bus's equivalent uniform box (same mass and
            principal moments; `spacearm.models.view_model.box_corners`).
        mounts: ``(r, 3)`` root (arm mount) origins.  mount_axes: ``(r, 3, 3)`` their axes as columns.
        body_origins: ``(n, 3)`` body frame origins (joint origins, slid along prismatic axes).
        segments: ``(s, 2, 3)`` links as segments joint to joint: parent body (or mount) to
            joint origin, joint origin to body origin where a prismatic joint slid, and body to tip.
        segment_arm: ``(s,)`` the arm (tip index) each segment belongs to, -1 when several share it.
        tips: ``(k, 3)`` tip origins.
        arm_names: ``k`` names, one per arm (the arm's name, else its tip's).
    """

    bus: np.ndarray
    bus_corners: np.ndarray
    mounts: np.ndarray
    mount_axes: np.ndarray
    body_origins: np.ndarray
    segments: np.ndarray
    segment_arm: np.ndarray
    tips: np.ndarray
    arm_names: tuple[str, ...]


def robot_drawing(robot, q, rotation=None) -> RobotDrawing:
    """The points drawn of ``robot`` at posture ``q`` (laid out as ``view_model(robot)["posture"]``
    says: the joints ``(n,)`` of a serial or tree arm) and bus attitude ``rotation`` (3, 3)
    (identity by default; a posture that holds the attitude turns the bus itself), from its view model
    (`spacearm.models.view_model.view_pose`, the tree walk the HTML views run; the tests hold
    it to the kernels' body frames and tips); see `RobotDrawing`."""
    model = view_model(robot)
    pose = view_pose(model, q, rotation)
    return RobotDrawing(
        bus=pose["bus"],
        bus_corners=pose["corners"],
        mounts=pose["mounts"],
        mount_axes=pose["mount_axes"],
        body_origins=pose["bodies"],
        segments=pose["segments"],
        segment_arm=pose["owner"],
        tips=pose["tips"],
        arm_names=tuple(model["tip_names"]),
    )


_EDGES = [(0, 1), (0, 2), (0, 4), (1, 3), (1, 5), (2, 3), (2, 6), (3, 7), (4, 5), (4, 6), (5, 7), (6, 7)]
SHARED_COLOR = "0.35"  # joints that move several tips (a shared torso or turret)


def draw_robot(
    ax, robot, q, rotation=None, *, colors=None, alpha=1.0, label=None, bus_half=None, frames=True, frame_length=0.15
) -> RobotDrawing:
    """Draw a robot in one posture on 3-D axes; returns what was drawn.

    The bus as a box (its equivalent uniform box from mass and inertia, or a cube of half
    edge ``bus_half`` about its centroid), a line from the bus centroid to each mount, the
    mount frames (x, y, z in red, green, blue, ``frame_length`` m), each arm's links as
    segments joint to joint in the arm's colour (joints several arms share in grey), and
    each tip as a marker.

    Args:
        ax: matplotlib 3-D axes.  q: ``(n,)`` joints, rad (m for prismatic joints).
        rotation: ``(3, 3)`` bus attitude (identity by default).
        colors: one colour for the whole robot, or one per arm; default matplotlib's cycle (C0, C1, ..).
        label: a legend label (one colour), else each arm is labelled with its name.
        bus_half: half edge of a cube drawn for the bus, m; default the equivalent box.
        frames: draw the mount frames.
    """
    drawing = robot_drawing(robot, q, rotation)
    k = len(drawing.arm_names)
    single = isinstance(colors, str) or (
        colors is not None and all(isinstance(c, (int, float, np.number)) for c in colors)  # one RGB(A) tuple
    )
    palette = [colors] * k if single else list(colors) if colors is not None else [f"C{t}" for t in range(k)]
    box = drawing.bus_corners
    if bus_half is not None:
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float) * bus_half
        box = drawing.bus + corners @ np.asarray(np.eye(3) if rotation is None else rotation, float).T
    bus_color = palette[0] if single else "0.4"
    for a, b in _EDGES:
        ax.plot(*box[[a, b]].T, color=bus_color, lw=0.8, alpha=0.6 * alpha)
    for mount in drawing.mounts:
        ax.plot(*np.vstack([drawing.bus, mount]).T, color=bus_color if single else SHARED_COLOR, lw=1.0, alpha=alpha)
    if frames:
        for mount, axes in zip(drawing.mounts, drawing.mount_axes, strict=True):
            for c, color in enumerate(("tab:red", "tab:green", "tab:blue")):
                ax.plot(*np.vstack([mount, mount + frame_length * axes[:, c]]).T, color=color, lw=1.2, alpha=alpha)
    for t in range(-1, k):
        pick = drawing.segment_arm == t
        if not pick.any():
            continue
        color = palette[t] if t >= 0 else (palette[0] if single else SHARED_COLOR)
        xyz = np.full((3 * int(pick.sum()), 3), np.nan)  # segments joined by NaN breaks: one line per arm
        xyz[0::3], xyz[1::3] = drawing.segments[pick, 0], drawing.segments[pick, 1]
        name = None if single else (drawing.arm_names[t] if t >= 0 else "shared joints")
        ax.plot(*xyz.T, "-o", color=color, lw=1.8, ms=2.5, alpha=alpha, label=name)
    for t in range(k):
        ax.scatter(*drawing.tips[t], color=palette[t], marker="D", s=22, alpha=alpha, depthshade=False)
    if single and label is not None:
        ax.plot([], [], "-o", color=palette[0], lw=1.8, ms=2.5, alpha=alpha, label=label)
    return drawing


def drawn_points(drawing: RobotDrawing) -> np.ndarray:
    """Every point of a `RobotDrawing`: bus box corners, mounts, segment ends and tips."""
    return np.vstack([drawing.bus_corners, drawing.mounts, drawing.segments.reshape(-1, 3), drawing.tips])


def _draw(ax, robot, q, R, color, alpha=1.0, label=None):
    draw_robot(ax, robot, q, R, colors=color, alpha=alpha, label=label, frames=False)


def _equal(ax, points):
    """Equal scales on the three axes, a cube that holds every point (with a 5 % margin)."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre, half = (lo + hi) / 2, 1.05 * max(float(np.max(hi - lo)) / 2, 0.1)
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1.0, 1.0, 1.0))
    ax.set_xlabel("x, m")
    ax.set_ylabel("y, m")
    ax.set_zlabel("z, m")


def demo_loop(segments: int = 16) -> np.ndarray:
    """``(segments + 1, n)`` a closed loop through `LOOP_START` (pan, shoulder and elbow; wrists still)."""
    s = np.linspace(0.0, 1.0, segments + 1)
    loop = np.repeat(LOOP_START[None], segments + 1, axis=0)
    loop[:, 1] += 0.6 * (np.cos(2 * np.pi * s) - 1.0)
    loop[:, 2] += 0.6 * np.sin(2 * np.pi * s)
    loop[:, 0] += 0.4 * np.sin(2 * np.pi * s)
    loop[-1] = LOOP_START
    return loop


def loop_history(robot, samples_per_segment: int = 8):
    loop = demo_loop()
    R, q = so3_joint_path_history(robot, loop[0], loop, samples_per_segment=samples_per_segment, steps=1)
    return np.asarray(R), np.asarray(q)


@figure("spatial-loop")
def fig_spatial_loop(out_dir: Path) -> list[Path]:
    """The UR5 and its bus along a closed joint loop (inertial axes, about the system centroid)."""
    robot = _robot()
    R, q = loop_history(robot)
    fig = plt.figure(figsize=(7.5, 6.5))
    ax = fig.add_subplot(projection="3d")
    picks = np.linspace(0, len(q) - 1, 7).astype(int)
    cmap = plt.get_cmap("viridis")
    everything = []
    for i, k in enumerate(picks):
        color = cmap(i / (len(picks) - 1))
        _draw(
            ax,
            robot,
            q[k],
            R[k],
            color,
            alpha=0.9 if k in (0, len(q) - 1) else 0.45,
            label="start" if k == 0 else ("end (joints back, bus turned)" if k == len(q) - 1 else None),
        )
        everything.append(_drawn_points(robot, q[k], R[k]))
    tips = np.array([arm_points(robot, qk, Rk)[0][-1] for qk, Rk in zip(q, R, strict=False)])
    ax.plot(*tips.T, color="C3", lw=1.0, label="tip")
    angle = float(np.linalg.norm(np.asarray(log(jnp.asarray(R[0].T @ R[-1])))))
    ax.set_title(f"UR5 on a 500 kg bus: closed joint loop turns the bus by {np.degrees(angle):.2f} deg")
    _equal(ax, np.vstack(everything + [tips]))
    ax.plot([], [], "-o", color=cmap(0.5), lw=1.6, ms=2.5, alpha=0.45, label="along the loop (colour: start to end)")
    ax.plot([], [], color="0.4", lw=0.8, label=BUS_LABEL)
    ax.legend(loc="upper left", fontsize=8)
    path = save_figure(fig, Path(out_dir) / "spatial_loop.png", dpi=130, bbox_inches="tight")
    plt.close(fig)
    return [path]


@figure("spatial-attitude")
def fig_spatial_attitude(out_dir: Path) -> list[Path]:
    """The bus rotation vector log(R0^T R) along the loop of ``spatial-loop``."""
    robot = _robot()
    R, q = loop_history(robot)
    vectors = np.asarray(log(jnp.asarray(np.swapaxes(R[:1], -1, -2) @ R)))
    s = np.linspace(0.0, 1.0, len(R))
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
    for i, name in enumerate("xyz"):
        top.plot(s, np.degrees(vectors[:, i]), label=f"bus {name}")
    top.plot(s, np.degrees(np.linalg.norm(vectors, axis=1)), "k--", lw=1, label="angle")
    top.set_ylabel("log(R0^T R), deg (bus axes)")
    top.legend(fontsize=8, ncol=4)
    for j in range(q.shape[1]):
        bottom.plot(s, q[:, j], label=robot.joint_names[j] if robot.joint_names else f"q{j + 1}")
    bottom.set_xlabel("loop parameter")
    bottom.set_ylabel("joint, rad")
    bottom.legend(fontsize=7, ncol=3)
    fig.suptitle("Bus attitude along a closed joint loop (6th-order Magnus on SO(3))")
    path = save_figure(fig, Path(out_dir) / "spatial_attitude.png", dpi=130, bbox_inches="tight")
    plt.close(fig)
    return [path]


@figure("spatial-straight")
def fig_spatial_straight(out_dir: Path) -> list[Path]:
    """A straight tip path of the UR5 to its end (dynamic singularity or 0.6 m), sampled by tip distance."""
    robot = _robot()
    q0, direction = LOOP_START, np.array([0.3, -0.5, 0.8])
    end = spatial_straight_tip_path(robot, q0, direction, 0.6)
    lengths = np.linspace(0.0, float(end.length), 25)
    samples = spatial_straight_tip_path(
        robot, np.broadcast_to(q0, (25, 6)), np.broadcast_to(direction, (25, 3)), lengths
    )
    q, R = np.asarray(samples.end_joints), np.asarray(samples.end_rotation)
    tips = np.asarray(samples.end_tip)
    fig = plt.figure(figsize=(11, 5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    _draw(ax, robot, q[0], R[0], "C0", label="start")
    _draw(ax, robot, q[-1], R[-1], "C3", label="end")
    ax.plot(*tips.T, "k-", lw=1.5, label="tip path")
    ends = [_drawn_points(robot, q[k], R[k]) for k in (0, -1)]
    _equal(ax, np.vstack(ends + [tips]))
    reason = {0: "J*_v loses rank", 1: "0.6 m reached", 2: "joint limit", 3: "approaching rank loss"}[int(end.reason)]
    ax.set_title(f"straight tip path, {float(end.length):.3f} m ({reason})", fontsize=10)
    ax.plot([], [], color="0.4", lw=0.8, label=BUS_LABEL)
    ax.legend(fontsize=8)
    right = fig.add_subplot(1, 2, 2)
    vectors = np.asarray(log(jnp.asarray(np.swapaxes(R[:1], -1, -2) @ R)))
    for i, name in enumerate("xyz"):
        right.plot(lengths, np.degrees(vectors[:, i]), label=f"bus {name}")
    right.set_xlabel("tip distance along the line, m")
    right.set_ylabel("bus rotation log(R0^T R), deg")
    right.legend(fontsize=8)
    path = save_figure(fig, Path(out_dir) / "spatial_straight.png", dpi=130, bbox_inches="tight")
    plt.close(fig)
    return [path]


def _drawn_points(robot, q, R) -> np.ndarray:
    """Every point drawn for one posture: links, tips and the bus box's corners."""
    return drawn_points(robot_drawing(robot, q, R))


def draw_spatial_reach(robot, plan, path) -> Path:
    """Draw a `SpatialReachPlan` in 3-D (for ``spacearm reach``), from its history.

    The arm at the start, after the bus-turning loop (joints back at q0, bus turned) and
    at the end; the tip along the loop and along the final straight path.

    Args:
        robot: the design. plan: the plan. path: the PNG to write.
    """
    joints, rotations, tips = (np.asarray(x, float) for x in (plan.joints, plan.base_rotation, plan.tips))
    loop_rows = np.flatnonzero(plan.phase == PHASE_LOOP)
    straight_rows = np.flatnonzero(plan.phase == PHASE_STRAIGHT)
    fig = plt.figure(figsize=(7.5, 6.5))
    ax = fig.add_subplot(projection="3d")
    _draw(ax, robot, joints[0], rotations[0], "C0", label="start")
    points = [_drawn_points(robot, joints[0], rotations[0]), tips]
    if loop_rows.size:
        ax.plot(*tips[loop_rows].T, color="C2", lw=0.8, label=f"tip along the loop ({plan.loops}x)")
        after = loop_rows[-1]
        _draw(ax, robot, joints[after], rotations[after], "C2", alpha=0.7, label="after the loop")
        points.append(_drawn_points(robot, joints[after], rotations[after]))
    ax.plot(*tips[straight_rows].T, "k-", lw=1.5, label="straight tip path")
    _draw(ax, robot, joints[-1], rotations[-1], "C3", label="end")
    points.append(_drawn_points(robot, joints[-1], rotations[-1]))
    ax.scatter(*np.asarray(plan.target), color="C3", marker="x", s=40, label="target")
    ax.set_title(
        f"reach ({plan.mode}): bus turned {np.degrees(plan.bus_turn):.2f} deg, tip error {plan.error:.1e} m",
        fontsize=10,
    )
    _equal(ax, np.vstack(points))
    ax.plot([], [], color="0.4", lw=0.8, label=BUS_LABEL)
    ax.legend(fontsize=8, loc="upper left")
    written = save_figure(fig, Path(path), dpi=130, bbox_inches="tight")
    plt.close(fig)
    return written


# Several arms on one bus ------------------------------------------------------------------------

# Postures of the tree figure: each UR5 reaching out from its face of the bus; the three-arm
# servicer with the telescope and the boom half out.
DUAL_UR5_POSTURE = np.array([0.4, -1.0, 1.4, -0.6, 1.2, 0.0, -0.4, -1.0, 1.4, -0.6, -1.2, 0.0])
THREE_ARM_POSTURE = np.array([0.5, -0.6, 0.8, 0.3, 0.6, 0.15, -0.5, 0.3, 0.7, 1.0])


def _tree_robot(name: str):
    path = CONFIGS / f"{name}.yaml"
    if not path.exists():
        raise FileNotFoundError(f"{path}: the tree figure uses the repository's configs/{name}.yaml")
    return load_robot(os.fspath(path))


def draw_tree_panel(ax, robot, q, title: str, view=(20.0, -35.0)) -> RobotDrawing:
    """One robot on its bus in one panel: the arms in their colours, equal axes, a legend;
    ``view`` is matplotlib's (elevation, azimuth) in degrees."""
    drawing = draw_robot(ax, robot, q)
    ax.view_init(*view)
    _equal(ax, drawn_points(drawing))
    ax.plot([], [], color="0.4", lw=0.8, label="bus (equivalent uniform box)")
    ax.plot([], [], color="tab:red", lw=1.2, label="mount frames (x red, y green, z blue)")
    ax.scatter([], [], color="0.3", marker="D", s=22, label="tips")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7, loc="upper left")
    return drawing


@figure("tree-arms")
def fig_tree_arms(out_dir: Path) -> list[Path]:
    """Two UR5 on a 400 kg servicer, and three arms on one servicer (a shared turret), each arm in its colour."""
    fig = plt.figure(figsize=(12, 6))
    dual = _tree_robot("dual-ur5-servicer")
    draw_tree_panel(
        fig.add_subplot(1, 2, 1, projection="3d"),
        dual,
        DUAL_UR5_POSTURE,
        f"{dual.name}: {dual.n_joints} joints, {dual.n_tips} tips, {float(dual.base_mass):g} kg bus",
        view=(15.0, 10.0),  # along the bus x axis: the arms on the +y and -y faces
    )
    three = _tree_robot("three-arm-servicer")
    draw_tree_panel(
        fig.add_subplot(1, 2, 2, projection="3d"),
        three,
        THREE_ARM_POSTURE,
        f"{three.name}: {three.n_joints} joints, {three.n_tips} tips (a shared turret, grey)",
    )
    fig.suptitle("Several arms on one bus: inertial axes about the system centroid, bus attitude identity")
    path = save_figure(fig, Path(out_dir) / "tree_arms.png", dpi=130, bbox_inches="tight")
    plt.close(fig)
    return [path]
