"""The robot as drawn: one outline (base centroid, joints, tip) and one base square, shared
by every figure that draws the arm in the inertial frame."""

from __future__ import annotations

import numpy as np

from ..paper.planar_parts import centroid_positions

__all__ = ["base_square", "draw_planar_robot", "robot_outline"]

_SQUARE = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1], [1, 1]])


def robot_outline(robot, phi) -> tuple[np.ndarray, np.ndarray]:
    """Base centroid and the chain [joint 1, ..., joint n, tip] in the inertial frame, m.

    Args:
        phi: ``(n+1,)`` posture, rad.

    Returns:
        ``(2,)`` base centroid and ``(n+1, 2)`` joints then tip.
    """
    phi = np.asarray(phi, float)
    theta = np.cumsum(phi)
    base = np.asarray(centroid_positions(robot, phi))[0]
    spans = np.r_[float(robot.base_attach), np.asarray(robot.link_length)]
    steps = spans[:, None] * np.stack([np.cos(theta), np.sin(theta)], axis=-1)
    return base, base + np.cumsum(steps, axis=0)


def base_square(base, phi0, half: float) -> np.ndarray:
    """``(5, 2)`` closed corners of a square of half side ``half`` about ``base``, turned by ``phi0``."""
    c, s = np.cos(phi0), np.sin(phi0)
    return base + (_SQUARE * half) @ np.array([[c, s], [-s, c]])


def draw_planar_robot(
    ax,
    robot,
    phi,
    color="0.2",
    label=None,
    *,
    alpha: float = 1.0,
    lw: float = 2.0,
    fill: float = 0.10,
    robot_frame: bool = False,
):
    """Draw a planar arm in one posture: its base as a square (side b0, at least 0.6 m) about
    the base centroid, and the chain base centroid, joints, tip as a polyline with dots.

    Args:
        ax: matplotlib axes.
        phi: ``(n+1,)`` posture, rad.
        fill: opacity of the base square's fill, relative to ``alpha`` (0 for none).
        robot_frame: move the origin to joint 1 (the paper's robot frame when phi0 = 0).
    """
    phi = np.asarray(phi, float)
    base, chain = robot_outline(robot, phi)
    box = base_square(base, phi[0], max(0.5 * float(robot.base_attach), 0.3))
    points = np.vstack([base, chain])
    if robot_frame:
        box, points = box - chain[0], points - chain[0]
    if fill:
        ax.fill(box[:, 0], box[:, 1], color=color, alpha=fill * alpha)
    ax.plot(box[:, 0], box[:, 1], color=color, lw=1.0, alpha=alpha)
    ax.plot(points[:, 0], points[:, 1], "-o", color=color, lw=lw, ms=3, alpha=alpha, label=label)
