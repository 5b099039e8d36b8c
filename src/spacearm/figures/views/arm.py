"""``view.html``: one robot on its bus, a slider per joint (and per bus attitude angle).

The page holds the kinematic model, not poses: moving a slider runs `fk.js` in the
browser, so any posture can be reached with no Python behind the page.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .model import view_model
from .page import write_page

__all__ = ["write_arm_view"]


def write_arm_view(robot, path: str | Path, posture=None, *, attitude_rpy=None) -> Path:
    """Write the interactive view of one robot.

    Args:
        robot: any spacearm robot (one design).
        path: the HTML file to write.
        posture: the first posture shown, laid out as the robot's family lays it out
            (``view_model(robot)["posture"]``: a planar arm's [phi0, phi1..phin], rad; a spatial
            or tree robot's joints, rad, m for prismatic joints); default zeros.
        attitude_rpy: the first bus attitude as URDF roll, pitch, yaw, rad, for robots whose
            posture does not hold it.

    Raises:
        MissingViewExtra: plotly is not installed.
    """
    model = view_model(robot)
    count = model["posture"]["size"]
    posture = np.zeros(count) if posture is None else np.asarray(posture, float).reshape(-1)
    if posture.shape != (count,):
        raise ValueError(f"posture: expected {count} values, got {posture.size}")
    arms = len(model["tip_bodies"])
    note = (
        "Drag to turn, scroll to zoom. Links are drawn from the kinematic model (joint origins and the tip"
        + ("s, each arm in its colour, the mount frames x, y, z in red, green, blue" if arms > 1 else "")
        + "), "
        "the bus as the uniform box of its mass and inertia; positions are about the system centroid"
        + (
            ", in the arm's plane."
            if model["plane"]
            else ", inertial axes (the bus attitude sliders turn the bus frame)."
        )
    )
    data = dict(
        mode="arm",
        model=model,
        posture=posture,
        extent=model["extent"],
        rpy=[0.0, 0.0, 0.0] if attitude_rpy is None else np.asarray(attitude_rpy, float),
        title=f"{model['name']}: {len(model['joint_kinds'])} joints"
        + (f", {arms} arms" if arms > 1 else "")
        + f" on a {model['base_mass']:g} kg bus",
    )
    return write_page(path, title=f"spacearm view: {model['name']}", note=note, data=data)
