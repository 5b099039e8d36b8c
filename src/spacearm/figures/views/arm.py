"""``view.html``: one robot on its bus, a slider per joint (and per bus attitude angle).

The page holds the kinematic model, not poses: moving a slider runs `fk.js` in the
browser, so any posture can be reached with no Python behind the page.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...models.planar import PlanarRobot
from ...models.tree import TreeRobot
from .model import chain_model, scene_extent
from .page import write_page

__all__ = ["write_arm_view"]


def write_arm_view(robot, path: str | Path, posture=None, *, attitude_rpy=None) -> Path:
    """Write the interactive view of one robot.

    Args:
        robot: a planar, spatial or tree robot (one design).
        path: the HTML file to write.
        posture: the first posture shown: planar ``(n+1,)`` [phi0, phi1..phin], rad;
            spatial and tree ``(n,)`` joints, rad (m for prismatic joints); default zeros.
        attitude_rpy: spatial robots: the first bus attitude as URDF roll, pitch, yaw, rad.

    Raises:
        MissingViewExtra: plotly is not installed.
    """
    model = chain_model(robot)
    count = len(model["joint_kinds"]) + (1 if isinstance(robot, PlanarRobot) else 0)
    posture = np.zeros(count) if posture is None else np.asarray(posture, float).reshape(-1)
    if posture.shape != (count,):
        raise ValueError(f"posture: expected {count} values, got {posture.size}")
    planar = isinstance(robot, PlanarRobot)
    note = (
        "Drag to turn, scroll to zoom. Links are drawn from the kinematic model (joint origins and the tip"
        + (
            "s, each arm in its colour, the mount frames x, y, z in red, green, blue"
            if isinstance(robot, TreeRobot)
            else ""
        )
        + "), "
        "the bus as the uniform box of its mass and inertia; positions are about the system centroid"
        + (", in the arm's plane." if planar else ", inertial axes (the bus attitude sliders turn the bus frame).")
    )
    data = dict(
        mode="arm",
        model=model,
        posture=posture,
        extent=scene_extent(robot),
        rpy=[0.0, 0.0, 0.0] if attitude_rpy is None else np.asarray(attitude_rpy, float),
        title=f"{model['name']}: {len(model['joint_kinds'])} joints"
        + (f", {robot.n_tips} arms" if isinstance(robot, TreeRobot) else "")
        + f" on a {model['base_mass']:g} kg bus",
    )
    return write_page(path, title=f"spacearm view: {model['name']}", note=note, data=data)
