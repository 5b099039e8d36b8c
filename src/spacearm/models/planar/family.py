"""The planar family's primitives (Umetani & Yoshida 1990, section 2) and its fast paths.

Posture ``phi = [phi0, phi1..phin]``: the base attitude is part of the posture, so the
base velocity is the single rate dphi0 (the linear momentum is eliminated by measuring
positions from the system centroid, eq. 3).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any, ClassVar

import jax
import jax.numpy as jnp
import numpy as np

import spacearm.models.planar.fields as planar_fields  # the module, not the package (no cycle)

from ..._core.groups import SO2
from ..._core.magnus import composite_gauss, line_integral
from ..family import Capabilities, FastPaths, RobotFamily
from ..payload import planar_payload
from .closed_forms import (
    arm_jacobian,
    base_jacobian,
    base_rate,
    fixed_base_jacobian,
    fixed_base_manipulability,
    generalized_jacobian,
    manipulability,
    momentum_inertias,
    reachable_radii,
    straight_path_field,
    tip_coefficients,
    tip_position,
)
from .embedding import as_tree
from .robot import PlanarRobot
from .schema import robot_to_mapping
from .singularities import two_link_path_independent_radius
from .view import planar_view_model

__all__ = ["PLANAR", "PlanarFamily"]


class PlanarFamily(RobotFamily):
    """Planar serial arms of n >= 2 revolute links (J* is 2 x n)."""

    name = "planar"
    task_rows = 2
    translational_rows = 2
    posture_offset = 1
    rotates_with_base = False
    fast_paths = FastPaths(
        tip_position=tip_position,
        generalized_jacobian=generalized_jacobian,
        manipulability=manipulability,
        base_rate=base_rate,
        fixed_base_jacobian=fixed_base_jacobian,
        fixed_base_manipulability=fixed_base_manipulability,
        straight_path_field=straight_path_field,
        reachable_radii=reachable_radii,
        path_independent_radius=two_link_path_independent_radius,
    )
    fields = planar_fields
    capabilities = Capabilities(virtual_manipulator=True, tip_radius_search=True)

    attitude = SO2
    twist_axes = (0, 1, 5)
    straight_field_loops = False  # the closed-form field: stages written out run faster
    straight_defaults: ClassVar[Mapping[str, Any]] = {
        "max_step": 0.25,
        "tol": None,
        "rtol": None,
        "sing_rate": -float("inf"),
        "max_steps": 4096,
    }

    def normal_form(self, robot: PlanarRobot) -> dict:
        """The ``robot:`` mapping of the design's numbers (`spacearm.models.planar.schema.robot_to_mapping`)."""
        return robot_to_mapping(robot)

    def view_model(self, robot: PlanarRobot) -> dict:
        """The arm as the view tree (`spacearm.models.planar.view`): joints about z, the bus turned by phi0."""
        return planar_view_model(robot)

    def joint_count(self, robot: PlanarRobot) -> int:
        return robot.n_links

    def with_payload(self, robot: PlanarRobot, mass, com, inertia, tip=0) -> PlanarRobot:
        """The payload merged into link n, exact for a payload centred on its line
        (`spacearm.models.payload.planar_payload`; ConfigError otherwise)."""
        return planar_payload(robot, mass, com, inertia, tip)

    def dynamic_tree(self, robot: PlanarRobot):
        """The arm in the bus's x-y plane (`spacearm.models.planar.embedding.as_tree`)."""
        return as_tree(robot)

    def attitude_rate_map(self, robot: PlanarRobot, joints: jax.Array) -> jax.Array:
        """``(..., 1, n)`` -I_M / I_S (eq. 5), for ``joints (..., n)`` with any leading batch."""
        zero = jnp.zeros(joints.shape[:-1] + (1,), joints.dtype)
        i_s, i_m = momentum_inertias(robot, jnp.concatenate([zero, joints], axis=-1))
        return (-i_m / i_s[..., None])[..., None, :]

    def loop_holonomy(self, robot: PlanarRobot, waypoints: jax.Array, *, nodes: int = 24, pieces: int = 1) -> jax.Array:
        """phi0 change along one joint polyline ``(k, n)``: the line integral of eq. (5), rad."""
        t, w = (jnp.asarray(x, waypoints.dtype) for x in composite_gauss(nodes, pieces))
        rate_map = functools.partial(self.attitude_rate_map, robot)
        return jnp.sum(line_integral(rate_map, waypoints[:-1], waypoints[1:] - waypoints[:-1], t, w))

    def straight_maps(self, robot: PlanarRobot, joints: jax.Array) -> tuple[jax.Array, jax.Array]:
        phi = jnp.concatenate([jnp.zeros((1,), joints.dtype), joints])  # base axes: phi0 = 0
        i_s, i_m = momentum_inertias(robot, phi)
        return generalized_jacobian(robot, phi), (-i_m / i_s)[None, :]

    def tip(self, robot: PlanarRobot, posture: jax.Array) -> jax.Array:
        return tip_position(robot, posture)

    def jacobians(self, robot: PlanarRobot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        return base_jacobian(robot, posture)[:, None], arm_jacobian(robot, posture)

    def momentum_map(self, robot: PlanarRobot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        i_s, i_m = momentum_inertias(robot, posture)
        return jnp.reshape(i_s, (1, 1)), i_m[None, :]

    def fixed_base_jacobian(self, robot: PlanarRobot, joints: jax.Array) -> jax.Array:
        return fixed_base_jacobian(robot, joints)

    # Planning hooks (spacearm.planning) ---------------------------------------------------

    def tip_shell(self, robot: PlanarRobot) -> tuple[float, float]:
        """Area 3 about the system centroid: K0 + .. + Kn and its hole (sec. 3.1 (3-a))."""
        K = np.abs(np.asarray(tip_coefficients(robot)))
        return max(0.0, float(2.0 * np.max(K) - np.sum(K))), float(np.sum(K))


PLANAR = PlanarFamily()
PlanarRobot.family = PLANAR
