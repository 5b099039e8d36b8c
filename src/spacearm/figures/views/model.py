"""The kinematic model a browser page needs, as plain JSON: no Python at view time.

Every page carries `spacearm.models.view_model.view_model` of its robot: one tree of
bodies on a free bus for every robot (a serial arm is the one-tip tree, a planar arm the
tree whose joints turn about z, its bus attitude a turn about z held in the posture).
`fk.js` (beside this file, `FK_SCRIPT`) evaluates it: joint origins, body origins and
tips about the system centroid, inertial axes, as `spacearm.tip_position` gives them
(tests/test_views.py runs the script with node against the library to 1e-9 m).

The bus is drawn as its equivalent box: the uniform box with the bus's mass and
principal moments, along its principal axes, about its centroid (a planar bus: the square
plate with the same moment).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...models.view_model import view_model

__all__ = ["FK_SCRIPT", "posture_prismatic", "view_model"]

# The forward kinematics in JavaScript (the same file every page inlines).
FK_SCRIPT = Path(__file__).with_name("fk.js")


def posture_prismatic(model: dict) -> np.ndarray:
    """``(size,)`` booleans over a posture of ``model`` (a `view_model` mapping): the entries
    that are prismatic joints (m); the others are angles (rad)."""
    layout = model["posture"]
    prismatic = np.zeros(layout["size"], bool)
    kinds = np.array([kind == "prismatic" for kind in model["joint_kinds"]], bool)
    prismatic[layout["joint_offset"] : layout["joint_offset"] + len(kinds)] = kinds
    return prismatic
