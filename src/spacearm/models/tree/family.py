"""The tree family on the robot-family seam: several arms (k tips) on one free-floating bus.

Posture ``q (n,)``: the joints of all arms in the robot's joint order; the bus attitude
is ``base_rotation`` in the public kernels, as for a spatial arm. Every per-tip result
carries a tip axis before its own axes: tips ``(k, 3)``, J* ``(k, 6, n)`` over all
joints, w* ``(k,)``; the bus quantities (C, H*, the attitude) have none.

Fast paths (each equals the generic path over the primitives; tests/test_tree_kernels.py):
the batch-last pass over the tree (`spacearm.models.tree.primitives`), J* by the 3x3
closed form for all tips at once, w* per tip by Cauchy-Binet inside the same batch-last pass.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import jax
import jax.numpy as jnp

from ..._core.groups import SO3
from ..._core.linalg import gram_root_determinant
from ..._core.magnus import DEFAULT_ORDER, DEFAULT_STEPS, path_rotation
from ..family import RobotFamily
from .primitives import (
    arm_inertia,
    base_twist_map,
    fixed_base_jacobian,
    generalized_jacobian,
    jacobians,
    manipulability,
    mass_matrix,
    momentum_map,
    posture_quantities,
    tip,
)
from .robot import TreeRobot

__all__ = ["TREE", "TreeFamily"]


def _base_rate(robot, posture, joint_rates):
    return jnp.einsum("...ij,...j->...i", base_twist_map(robot, posture), joint_rates)


def _fixed_base_manipulability(robot, joints):
    return gram_root_determinant(fixed_base_jacobian(robot, joints)[..., :3, :])


class TreeFamily(RobotFamily):
    """Arms from URDF on one free-floating bus, k tips (J* is k x 6 x n, rows [v; w]).

    Base twist coordinates b = [v of the bus centroid; w], bus axes. The generic
    ``jacobians`` stack the tips' rows (6k rows); the public kernels split them per tip.
    """

    name = "tree"
    task_rows = 6
    translational_rows = 3
    posture_offset = 0
    rotates_with_base = True
    fast_paths: ClassVar[Mapping[str, Callable[..., Any]]] = {
        "tip_position": tip,
        "generalized_jacobian": generalized_jacobian,
        "manipulability": manipulability,
        "base_rate": _base_rate,
        "base_rate_matrix": base_twist_map,
        "fixed_base_jacobian": fixed_base_jacobian,
        "fixed_base_manipulability": _fixed_base_manipulability,
        "posture_quantities": posture_quantities,
    }
    fields = None  # design fields for trees are not defined yet
    attitude = SO3
    straight_field_loops = True

    def joint_count(self, robot: TreeRobot) -> int:
        return robot.n_joints

    def tip_count(self, robot: TreeRobot) -> int | None:
        return robot.n_tips

    def attitude_rate_map(self, robot: TreeRobot, joints: jax.Array) -> jax.Array:
        """``(..., 3, n)`` bus angular velocity per joint rate (all arms), bus axes."""
        return base_twist_map(robot, joints)[..., 3:, :]

    def loop_holonomy(
        self, robot: TreeRobot, waypoints: jax.Array, *, steps: int = DEFAULT_STEPS, order=DEFAULT_ORDER
    ) -> jax.Array:
        """``(..., 3, 3)`` bus rotation along joint polylines ``(..., k, n)``, bus axes (6th-order Magnus)."""
        return path_rotation(functools.partial(self.attitude_rate_map, robot), waypoints, steps, order)

    def tip(self, robot: TreeRobot, posture: jax.Array) -> jax.Array:
        """``(k, 3)`` tips about the system centroid, bus axes."""
        return tip(robot, posture)

    def jacobians(self, robot: TreeRobot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        return jacobians(robot, posture)

    def momentum_map(self, robot: TreeRobot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        return momentum_map(robot, posture)

    def fixed_base_jacobian(self, robot: TreeRobot, joints: jax.Array) -> jax.Array:
        """``(k, 6, n)`` fixed-base Jacobians of the tips, bus axes."""
        return fixed_base_jacobian(robot, joints)

    def mass_matrix(self, robot: TreeRobot, joints: jax.Array) -> jax.Array:
        """``(n, n)`` H_m, all arms with the bus held fixed."""
        return mass_matrix(robot, joints)

    def arm_inertia(self, robot: TreeRobot, joints: jax.Array) -> jax.Array:
        """``(n, n)`` H*, the inertia of all arms at zero momentum."""
        return arm_inertia(robot, joints)

    # Not defined for trees yet: a straight path or a shell needs a chosen tip.

    def straight_maps(self, robot: TreeRobot, joints: jax.Array):
        raise TypeError(
            "straight tip paths are not available for trees of arms yet (a path needs a chosen tip); "
            "use integrate_joint_path for joint paths of all arms"
        )

    def tip_shell(self, robot: TreeRobot):
        raise TypeError("the reach shell is not available for trees of arms yet (it needs a chosen tip)")


TREE = TreeFamily()
TreeRobot.family = TREE
