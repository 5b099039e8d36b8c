"""Kernels over the arm inertia and the rotational rows of J*, written once for every robot.

Each takes a robot whose J* has rotational rows (a spatial arm, or a tree of arms: per-tip
results then carry a tip axis ``k``) and joints ``q (..., n)`` with any leading batch shape:

- `rotational_manipulability`: sqrt det(J*_w J*_w^T), how freely the tip turns;
- `full_manipulability`: the product of the singular values of [J*_v / L; J*_w];
- `dynamic_manipulability`: w_d = sqrt det(J*_v (H*^T H*)^-1 J*_v^T) (Yoshikawa 1985
  applied to J*): tip acceleration per joint torque;
- `base_twist_map`: C(q), the bus twist [v of the bus centroid; w] per joint rate, whose
  angular rows are the disturbance map of Dubowsky & Torres (1991);
- `rotational_ellipsoid`, `fixed_base_ellipsoid`: the axes of {J*_w qdot} and of the
  fixed-base {J_v qdot} for unit joint rates.

H* is the reduced inertia of `spacearm.dynamics`; everything else is the generic J*, C and
fixed-base Jacobian of `spacearm.kinematics`.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ._core.linalg import gram_root_determinant
from .dynamics import arm_inertia
from .kinematics import base_rate_matrix, fixed_base_jacobian, generalized_jacobian, rotate_twist_rows
from .models.family import family_of

__all__ = [
    "base_twist_map",
    "dynamic_manipulability",
    "fixed_base_ellipsoid",
    "full_manipulability",
    "rotational_ellipsoid",
    "rotational_manipulability",
]


def _spatial_rows(robot, what: str) -> None:
    """Refuse a robot whose J* has no rotational rows (the paper's planar arm: [x, y] only)."""
    family = family_of(robot)
    if family.task_rows != 6:
        raise TypeError(f"{what}: the tip twist has no rotational rows for a {family.name} robot (J* is 2 x n)")


def _axes(J):
    directions, semi_axes, _ = jnp.linalg.svd(J, full_matrices=False)
    return semi_axes, directions


@jax.jit
def rotational_manipulability(robot, q: jax.Array) -> jax.Array:
    """``(...)`` (``(..., k)`` per tip) w*_w = sqrt det(J*_w J*_w^T), (rad/s per rad/s)^3."""
    _spatial_rows(robot, "rotational_manipulability")
    return gram_root_determinant(generalized_jacobian(robot, q)[..., 3:, :])


@jax.jit
def full_manipulability(robot, q: jax.Array, characteristic_length: jax.Array) -> jax.Array:
    """``(...)`` the product of the min(6, n) singular values of [J*_v / L; J*_w] (dimensionless).

    The characteristic length L (m) puts translation and rotation on one scale; for
    n >= 6 this is sqrt det(J_L J_L^T), for n < 6 sqrt det(J_L^T J_L).
    """
    _spatial_rows(robot, "full_manipulability")
    J = generalized_jacobian(robot, q)
    length = jnp.asarray(characteristic_length)[..., None, None]
    scaled = jnp.concatenate([J[..., :3, :] / length, J[..., 3:, :]], axis=-2)
    wide = scaled.shape[-1] >= 6
    gram = scaled @ jnp.swapaxes(scaled, -1, -2) if wide else jnp.swapaxes(scaled, -1, -2) @ scaled
    det = jnp.linalg.det(gram)
    positive = det > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, det, 1.0)), 0.0)


@jax.jit
def dynamic_manipulability(robot, q: jax.Array) -> jax.Array:
    """``(...)`` (``(..., k)`` per tip) w_d = sqrt det(J*_v (H*^T H*)^-1 J*_v^T), with H* of the whole robot."""
    _spatial_rows(robot, "dynamic_manipulability")
    family = family_of(robot)
    J = generalized_jacobian(robot, q)[..., :3, :]
    H = arm_inertia(robot, q)
    if family.tip_count(robot) is not None:
        H = H[..., None, :, :]
    # J (H^T H)^-1 J^T = (J H^-1)(J H^-1)^T, with H symmetric positive definite.
    K = jnp.swapaxes(jnp.linalg.solve(H, jnp.swapaxes(J, -1, -2)), -1, -2)
    return gram_root_determinant(K)


@jax.jit
def base_twist_map(robot, q: jax.Array, base_rotation: jax.Array | None = None) -> jax.Array:
    """``(..., 6, n)`` C(q): bus twist [v of the bus centroid; w] per joint rate at zero momentum.

    Bus axes, or inertial axes with ``base_rotation``. C_w (rows 3:6) is the disturbance
    map of Dubowsky & Torres (1991); its kernel is the reaction null space.
    """
    _spatial_rows(robot, "base_twist_map")
    C = base_rate_matrix(robot, q)
    return C if base_rotation is None else rotate_twist_rows(C, jnp.asarray(base_rotation))


@jax.jit
def rotational_ellipsoid(robot, q: jax.Array, base_rotation: jax.Array | None = None):
    """Semi-axes ``(..., 3)`` (largest first) and directions ``(..., 3, 3)`` of {J*_w qdot : |qdot| <= 1}."""
    _spatial_rows(robot, "rotational_ellipsoid")
    return _axes(generalized_jacobian(robot, q, base_rotation)[..., 3:, :])


@jax.jit
def fixed_base_ellipsoid(robot, q: jax.Array):
    """Semi-axes ``(..., 3)`` and directions ``(..., 3, 3)`` (bus axes) of the fixed-base {J_v qdot : |qdot| <= 1}."""
    _spatial_rows(robot, "fixed_base_ellipsoid")
    return _axes(fixed_base_jacobian(robot, q)[..., :3, :])
