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
  (`spacearm.paper.straight_workspace.straight_path_workspace`).
- Eq. (8) takes the straight-path boundary to be the kinematic singularity phi_2 = 0.
  The Generalized Jacobian J* does not lose rank there when b0 > 0; it loses rank on
  curves that pass through the collinear postures (phi_1, phi_2) in {0, pi} x {0, pi}
  and bulge up to ~18 deg away from phi_2 = 0 (Table 1) -- and a second branch near
  the folded arm, phi_2 ~ pi, which eq. (8) ignores. `dynamic_singularities`
  traces the zero set of det J* (n = 2) and `path_independent_radius` gives the
  largest singularity-free disk about the system centroid (the path-independent
  workspace of Papadopoulos & Dubowsky 1991). For Table 1 that radius is
  |K0 + K1 - K2| = 1.0 m, not eq. (8)'s 2.5 m.
- When K0 > K1+..+Kn the Guaranteed "disk" is exactly the unreachable hole of Area 3,
  so Area 2 does not contain Area 5 and the paper's "always" fails.
- Under joint limits (sec. 3.2, last paragraph) the radii of Area 3 come from a search
  over the joint box (`maximum_reachable_radii`); the base attitude stays free
  because cyclic joint motions inside the box can turn the base by any angle.
- Fig. 4 draws Area 1 in the inertial frame; we place it about joint 1 of the
  stretched posture phi = 0, the one placement where eq. (9) is exactly the condition
  for Area 3 >= Area 1 (all three circles then touch at (K0+..+Kn, 0)).

