"""Kernels written once over the robot-family primitives: tip, J*, w*, ellipsoids, base rates.

Each public kernel takes a robot of any family and a posture with any leading batch
shape (planar ``phi (..., n+1)``; spatial ``q (..., n)`` with an optional
``base_rotation (..., 3, 3)``). A family's closed form, where it registered one, is
chosen by type at trace time; otherwise the generic formula runs per posture under
``vmap``. The planar closed forms equal the generic path to ~1e-15 (tests/test_seam.py).

Generalized Jacobian (Umetani & Yoshida 1990, eq. 6, in any dimension):

    J* = J_M - J_S I_S^-1 I_M,

the tip twist per joint rate at zero momentum. Spatial J* is expressed in inertial axes
as blkdiag(R, R) J*_bus, R the bus attitude.

A family with several tips (trees of arms on one bus) puts a tip axis before each
per-tip result: tips ``(..., k, 3)``, J* ``(..., k, 6, n)``, w* ``(..., k)``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ._core.batching import map_leading
from ._core.linalg import adjugate, gram_determinant, gram_root_determinant, square_determinant
from .models.family import RobotFamily, family_of

__all__ = [
    "base_rate",
    "base_rate_matrix",
    "fixed_base_jacobian",
    "fixed_base_manipulability",
    "generalized_jacobian",
    "generic_generalized_jacobian",
    "generic_manipulability",
    "generic_tip_position",
    "gram_determinant",
    "gram_root_determinant",
    "manipulability",
    "manipulability_ellipsoid",
    "relative_jacobian",
    "rotate_twist_rows",
    "square_determinant",
    "straight_path_rates",
    "tip_pose",
    "tip_position",
]


# One posture -----------------------------------------------------------------------------


def _jstar_one(family: RobotFamily, robot, posture):
    J_S, J_M = family.jacobians(robot, posture)
    I_S, I_M = family.momentum_map(robot, posture)
    return J_M - J_S @ jnp.linalg.solve(I_S, I_M)


def _base_matrix_one(family: RobotFamily, robot, posture):
    I_S, I_M = family.momentum_map(robot, posture)
    return -jnp.linalg.solve(I_S, I_M)


def straight_path_rates(J: jax.Array, direction: jax.Array, sign0: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Regularized joint rates moving the tip along ``direction`` (one posture).

    For a square J (t = n): dq/dsigma = sgn0 adj(J) d / |adj(J) d| and
    ds/dsigma = sgn0 det(J) / |adj(J) d|; for t < n the minimum-norm rates
    J^T (J J^T)^-1 d regularized the same way with adj(J J^T). sigma is the joint-space
    arc length and s the tip distance travelled; both stay finite through rank loss,
    where ds/dsigma = 0 marks the end of the straight path (a dynamic singularity).

    Args:
        J: ``(t, n)`` translational Generalized Jacobian, m/rad.
        direction: ``(t,)`` unit direction of the tip motion, inertial axes.
        sign0: sign of det J at the start of the path (square J), else 1.

    Returns:
        ``(dq (n,), ds)``: unit joint rates and the tip speed per unit joint arc length.
    """
    t, n = J.shape
    if t == n:
        v = sign0 * (adjugate(J) @ direction)
        rate = sign0 * square_determinant(J)
    else:
        v = J.T @ (adjugate(J @ J.T) @ direction)
        rate = gram_determinant(J)
    norm_sq = jnp.sum(v * v)
    positive = norm_sq > 0
    inv_norm = jnp.where(positive, 1.0 / jnp.sqrt(jnp.where(positive, norm_sq, 1.0)), 0.0)
    return v * inv_norm, rate * inv_norm


# Batched over leading axes -------------------------------------------------------------


def _attitude(family: RobotFamily, robot, base_rotation):
    """The bus attitude ``(..., 3, 3)``, with a tip axis inserted for a family with several tips."""
    if not family.rotates_with_base:
        raise TypeError(f"base_rotation applies to spatial robots; a {family.name} posture carries its base attitude")
    R = jnp.asarray(base_rotation)
    return R if family.tip_count(robot) is None else R[..., None, :, :]


