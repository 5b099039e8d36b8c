"""A planar arm as the family-free view tree of `spacearm.models.view_model`.

The planar arm of Umetani & Yoshida (1990, Fig. 1) is the one-tip tree whose joints all
turn about z: one mount on the bus at b0 along the bus x axis, joint i at a_{i-1} + b_{i-1}
along its parent link, link i's centroid a_i along it and the tip a_n + b_n along the last
link. The posture [phi0, phi1..phin] puts the bus attitude first, as a turn about z by phi0.
The bus is drawn as the square plate with its mass and moment, about the base centroid.
"""

from __future__ import annotations

import numpy as np

from ..view_model import chain_owners, check_one_design, joint_limits, plate_corners

__all__ = ["planar_view_model"]


def planar_view_model(robot) -> dict:
    """The `spacearm.models.view_model.view_model` mapping of a `PlanarRobot` (one design)."""
    check_one_design(robot.batch_shape)
    a, b = np.asarray(robot.link_a, float), np.asarray(robot.link_b, float)
    masses = np.asarray(robot.link_mass, float)
    n = len(a)
    corners, _ = plate_corners(robot.base_mass, robot.base_inertia)
    along = lambda x: [float(x), 0.0, 0.0]
    reach = float(robot.base_attach) + float(np.sum(a + b))
    bus = float(np.max(np.linalg.norm(corners, axis=-1)))
    fraction = masses.sum() / (masses.sum() + float(robot.base_mass))
    return dict(
        name=str(robot.name),
        joint_names=[f"joint {i + 1}" for i in range(n)],
        joint_kinds=["revolute"] * n,
        lower=joint_limits(robot.joint_lower),
        upper=joint_limits(robot.joint_upper),
        mount_rotation=[np.eye(3).tolist()],
        mount_xyz=[along(robot.base_attach)],
        root_mass=[0.0],
        root_com=[[0.0, 0.0, 0.0]],
        parents=[-1] + list(range(n - 1)),
        joint_rotation=[np.eye(3).tolist()] * n,
        joint_translation=[along(0.0)] + [along(a[i] + b[i]) for i in range(n - 1)],
        joint_axis=[[0.0, 0.0, 1.0]] * n,
        link_mass=masses.tolist(),
        link_com=[along(x) for x in a],
        tip_bodies=[n - 1],
        tip_translation=[along(a[-1] + b[-1])],
        tip_names=[str(robot.name)],
        owner=chain_owners(n),
        base_mass=float(robot.base_mass),
        base_com=[0.0, 0.0, 0.0],
        bus_corners=corners.tolist(),
        extent=1.1 * (max(bus, reach) + fraction * reach),
        posture=dict(
            size=n + 1, joint_offset=1, base_turn=dict(index=0, axis=[0.0, 0.0, 1.0], name="phi0 (base attitude)")
        ),
        plane=dict(normal=[0.0, 0.0, 1.0]),
    )