Areas are normalized by pi L^2 (sec. 5): `normalized_areas` gives Table 2's S_M and
S_G, `normalized_workspace_areas` the areas of workspaces 1-3 and 5.
"""

from __future__ import annotations

import functools
import itertools

import jax
import jax.numpy as jnp

from ..analysis.joint_box import joint_box
from ..models.family import require_family
from ..models.planar.closed_forms import reachable_radii, tip_coefficients, tip_position
from ..models.planar.robot import PlanarRobot

__all__ = [
    "attachment_condition",
    "attitude_constraint",
    "attitude_constraint_inner_radius",
    "fixed_vehicle_center",
    "fixed_vehicle_inner_radius",
    "fixed_vehicle_radius",
    "guaranteed_radius",
    "kinematic_singularity_radius",
    "maximum_reachable_inner_radius",
    "maximum_reachable_radii",
    "maximum_reachable_radius",
    "normalized_areas",
    "normalized_workspace_areas",
    "workspace_relations",
]


# Closed forms --------------------------------------------------------------------------


def fixed_vehicle_radius(robot: PlanarRobot) -> jax.Array:
    """``(...)`` Area 1 outer radius L = l_1 + .. + l_n about joint 1, m (sec. 3.1 (1)).

    Planar arms only (another family raises TypeError).
    """
    require_family(robot, "planar", "fixed_vehicle_radius")
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
    """Area 2 with phi0 = 0: centre ``(..., 2)`` (K0, 0) and radius ``(...)`` K1+..+Kn, m (eq. 7).

    Planar arms only (another family raises TypeError).
    """
    require_family(robot, "planar", "attitude_constraint")
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
    return reachable_radii(robot)[0]


def maximum_reachable_inner_radius(robot: PlanarRobot) -> jax.Array:
    """``(...)`` Area 3 hole: max(0, 2 max_k K_k - (K0+..+Kn)), m (non-zero when K0 > K1+..+Kn)."""
    return reachable_radii(robot)[1]


def guaranteed_radius(robot: PlanarRobot) -> jax.Array:
    """``(...)`` Area 5 radius |K0 - (K1 + .. + Kn)| about the system centroid, m (eq. 8).

    Planar arms only (another family raises TypeError).

    The paper's derivation: the closest approach to the centroid of the tip on the
    stretched-arm singularity (phi_2 = .. = phi_n = 0). See `path_independent_radius`
    for the radius that accounts for where det J* really vanishes.
    """
    require_family(robot, "planar", "guaranteed_radius")
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


@jax.jit
def normalized_areas(robot: PlanarRobot) -> tuple[jax.Array, jax.Array]:
    """Maximum Reachable and Guaranteed areas normalized by pi L^2 (Table 2).

    Planar arms only (another family raises TypeError).

    S_M = (K0 + K1 + ... + Kn)^2 / L^2 (section 3.1, 3-a) and
    S_G = (K0 - (K1 + ... + Kn))^2 / L^2 (eq. 8): the disks of radius
    `maximum_reachable_radius` and `guaranteed_radius`, holes not removed.

    Args:
        robot: a design or a batch of designs.

    Returns:
        ``(S_M, S_G)``, each ``(...)``, dimensionless.
    """
    require_family(robot, "planar", "normalized_areas")
    reach = robot.reach
    return (maximum_reachable_radius(robot) / reach) ** 2, (guaranteed_radius(robot) / reach) ** 2


def normalized_workspace_areas(robot: PlanarRobot) -> dict[str, jax.Array]:
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
        "maximum_reachable": (maximum_reachable_radius(robot) ** 2 - maximum_reachable_inner_radius(robot) ** 2) / L2,
        "maximum_reachable_disk": maximum_reachable_radius(robot) ** 2 / L2,
        "guaranteed": guaranteed_radius(robot) ** 2 / L2,
    }


def _disk_inside(center_in, radius_in, center_out, radius_out, tol):
    gap = jnp.linalg.norm(center_in - center_out, axis=-1)
    return gap + radius_in <= radius_out + tol


def workspace_relations(robot: PlanarRobot, tol: float = 1e-9) -> dict[str, jax.Array]:
    """The containments of sec. 3.2, for the workspaces drawn as disks as in Fig. 4.

    Planar arms only (another family raises TypeError).

    Returns:
        ``(...)`` bools: ``"3>=2"``, ``"2>=5"``, ``"3>=1"``, ``"1>=2"``, ``"eq9"`` (the
        condition), and ``"2>=5_with_hole"`` (Area 2 taken as the annulus it is, with the
        hole of `attitude_constraint_inner_radius`).
    """
    require_family(robot, "planar", "workspace_relations")
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


@functools.partial(jax.jit, static_argnames=("points_per_axis", "zoom_levels"))
def _reach_extremes(robot: PlanarRobot, points_per_axis: int, zoom_levels: int):
    n = robot.n_links
    lower, upper = joint_box(robot)
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

    Planar arms only (another family raises TypeError).

    The base attitude is free (cyclic motions inside the joint box turn it by any
    angle), so Area 3 is the rotation-swept set of the tip over the joint box: an
    annulus between the smallest and largest |tip| over the box. Found by a grid over
    the box, then ``zoom_levels`` finer grids about the best point. Without limits this
    reproduces `maximum_reachable_radius` and `maximum_reachable_inner_radius`.

    Args:
        robot: a single design; the box of `spacearm.analysis.joint_box.joint_box`
            (free joints span [-pi, pi), one-sided ones one turn from their limit).
        points_per_axis: grid points per joint (default: about 2e5 points in all).

    Returns:
        ``(inner, outer, joints_inner, joints_outer)``: radii (m) and the ``(n,)`` joint
        angles (rad) where they occur.
    """
    require_family(robot, "planar", "maximum_reachable_radii")
    if robot.batch_shape:
        raise ValueError("maximum_reachable_radii takes a single design; vmap it for batches")
    n = robot.n_links
    if points_per_axis is None:
        points_per_axis = max(9, int(round(2.0e5 ** (1.0 / n))))
    (inner, j_in), (outer, j_out) = _reach_extremes(robot, points_per_axis, zoom_levels)
    return inner, outer, j_in, j_out
