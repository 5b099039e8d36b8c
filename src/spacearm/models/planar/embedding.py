"""The planar arm as the one-tip tree in the bus's x-y plane (Umetani & Yoshida 1990, Fig. 1).

One root body (massless) at b0 along the bus x axis; joint i turns about z, link i's
centroid a_i along its x axis, joint i+1 (or the tip) a_i + b_i along it. At zero joint
angles every link points along the bus x axis, as in the paper, and the posture
[phi0, phi1..phin] is the bus turned by phi0 about z with joints [phi1..phin].

Every centroid lies in the plane and every inertia is diagonal with z a principal
axis, so motion in the plane never drives the out-of-plane coordinates [z, rx, ry]: the
planar dynamics are the tree's rows and columns [x, y, rz] and the joints. The
out-of-plane moments (half the in-plane moment about x and about y, a thin plate) take no
part in them; they only keep the 3-D inertias physical.
"""

from __future__ import annotations

import jax.numpy as jnp

from ..tree.robot import TreeLabels, TreeRobot, tree_view
from .robot import PlanarRobot

__all__ = ["as_tree"]


def _along_x(length):
    zero = jnp.zeros_like(length)
    return jnp.stack([length, zero, zero], axis=-1)


def _plate_inertia(moment):
    """``(..., 3, 3)`` diag(I/2, I/2, I) for the in-plane moment I about z."""
    return jnp.asarray(moment)[..., None, None] * jnp.diag(jnp.array([0.5, 0.5, 1.0]))


def as_tree(robot: PlanarRobot) -> TreeRobot:
    """The arm as a `TreeRobot` (the design batch kept on every leaf; traced leaves stay traced)."""
    a, b = jnp.asarray(robot.link_a), jnp.asarray(robot.link_b)
    n = robot.n_links
    batch = a.shape[:-1]
    lengths = a + b
    zero = jnp.zeros(batch, a.dtype)
    eye = jnp.broadcast_to(jnp.eye(3, dtype=a.dtype), batch + (n, 3, 3))
    leaves = dict(
        base_mass=jnp.asarray(robot.base_mass),
        base_com=jnp.zeros(batch + (3,), a.dtype),
        base_inertia=_plate_inertia(robot.base_inertia),
        mount_xyz=_along_x(jnp.asarray(robot.base_attach))[..., None, :],
        mount_rpy=jnp.zeros(batch + (1, 3), a.dtype),
        root_mass=zero[..., None],
        root_com=jnp.zeros(batch + (1, 3), a.dtype),
        root_inertia=jnp.zeros(batch + (1, 3, 3), a.dtype),
        joint_rotation=eye,
        joint_translation=_along_x(jnp.concatenate([zero[..., None], lengths[..., :-1]], axis=-1)),
        joint_axis=jnp.broadcast_to(jnp.array([0.0, 0.0, 1.0], a.dtype), batch + (n, 3)),
        link_mass=jnp.asarray(robot.link_mass),
        link_com=_along_x(a),
        link_inertia=_plate_inertia(robot.link_inertia),
        tip_rotation=eye[..., :1, :, :],
        tip_translation=_along_x(lengths[..., -1:]),
        joint_lower=robot.joint_lower,
        joint_upper=robot.joint_upper,
    )
    labels = TreeLabels(
        name=robot.name,
        joint_names=tuple(f"joint {i + 1}" for i in range(n)),
        tip_names=(robot.name,),
        root_names=(robot.name,),
        joint_roots=(0,) * n,
    )
    return tree_view(robot, ("revolute",) * n, tuple(range(-1, n - 1)), (n - 1,), labels, **leaves)
