"""A robot as one family-free JSON tree of bodies on a free bus, for drawing.

`view_model` describes any robot as one articulated tree on a free bus: bodies joined
by revolute or prismatic joints, rooted at mount frames fixed on the bus, with tips on
bodies. A spatial arm is the one-tip tree with one mount; a planar arm is the same tree
with every joint about z and the bus attitude a turn about z. The browser's forward
kinematics (``spacearm/figures/views/fk.js``) evaluates this mapping for every robot,
and the matplotlib figures read the bus box, the arm names and the joint owners from it,
so nothing above this layer asks which family it holds.

Each family writes its own description (``models/<family>/view.py``), reached through
`spacearm.models.family.RobotFamily.view_model`; this module holds the shared pieces.

The mapping (all lengths m, angles rad, one design, bus frame):

- ``name``; ``joint_names``, ``joint_kinds`` (``"revolute"``/``"prismatic"``), ``lower``,
  ``upper`` (``None`` where free): ``n`` each.
- ``mount_rotation (r, 3, 3)``, ``mount_xyz (r, 3)``: the frames the arms hang from;
  ``root_mass (r,)``, ``root_com (r, 3)``: the fixed bodies at the mounts (mount frame).
- ``parents (n,)``: each joint's parent body, or ``-1 - r`` for mount r.
- ``joint_rotation (n, 3, 3)``, ``joint_translation (n, 3)``: the joint's placement in
  its parent's frame; ``joint_axis (n, 3)``: unit axis in the joint frame.
- ``link_mass (n,)``, ``link_com (n, 3)``: each body's mass and centroid (body frame).
- ``tip_bodies (k,)``, ``tip_translation (k, 3)``, ``tip_names (k,)``; ``owner (n,)``:
  the tip each joint moves, -1 when it moves several.
- ``base_mass``, ``base_com (3,)``; ``bus_corners (8, 3)``: the bus's equivalent box
  (`box_corners`); ``extent``: a half width about the system centroid that holds the
  robot in every posture.
- ``posture``: how a posture vector maps to the joints and the bus attitude:
  ``size`` entries, the joints from ``joint_offset`` on, and ``base_turn`` (``None``, or
  ``{"index", "axis", "name"}``: the bus attitude is a turn by that entry about that
  axis, and no separate attitude is given).
- ``plane``: ``None``, or ``{"normal": (3,)}`` when every posture stays in the plane
  through the centroid with that normal (drawn flat).
"""

from __future__ import annotations

import math

import numpy as np

from .family import family_of

__all__ = [
    "box_corners",
    "chain_owners",
    "check_one_design",
    "joint_limits",
    "plate_corners",
    "unit_axes",
    "view_model",
    "view_pose",
]

# Corner order of a box: x, y, z signs (corner c has the bits 4, 2, 1).
_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)


def view_model(robot) -> dict:
    """The robot (one design) as the JSON-ready tree described in this module's docstring.

    Raises:
        TypeError: not a spacearm robot.
        ValueError: a batch of designs.
        NotImplementedError: a family that writes no view description.
    """
    return family_of(robot).view_model(robot)


