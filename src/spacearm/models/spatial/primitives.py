"""Per-posture primitives of the spatial family: a serial arm is the one-tip tree.

`as_tree` views a `SpatialRobot` as a `TreeRobot` with one root body (the mount), its
joints each hanging from the previous body and one tip on the last; every primitive here
is the tree pass's (`spacearm.models.tree.primitives`) with the tip axis dropped, so the
forward and backward passes, and the closed form of J* (Umetani & Yoshida 1990, eq. 6,
in 3-D; only a 3x3 system is solved), are written once for every spatial robot.

Everything is expressed in the bus frame (base_rotation = identity); the generic layer
rotates results by the bus attitude R (blkdiag(R, R) for twists, R for points). Base
twist coordinates of `momentum_map` and `jacobians`: b = [v; w], the velocity of the bus
centroid and the bus angular velocity, bus axes (J* does not depend on this choice;
``-I_S^-1 I_M`` is then the bus centroid's twist per joint rate).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

import spacearm.models.tree.primitives as tree  # the module, not the package (no cycle)

from ..tree.algebra import rpy_to_matrix
from ..tree.robot import TreeLabels, TreeRobot, tree_view
from .robot import SpatialRobot

__all__ = [
    "POSTURE_QUANTITIES",
    "as_tree",
    "base_twist_map",
    "fixed_base_jacobian",
    "generalized_jacobian",
    "jacobians",
    "momentum_map",
    "posture_quantities",
    "rpy_to_matrix",
    "straight_maps_and_ends",
    "straight_path_maps",
    "tip",
    "tip_and_fixed_base_jacobian",
    "tip_and_generalized_jacobian",
    "tip_frame",
    "tip_pose",
]

POSTURE_QUANTITIES = tree.POSTURE_QUANTITIES

# Leaves that gain the root (and tip) axis of a tree, with their trailing rank in the arm.
_ONE_OF = {"mount_xyz": 1, "mount_rpy": 1, "root_mass": 0, "root_com": 1, "root_inertia": 2}
_ONE_OF |= {"tip_rotation": 2, "tip_translation": 1}


def _insert_axis(value, rank: int):
    xp = np if isinstance(value, (np.ndarray, np.generic, float, int)) else jnp
    return xp.expand_dims(xp.asarray(value), -1 - rank)


def as_tree(robot: SpatialRobot) -> TreeRobot:
    """The arm as a tree: one root (the mount), joint j hanging from body j - 1, one tip on the
    last body. The leaves are the arm's (a root and a tip axis added), so this is free under
    ``jit`` and exact: every kernel of the tree pass gives the arm's quantities."""
    n = robot.n_joints
    labels = robot.labels
    tree_labels = TreeLabels(
        name=labels.name,
        joint_names=labels.joint_names,
        tip_names=(labels.tip,),
        root_names=(labels.name,),
        root_links=((labels.root_link,),),
        joint_roots=(0,) * n,
        urdf_types=labels.urdf_types,
        body_links=labels.body_links,
        source=labels.source,
    )
    with_axes = {field: _insert_axis(getattr(robot, field), rank) for field, rank in _ONE_OF.items()}
    return tree_view(robot, robot.joint_kinds, tuple(range(-1, n - 1)), (n - 1,), tree_labels, **with_axes)


