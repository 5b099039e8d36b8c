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

import functools
from collections.abc import Mapping
from typing import Any, ClassVar

import jax
import jax.numpy as jnp

import spacearm.models.spatial.fields as spatial_fields  # the module, not the package (no cycle)

from ..._core.errors import ConfigError
from ..._core.groups import SO3
from ..._core.linalg import gram_root_determinant
from ..._core.magnus import DEFAULT_ORDER, DEFAULT_STEPS, path_rotation
from ..family import Capabilities, FastPaths, RobotFamily
from ..payload import merged_link_fields
from ..tree.shell import tip_shell
from .primitives import (
    as_tree,
    base_twist_map,
    fixed_base_jacobian,
    generalized_jacobian,
    jacobians,
    momentum_map,
    posture_quantities,
    straight_maps_and_ends,
    straight_path_maps,
    tip,
    tip_and_fixed_base_jacobian,
    tip_and_generalized_jacobian,
    tip_frame,
)
from .robot import SpatialRobot
from .view import spatial_view_model

__all__ = ["SPATIAL", "SpatialFamily"]


def _manipulability(robot, posture):
    return gram_root_determinant(generalized_jacobian(robot, posture)[..., :3, :])


def _base_rate(robot, posture, joint_rates):
    C = base_twist_map(robot, posture)
    return jnp.einsum("...ij,...j->...i", C, joint_rates)


def _fixed_base_manipulability(robot, joints):
    return gram_root_determinant(fixed_base_jacobian(robot, joints)[..., :3, :])


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
    fast_paths = FastPaths(
        tip_position=tip,
        generalized_jacobian=generalized_jacobian,
        manipulability=_manipulability,
        base_rate=_base_rate,
        base_rate_matrix=base_twist_map,
        fixed_base_jacobian=fixed_base_jacobian,
        fixed_base_manipulability=_fixed_base_manipulability,
        posture_quantities=posture_quantities,
        tip_and_generalized_jacobian=tip_and_generalized_jacobian,
        tip_and_fixed_base_jacobian=tip_and_fixed_base_jacobian,
        straight_maps_and_ends=straight_maps_and_ends,
    )
    fields = spatial_fields
    capabilities = Capabilities(joint_box_averages=True, tip_radius_search=True)

    attitude = SO3
    straight_field_loops = True  # the chain pass is a scan: roll the DOP853 stages
    straight_defaults: ClassVar[Mapping[str, Any]] = {
        "max_step": 0.1,
        "tol": 1e-11,
        "rtol": 1e-12,
        "sing_rate": 1e-6,
        "tip_tol": 1e-3,
        "max_steps": 4000,
    }

    def joint_count(self, robot: SpatialRobot) -> int:
        return robot.n_joints

    def attitude_rate_map(self, robot: SpatialRobot, joints: jax.Array) -> jax.Array:
        return base_twist_map(robot, joints)[..., 3:, :]

    def loop_holonomy(
        self, robot: SpatialRobot, waypoints: jax.Array, *, steps: int = DEFAULT_STEPS, order=DEFAULT_ORDER
    ) -> jax.Array:
        """``(..., 3, 3)`` bus rotation along joint polylines ``(..., k, n)``, bus axes (6th-order Magnus)."""
        return path_rotation(functools.partial(self.attitude_rate_map, robot), waypoints, steps, order)

    def straight_maps(self, robot: SpatialRobot, joints: jax.Array) -> tuple[jax.Array, jax.Array]:
        maps = straight_path_maps(robot, joints)
        return maps[:3], maps[3:]

    def tip(self, robot: SpatialRobot, posture: jax.Array) -> jax.Array:
        return tip(robot, posture)

    def pose_maps(self, robot: SpatialRobot, joints: jax.Array) -> tuple[jax.Array, jax.Array]:
        """J* ``(6, n)`` and C_w ``(3, n)``, bus axes, from one chain pass."""
        maps = posture_quantities(robot, joints, ("jacobian", "base_rate"))
        return maps["jacobian"], maps["base_rate"][3:]

    def tip_frame(self, robot: SpatialRobot, joints: jax.Array) -> tuple[jax.Array, jax.Array]:
        """Tip origin about the system centroid ``(3,)`` and tip axes ``(3, 3)``, bus axes (one chain pass)."""
        return tip_frame(robot, joints)

    def jacobians(self, robot: SpatialRobot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        return jacobians(robot, posture)

    def momentum_map(self, robot: SpatialRobot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        return momentum_map(robot, posture)

    def fixed_base_jacobian(self, robot: SpatialRobot, joints: jax.Array) -> jax.Array:
        return fixed_base_jacobian(robot, joints)

    def with_payload(self, robot: SpatialRobot, mass, com, inertia, tip=0) -> SpatialRobot:
        """The payload (tip frame) merged into body n, which carries the tip (`spacearm.models.payload`)."""
        if not (tip == 0 or (isinstance(tip, str) and tip == robot.labels.tip)):
            raise ConfigError(f"tip {tip!r}: a spatial arm has one tip, 0 ({robot.labels.tip or 'its tip link'})")
        fields = merged_link_fields(
            robot, robot.n_joints - 1, robot.tip_rotation, robot.tip_translation, mass, com, inertia
        )
        return robot.replace(**fields)

    def dynamic_tree(self, robot: SpatialRobot):
        """The arm as its one-tip tree (`spacearm.models.spatial.primitives.as_tree`)."""
        return as_tree(robot)

    def joint_kinds(self, robot: SpatialRobot) -> tuple[str, ...]:
        return tuple(robot.joint_kinds)

    def joint_names(self, robot: SpatialRobot) -> tuple[str, ...]:
        return tuple(robot.labels.joint_names)

    # Planning hooks (spacearm.planning) ---------------------------------------------------

    def tip_shell(self, robot: SpatialRobot) -> tuple[float, float]:
        """The virtual manipulator's shell of the arm as a one-tip tree (`spacearm.models.tree.shell`)."""
        return tip_shell(as_tree(robot), 0)

    def view_model(self, robot: SpatialRobot) -> dict:
        """The arm as the one-tip view tree (`spacearm.models.spatial.view`)."""
        return spatial_view_model(robot)


SPATIAL = SpatialFamily()
SpatialRobot.family = SPATIAL