def _rotate_vector(family: RobotFamily, robot, value, base_rotation):
    if base_rotation is None:
        return value
    return jnp.einsum("...ij,...j->...i", _attitude(family, robot, base_rotation), value)


def rotate_twist_rows(J: jax.Array, R: jax.Array) -> jax.Array:
    """blkdiag(R, R) J for twist rows [v; w] ``(..., 6, n)``: bus axes to inertial axes."""
    top = jnp.einsum("...ij,...jk->...ik", R, J[..., :3, :])
    bottom = jnp.einsum("...ij,...jk->...ik", R, J[..., 3:, :])
    return jnp.concatenate([top, bottom], axis=-2)


def _rotate_twist_rows(family: RobotFamily, robot, J, base_rotation):
    """J*_inertial = blkdiag(R, R) J*_bus (R with a tip axis for a family with several tips)."""
    if base_rotation is None:
        return J
    return rotate_twist_rows(J, _attitude(family, robot, base_rotation))


def generic_tip_position(robot, posture: jax.Array) -> jax.Array:
    """`tip_position` through the family's ``tip`` primitive only (no closed form)."""
    family = family_of(robot)
    return map_leading(lambda p: family.tip(robot, p), posture, core_ndims=(1,))


def generic_generalized_jacobian(robot, posture: jax.Array) -> jax.Array:
    """J* = J_M - J_S I_S^-1 I_M (eq. 6) from the family's primitives only, ``(..., m, n)``."""
    family = family_of(robot)
    J = map_leading(lambda p: _jstar_one(family, robot, p), posture, core_ndims=(1,))
    tips = family.tip_count(robot)
    return J if tips is None else J.reshape(J.shape[:-2] + (tips, -1, J.shape[-1]))


def generic_manipulability(robot, posture: jax.Array) -> jax.Array:
    """w* = sqrt det(J*_v J*_v^T) (eq. 10) from the generic J*."""
    family = family_of(robot)
    J = generic_generalized_jacobian(robot, posture)
    return gram_root_determinant(J[..., : family.translational_rows, :])


@jax.jit
def tip_position(robot, posture: jax.Array, base_rotation: jax.Array | None = None) -> jax.Array:
    """Tip position about the system centroid, inertial axes (eq. 1), m.

    Args:
        robot: a design of either family.
        posture: planar ``(..., n+1)`` [phi0, phi1..phin], rad; spatial ``(..., n)`` joints.
        base_rotation: spatial only, ``(..., 3, 3)`` bus attitude R (default identity).

    Returns:
        ``(..., 2)`` planar, ``(..., 3)`` spatial or ``(..., k, 3)`` for k tips, m.
    """
    family = family_of(robot)
    fast = family.fast_paths.tip_position
    p = fast(robot, posture) if fast is not None else generic_tip_position(robot, posture)
    return _rotate_vector(family, robot, p, base_rotation)


@jax.jit
def tip_pose(robot, joints: jax.Array, base_rotation: jax.Array | None = None) -> tuple[jax.Array, jax.Array]:
    """The tip frame: its origin about the system centroid and its axes, inertial axes.

    What a pose target (``spacearm reach --to-rpy``) is measured against: the rotation is
    the tip frame's axes in inertial axes, so its URDF roll-pitch-yaw is the ``--to-rpy``
    that holds the current orientation.

    Args:
        robot: a design whose tip has an orientation (a spatial arm, or a tree focused on one tip).
        joints: ``(..., n)`` joint positions.
        base_rotation: ``(..., 3, 3)`` bus attitude R (default identity).

    Returns:
        ``(position (..., 3) m, rotation (..., 3, 3))``.
    """
    family = family_of(robot)
    frame = jnp.vectorize(lambda q: family.tip_frame(robot, q), signature="(n)->(s),(s,s)")
    position, axes = frame(jnp.asarray(joints))
    if base_rotation is None:
        return position, axes
    R = jnp.asarray(base_rotation)
    return jnp.einsum("...ij,...j->...i", R, position), R @ axes