def view_pose(model: dict, posture, rotation=None) -> dict[str, np.ndarray]:
    """The points of a `view_model` mapping at one posture, inertial axes about the system
    centroid, m: the NumPy twin of ``spacearmPose`` in ``figures/views/fk.js`` (the same walk
    over the tree, parents before children), for figures drawn without a browser.

    Args:
        model: a `view_model` mapping.
        posture: ``(size,)`` laid out as ``model["posture"]`` says (rad; m for prismatic joints).
        rotation: ``(3, 3)`` the bus attitude, for a posture that does not hold it (identity when absent).

    Returns:
        ``joints (n, 3)`` joint origins; ``bodies (n, 3)`` body origins (slid along prismatic
        axes); ``tips (k, 3)``; ``segments (s, 2, 3)`` links parent to joint, joint to body where
        it slid, body to tip, with ``owner (s,)`` the tip of each (-1: shared); ``mounts (r, 3)``,
        ``mount_axes (r, 3, 3)`` (axes as columns); ``bus (3,)`` its centroid; ``corners (8, 3)``.
    """
    layout, posture = model["posture"], np.asarray(posture, float)
    turn, n = layout["base_turn"], len(model["joint_kinds"])
    q = posture[layout["joint_offset"] : layout["joint_offset"] + n]
    R = np.eye(3) if rotation is None else np.asarray(rotation, float)
    if turn is not None:
        R = _axis_angle(np.asarray(turn["axis"], float), posture[turn["index"]])
    get = lambda key: np.asarray(model[key], float)
    mount_axes, mounts = get("mount_rotation"), get("mount_xyz")
    root_mass, axes = get("root_mass"), get("joint_axis")
    mass = float(model["base_mass"]) + root_mass.sum()
    moment = float(model["base_mass"]) * get("base_com")
    moment = moment + root_mass @ (mounts + np.einsum("rij,rj->ri", mount_axes, get("root_com")))
    rots, bodies, joints, segments, owner = [], [], [], [], []
    for k, parent in enumerate(model["parents"]):
        rot, origin = (mount_axes[-1 - parent], mounts[-1 - parent]) if parent < 0 else (rots[parent], bodies[parent])
        joint, frame = origin + rot @ get("joint_translation")[k], rot @ get("joint_rotation")[k]
        joints.append(joint)
        segments.append((origin, joint))
        owner.append(model["owner"][k])
        if model["joint_kinds"][k] == "prismatic":
            rots.append(frame)
            bodies.append(joint + q[k] * (frame @ axes[k]))
            segments.append((joint, bodies[k]))
            owner.append(model["owner"][k])
        else:
            rots.append(frame @ _axis_angle(axes[k], q[k]))
            bodies.append(joint)
        mass += model["link_mass"][k]
        moment = moment + model["link_mass"][k] * (bodies[k] + rots[k] @ get("link_com")[k])
    tips = []
    for t, body in enumerate(model["tip_bodies"]):
        tips.append(bodies[body] + rots[body] @ get("tip_translation")[t])
        segments.append((bodies[body], tips[t]))
        owner.append(t)
    place = lambda p: (np.asarray(p, float).reshape(-1, 3) - moment / mass) @ R.T
    return dict(
        joints=place(joints),
        bodies=place(bodies),
        tips=place(tips),
        segments=place(segments).reshape(-1, 2, 3),
        owner=np.asarray(owner, int),
        mounts=place(mounts),
        mount_axes=R @ mount_axes,
        bus=place(get("base_com"))[0],
        corners=place(get("bus_corners")),
    )


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    """``(3, 3)`` rotation by ``angle`` (rad) about the unit ``axis`` (Rodrigues)."""
    skew = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle) * skew + (1.0 - np.cos(angle)) * skew @ skew


def box_corners(mass, inertia, centroid) -> tuple[np.ndarray, np.ndarray]:
    """The uniform box with this ``mass`` (kg) and ``(3, 3)`` inertia about its centroid
    (kg m^2): its ``(8, 3)`` corners at ``centroid`` along the principal axes, and its
    ``(3,)`` half sides (side_i^2 = 6 (I_j + I_k - I_i) / m), m."""
    moments, axes = np.linalg.eigh(np.asarray(inertia, float))
    total = moments.sum()
    sides = np.sqrt(np.maximum(6.0 * (total - 2.0 * moments) / float(mass), 1e-6))
    half = sides / 2
    return np.asarray(centroid, float) + (_CORNERS * half) @ axes.T, half


def plate_corners(mass, moment) -> tuple[np.ndarray, np.ndarray]:
    """The square plate with this ``mass`` and ``moment`` about its normal (side =
    sqrt(6 I / m)), 2 % of a side thick, about the origin: corners ``(8, 3)`` and half sides."""
    side = math.sqrt(6.0 * float(moment) / float(mass))
    half = np.array([side / 2, side / 2, side / 100])
    return _CORNERS * half, half


def joint_limits(values) -> list:
    """Joint limits as JSON: floats, ``None`` where a joint is free."""
    return [float(x) if math.isfinite(x) else None for x in np.asarray(values, float).ravel()]


def unit_axes(axes) -> list:
    """``(n, 3)`` joint axes scaled to unit length."""
    axes = np.asarray(axes, float)
    return (axes / np.linalg.norm(axes, axis=-1, keepdims=True)).tolist()


def chain_owners(n: int) -> list[int]:
    """Every joint of a serial arm moves its one tip."""
    return [0] * n


def check_one_design(batch_shape) -> None:
    """Refuse a batch of designs (a view draws one)."""
    if batch_shape:
        raise ValueError(f"view_model: one design, got a batch of shape {tuple(batch_shape)}")
