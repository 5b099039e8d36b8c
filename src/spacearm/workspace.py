"""The five workspaces of a free-floating arm and their relations (Umetani & Yoshida 1990, sec. 3).

Closed forms (any n >= 2, batched over designs; K_k are eq. 1's tip coefficients):

====================  ==========================================  =====================================
workspace             paper (n = 2)                               here, n links
====================  ==========================================  =====================================
1 Fixed-Vehicle       disk radius L about joint 1                 annulus about joint 1, outer L, inner
                                                                  max(0, 2 max l_k - L)
2 Attitude-Constraint disk radius K1+K2 about (K0, 0) (eq. 7)     annulus about (K0, 0), outer
                                                                  K1+..+Kn, inner max(0, 2 max_{k>=1}
                                                                  K_k - (K1+..+Kn)); for n = 2 the
                                                                  inner radius is |K1 - K2|
3 Maximum Reachable   disk radius K0+K1+K2 about the centroid     annulus, outer K0+..+Kn, inner
                                                                  max(0, 2 max_k K_k - (K0+..+Kn))
5 Guaranteed          disk radius |K0 - (K1+K2)| (eq. 8)          |K0 - (K1+..+Kn)| (the paper's
                                                                  argument with the arm stretched,
                                                                  phi_2 = .. = phi_n = 0)
====================  ==========================================  =====================================

Where the closed forms stop holding:

- Area 4 (Straight-Path) has none; it is integrated numerically
  (:func:`straight_path_workspace`, on ``motion.straight_tip_path``).
- Eq. (8) takes the straight-path boundary to be the kinematic singularity phi_2 = 0.
  The Generalized Jacobian J* does not lose rank there when b0 > 0; it loses rank on
  curves that pass through the collinear postures (phi_1, phi_2) in {0, pi} x {0, pi}
  and bulge up to ~18 deg away from phi_2 = 0 (Table 1) -- and a second branch near
  the folded arm, phi_2 ~ pi, which eq. (8) ignores. :func:`dynamic_singularities`
  traces the zero set of det J* (n = 2) and :func:`path_independent_radius` gives the
  largest singularity-free disk about the system centroid (the path-independent
  workspace of Papadopoulos & Dubowsky 1991). For Table 1 that radius is
  |K0 + K1 - K2| = 1.0 m, not eq. (8)'s 2.5 m.
- When K0 > K1+..+Kn the Guaranteed "disk" is exactly the unreachable hole of Area 3,
  so Area 2 does not contain Area 5 and the paper's "always" fails.
- Under joint limits (sec. 3.2, last paragraph) the radii of Area 3 come from a search
  over the joint box (:func:`maximum_reachable_radii`); the base attitude stays free
  because cyclic joint motions inside the box can turn the base by any angle.
- Fig. 4 draws Area 1 in the inertial frame; we place it about joint 1 of the
  stretched posture phi = 0, the one placement where eq. (9) is exactly the condition
  for Area 3 >= Area 1 (all three circles then touch at (K0+..+Kn, 0)).

Areas are normalized by pi L^2 (sec. 5).
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math

import jax
import jax.numpy as jnp
import numpy as np

from .kinematics import generalized_jacobian, robot_frame_tip_position, tip_coefficients, tip_position
from .robot import ConfigError, PlanarRobot

__all__ = [
    "fixed_vehicle_radius",
    "fixed_vehicle_inner_radius",
    "fixed_vehicle_center",
    "attitude_constraint",
    "attitude_constraint_inner_radius",
    "maximum_reachable_radius",
    "maximum_reachable_inner_radius",
    "guaranteed_radius",
    "kinematic_singularity_radius",
    "attachment_condition",
    "normalized_areas",
    "workspace_relations",
    "maximum_reachable_radii",
    "SingularSet",
    "dynamic_singularities",
    "path_independent_radius",
    "evenly_spaced_directions",
    "straight_path_ends",
    "straight_path_workspace",
    "straight_path_union_radius",
    "straight_path_intersection_radius",
    "clearance_radius",
    "inside_straight_path_workspace",
    "random_joint_postures",
    "straight_path_study",
    "summarize_straight_paths",
]


# Closed forms --------------------------------------------------------------------------


def fixed_vehicle_radius(robot: PlanarRobot) -> jax.Array:
    """``(...)`` Area 1 outer radius L = l_1 + .. + l_n about joint 1, m (sec. 3.1 (1))."""
    return robot.reach


def fixed_vehicle_inner_radius(robot: PlanarRobot) -> jax.Array:
    """``(...)`` Area 1 inner radius max(0, 2 max_k l_k - L), m (0 for Table 1)."""
    lengths = robot.link_length
    return jnp.maximum(0.0, 2.0 * jnp.max(lengths, axis=-1) - robot.reach)


def fixed_vehicle_center(robot: PlanarRobot) -> jax.Array:
    """``(..., 2)`` joint 1 in the inertial frame at the stretched posture phi = 0, m.

    (K0 + K1 + .. + Kn - L, 0): the placement of Area 1 in Fig. 4 under which eq. (9)
    is exactly the condition Area 3 >= Area 1.
    """
    x = jnp.sum(tip_coefficients(robot), axis=-1) - robot.reach
    return jnp.stack([x, jnp.zeros_like(x)], axis=-1)


def attitude_constraint(robot: PlanarRobot) -> tuple[jax.Array, jax.Array]:
    """Area 2 with phi0 = 0: centre ``(..., 2)`` (K0, 0) and radius ``(...)`` K1+..+Kn, m (eq. 7)."""
    K = tip_coefficients(robot)
    center = jnp.stack([K[..., 0], jnp.zeros_like(K[..., 0])], axis=-1)
    return center, jnp.sum(K[..., 1:], axis=-1)


def attitude_constraint_inner_radius(robot: PlanarRobot) -> jax.Array:
    """``(...)`` Area 2 hole about (K0, 0): max(0, 2 max_{k>=1} K_k - (K1+..+Kn)), m.

    The paper draws Area 2 as a full disk; for n = 2 the hole has radius |K1 - K2|.
    """
    K = tip_coefficients(robot)[..., 1:]
    return jnp.maximum(0.0, 2.0 * jnp.max(K, axis=-1) - jnp.sum(K, axis=-1))


def maximum_reachable_radius(robot: PlanarRobot) -> jax.Array:
    """``(...)`` Area 3 radius K0 + K1 + .. + Kn about the system centroid, m (sec. 3.1 (3-a))."""
    return jnp.sum(tip_coefficients(robot), axis=-1)


def maximum_reachable_inner_radius(robot: PlanarRobot) -> jax.Array:
    """``(...)`` Area 3 hole: max(0, 2 max_k K_k - (K0+..+Kn)), m (non-zero when K0 > K1+..+Kn)."""
    K = tip_coefficients(robot)
    return jnp.maximum(0.0, 2.0 * jnp.max(K, axis=-1) - jnp.sum(K, axis=-1))


def guaranteed_radius(robot: PlanarRobot) -> jax.Array:
    """``(...)`` Area 5 radius |K0 - (K1 + .. + Kn)| about the system centroid, m (eq. 8).

    The paper's derivation: the closest approach to the centroid of the tip on the
    stretched-arm singularity (phi_2 = .. = phi_n = 0). See :func:`path_independent_radius`
    for the radius that accounts for where det J* really vanishes.
    """
    K = tip_coefficients(robot)
    return jnp.abs(K[..., 0] - jnp.sum(K[..., 1:], axis=-1))


def kinematic_singularity_radius(robot: PlanarRobot) -> jax.Array:
    """``(...)`` closest approach to the centroid over all kinematically singular postures, m.

    Eq. (8) extended to every collinear arm (phi_j in {0, pi} for j >= 2, folded ones
    included): min over the signs e_k of |K0 - |K1 + e_2 K2 + .. + e_n Kn||.
    For n = 2 this is min(|K0 - (K1+K2)|, |K0 - |K1-K2||); Table 1: 1.0 m, not 2.5 m.
    """
    K = tip_coefficients(robot)
    n = K.shape[-1] - 1
    best = None
    for signs in itertools.product((1.0, -1.0), repeat=n - 1):
        span = K[..., 1] + sum(s * K[..., k + 2] for k, s in enumerate(signs))
        value = jnp.abs(K[..., 0] - jnp.abs(span))
        best = value if best is None else jnp.minimum(best, value)
    return best


def attachment_condition(robot: PlanarRobot) -> jax.Array:
    """``(...)`` bool, eq. (9): b0 >= (w / m0)(L - K1 - .. - Kn), i.e. K0 + .. + Kn >= L."""
    K = tip_coefficients(robot)
    bound = robot.total_mass / robot.base_mass * (robot.reach - jnp.sum(K[..., 1:], axis=-1))
    return robot.base_attach >= bound


def normalized_areas(robot: PlanarRobot) -> dict[str, jax.Array]:
    """Areas of the closed-form workspaces (holes removed), each normalized by pi L^2.

    Returns:
        ``{"fixed_vehicle", "attitude_constraint", "maximum_reachable", "guaranteed",
        "maximum_reachable_disk"}`` -> ``(...)`` dimensionless. ``maximum_reachable_disk``
        is the paper's S_M = (K0+..+Kn)^2 / L^2 (Table 2), without the hole.
    """
    L2 = robot.reach**2
    _, r2 = attitude_constraint(robot)
    return {
        "fixed_vehicle": (robot.reach**2 - fixed_vehicle_inner_radius(robot) ** 2) / L2,
        "attitude_constraint": (r2**2 - attitude_constraint_inner_radius(robot) ** 2) / L2,
        "maximum_reachable": (maximum_reachable_radius(robot) ** 2 - maximum_reachable_inner_radius(robot) ** 2)
        / L2,
        "maximum_reachable_disk": maximum_reachable_radius(robot) ** 2 / L2,
        "guaranteed": guaranteed_radius(robot) ** 2 / L2,
    }


def _disk_inside(center_in, radius_in, center_out, radius_out, tol):
    gap = jnp.linalg.norm(center_in - center_out, axis=-1)
    return gap + radius_in <= radius_out + tol


def workspace_relations(robot: PlanarRobot, tol: float = 1e-9) -> dict[str, jax.Array]:
    """The containments of sec. 3.2, for the workspaces drawn as disks as in Fig. 4.

    Returns:
        ``(...)`` bools: ``"3>=2"``, ``"2>=5"``, ``"3>=1"``, ``"1>=2"``, ``"eq9"`` (the
        condition), and ``"2>=5_with_hole"`` (Area 2 taken as the annulus it is, with the
        hole of :func:`attitude_constraint_inner_radius`).
    """
    zero = jnp.zeros_like(fixed_vehicle_center(robot))
    c1, r1 = fixed_vehicle_center(robot), fixed_vehicle_radius(robot)
    c2, r2 = attitude_constraint(robot)
    r3, r5 = maximum_reachable_radius(robot), guaranteed_radius(robot)
    hole2 = attitude_constraint_inner_radius(robot)
    two_over_five = _disk_inside(zero, r5, c2, r2, tol)
    # The annulus contains the disk when the disk also misses the hole.
    misses_hole = jnp.linalg.norm(c2, axis=-1) >= r5 + hole2 - tol
    return {
        "3>=2": _disk_inside(c2, r2, zero, r3, tol),
        "2>=5": two_over_five,
        "2>=5_with_hole": two_over_five & (misses_hole | (hole2 <= tol)),
        "3>=1": _disk_inside(c1, r1, zero, r3, tol),
        "1>=2": _disk_inside(c2, r2, c1, r1, tol),
        "eq9": attachment_condition(robot),
    }


# Maximum Reachable under joint limits ---------------------------------------------------


def _box(robot: PlanarRobot):
    lower = jnp.where(jnp.isfinite(robot.joint_lower), robot.joint_lower, -jnp.pi)
    upper = jnp.where(jnp.isfinite(robot.joint_upper), robot.joint_upper, jnp.pi)
    return lower, jnp.minimum(upper, lower + 2.0 * jnp.pi)


@functools.partial(jax.jit, static_argnames=("points_per_axis", "zoom_levels"))
def _reach_extremes(robot: PlanarRobot, points_per_axis: int, zoom_levels: int):
    n = robot.n_links
    lower, upper = _box(robot)
    unit = jnp.linspace(0.0, 1.0, points_per_axis)
    mesh = jnp.stack(jnp.meshgrid(*([unit] * n), indexing="ij"), axis=-1).reshape(-1, n)

    def radius(joints):
        phi = jnp.concatenate([jnp.zeros(joints.shape[:-1] + (1,), joints.dtype), joints], axis=-1)
        return jnp.linalg.norm(tip_position(robot, phi), axis=-1)

    def search(sign):
        lo, hi = lower, upper
        best = None
        for _ in range(zoom_levels + 1):
            joints = lo + mesh * (hi - lo)
            values = sign * radius(joints)
            k = jnp.argmax(values)
            best = joints[k]
            step = (hi - lo) / (points_per_axis - 1)
            lo = jnp.maximum(lower, best - 2.0 * step)
            hi = jnp.minimum(upper, best + 2.0 * step)
        return radius(best), best

    return search(-1.0), search(1.0)


def maximum_reachable_radii(robot: PlanarRobot, points_per_axis: int | None = None, zoom_levels: int = 4):
    """Area 3 under joint limits: the annulus radii about the system centroid, searched numerically.

    The base attitude is free (cyclic motions inside the joint box turn it by any
    angle), so Area 3 is the rotation-swept set of the tip over the joint box: an
    annulus between the smallest and largest |tip| over the box. Found by a grid over
    the box, then ``zoom_levels`` finer grids about the best point. Without limits this
    reproduces :func:`maximum_reachable_radius` and :func:`maximum_reachable_inner_radius`.

    Args:
        robot: a single design; free joints span [-pi, pi].
        points_per_axis: grid points per joint (default: about 2e5 points in all).

    Returns:
        ``(inner, outer, joints_inner, joints_outer)``: radii (m) and the ``(n,)`` joint
        angles (rad) where they occur.
    """
    if robot.batch_shape:
        raise ValueError("maximum_reachable_radii takes a single design; vmap it for batches")
    n = robot.n_links
    if points_per_axis is None:
        points_per_axis = max(9, int(round(2.0e5 ** (1.0 / n))))
    (inner, j_in), (outer, j_out) = _reach_extremes(robot, points_per_axis, zoom_levels)
    return inner, outer, j_in, j_out


# Dynamic singularities (n = 2) ---------------------------------------------------------


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class SingularSet:
    """Postures where det J* = 0 (n = 2), traced on a grid of phi_1 values.

    Each row is one phi_1; each column one cell of the phi_2 grid that holds a root
    (NaN where it does not). phi0 = 0: det J* does not depend on phi0, and a change of
    phi0 rotates the tip about the system centroid, so the inertial singular set is the
    union of the circles of radius ``radius``.

    Attributes:
        phi1: ``(M, N)`` joint 1 angle, rad (N = max_roots slots per phi_1).
        phi2: ``(M, N)`` joint 2 angle where det J* = 0, rad in [-pi, pi), NaN if none.
        radius: ``(M, N)`` |tip| in the inertial frame (distance to the system centroid), m.
        tip_inertial: ``(M, N, 2)`` tip at phi0 = 0, inertial frame, m.
        tip_robot: ``(M, N, 2)`` tip in the robot frame Sigma_R (origin at joint 1), m.
        folded: ``(M, N)`` bool, the branch near the folded arm (|phi2| > pi/2).
    """

    phi1: jax.Array
    phi2: jax.Array
    radius: jax.Array
    tip_inertial: jax.Array
    tip_robot: jax.Array
    folded: jax.Array


def _det_generalized_jacobian(robot, phi1, phi2):
    phi = jnp.stack(jnp.broadcast_arrays(jnp.zeros_like(phi1), phi1, phi2), axis=-1)
    J = generalized_jacobian(robot, phi)
    return J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]


@functools.partial(jax.jit, static_argnames=("n_phi1", "n_phi2", "bisection_steps", "max_roots"))
def _singular_roots(robot, n_phi1, n_phi2, bisection_steps, max_roots):
    dtype = jnp.asarray(robot.link_a).dtype
    phi1 = -jnp.pi + 2.0 * jnp.pi * jnp.arange(n_phi1, dtype=dtype) / n_phi1
    # Offset by half a cell so the collinear roots phi2 = 0 and pi fall inside cells.
    step = 2.0 * jnp.pi / n_phi2
    left = -jnp.pi + step * (jnp.arange(n_phi2, dtype=dtype) + 0.5)
    d_left = _det_generalized_jacobian(robot, phi1[:, None], left[None, :])
    d_right = jnp.roll(d_left, -1, axis=1)  # the last cell wraps through pi
    crossing = d_left * d_right < 0
    # Keep the first max_roots bracketing cells of each row (static shape).
    cells = jnp.argsort(~crossing, axis=1, stable=True)[:, :max_roots]
    has_root = jnp.take_along_axis(crossing, cells, axis=1)
    P1 = jnp.broadcast_to(phi1[:, None], cells.shape)
    lo0 = left[cells]

    def bisect(_, bracket):
        lo, hi, f_lo = bracket
        mid = 0.5 * (lo + hi)
        f_mid = _det_generalized_jacobian(robot, P1, mid)
        go_left = f_lo * f_mid <= 0
        return jnp.where(go_left, lo, mid), jnp.where(go_left, mid, hi), jnp.where(go_left, f_lo, f_mid)

    f0 = jnp.take_along_axis(d_left, cells, axis=1)
    lo, hi, _ = jax.lax.fori_loop(0, bisection_steps, bisect, (lo0, lo0 + step, f0))
    root = jnp.mod(0.5 * (lo + hi) + jnp.pi, 2.0 * jnp.pi) - jnp.pi
    safe = jnp.where(has_root, root, 0.0)
    phi = jnp.stack([jnp.zeros_like(P1), P1, safe], axis=-1)
    tip = tip_position(robot, phi)
    tip_r = robot_frame_tip_position(robot, phi[..., 1:])
    nan2 = jnp.where(has_root[..., None], 1.0, jnp.nan)
    return SingularSet(
        phi1=P1,
        phi2=jnp.where(has_root, root, jnp.nan),
        radius=jnp.where(has_root, jnp.linalg.norm(tip, axis=-1), jnp.nan),
        tip_inertial=tip * nan2,
        tip_robot=tip_r * nan2,
        folded=has_root & (jnp.abs(safe) > 0.5 * jnp.pi),
    )


def dynamic_singularities(
    robot: PlanarRobot, n_phi1: int = 1440, n_phi2: int = 256, bisection_steps: int = 55, max_roots: int = 4
) -> SingularSet:
    """The zero set of det J* (eq. 6) for a two-link arm: the free base's real singularities.

    For every phi_1 on an even grid of ``n_phi1`` values in [-pi, pi), the roots in phi_2
    are bracketed by sign changes on ``n_phi2`` cells (the first ``max_roots`` per row
    are kept; rows of the shape ``(M, max_roots)``) and refined by bisection to
    2 pi / n_phi2 / 2**bisection_steps rad. A root of even multiplicity (a tangency
    without sign change) would be missed; for the designs we tried det J* changes sign
    across both branches everywhere but at the collinear crossings.

    Raises:
        ConfigError: for n != 2 (for n > 2, J* loses rank on a set of codimension 2 in
            joint space, which a one-dimensional scan cannot trace).
    """
    if robot.n_links != 2:
        raise ConfigError(f"links: dynamic_singularities traces det J* for n = 2 links, got n = {robot.n_links}")
    if robot.batch_shape:
        return jax.vmap(lambda r: _singular_roots(r, n_phi1, n_phi2, bisection_steps, max_roots))(robot)
    return _singular_roots(robot, n_phi1, n_phi2, bisection_steps, max_roots)


def path_independent_radius(robot: PlanarRobot, **grid) -> jax.Array:
    """``(...)`` radius of the largest disk about the system centroid that no singular posture reaches, m.

    The min of |tip| over the zero set of det J* (n = 2): inside this disk a tip path
    meets no dynamic singularity whatever the base attitude (Papadopoulos & Dubowsky
    1991's path-independent workspace; it contains points only where Area 3 has no hole).
    Compare :func:`guaranteed_radius` (eq. 8), which considers phi_2 = 0 only.
    """
    return jnp.nanmin(dynamic_singularities(robot, **grid).radius, axis=(-2, -1))


# Straight-Path workspace (numerical, on motion.straight_tip_path) -----------------------


def evenly_spaced_directions(n_directions: int, dtype=None) -> jax.Array:
    """``(n_directions, 2)`` inertial unit vectors, the first along the inertial x axis."""
    angle = 2.0 * jnp.pi * jnp.arange(n_directions, dtype=dtype) / n_directions
    return jnp.stack([jnp.cos(angle), jnp.sin(angle)], axis=-1)


@functools.partial(jax.jit, static_argnames=("n_directions", "options"))
def _straight_path_ends(robot, phi_start, n_directions, options):
    from .motion import straight_tip_path

    phi_start = jnp.asarray(phi_start)
    directions = evenly_spaced_directions(n_directions, phi_start.dtype)
    # One vmapped batch: measured faster than lax.map over chunks of 512-16384 paths.
    return straight_tip_path(robot, phi_start[..., None, :], directions, **dict(options))


def straight_path_ends(robot: PlanarRobot, phi_start: jax.Array, n_directions: int = 360, **path_options):
    """Straight tip paths from ``phi_start`` in ``n_directions`` evenly spaced directions (Fig. 3).

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
    return _straight_path_ends(robot, phi_start, n_directions, tuple(sorted(path_options.items())))


def straight_path_workspace(robot: PlanarRobot, phi_start: jax.Array, n_directions: int = 360, **path_options):
    """Boundary of the Straight-Path Workspace (Area 4, Fig. 3b) from an initial posture.

    Args:
        robot: the design.
        phi_start: ``(..., n+1)`` initial posture(s), rad.
        n_directions: number of directions, evenly spaced starting along the inertial x axis.

    Returns:
        ``(..., n_directions, 2)`` inertial end points (origin at the system centroid), m:
        where the straight tip path from ``tip_position(robot, phi_start)`` in each
        direction meets a singularity of J* (or a joint limit).
    """
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
        ``(...)`` m; compare :func:`maximum_reachable_radius`.
    """
    return jnp.max(jnp.linalg.norm(end_tip, axis=-1), axis=(-2, -1))


def straight_path_intersection_radius(start_tip: jax.Array, end_tip: jax.Array) -> jax.Array:
    """Measured Area 5 radius: the largest centred disk inside every Straight-Path Workspace, m.

    Args:
        start_tip: ``(..., P, 2)`` start points of P initial postures.
        end_tip: ``(..., P, D, 2)`` end points.

    Returns:
        ``(...)`` m; compare :func:`guaranteed_radius` (eq. 8) and :func:`path_independent_radius`.
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
    lower, upper = (np.asarray(x) for x in _box(robot))
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
    the centroid, which :func:`clearance_radius` accounts for exactly).

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
    """The numbers of :func:`straight_path_study` from already integrated paths.

    Args:
        phis: ``(P, n+1)`` initial postures, rad.
        ends: ``motion.StraightPath`` of batch shape ``(P, D)`` (evenly spaced directions).
    """
    n_postures, n_directions = np.asarray(ends.length).shape
    starts = np.asarray(tip_position(robot, phis))
    end_tip = np.asarray(ends.end_tip)
    clearance = np.asarray(clearance_radius(starts, end_tip))
    from .kinematics import manipulability

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
