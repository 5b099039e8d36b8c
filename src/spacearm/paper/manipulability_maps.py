"""Manipulability maps over the posture space and the tip plane (section 4.2, Fig. 6-8).

Everything here lives in the robot frame Sigma_R (origin at joint 1, axes along the
base): w* does not depend on the base attitude phi0, so phi0 = 0 throughout.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import jax
import jax.numpy as jnp

from .._core.errors import ConfigError
from ..models.planar.closed_forms import (
    design_coefficients,
    fixed_base_manipulability,
    grid_angle_tables,
    manipulability_from_angles,
)
from ..models.planar.robot import PlanarRobot


def check_single_design(robot: PlanarRobot, where: str) -> None:
    """Refuse a batch of designs where a function takes one design (vmap over designs instead)."""
    if robot.batch_shape:
        raise ConfigError(f"{where}: takes one design; vmap over a batch of designs (batch shape {robot.batch_shape})")


__all__ = [
    "check_single_design",
    "grid_average",
    "inverse_kinematics",
    "joint_grid",
    "manipulability_map",
    "workspace_map",
]

# Posture grids and maps --------------------------------------------------------------


def joint_grid(n_points: int, *, lower: float = -math.pi, upper: float = math.pi, periodic: bool = True) -> jax.Array:
    """Evenly spaced joint angles, rad: ``(n_points,)``; the last point omitted when periodic."""
    if n_points < 2:
        raise ConfigError(f"n_points: need at least 2 grid points, got {n_points}")
    return jnp.linspace(lower, upper, n_points, endpoint=not periodic)


@functools.partial(jax.jit, static_argnames=("normalized", "rows_per_chunk"))
def manipulability_map(
    robot: PlanarRobot,
    joint_axes: Sequence[jax.Array],
    *,
    normalized: bool = True,
    rows_per_chunk: int = 64,
) -> jax.Array:
    """w* (or w*/L^2, eq. 11) on the outer-product grid of joint axes, in bounded memory.

    The first axis is processed in chunks of ``rows_per_chunk`` rows with
    ``jax.lax.map(..., batch_size=...)``, so the working memory is that of one chunk;
    only the result is held whole. Use `grid_average` when even the result is
    too large.

    Args:
        robot: one design.
        joint_axes: n arrays phi_1..phi_n, rad, sizes ``(A_1, ..., A_n)``.
        normalized: divide by L^2 (eq. 11).
        rows_per_chunk: rows of the first axis per chunk.

    Returns:
        ``(A_1, ..., A_n)`` w*/L^2 (dimensionless) or w* (m^2).
    """
    check_single_design(robot, "manipulability_map")
    coeffs = design_coefficients(robot)
    first, rest = jnp.asarray(joint_axes[0]), [jnp.asarray(a) for a in joint_axes[1:]]
    shape = tuple(int(jnp.shape(a)[0]) for a in joint_axes)
    scale = 1.0 / robot.reach**2 if normalized else 1.0

    def row(phi1):
        w = manipulability_from_angles(coeffs, *grid_angle_tables([phi1[None], *rest]))
        return jnp.broadcast_to(w, (1, *shape[1:]))[0] * scale

    return jax.lax.map(row, first, batch_size=max(1, min(rows_per_chunk, shape[0])))


def grid_average(robot: PlanarRobot, n_points: int, *, rows_per_chunk: int = 16) -> jax.Array:
    """Mean of w*/L^2 over a periodic n_points^n joint grid, streamed (never materialized).

    This is the joint-measure average (uniform over the joint torus) for any n, by the
    periodic trapezoid rule, at a cost of n_points^n postures in memory of
    ``rows_per_chunk * n_points^(n-1)`` postures.
    """
    check_single_design(robot, "grid_average")
    coeffs = design_coefficients(robot)
    n = robot.n_links
    axis = joint_grid(n_points)
    rest = [axis] * (n - 1)
    chunks = axis.reshape(-1, _divisor(n_points, rows_per_chunk))

    def chunk_sum(total, phi1_chunk):
        w = manipulability_from_angles(coeffs, *grid_angle_tables([phi1_chunk, *rest]))
        full = jnp.broadcast_to(w, (phi1_chunk.shape[0],) + (n_points,) * (n - 1))
        return total + jnp.sum(full), None

    total, _ = jax.lax.scan(chunk_sum, jnp.zeros((), axis.dtype), chunks)
    return total / robot.reach**2 / n_points**n


def _divisor(total: int, wanted: int) -> int:
    wanted = max(1, min(wanted, total))
    while total % wanted:
        wanted -= 1
    return wanted


def inverse_kinematics(robot: PlanarRobot, tip: jax.Array, *, elbow: str = "down") -> tuple[jax.Array, jax.Array]:
    """Joint angles of the 2-link arm that put the tip at ``tip`` in the robot frame.

    Args:
        robot: one design with n = 2.
        tip: ``(..., 2)`` points in Sigma_R, m.
        elbow: "down" (phi2 >= 0, the paper's choice) or "up" (phi2 <= 0).

    Returns:
        ``(phi_arm, reachable)``: ``(..., 2)`` joint angles, rad, and ``(...)`` bool
        (points outside the annulus get the nearest boundary posture and False).
    """
    if robot.n_links != 2:
        raise ConfigError(f"links: inverse_kinematics is closed-form for n = 2, got n = {robot.n_links}")
    if elbow not in ("down", "up"):
        raise ConfigError(f"elbow: must be 'down' or 'up', got {elbow!r}")
    l1, l2 = robot.link_length[..., 0], robot.link_length[..., 1]
    x, y = tip[..., 0], tip[..., 1]
    cos2 = (x * x + y * y - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    reachable = jnp.abs(cos2) <= 1.0
    phi2 = jnp.arccos(jnp.clip(cos2, -1.0, 1.0))
    if elbow == "up":
        phi2 = -phi2
    phi1 = jnp.arctan2(y, x) - jnp.arctan2(l2 * jnp.sin(phi2), l1 + l2 * jnp.cos(phi2))
    phi1 = jnp.mod(phi1 + jnp.pi, 2 * jnp.pi) - jnp.pi
    return jnp.stack([phi1, phi2], axis=-1), reachable


@functools.partial(jax.jit, static_argnames=("n_cells", "elbow", "ground"))
def workspace_map(
    robot: PlanarRobot, n_cells: int = 201, *, elbow: str = "down", ground: bool = False
) -> tuple[jax.Array, jax.Array, jax.Array]:
    """w*/L^2 on a Cartesian grid of the robot frame (the contour maps of Fig. 7 and 10).

    Args:
        robot: one design with n = 2.
        n_cells: grid points per axis over [-L, L].
        elbow: the arm configuration that reaches each point ("down" or "up").
        ground: the fixed-base (ground robot) w = l1 l2 |sin phi2| instead of w*.

    Returns:
        ``(x, y, w)``: ``(n_cells,)`` axes in Sigma_R, m, and ``(n_cells, n_cells)``
        w*/L^2 indexed [iy, ix], NaN outside the reachable annulus.
    """
    check_single_design(robot, "workspace_map")
    reach = robot.reach
    axis = jnp.linspace(-1.0, 1.0, n_cells) * reach
    gx, gy = jnp.meshgrid(axis, axis, indexing="xy")
    phi_arm, reachable = inverse_kinematics(robot, jnp.stack([gx, gy], axis=-1), elbow=elbow)
    if ground:
        w = fixed_base_manipulability(robot, phi_arm)
    else:
        c, s = jnp.cos(phi_arm[..., 0]), jnp.sin(phi_arm[..., 0])
        c12, s12 = jnp.cos(phi_arm.sum(-1)), jnp.sin(phi_arm.sum(-1))
        w = manipulability_from_angles(design_coefficients(robot), [c, c12], [s, s12])
    return axis, axis, jnp.where(reachable, w / reach**2, jnp.nan)
