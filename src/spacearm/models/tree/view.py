"""A tree of arms as the family-free view tree of `spacearm.models.view_model`.

A `TreeRobot` already is that tree: each root's mount, each joint's parent body (or
``-1 - r`` for root r), its URDF placement and axis, and each tip's body and offset. Its
tips are named by their arm (an ``arms:`` file), else by their own name.
"""

from __future__ import annotations

import numpy as np

from ..._core.groups import rpy_matrix
from ..view_model import box_corners, check_one_design, joint_limits, unit_axes

__all__ = ["arm_names", "joint_owners", "tree_view_model"]


def tree_view_model(robot) -> dict:
    """The `spacearm.models.view_model.view_model` mapping of a `TreeRobot` (one design)."""
    check_one_design(robot.batch_shape)
    corners, _ = box_corners(robot.base_mass, robot.base_inertia, robot.base_com)
    return dict(
        name=robot.name,
        joint_names=list(robot.joint_names or tuple(f"q{i + 1}" for i in range(robot.n_joints))),
        joint_kinds=list(robot.joint_kinds),
        lower=joint_limits(robot.joint_lower),
        upper=joint_limits(robot.joint_upper),
        mount_rotation=[rpy_matrix(np.asarray(rpy, float)).tolist() for rpy in robot.mount_rpy],
        mount_xyz=np.asarray(robot.mount_xyz, float).tolist(),
        root_mass=np.asarray(robot.root_mass, float).tolist(),
        root_com=np.asarray(robot.root_com, float).tolist(),
        parents=list(robot.parents),
        joint_rotation=np.asarray(robot.joint_rotation, float).tolist(),
        joint_translation=np.asarray(robot.joint_translation, float).tolist(),
        joint_axis=unit_axes(robot.joint_axis),
        link_mass=np.asarray(robot.link_mass, float).tolist(),
        link_com=np.asarray(robot.link_com, float).tolist(),
        tip_bodies=list(robot.tip_bodies),
        tip_translation=np.asarray(robot.tip_translation, float).tolist(),
        tip_names=arm_names(robot),
        owner=joint_owners(robot),
        base_mass=float(robot.base_mass),
        base_com=np.asarray(robot.base_com, float).tolist(),
        bus_corners=corners.tolist(),
        extent=_extent(robot, corners),
        posture=dict(size=robot.n_joints, joint_offset=0, base_turn=None),
        plane=None,
    )


def arm_names(robot) -> list[str]:
    """One name per tip: the arm's name (an ``arms:`` file), else the tip's name."""
    roots = robot.labels.joint_roots
    if robot.n_roots > 1 and robot.labels.root_names and roots:
        return [robot.labels.root_names[roots[body]] for body in robot.tip_bodies]
    return list(robot.tip_names) or [f"tip {t + 1}" for t in range(robot.n_tips)]


def joint_owners(robot) -> list[int]:
    """``n``: the tip each joint moves (the arm it is drawn in), -1 for a joint several tips share."""
    support = robot.support
    return [int(np.flatnonzero(support[:, j])[0]) if support[:, j].sum() == 1 else -1 for j in range(robot.n_joints)]


def _reach(robot) -> float:
    """An upper bound on how far a tip or body gets from its root's origin, m: along the
    longest tip path, the joint offsets, the prismatic travel and the tip offset (plus the
    farthest link centroid from its joint)."""
    prismatic = np.array([k == "prismatic" for k in robot.joint_kinds])
    bound = lambda v: np.nan_to_num(np.abs(np.asarray(v, float)), posinf=1.0)
    travel = np.where(prismatic, np.maximum(bound(robot.joint_lower), bound(robot.joint_upper)), 0.0)
    steps = np.linalg.norm(np.asarray(robot.joint_translation, float), axis=-1) + travel
    paths = robot.support @ steps + np.linalg.norm(np.asarray(robot.tip_translation, float), axis=-1)
    return float(np.max(paths) + np.max(np.linalg.norm(np.asarray(robot.link_com, float), axis=-1), initial=0.0))


def _extent(robot, corners) -> float:
    """A half width, m, of a cube about the system centroid holding the bus and every arm in
    every posture, +10 % (as the spatial arm's, with every mount and the longest tip path)."""
    com = np.asarray(robot.base_com, float)
    bus = float(np.max(np.linalg.norm(corners - com, axis=-1)))
    mount = float(np.max(np.linalg.norm(np.asarray(robot.mount_xyz, float) - com, axis=-1)))
    arm = mount + _reach(robot)
    off_bus = float(np.sum(robot.root_mass)) + float(np.sum(robot.link_mass))
    fraction = off_bus / (off_bus + float(robot.base_mass))
    return 1.1 * (max(bus, arm) + fraction * arm)
