"""The kinematic model a browser page needs, as plain JSON: no Python at view time.

`chain_model` writes what `fk.js` (beside this file) evaluates: for a spatial robot
the mount pose, each joint's origin, axes and unit axis in its parent body (the URDF
``<joint>`` numbers as `spacearm.models.spatial.robot.SpatialRobot` holds them), the
tip offset and every body's mass and centroid (for the system centroid the tip is
measured from); for a planar robot the paper's a_i, b_i, b0 and masses (Umetani &
Yoshida 1990, Fig. 1); for a tree robot (several arms on one bus) every root's mount,
each joint's parent body and each tip's body as well. All give joint origins and the tips
about the system centroid, inertial axes, as `spacearm.tip_position` does
(tests/test_views.py runs the script with node against it to 1e-9 m).

The bus is drawn as its equivalent box: the uniform box with the bus's mass and
principal moments (side_i^2 = 6 (I_j + I_k - I_i) / m), along its principal axes,
about its centroid; a planar bus is the square plate with the same moment.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ...models.planar import PlanarRobot
from ...models.spatial import SpatialRobot
from ...models.spatial.urdf import rpy_matrix
from ...models.tree import TreeRobot

__all__ = ["FK_SCRIPT", "arm_names", "bus_box", "chain_model", "joint_owners", "scene_extent"]

# The forward kinematics in JavaScript (the same file every page inlines).
FK_SCRIPT = Path(__file__).with_name("fk.js")

# Corner order of a box: x, y, z signs; the 12 edges between corners.
_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)


def bus_box(robot) -> tuple[np.ndarray, np.ndarray]:
    """The bus's equivalent uniform box: ``(8, 3)`` corners in the bus frame, m, and its ``(3,)`` half sides.

    Spatial: centred at the bus centroid, edges along the principal axes of the bus
    inertia, side_i = sqrt(6 (I_j + I_k - I_i) / m). Planar: the square plate of the same
    mass and moment about its normal (side = sqrt(6 I / m)), 2 % of a side thick,
    centred at the base centroid.
    """
    if isinstance(robot, PlanarRobot):
        side = math.sqrt(6.0 * float(robot.base_inertia) / float(robot.base_mass))
        half = np.array([side / 2, side / 2, side / 100])
        return _CORNERS * half, half
    inertia = np.asarray(robot.base_inertia, float)
    moments, axes = np.linalg.eigh(inertia)
    total = moments.sum()
    sides = np.sqrt(np.maximum(6.0 * (total - 2.0 * moments) / float(robot.base_mass), 1e-6))
    half = sides / 2
    corners = np.asarray(robot.base_com, float) + (_CORNERS * half) @ axes.T
    return corners, half


def chain_model(robot) -> dict:
    """The robot as a JSON-ready mapping for `fk.js` (one design, no batch axes).

    Keys common to both families: ``family`` (``"spatial"`` or ``"planar"``), ``name``,
    ``joint_names``, ``joint_kinds``, ``lower`` and ``upper`` (joint limits, ``None`` where
    free), ``bus_corners`` (the `bus_box` corners, bus frame, m). Spatial: ``mount_rotation``,
    ``mount_xyz``, ``joint_rotation``, ``joint_translation``, ``joint_axis`` (unit),
    ``tip_translation``, ``base_mass``, ``base_com``, ``root_mass``, ``root_com``,
    ``link_mass``, ``link_com``. Planar: ``base_mass``, ``attach`` (b0), ``link_mass``,
    ``a``, ``b``.
    """
    corners, _ = bus_box(robot)
    limits = lambda v: [float(x) if math.isfinite(x) else None for x in np.asarray(v, float).ravel()]
    if isinstance(robot, PlanarRobot):
        n = int(np.shape(robot.link_a)[-1])
        return dict(
            family="planar",
            name=str(robot.name),
            joint_names=[f"joint {i + 1}" for i in range(n)],
            joint_kinds=["revolute"] * n,
            lower=limits(robot.joint_lower),
            upper=limits(robot.joint_upper),
            bus_corners=corners.tolist(),
            base_mass=float(robot.base_mass),
            attach=float(robot.base_attach),
            link_mass=np.asarray(robot.link_mass, float).tolist(),
            a=np.asarray(robot.link_a, float).tolist(),
            b=np.asarray(robot.link_b, float).tolist(),
        )
    if isinstance(robot, TreeRobot):
        return _tree_model(robot, corners, limits)
    if not isinstance(robot, SpatialRobot):
        raise TypeError(f"chain_model: a planar, spatial or tree robot, got {type(robot).__name__}")
    if robot.batch_shape:
        raise ValueError(f"chain_model: one design, got a batch of shape {robot.batch_shape}")
    axis = np.asarray(robot.joint_axis, float)
    names = robot.joint_names or tuple(f"q{i + 1}" for i in range(robot.n_joints))
    return dict(
        family="spatial",
        name=robot.name,
        joint_names=list(names),
        joint_kinds=list(robot.joint_kinds),
        lower=limits(robot.joint_lower),
        upper=limits(robot.joint_upper),
        bus_corners=corners.tolist(),
        mount_rotation=rpy_matrix(np.asarray(robot.mount_rpy, float)).tolist(),
        mount_xyz=np.asarray(robot.mount_xyz, float).tolist(),
        joint_rotation=np.asarray(robot.joint_rotation, float).tolist(),
        joint_translation=np.asarray(robot.joint_translation, float).tolist(),
        joint_axis=(axis / np.linalg.norm(axis, axis=-1, keepdims=True)).tolist(),
        tip_translation=np.asarray(robot.tip_translation, float).tolist(),
        base_mass=float(robot.base_mass),
        base_com=np.asarray(robot.base_com, float).tolist(),
        root_mass=float(robot.root_mass),
        root_com=np.asarray(robot.root_com, float).tolist(),
        link_mass=np.asarray(robot.link_mass, float).tolist(),
        link_com=np.asarray(robot.link_com, float).tolist(),
    )


def arm_names(robot: TreeRobot) -> list[str]:
    """One name per tip: the arm's name (an ``arms:`` file), else the tip's name."""
    roots = robot.labels.joint_roots
    if robot.n_roots > 1 and robot.labels.root_names and roots:
        return [robot.labels.root_names[roots[body]] for body in robot.tip_bodies]
    return list(robot.tip_names) or [f"tip {t + 1}" for t in range(robot.n_tips)]


def joint_owners(robot: TreeRobot) -> list[int]:
    """``n``: the tip each joint moves (the arm it is drawn in), -1 for a joint several tips share."""
    support = robot.support
    return [int(np.flatnonzero(support[:, j])[0]) if support[:, j].sum() == 1 else -1 for j in range(robot.n_joints)]


def _tree_model(robot: TreeRobot, corners, limits) -> dict:
    """`chain_model` of a tree: the spatial keys per root and per joint, with ``parents``
    (body index, or ``-1 - r`` for root r), ``tip_bodies``, ``tip_translation (k, 3)``,
    ``owner`` (the tip each joint moves, -1 when it moves several) and ``arm_names``."""
    if robot.batch_shape:
        raise ValueError(f"chain_model: one design, got a batch of shape {robot.batch_shape}")
    axis = np.asarray(robot.joint_axis, float)
    return dict(
        family="tree",
        name=robot.name,
        joint_names=list(robot.joint_names or tuple(f"q{i + 1}" for i in range(robot.n_joints))),
        joint_kinds=list(robot.joint_kinds),
        lower=limits(robot.joint_lower),
        upper=limits(robot.joint_upper),
        bus_corners=corners.tolist(),
        mount_rotation=[rpy_matrix(np.asarray(rpy, float)).tolist() for rpy in robot.mount_rpy],
        mount_xyz=np.asarray(robot.mount_xyz, float).tolist(),
        parents=list(robot.parents),
        tip_bodies=list(robot.tip_bodies),
        owner=joint_owners(robot),
        arm_names=arm_names(robot),
        joint_rotation=np.asarray(robot.joint_rotation, float).tolist(),
        joint_translation=np.asarray(robot.joint_translation, float).tolist(),
        joint_axis=(axis / np.linalg.norm(axis, axis=-1, keepdims=True)).tolist(),
        tip_translation=np.asarray(robot.tip_translation, float).tolist(),
        base_mass=float(robot.base_mass),
        base_com=np.asarray(robot.base_com, float).tolist(),
        root_mass=np.asarray(robot.root_mass, float).tolist(),
        root_com=np.asarray(robot.root_com, float).tolist(),
        link_mass=np.asarray(robot.link_mass, float).tolist(),
        link_com=np.asarray(robot.link_com, float).tolist(),
    )


def _tree_reach(robot: TreeRobot) -> float:
    """An upper bound on how far a tip or body gets from its root's origin, m: along the
    longest tip path, the joint offsets, the prismatic travel and the tip offset (plus the
    farthest link centroid from its joint)."""
    prismatic = np.array([k == "prismatic" for k in robot.joint_kinds])
    bound = lambda v: np.nan_to_num(np.abs(np.asarray(v, float)), posinf=1.0)
    travel = np.where(prismatic, np.maximum(bound(robot.joint_lower), bound(robot.joint_upper)), 0.0)
    steps = np.linalg.norm(np.asarray(robot.joint_translation, float), axis=-1) + travel
    paths = robot.support @ steps + np.linalg.norm(np.asarray(robot.tip_translation, float), axis=-1)
    return float(np.max(paths) + np.max(np.linalg.norm(np.asarray(robot.link_com, float), axis=-1), initial=0.0))


def scene_extent(robot) -> float:
    """A half width, m, of a cube about the system centroid that holds the bus and the arm in
    every posture, +10 %: the farther of the bus corners and the arm's reach from the bus
    centroid, plus the most the system centroid can stray from the bus centroid (the mass
    fraction off the bus times that reach)."""
    corners, _ = bus_box(robot)
    if isinstance(robot, TreeRobot):
        com = np.asarray(robot.base_com, float)
        bus = float(np.max(np.linalg.norm(corners - com, axis=-1)))
        mount = float(np.max(np.linalg.norm(np.asarray(robot.mount_xyz, float) - com, axis=-1)))
        arm = mount + _tree_reach(robot)
        off_bus = float(np.sum(robot.root_mass)) + float(np.sum(robot.link_mass))
        fraction = off_bus / (off_bus + float(robot.base_mass))
        return 1.1 * (max(bus, arm) + fraction * arm)
    if isinstance(robot, PlanarRobot):
        masses = np.asarray(robot.link_mass, float)
        arm = float(robot.base_attach) + float(np.sum(np.asarray(robot.link_a) + np.asarray(robot.link_b)))
        bus = float(np.max(np.linalg.norm(corners, axis=-1)))
        fraction = masses.sum() / (masses.sum() + float(robot.base_mass))
    else:
        com = np.asarray(robot.base_com, float)
        bus = float(np.max(np.linalg.norm(corners - com, axis=-1)))
        mount = float(np.linalg.norm(np.asarray(robot.mount_xyz, float) - com))
        arm = mount + max(float(robot.reach), float(np.linalg.norm(robot.root_com)))
        off_bus = float(robot.root_mass) + float(np.sum(robot.link_mass))
        fraction = off_bus / (off_bus + float(robot.base_mass))
    return 1.1 * (max(bus, arm) + fraction * arm)