def tip(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """``(..., 3)`` tip origin about the system centroid, bus axes, m, for ``q (..., n)``."""
    return tree.tip(as_tree(robot), q)[..., 0, :]


def fixed_base_jacobian(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """``(..., 6, n)`` tip twist [v; w] per joint rate with the bus held fixed, bus axes."""
    return tree.fixed_base_jacobian(as_tree(robot), q)[..., 0, :, :]


def generalized_jacobian(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """``(..., 6, n)`` J*: tip twist [v; w] per joint rate at zero momentum, bus axes."""
    return tree.generalized_jacobian(as_tree(robot), q)[..., 0, :, :]


def base_twist_map(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """``(..., 6, n)`` C(q): bus twist [v of bus centroid; w] per joint rate at zero momentum, bus axes."""
    return tree.base_twist_map(as_tree(robot), q)


def straight_path_maps(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """``(..., 6, n)``: rows 0-2 J*_v (tip velocity per joint rate at zero momentum) and rows 3-5
    C_w (bus angular velocity per joint rate), bus axes, from one pass (what a straight tip path needs)."""
    maps = tree.straight_path_maps(as_tree(robot), q)  # rows: J*_v, J*_w, C_w
    return jnp.concatenate([maps[..., :3, :], maps[..., 6:, :]], axis=-2)


def straight_maps_and_ends(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """`straight_path_maps` ``(..., 6, n)``, the fixed-base J_v ``(..., 3, n)`` and the tip about
    the system centroid ``(..., 3)``, bus axes, from one pass per posture: a straight path's field
    and its end quantities."""
    maps, fixed_v, tips = tree.straight_maps_and_ends(as_tree(robot), q)
    return jnp.concatenate([maps[..., :3, :], maps[..., 6:, :]], axis=-2), fixed_v[..., 0, :, :], tips[..., 0, :]


def tip_and_generalized_jacobian(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(..., 6, n)`` J* and ``(..., 3)`` tip about the system centroid, bus axes, from one pass
    per posture (equal to `generalized_jacobian` and `tip`)."""
    J, tips = tree.tip_and_generalized_jacobian(as_tree(robot), q)
    return J[..., 0, :, :], tips[..., 0, :]


def tip_and_fixed_base_jacobian(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(..., 6, n)`` fixed-base Jacobian and ``(..., 3)`` tip about the system centroid, bus axes,
    from one pass per posture (equal to `fixed_base_jacobian` and `tip`)."""
    J, tips = tree.tip_and_fixed_base_jacobian(as_tree(robot), q)
    return J[..., 0, :, :], tips[..., 0, :]


def tip_pose(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Tip frame with the bus frame fixed, one posture: ``(3, 3)`` axes and ``(3,)`` origin."""
    rotations, origins = tree.tip_pose(as_tree(robot), q)
    return rotations[0], origins[0]


def tip_frame(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """One posture: the tip origin about the system centroid ``(3,)`` and the tip axes ``(3, 3)``,
    bus axes, from one pass (equal to `tip` and `tip_pose`'s axes)."""
    origins, axes = tree.tip_frames(as_tree(robot), q)
    return origins[0], axes[0]


def jacobians(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """One posture: J_S ``(6, 6)`` (tip twist per bus twist [v of bus centroid; w]) and J_M ``(6, n)``, bus axes."""
    return tree.jacobians(as_tree(robot), q)


def momentum_map(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """One posture: I_S ``(6, 6)`` and I_M ``(6, n)``; total [linear; angular about the bus
    centroid] momentum is I_S [v; w] + I_M qdot (bus twist [v of bus centroid; w]), bus axes."""
    return tree.momentum_map(as_tree(robot), q)


def posture_quantities(robot: SpatialRobot, q: jax.Array, needs: tuple[str, ...]) -> dict[str, jax.Array]:
    """The per-posture matrices posture metrics need, from one pass per posture.

    Args:
        robot: one design.
        q: ``(..., n)`` joint positions.
        needs: a subset of `POSTURE_QUANTITIES` (static): ``"jacobian"`` J* ``(..., 6, n)``,
            ``"base_rate"`` C ``(..., 6, n)`` (bus twist per joint rate), ``"arm_inertia"``
            H* ``(..., n, n)``; bus axes, each equal to its own kernel above.

    Returns:
        ``{name: array}`` for the names in ``needs``.
    """
    out = tree.posture_quantities(as_tree(robot), q, needs)
    if "jacobian" in out:
        out["jacobian"] = out["jacobian"][..., 0, :, :]
    return out
