"""Spatial arms on their bus in 3-D: a joint loop, the attitude history, a straight tip path.

Registered figures (``spacearm figures``), all for the UR5 on its 500 kg smallsat
(configs/ur5-smallsat.yaml):

- ``spatial-loop``: the arm and its bus drawn along a closed joint loop, inertial axes,
  about the system centroid; the tip trace; the bus turned by the loop.
- ``spatial-attitude``: the bus rotation vector log(R0^T R) and its angle along the loop.
- ``spatial-straight``: a straight tip path to its dynamic singularity (or 0.6 m), the
  arm at the start and the end, the bus attitude along the path.
"""

from __future__ import annotations

import os
from pathlib import Path

import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np

from ..io import save_figure
from ..models import load_robot
from ..models.spatial import primitives
from ..motion.attitude import log, spatial_joint_path_history
from ..motion.spatial_paths import spatial_straight_tip_path
from ..planning.spatial_reach import PHASE_LOOP, PHASE_STRAIGHT
from . import figure

CONFIG = Path(__file__).resolve().parents[3] / "configs" / "ur5-smallsat.yaml"
LOOP_START = np.array([0.3, -1.2, 1.6, -0.9, 1.2, 0.2])


def _robot():
    if not CONFIG.exists():
        raise FileNotFoundError(f"{CONFIG}: the spatial figures use the repository's configs/ur5-smallsat.yaml")
    return load_robot(os.fspath(CONFIG))


def arm_points(robot, q, rotation) -> tuple[np.ndarray, np.ndarray]:
    """Joint origins then tip ``(n + 1, 3)``, and the bus centroid ``(3,)``, inertial axes
    about the system centroid, m, for one posture ``q (n,)`` and bus attitude ``rotation``."""
    state = primitives._chain_pass(robot, jnp.asarray(q, float))  # one posture: (n,) batch-last
    centroid = np.array([float(x) for x in state.centroid])
    origins = np.stack([np.asarray(c, float) for c in state.origins], axis=-1)  # (n, 3): joint origins
    chain = np.vstack([origins, [[float(x) for x in state.tip]]])
    bus = np.asarray(robot.base_com, float)
    R = np.asarray(rotation, float)
    return (chain - centroid) @ R.T, R @ (bus - centroid)


BUS_HALF = 0.35  # m, half the edge of the cube drawn for the bus (a marker, not its shape)


def bus_corners(centre, rotation, half: float = BUS_HALF) -> np.ndarray:
    """``(8, 3)`` corners of the cube drawn for the bus, inertial axes."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float) * half
    return np.asarray(centre) + corners @ np.asarray(rotation).T


def _bus_box(ax, centre, rotation, half, color, alpha):
    points = bus_corners(centre, rotation, half)
    edges = [(0, 1), (0, 2), (0, 4), (1, 3), (1, 5), (2, 3), (2, 6), (3, 7), (4, 5), (4, 6), (5, 7), (6, 7)]
    for a, b in edges:
        ax.plot(*points[[a, b]].T, color=color, lw=0.8, alpha=alpha)


def _draw(ax, robot, q, R, color, alpha=1.0, label=None):
    chain, bus = arm_points(robot, q, R)
    _bus_box(ax, bus, R, BUS_HALF, color, 0.6 * alpha)
    ax.plot(*np.vstack([bus, chain]).T, "-o", color=color, lw=1.6, ms=2.5, alpha=alpha, label=label)


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
    R, q = spatial_joint_path_history(robot, loop[0], loop, samples_per_segment=samples_per_segment, steps=1)
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
        chain, bus = arm_points(robot, q[k], R[k])
        everything.append(np.vstack([chain, bus_corners(bus, R[k])]))
    tips = np.array([arm_points(robot, qk, Rk)[0][-1] for qk, Rk in zip(q, R, strict=False)])
    ax.plot(*tips.T, color="C3", lw=1.0, label="tip")
    angle = float(np.linalg.norm(np.asarray(log(jnp.asarray(R[0].T @ R[-1])))))
    ax.set_title(f"UR5 on a 500 kg bus: closed joint loop turns the bus by {np.degrees(angle):.2f} deg")
    _equal(ax, np.vstack(everything + [tips]))
    ax.plot([], [], "-o", color=cmap(0.5), lw=1.6, ms=2.5, alpha=0.45, label="along the loop (colour: start to end)")
    ax.plot([], [], color="0.4", lw=0.8, label="bus (a 0.7 m cube about its centroid)")
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
    ends = [
        np.vstack([arm_points(robot, q[k], R[k])[0], bus_corners(arm_points(robot, q[k], R[k])[1], R[k])])
        for k in (0, -1)
    ]
    _equal(ax, np.vstack(ends + [tips]))
    reason = {0: "J*_v loses rank", 1: "0.6 m reached", 2: "joint limit", 3: "approaching rank loss"}[int(end.reason)]
    ax.set_title(f"straight tip path, {float(end.length):.3f} m ({reason})", fontsize=10)
    ax.plot([], [], color="0.4", lw=0.8, label="bus (a 0.7 m cube about its centroid)")
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
    """Every point drawn for one posture: joint origins, tip and the bus cube's corners."""
    chain, bus = arm_points(robot, q, R)
    return np.vstack([chain, bus_corners(bus, R)])


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
    ax.plot([], [], color="0.4", lw=0.8, label=f"bus (a {2 * BUS_HALF:.1f} m cube about its centroid)")
    ax.legend(fontsize=8, loc="upper left")
    written = save_figure(fig, Path(path), dpi=130, bbox_inches="tight")
    plt.close(fig)
    return written
