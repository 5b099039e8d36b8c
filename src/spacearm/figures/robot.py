"""The robot as drawn: one outline (base centroid, joints, tip) and one base square, shared
by every figure that draws the arm in the inertial frame."""

from __future__ import annotations

import numpy as np

from ..models.planar.closed_forms import centroid_positions

__all__ = ["base_square", "robot_outline"]

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
