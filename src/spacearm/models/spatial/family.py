"""The spatial family on the robot-family seam: primitives and closed-form fast paths.

Posture ``q (n,)``: joint positions in path order (rad, or m for prismatic joints); the
bus attitude is not part of the posture (``base_rotation`` in the public kernels). The
primitives work in bus axes; the generic layer applies blkdiag(R, R) to twists and R
to points.

Fast paths (each equals the generic path over the primitives; tests/test_spatial_kinematics.py):
the primitives' batch-last pass over any leading batch shape (posture batch as the
contiguous minor axis, instead of ``vmap`` over a per-posture function); J* by the 3x3
closed form instead of a 6x6 solve; w* from it by Cauchy-Binet (the sum of squared
3x3 minors, accurate near singular postures); the tip; the base rate; the fixed-base
Jacobian and manipulability.
"""

from __future__ import annotations

import itertools

import jax
import jax.numpy as jnp

from ..family import RobotFamily
from . import primitives
from .robot import SpatialRobot

__all__ = ["SPATIAL", "SpatialFamily", "root_gram_determinant"]


def root_gram_determinant(J: jax.Array) -> jax.Array:
    """sqrt(det(J J^T)) of ``(..., t, n)`` matrices, t <= n, by Cauchy-Binet for small n.

    det(J J^T) is the sum of the squared t x t minors; summing squares avoids the
    cancellation of the Gram determinant near rank loss. Exactly 0 at rank loss, with
    finite gradients there. For t > n the result is 0 (rank at most n).
    """
    t, n = J.shape[-2], J.shape[-1]
    if t > n:
        return jnp.zeros(J.shape[:-2], J.dtype)
    subsets = list(itertools.combinations(range(n), t))
    if t <= 3 and len(subsets) <= 84:  # n <= 9 for t = 3
        squares = sum(jnp.square(_det_small(J, s)) for s in subsets)
    else:
        squares = jnp.linalg.det(J @ jnp.swapaxes(J, -1, -2))
    positive = squares > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, squares, 1.0)), 0.0)


def _det_small(J, columns):
    t = len(columns)
    a = lambda r, c: J[..., r, columns[c]]
    if t == 1:
        return a(0, 0)
    if t == 2:
        return a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0)
    return (
        a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1))
        - a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0))
        + a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0))
    )


def _manipulability(robot, posture):
    return root_gram_determinant(primitives.generalized_jacobian(robot, posture)[..., :3, :])


def _base_rate(robot, posture, joint_rates):
    C = primitives.base_twist_map(robot, posture)
    return jnp.einsum("...ij,...j->...i", C, joint_rates)


def _fixed_base_manipulability(robot, joints):
    return root_gram_determinant(primitives.fixed_base_jacobian(robot, joints)[..., :3, :])


class SpatialFamily(RobotFamily):
    """Spatial serial arms from URDF on a free-floating bus (J* is 6 x n, rows [v; w]).

    Base twist coordinates b = [v of the bus centroid; w], bus axes (so the generic
    base-rate matrix -I_S^-1 I_M is the bus centroid's twist per joint rate).
    """

    name = "spatial"
    task_rows = 6
    translational_rows = 3
    posture_offset = 0
    rotates_with_base = True
    fast_paths = {
        "tip_position": primitives.tip,
        "generalized_jacobian": primitives.generalized_jacobian,
        "manipulability": _manipulability,
        "base_rate": _base_rate,
        "fixed_base_jacobian": primitives.fixed_base_jacobian,
        "fixed_base_manipulability": _fixed_base_manipulability,
    }

    def joint_count(self, robot: SpatialRobot) -> int:
        return robot.n_joints

    def tip(self, robot: SpatialRobot, posture: jax.Array) -> jax.Array:
        return primitives.tip(robot, posture)

    def jacobians(self, robot: SpatialRobot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        return primitives.jacobians(robot, posture)

    def momentum_map(self, robot: SpatialRobot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        return primitives.momentum_map(robot, posture)

    def fixed_base_jacobian(self, robot: SpatialRobot, joints: jax.Array) -> jax.Array:
        return primitives.fixed_base_jacobian(robot, joints)

    def mass_matrix(self, robot: SpatialRobot, joints: jax.Array) -> jax.Array:
        """``(n, n)`` H_m, the arm inertia with the bus held fixed."""
        return primitives.mass_matrix(robot, joints)

    def arm_inertia(self, robot: SpatialRobot, joints: jax.Array) -> jax.Array:
        """``(n, n)`` H*, the arm inertia at zero momentum."""
        return primitives.arm_inertia(robot, joints)


SPATIAL = SpatialFamily()
SpatialRobot.family = SPATIAL
