"""The planar family's primitives (Umetani & Yoshida 1990, section 2) and its fast paths.

Posture ``phi = [phi0, phi1..phin]``: the base attitude is part of the posture, so the
base velocity is the single rate dphi0 (the linear momentum is eliminated by measuring
positions from the system centroid, eq. 3).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..family import RobotFamily
from . import fields as planar_fields
from .closed_forms import (
    arm_jacobian,
    base_jacobian,
    base_rate,
    fixed_base_jacobian,
    fixed_base_manipulability,
    generalized_jacobian,
    manipulability,
    momentum_inertias,
    straight_path_field,
    tip_position,
)
from .robot import PlanarRobot

__all__ = ["PlanarFamily", "PLANAR"]


class PlanarFamily(RobotFamily):
    """Planar serial arms of n >= 2 revolute links (J* is 2 x n)."""

    name = "planar"
    task_rows = 2
    translational_rows = 2
    posture_offset = 1
    rotates_with_base = False
    fast_paths = {
        "tip_position": tip_position,
        "generalized_jacobian": generalized_jacobian,
        "manipulability": manipulability,
        "base_rate": base_rate,
        "fixed_base_jacobian": fixed_base_jacobian,
        "fixed_base_manipulability": fixed_base_manipulability,
        "straight_path_field": straight_path_field,
    }
    fields = planar_fields

    def joint_count(self, robot: PlanarRobot) -> int:
        return robot.n_links

    def tip(self, robot: PlanarRobot, posture: jax.Array) -> jax.Array:
        return tip_position(robot, posture)

    def jacobians(self, robot: PlanarRobot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        return base_jacobian(robot, posture)[:, None], arm_jacobian(robot, posture)

    def momentum_map(self, robot: PlanarRobot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        i_s, i_m = momentum_inertias(robot, posture)
        return jnp.reshape(i_s, (1, 1)), i_m[None, :]

    def fixed_base_jacobian(self, robot: PlanarRobot, joints: jax.Array) -> jax.Array:
        return fixed_base_jacobian(robot, joints)


PLANAR = PlanarFamily()
PlanarRobot.family = PLANAR