@jax.jit
def generalized_jacobian(robot, posture: jax.Array, base_rotation: jax.Array | None = None) -> jax.Array:
    """The Generalized Jacobian J* = J_M - J_S I_S^-1 I_M (eq. 6), inertial axes.

    Args:
        robot: a design of either family.
        posture: planar ``(..., n+1)``, rad; spatial ``(..., n)`` joint positions.
        base_rotation: spatial only, ``(..., 3, 3)`` bus attitude (default identity).

    Returns:
        Planar ``(..., 2, n)``: tip velocity (m/s) per joint rate. Spatial ``(..., 6, n)``:
        rows [v; w] of the tip-frame origin, inertial axes, per joint rate; ``(..., k, 6, n)``
        for k tips, over all joints (a tip's J* is not zero in other arms' columns).
    """
    family = family_of(robot)
    fast = family.fast_paths.generalized_jacobian
    J = fast(robot, posture) if fast is not None else generic_generalized_jacobian(robot, posture)
    return _rotate_twist_rows(family, robot, J, base_rotation)


@jax.jit
def manipulability(robot, posture: jax.Array) -> jax.Array:
    """Translational w* = sqrt(det(J*_v J*_v^T)) (eq. 10): m^2 planar, m^3 spatial.

    Independent of the base attitude. Exactly 0 at singular postures, with finite
    gradients there.

    Args:
        posture: planar ``(..., n+1)`` (phi0 ignored); spatial ``(..., n)``.

    Returns:
        ``(...)``, or ``(..., k)`` per tip for k tips.
    """
    family = family_of(robot)
    fast = family.fast_paths.manipulability
    return fast(robot, posture) if fast is not None else generic_manipulability(robot, posture)


@jax.jit
def manipulability_ellipsoid(robot, posture: jax.Array, base_rotation: jax.Array | None = None):
    """Principal semi-axes and directions of {J*_v q_dot : |q_dot| <= 1} (section 4.1).

    Returns:
        ``(semi_axes (..., t), directions (..., t, t))``: singular values of the
        translational J*, largest first (m/rad; their product is w*), and the unit
        axis directions as columns, inertial axes.
    """
    family = family_of(robot)
    J = generalized_jacobian(robot, posture, base_rotation)[..., : family.translational_rows, :]
    directions, semi_axes, _ = jnp.linalg.svd(J, full_matrices=False)
    return semi_axes, directions


@jax.jit
def base_rate_matrix(robot, posture: jax.Array) -> jax.Array:
    """C = -I_S^-1 I_M: base velocity per joint rate at zero momentum (eq. 5).

    Returns:
        Planar ``(..., 1, n)`` (dphi0 per joint rate). Spatial ``(..., 6, n)``: the
        family's base twist coordinates per joint rate, bus axes.
    """
    family = family_of(robot)
    fast = family.fast_paths.base_rate_matrix
    if fast is not None:
        return fast(robot, posture)
    return map_leading(lambda p: _base_matrix_one(family, robot, p), posture, core_ndims=(1,))


@jax.jit
def base_rate(robot, posture: jax.Array, joint_rates: jax.Array) -> jax.Array:
    """Base velocity for given joint rates at zero momentum (eq. 5).

    Returns:
        Planar ``(...)`` dphi0 = -(I_M . dphi_M) / I_S, rad per unit time. Spatial
        ``(..., 6)`` base twist (family coordinates, bus axes).
    """
    family = family_of(robot)
    fast = family.fast_paths.base_rate
    if fast is not None:
        return fast(robot, posture, joint_rates)
    return jnp.einsum("...ij,...j->...i", base_rate_matrix(robot, posture), joint_rates)


