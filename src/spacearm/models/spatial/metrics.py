"""Spatial-only kernels beyond the generic layer: rotational and full manipulability,
the arm inertia at zero momentum H*, dynamic manipulability, the bus twist map C(q),
and the rotational and fixed-base ellipsoids.

Spatial arms only: each refuses a robot of another family with a TypeError. All take
``q (..., n)`` with any leading batch shape and are jitted at the entry point.
Results are in bus axes unless a ``base_rotation (..., 3, 3)`` is given (then inertial
axes; scalar measures do not depend on it).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..._core.linalg import gram_root_determinant
from ..family import require_family
from .primitives import (
    arm_inertia as _arm_inertia,
    base_twist_map as _base_twist_map,
    fixed_base_jacobian as _fixed_base_jacobian,
    generalized_jacobian as _generalized_jacobian,
    mass_matrix as _mass_matrix,
)
from .robot import SpatialRobot

__all__ = [
    "arm_inertia",
    "base_twist_map",
    "dynamic_manipulability",
    "fixed_base_ellipsoid",
    "full_manipulability",
    "mass_matrix",
    "rotational_ellipsoid",
    "rotational_manipulability",
]


def _map(function, robot, q):
    return function(robot, q)  # the primitives take any leading batch shape


def _rotate_rows(J, base_rotation):
    if base_rotation is None:
        return J
    R = jnp.asarray(base_rotation)
    return jnp.concatenate(
        [jnp.einsum("...ij,...jk->...ik", R, J[..., :3, :]), jnp.einsum("...ij,...jk->...ik", R, J[..., 3:, :])],
        axis=-2,
    )


@jax.jit
def rotational_manipulability(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """``(...)`` w*_w = sqrt det(J*_w J*_w^T), (rad/s per rad/s)^3: how freely the tip turns."""
    require_family(robot, "spatial", "rotational_manipulability")
    return gram_root_determinant(_map(_generalized_jacobian, robot, q)[..., 3:, :])


@jax.jit
def full_manipulability(robot: SpatialRobot, q: jax.Array, characteristic_length: jax.Array) -> jax.Array:
    """``(...)`` the product of the min(6, n) singular values of [J*_v / L; J*_w] (dimensionless).

    The characteristic length L (m) puts translation and rotation on one scale; for
    n >= 6 this is sqrt det(J_L J_L^T), for n < 6 sqrt det(J_L^T J_L).
    """
    require_family(robot, "spatial", "full_manipulability")
    J = _map(_generalized_jacobian, robot, q)
    length = jnp.asarray(characteristic_length)[..., None, None]
    scaled = jnp.concatenate([J[..., :3, :] / length, J[..., 3:, :]], axis=-2)
    wide = scaled.shape[-1] >= 6
    gram = scaled @ jnp.swapaxes(scaled, -1, -2) if wide else jnp.swapaxes(scaled, -1, -2) @ scaled
    det = jnp.linalg.det(gram)
    positive = det > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, det, 1.0)), 0.0)


@jax.jit
def mass_matrix(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """``(..., n, n)`` H_m: the arm's joint-space inertia with the bus held fixed."""
    require_family(robot, "spatial", "mass_matrix")
    return _map(_mass_matrix, robot, q)


@jax.jit
def arm_inertia(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """``(..., n, n)`` H* = H_m - H_bm^T H_b^-1 H_bm: the arm inertia at zero momentum."""
    require_family(robot, "spatial", "arm_inertia")
    return _map(_arm_inertia, robot, q)


@jax.jit
def dynamic_manipulability(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """``(...)`` w_d = sqrt det(J*_v (H*^T H*)^-1 J*_v^T) (Yoshikawa 1985 applied to J*)."""
    require_family(robot, "spatial", "dynamic_manipulability")
    J = _map(_generalized_jacobian, robot, q)[..., :3, :]
    H = arm_inertia(robot, q)
    # J (H^T H)^-1 J^T = (J H^-1)(J H^-1)^T, with H symmetric positive definite.
    K = jnp.swapaxes(jnp.linalg.solve(H, jnp.swapaxes(J, -1, -2)), -1, -2)
    return gram_root_determinant(K)


@jax.jit
def base_twist_map(robot: SpatialRobot, q: jax.Array, base_rotation: jax.Array | None = None) -> jax.Array:
    """``(..., 6, n)`` C(q): bus twist [v of the bus centroid; w] per joint rate at zero momentum.

    Bus axes, or inertial axes with ``base_rotation``. C_w (rows 3:6) is the
    disturbance map of Dubowsky & Torres (1991); its kernel is the reaction null space.
    """
    require_family(robot, "spatial", "base_twist_map")
    return _rotate_rows(_map(_base_twist_map, robot, q), base_rotation)


def _axes(J):
    directions, semi_axes, _ = jnp.linalg.svd(J, full_matrices=False)
    return semi_axes, directions


@jax.jit
def rotational_ellipsoid(robot: SpatialRobot, q: jax.Array, base_rotation: jax.Array | None = None):
    """Semi-axes ``(..., 3)`` (largest first) and directions ``(..., 3, 3)`` of {J*_w qdot : |qdot| <= 1}."""
    require_family(robot, "spatial", "rotational_ellipsoid")
    J = _rotate_rows(_map(_generalized_jacobian, robot, q), base_rotation)
    return _axes(J[..., 3:, :])


@jax.jit
def fixed_base_ellipsoid(robot: SpatialRobot, q: jax.Array):
    """Semi-axes ``(..., 3)`` and directions ``(..., 3, 3)`` (bus axes) of the fixed-base {J_v qdot : |qdot| <= 1}."""
    require_family(robot, "spatial", "fixed_base_ellipsoid")
    J = _map(_fixed_base_jacobian, robot, q)
    return _axes(J[..., :3, :])
