"""A spatial arm as the family-free view tree of `spacearm.models.view_model`.

The URDF chain (`spacearm.models.spatial.robot.SpatialRobot`) is the one-tip tree with one
mount: joint 1 hangs from the mount frame, joint i from body i - 1, the tip from the last
body, with the URDF ``<joint>`` placements and axes as the robot holds them. The posture is
the joints; the bus attitude is a rotation given beside it.
"""

from __future__ import annotations

import numpy as np

from ..._core.groups import rpy_matrix
from ..view_model import box_corners, chain_owners, check_one_design, joint_limits, unit_axes

__all__ = ["spatial_view_model"]


def spatial_view_model(robot) -> dict:
    """The `spacearm.models.view_model.view_model` mapping of a `SpatialRobot` (one design)."""
    check_one_design(robot.batch_shape)
    n = robot.n_joints
    corners, _ = box_corners(robot.base_mass, robot.base_inertia, robot.base_com)
    return dict(
        name=robot.name,
        joint_names=list(robot.joint_names or tuple(f"q{i + 1}" for i in range(n))),
        joint_kinds=list(robot.joint_kinds),
        lower=joint_limits(robot.joint_lower),
        upper=joint_limits(robot.joint_upper),
        mount_rotation=[rpy_matrix(np.asarray(robot.mount_rpy, float)).tolist()],
        mount_xyz=[np.asarray(robot.mount_xyz, float).tolist()],
        root_mass=[float(robot.root_mass)],
        root_com=[np.asarray(robot.root_com, float).tolist()],
        parents=[-1] + list(range(n - 1)),
        joint_rotation=np.asarray(robot.joint_rotation, float).tolist(),
        joint_translation=np.asarray(robot.joint_translation, float).tolist(),
        joint_axis=unit_axes(robot.joint_axis),
        link_mass=np.asarray(robot.link_mass, float).tolist(),
        link_com=np.asarray(robot.link_com, float).tolist(),
        tip_bodies=[n - 1],
        tip_translation=[np.asarray(robot.tip_translation, float).tolist()],
        tip_names=[robot.name],
        owner=chain_owners(n),
        base_mass=float(robot.base_mass),
        base_com=np.asarray(robot.base_com, float).tolist(),
        bus_corners=corners.tolist(),
        extent=_extent(robot, corners),
        posture=dict(size=n, joint_offset=0, base_turn=None),
        plane=None,
    )


def _extent(robot, corners) -> float:
    """A half width, m, of a cube about the system centroid holding the bus and the arm in every
    posture, +10 %: the farther of the bus corners and the arm's reach from the bus centroid,
    plus the most the system centroid strays from it (the mass fraction off the bus times that reach)."""
    com = np.asarray(robot.base_com, float)
    bus = float(np.max(np.linalg.norm(corners - com, axis=-1)))
    mount = float(np.linalg.norm(np.asarray(robot.mount_xyz, float) - com))
    arm = mount + max(float(robot.reach), float(np.linalg.norm(robot.root_com)))
    off_bus = float(robot.root_mass) + float(np.sum(robot.link_mass))
    fraction = off_bus / (off_bus + float(robot.base_mass))
    return 1.1 * (max(bus, arm) + fraction * arm)