@jax.jit
def fixed_base_jacobian(robot, joints: jax.Array) -> jax.Array:
    """Jacobian of the same arm on a fixed base (Fig. 7b), ``(..., m, n)``, base axes.

    Args:
        joints: ``(..., n)`` joint positions (no base attitude).
    """
    family = family_of(robot)
    fast = family.fast_paths.fixed_base_jacobian
    if fast is not None:
        return fast(robot, joints)
    return map_leading(lambda q: family.fixed_base_jacobian(robot, q), joints, core_ndims=(1,))


@jax.jit
def fixed_base_manipulability(robot, joints: jax.Array) -> jax.Array:
    """Yoshikawa's w = sqrt(det(J_v J_v^T)) of the fixed-base arm (for n = 2 planar, l1 l2 |sin phi2|)."""
    family = family_of(robot)
    fast = family.fast_paths.fixed_base_manipulability
    if fast is not None:
        return fast(robot, joints)
    return gram_root_determinant(fixed_base_jacobian(robot, joints)[..., : family.translational_rows, :])


def _tip_index(robot, tip) -> int:
    names = family_of(robot).tip_names(robot)
    count = family_of(robot).tip_count(robot)
    if isinstance(tip, str):
        if tip not in names:
            raise ValueError(f"relative_jacobian: unknown tip {tip!r}; the tips are {list(names)}")
        return names.index(tip)
    index = int(tip)
    if not -count <= index < count:
        raise ValueError(f"relative_jacobian: tip index {index} out of range for {count} tips")
    return index % count


def relative_jacobian(robot, posture: jax.Array, base_rotation: jax.Array | None = None, *, tips=(0, 1)):
    """Twist of tip j seen from a frame moving with tip i, per joint rate, inertial axes.

    J_rel = [Jv_j - Jv_i + [p_j - p_i]x Jw_i ; Jw_j - Jw_i] from the two tips' J*: the
    velocity of tip j's origin and the angular velocity of its frame relative to tip i.
    The common bus twist cancels, so it equals the same expression from the fixed-base
    Jacobians (in bus axes, rotated by R): relative tasks do not see the bus inertia.

    Args:
        robot: a robot with several tips (a tree of arms).
        posture: ``(..., n)`` joint positions.
        base_rotation: ``(..., 3, 3)`` bus attitude (default identity).
        tips: ``(i, j)`` tip indices or tip names (one compiled program serves every pair).

    Returns:
        ``(..., 6, n)``.
    """
    family = family_of(robot)
    if family.tip_count(robot) is None:
        raise TypeError(f"relative_jacobian: needs a robot with several tips, got a {type(robot).__name__}")
    i, j = (_tip_index(robot, t) for t in tips)
    return _relative_jacobian(robot, posture, base_rotation, jnp.asarray(i), jnp.asarray(j))


@jax.jit
def _relative_jacobian(robot, posture, base_rotation, i, j):
    family = family_of(robot)
    fast = family.fast_paths.fixed_base_jacobian_and_tips
    if fast is not None:
        # The bus twist drops out: the fixed-base twists and the tips (about the bus frame:
        # only their differences enter) from one pass without momenta, turned by R.
        J, p = fast(robot, posture)
        J, p = _rotate_twist_rows(family, robot, J, base_rotation), _rotate_vector(family, robot, p, base_rotation)
        return _relative_rows(J, p, i, j)
    J = generalized_jacobian(robot, posture, base_rotation)
    p = tip_position(robot, posture, base_rotation)
    return _relative_rows(J, p, i, j)


def _relative_rows(J, p, i, j):
    """J_rel of tip j seen from tip i, from every tip's twists ``(..., k, 6, n)`` and origins ``(..., k, 3)``."""
    take = lambda x, index, axis: jnp.take(x, index, axis=axis)
    J_i, J_j = take(J, i, -3), take(J, j, -3)
    d = take(p, j, -2) - take(p, i, -2)
    w_i = J_i[..., 3:, :]
    lever = jnp.cross(d[..., :, None], w_i, axisa=-2, axisb=-2, axisc=-2)
    top = J_j[..., :3, :] - J_i[..., :3, :] + lever
    return jnp.concatenate([top, J_j[..., 3:, :] - w_i], axis=-2)
