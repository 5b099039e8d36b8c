"""The Straight-Path workspace (Area 4, Fig. 3a, 5): where straight tip paths end.

It has no closed form: each direction's path is integrated numerically with
`spacearm.motion.straight_tip_path` until J* loses rank.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from ..analysis.joint_box import joint_box
from ..kinematics import manipulability, tip_position
from ..models.family import require_family
from ..models.planar.robot import PlanarRobot
from ..models.planar.singularities import path_independent_radius
from ..motion import straight_tip_path
from .workspaces import guaranteed_radius, kinematic_singularity_radius, maximum_reachable_radius

__all__ = [
    "clearance_radius",
    "evenly_spaced_directions",
    "inside_straight_path_workspace",
    "random_joint_postures",
    "straight_path_ends",
    "straight_path_intersection_radius",
    "straight_path_study",
    "straight_path_union_radius",
    "straight_path_workspace",
    "summarize_straight_paths",
]


def evenly_spaced_directions(n_directions: int, dtype=None) -> jax.Array:
    """``(n_directions, 2)`` inertial unit vectors, the first along the inertial x axis."""
    angle = 2.0 * jnp.pi * jnp.arange(n_directions, dtype=dtype) / n_directions
    return jnp.stack([jnp.cos(angle), jnp.sin(angle)], axis=-1)


def straight_path_ends(robot: PlanarRobot, phi_start: jax.Array, n_directions: int = 360, **path_options):
    """Straight tip paths from ``phi_start`` in ``n_directions`` evenly spaced directions (Fig. 3).

    Planar arms only (another family raises TypeError).

    A thin batched wrapper on ``motion.straight_tip_path``: every path runs until J*
    loses rank (or a joint limit, or ``max_length``); one compiled call for all
    initial postures and directions.

    Args:
        robot: the design (a single design; vmap for batches of designs).
        phi_start: ``(..., n+1)`` initial postures, rad.
        n_directions: directions per posture, evenly spaced from the inertial x axis.
        **path_options: passed to ``straight_tip_path`` (hashable values, e.g. tolerances).

    Returns:
        ``motion.StraightPath`` with batch shape ``(..., n_directions)``.
    """
    require_family(robot, "planar", "straight_path_ends")
    # No jit wrapper here: straight_tip_path is the compiled entry point, and a wrapper
    # would trace (and compile) the whole integrator again for every shape it sees. The
    # directions are built in NumPy, so no small program compiles for them either.
    angle = 2.0 * np.pi * np.arange(n_directions) / n_directions
    directions = np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    phi_start = phi_start if isinstance(phi_start, jax.core.Tracer) else np.asarray(phi_start)
    return straight_tip_path(robot, phi_start[..., None, :], directions, **path_options)


def straight_path_workspace(robot: PlanarRobot, phi_start: jax.Array, n_directions: int = 360, **path_options):
    """Boundary of the Straight-Path Workspace (Area 4, Fig. 3b) from an initial posture.

    Planar arms only (another family raises TypeError).

    Args:
        robot: the design.
        phi_start: ``(..., n+1)`` initial posture(s), rad.
        n_directions: number of directions, evenly spaced starting along the inertial x axis.

    Returns:
        ``(..., n_directions, 2)`` inertial end points (origin at the system centroid), m:
        where the straight tip path from ``tip_position(robot, phi_start)`` in each
        direction meets a singularity of J* (or a joint limit).
    """
    require_family(robot, "planar", "straight_path_workspace")
    return straight_path_ends(robot, phi_start, n_directions, **path_options).end_tip


def clearance_radius(start_tip: jax.Array, end_tip: jax.Array) -> jax.Array:
    """Radius of the largest centred disk inside the Straight-Path Workspace of every base attitude.

    The Straight-Path Workspace of one posture is star-shaped about its start tip; the
    points it misses are the rays beyond each end point. Turning the base (phi0) turns
    the workspace about the system centroid, so the workspaces of all base attitudes
    with the same joint angles share exactly the disk of radius min over directions of
    the distance from the centroid to those rays.

    Args:
        start_tip: ``(..., 2)`` inertial start point, m.
        end_tip: ``(..., D, 2)`` end points for D evenly spaced directions (from the x axis), m.

    Returns:
        ``(...)`` radius, m (0 when the workspace misses the centroid itself).
    """
    n_directions = end_tip.shape[-2]
    d = evenly_spaced_directions(n_directions, end_tip.dtype)
    start = start_tip[..., None, :]
    length = jnp.sum((end_tip - start) * d, axis=-1)
    # Ray {start + t d : t > length}; its closest point to the origin is at t = -start . d.
    t_closest = -jnp.sum(start * d, axis=-1)
    perpendicular = jnp.abs(start[..., 0] * d[..., 1] - start[..., 1] * d[..., 0])
    distance = jnp.where(t_closest > length, perpendicular, jnp.linalg.norm(end_tip, axis=-1))
    return jnp.min(distance, axis=-1)


def straight_path_union_radius(end_tip: jax.Array) -> jax.Array:
    """Measured Area 3 radius: the farthest straight-path end point from the centroid, m.

    Args:
        end_tip: ``(..., P, D, 2)`` end points over P initial postures and D directions.

    Returns:
        ``(...)`` m; compare `maximum_reachable_radius`.
    """
    return jnp.max(jnp.linalg.norm(end_tip, axis=-1), axis=(-2, -1))


def straight_path_intersection_radius(start_tip: jax.Array, end_tip: jax.Array) -> jax.Array:
    """Measured Area 5 radius: the largest centred disk inside every Straight-Path Workspace, m.

    Args:
        start_tip: ``(..., P, 2)`` start points of P initial postures.
        end_tip: ``(..., P, D, 2)`` end points.

    Returns:
        ``(...)`` m; compare `guaranteed_radius` (eq. 8) and `path_independent_radius`.
    """
    return jnp.min(clearance_radius(start_tip, end_tip), axis=-1)


def inside_straight_path_workspace(start_tip: jax.Array, end_tip: jax.Array, points: jax.Array) -> jax.Array:
    """Whether points lie in the star-shaped Straight-Path Workspace (linear in the direction angle).

    Args:
        start_tip: ``(2,)`` start point, m.
        end_tip: ``(D, 2)`` end points for evenly spaced directions, m.
        points: ``(..., 2)`` query points, inertial, m.

    Returns:
        ``(...)`` bool.
    """
    n_directions = end_tip.shape[-2]
    reach = jnp.linalg.norm(end_tip - start_tip, axis=-1)
    offset = points - start_tip
    angle = jnp.mod(jnp.arctan2(offset[..., 1], offset[..., 0]), 2.0 * jnp.pi) / (2.0 * jnp.pi) * n_directions
    k = jnp.floor(angle).astype(jnp.int32) % n_directions
    frac = angle - jnp.floor(angle)
    radius = (1.0 - frac) * reach[k] + frac * reach[(k + 1) % n_directions]
    return jnp.linalg.norm(offset, axis=-1) <= radius


def random_joint_postures(robot: PlanarRobot, count: int, seed: int = 0) -> np.ndarray:
    """``(count, n+1)`` postures with phi0 = 0 and joints uniform in the joint box, rad."""
    lower, upper = (np.asarray(x) for x in joint_box(robot))
    rng = np.random.default_rng(seed)
    joints = lower + rng.uniform(size=(count, robot.n_links)) * (upper - lower)
    return np.concatenate([np.zeros((count, 1)), joints], axis=1)


def straight_path_study(
    robot: PlanarRobot,
    n_postures: int = 1000,
    n_directions: int = 180,
    seed: int = 0,
    conditioning: float = 0.01,
    **path_options,
) -> dict[str, float]:
    """Areas 3 and 5 measured as the union and intersection of Straight-Path Workspaces (sec. 3.2).

    One batched call integrates ``n_postures x n_directions`` straight tip paths from
    random joint postures (phi0 = 0; a change of phi0 only turns each workspace about
    the centroid, which `clearance_radius` accounts for exactly).

    Args:
        robot: a single design.
        conditioning: starts with w*/L^2 below this count as near-singular, reported apart.

    Returns:
        Radii in m (closed forms beside measured ones) and fractions:
        ``union_radius`` vs ``maximum_reachable_radius``; ``intersection_radius`` (all
        starts), ``intersection_radius_conditioned`` (w*/L^2 >= conditioning) and the
        median clearance vs ``guaranteed_radius`` (eq. 8) and ``path_independent_radius``;
        for starts inside the eq. (8) disk: how many, the fraction of their paths that end
        inside it, and the smallest end radius; for n = 2 the intersection over starts
        inside the path-independent disk (at least its radius: a straight path between two
        points of a disk free of singular postures stays in it) and inside the eq. (8) disk.
    """
    phis = random_joint_postures(robot, n_postures, seed)
    ends = straight_path_ends(robot, phis, n_directions, **path_options)
    return summarize_straight_paths(robot, phis, ends, conditioning)


def summarize_straight_paths(robot: PlanarRobot, phis, ends, conditioning: float = 0.01) -> dict[str, float]:
    """The numbers of `straight_path_study` from already integrated paths.

    Args:
        phis: ``(P, n+1)`` initial postures, rad.
        ends: ``motion.StraightPath`` of batch shape ``(P, D)`` (evenly spaced directions).
    """
    n_postures, n_directions = np.asarray(ends.length).shape
    starts = np.asarray(tip_position(robot, phis))
    end_tip = np.asarray(ends.end_tip)
    clearance = np.asarray(clearance_radius(starts, end_tip))
    w = np.asarray(manipulability(robot, phis)) / float(robot.reach) ** 2
    conditioned = w >= conditioning
    r_g = float(guaranteed_radius(robot))
    inside = np.linalg.norm(starts, axis=-1) < r_g
    end_radius = np.linalg.norm(end_tip, axis=-1)
    result = {
        "n_postures": n_postures,
        "n_directions": n_directions,
        "maximum_reachable_radius": float(maximum_reachable_radius(robot)),
        "union_radius": float(end_radius.max()),
        "guaranteed_radius_eq8": r_g,
        "kinematic_singularity_radius": float(kinematic_singularity_radius(robot)),
        "intersection_radius": float(clearance.min()),
        "intersection_radius_conditioned": float(clearance[conditioned].min()) if conditioned.any() else math.nan,
        "conditioned_fraction": float(conditioned.mean()),
        "median_clearance": float(np.median(clearance)),
        "starts_inside_guaranteed": int(inside.sum()),
        "paths_from_inside_ending_inside": float((end_radius[inside] < r_g).mean()) if inside.any() else math.nan,
        "min_end_radius_from_inside": float(end_radius[inside].min()) if inside.any() else math.nan,
        "singular_end_fraction": float((np.asarray(ends.reason) == 0).mean()),
        "folded_end_fraction": float((np.abs(np.asarray(ends.end_posture)[..., 2]) > np.pi / 2).mean())
        if robot.n_links == 2
        else math.nan,
    }
    if robot.n_links == 2:
        r_piw = float(path_independent_radius(robot))
        inside_piw = np.linalg.norm(starts, axis=-1) < r_piw
        result["path_independent_radius"] = r_piw
        result["starts_inside_path_independent"] = int(inside_piw.sum())
        result["intersection_radius_inside_path_independent"] = (
            float(clearance[inside_piw].min()) if inside_piw.any() else math.nan
        )
        result["intersection_radius_inside_guaranteed"] = float(clearance[inside].min()) if inside.any() else math.nan
    return result
