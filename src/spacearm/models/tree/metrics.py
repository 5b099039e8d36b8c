"""Tree-only kernels beyond the generic layer: the bus twist map and the reaction null
space over all arms, H_m and H* over all joints, rotational and dynamic manipulability
per tip.

Trees only: each refuses a robot of another family with a TypeError. All take
``q (..., n)`` with any leading batch shape and are jitted at the entry point; per-tip
results carry a tip axis ``k`` before their own axes.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..._core.linalg import gram_root_determinant
from ..family import require_family
from .primitives import (
    arm_inertia as _arm_inertia,
    base_twist_map as _base_twist_map,
    generalized_jacobian as _generalized_jacobian,
    mass_matrix as _mass_matrix,
)
from .robot import TreeRobot

__all__ = [
    "arm_inertia",
    "base_twist_map",
    "dynamic_manipulability",
    "mass_matrix",
    "reaction_null_space",
    "rotational_manipulability",
]


@jax.jit
def base_twist_map(robot: TreeRobot, q: jax.Array, base_rotation: jax.Array | None = None) -> jax.Array:
    """``(..., 6, n)`` C(q): bus twist [v of the bus centroid; w] per joint rate of all arms.

    Bus axes, or inertial axes with ``base_rotation``. C_w (rows 3:6) is the disturbance
    map of Dubowsky & Torres (1991) over all joints. The bus centroid is that of the
    ``base:`` body in an ``arms:`` file (the arms' root links are arm bodies) and that of
    ``base_link`` with every link rigidly attached to it in a ``system:`` file, so one
    robot written both ways has the same C_w but v rows that differ by w x (c_1 - c_2).
    """
    require_family(robot, "tree", "base_twist_map")
    C = _base_twist_map(robot, q)
    if base_rotation is None:
        return C
    R = jnp.asarray(base_rotation)
    rotate = lambda rows: jnp.einsum("...ij,...jk->...ik", R, rows)
    return jnp.concatenate([rotate(C[..., :3, :]), rotate(C[..., 3:, :])], axis=-2)


@jax.jit
def reaction_null_space(robot: TreeRobot, q: jax.Array) -> jax.Array:
    """``(..., n, n - 3)`` an orthonormal basis of the joint rates that leave the bus attitude
    still (the kernel of C_w, rank 3 away from degenerate designs): one arm may cancel
    another's reaction (a balance arm; reaction null space: Nenchev, Umetani & Yoshida, IEEE TRA 8(1), 1992)."""
    require_family(robot, "tree", "reaction_null_space")
    C_w = _base_twist_map(robot, q)[..., 3:, :]
    _, _, vt = jnp.linalg.svd(C_w, full_matrices=True)
    return jnp.swapaxes(vt[..., 3:, :], -1, -2)


@jax.jit
def mass_matrix(robot: TreeRobot, q: jax.Array) -> jax.Array:
    """``(..., n, n)`` H_m: the joint-space inertia of all arms with the bus held fixed."""
    require_family(robot, "tree", "mass_matrix")
    return _mass_matrix(robot, q)


@jax.jit
def arm_inertia(robot: TreeRobot, q: jax.Array) -> jax.Array:
    """``(..., n, n)`` H* = H_m - H_bm^T H_b^-1 H_bm over all joints, at zero momentum."""
    require_family(robot, "tree", "arm_inertia")
    return _arm_inertia(robot, q)


@jax.jit
def rotational_manipulability(robot: TreeRobot, q: jax.Array) -> jax.Array:
    """``(..., k)`` w*_w = sqrt det(J*_w J*_w^T) of every tip, over all joints."""
    require_family(robot, "tree", "rotational_manipulability")
    return gram_root_determinant(_generalized_jacobian(robot, q)[..., 3:, :])


@jax.jit
def dynamic_manipulability(robot: TreeRobot, q: jax.Array) -> jax.Array:
    """``(..., k)`` w_d = sqrt det(J*_v (H*^T H*)^-1 J*_v^T) of every tip (Yoshikawa 1985 applied
    to J*, with H* of the whole tree)."""
    require_family(robot, "tree", "dynamic_manipulability")
    J = _generalized_jacobian(robot, q)[..., :3, :]  # (..., k, 3, n)
    H = _arm_inertia(robot, q)[..., None, :, :]
    K = jnp.swapaxes(jnp.linalg.solve(H, jnp.swapaxes(J, -1, -2)), -1, -2)
    return gram_root_determinant(K)
