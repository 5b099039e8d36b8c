"""Closed forms of the planar family: eq. (1), (2), (5), (6), (10) of Umetani & Yoshida 1990.

The virtual-manipulator split. Every body centroid and the tip is a fixed linear
combination of the unit vectors u(theta_k) = (cos theta_k, sin theta_k), with
coefficients that depend on the design alone (for the tip these are eq. 1's K_k).
The angular momentum about the system centroid is then

    L = sum_l h_l(theta) dtheta_l,   h_l = I_l + sum_k W_kl cos(theta_k - theta_l),

with the design-only matrix W_kl = sum_i m_i R_ik R_il. `design_coefficients`
computes K, W and the inertias once per design; the per-posture work is n sines and
cosines, a few products and the reverse sums that turn absolute rates into joint
rates. Public kernels are jitted at the entry point (nested calls inline), so a
plain call from Python costs one dispatch, not one per operation. Kernels are written for any leading batch shape of the posture (and of the
design, where it broadcasts), unrolled over the small static link count.

Postures are ``phi = [phi0, phi1, ..., phin]`` (base attitude, joint angles), rad.
The inertial frame has its origin at the system centroid.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import jax
import jax.numpy as jnp

from ..family import require_family
from .robot import PlanarRobot

__all__ = [
    "DesignCoefficients",
    "angular_momentum",
    "arm_jacobian",
    "base_jacobian",
    "base_rate",
    "centroid_coefficients",
    "centroid_positions",
    "design_coefficients",
    "fixed_base_jacobian",
    "fixed_base_manipulability",
    "fixed_base_tip_position",
    "generalized_jacobian",
    "grid_angle_tables",
    "manipulability",
    "manipulability_ellipse",
    "manipulability_from_angles",
    "manipulability_on_grid",
    "momentum_inertias",
    "robot_frame_tip_position",
    "tip_coefficients",
    "tip_position",
]


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class DesignCoefficients:
    """Design-only arrays of the virtual-manipulator view (computed once per design).

    Attributes:
        tip: ``(..., n+1)`` K_k, tip = sum_k K_k u(theta_k) (eq. 1), m.
        centroids: ``(..., n+1, n+1)`` R_ik, centroid of body i = sum_k R_ik u(theta_k), m.
        inertia_coupling: ``(..., n+1, n+1)`` W_kl = sum_i m_i R_ik R_il, kg m^2.
        inertia: ``(..., n+1)`` I_0..I_n about the body centroids, kg m^2.
    """

    tip: jax.Array
    centroids: jax.Array
    inertia_coupling: jax.Array
    inertia: jax.Array


def _chain_offsets(robot: PlanarRobot) -> tuple[jax.Array, jax.Array]:
    """Offsets from the base centroid as coefficients of u(theta_k), before the shift to
    the system centroid: centroid rows ``(..., n+1, n+1)`` and the tip row ``(..., n+1)``."""
    n = robot.n_links
    b0 = jnp.asarray(robot.base_attach)
    lengths = robot.link_length
    # spans[k] is the length along u(theta_k) passed on the way to anything beyond body k.
    spans = jnp.concatenate([b0[..., None], lengths], axis=-1)  # (..., n+1)
    k = jnp.arange(n + 1)
    before = (k[None, :] < k[:, None]).astype(spans.dtype)  # [i, k]: k < i
    own = jnp.concatenate([jnp.zeros_like(b0)[..., None], robot.link_a], axis=-1)
    rows = spans[..., None, :] * before + jnp.eye(n + 1, dtype=spans.dtype) * own[..., None, :]
    return rows, spans


@jax.jit
def design_coefficients(robot: PlanarRobot) -> DesignCoefficients:
    """K, R, W and the inertias of a design (or a batch of designs).

    Planar arms only (a `PlanarRobot`; another family raises TypeError).

    Shifting the origin to the system centroid subtracts the mass-weighted mean of
    the body offsets (eq. 3 integrated, zero initial linear momentum).
    """
    require_family(robot, "planar", "design_coefficients")
    rows, tip_row = _chain_offsets(robot)
    masses = jnp.concatenate([jnp.asarray(robot.base_mass)[..., None], robot.link_mass], axis=-1)
    mean = jnp.einsum("...i,...ik->...k", masses, rows) / jnp.sum(masses, axis=-1)[..., None]
    centroids = rows - mean[..., None, :]
    tip = tip_row - mean
    coupling = jnp.einsum("...i,...ik,...il->...kl", masses, centroids, centroids)
    inertia = jnp.concatenate([jnp.asarray(robot.base_inertia)[..., None], robot.link_inertia], axis=-1)
    return DesignCoefficients(tip=tip, centroids=centroids, inertia_coupling=coupling, inertia=inertia)


@jax.jit
def tip_coefficients(robot: PlanarRobot) -> jax.Array:
    """``(..., n+1)`` K_0..K_n of eq. (1), m; for n = 2 these are the paper's K0, K1, K2.

    Planar arms only (a `PlanarRobot`; another family raises TypeError).
    """
    require_family(robot, "planar", "tip_coefficients")
    return design_coefficients(robot).tip


@jax.jit
def reachable_radii(robot: PlanarRobot) -> tuple[jax.Array, jax.Array]:
    """``(outer (...), inner (...))`` Area 3 about the system centroid, m (sec. 3.1 (3-a)):
    K0 + K1 + .. + Kn, and the hole max(0, 2 max_k K_k - (K0+..+Kn)) (non-zero when K0 > K1+..+Kn)."""
    K = tip_coefficients(robot)
    outer = jnp.sum(K, axis=-1)
    return outer, jnp.maximum(0.0, 2.0 * jnp.max(K, axis=-1) - outer)


def centroid_coefficients(robot: PlanarRobot) -> jax.Array:
    """``(..., n+1, n+1)`` R_ik: centroid of body i = sum_k R_ik u(theta_k), m.

    Planar arms only (a `PlanarRobot`; another family raises TypeError).
    """
    require_family(robot, "planar", "centroid_coefficients")
    return design_coefficients(robot).centroids


# Unit vectors ------------------------------------------------------------------------


def _unit_vectors(phi: jax.Array, with_base: bool = True):
    """cos and sin of the absolute angles theta_k = phi0 + ... + phik as lists of arrays.

    With ``with_base=False`` the base attitude is taken as zero (the robot frame):
    the base entries are the Python constants 1 and 0, which cost nothing.
    """
    phi = jnp.asarray(phi)
    theta = jnp.cumsum(phi, axis=-1) if with_base else jnp.cumsum(phi[..., 1:], axis=-1)
    cos, sin = jnp.cos(theta), jnp.sin(theta)
    count = theta.shape[-1]
    c = [cos[..., k] for k in range(count)]
    s = [sin[..., k] for k in range(count)]
    if not with_base:
        c, s = [1.0] + c, [0.0] + s
    return c, s


def _tip_from(coeffs: DesignCoefficients, c, s):
    K = coeffs.tip
    x = sum(K[..., k] * c[k] for k in range(len(c)))
    y = sum(K[..., k] * s[k] for k in range(len(c)))
    return jnp.stack(jnp.broadcast_arrays(x, y), axis=-1)


def _tip_columns(coeffs: DesignCoefficients, c, s):
    """d tip / d phi_j as lists (x_j, y_j), j = 0..n: reverse sums of K_k u_perp(theta_k)."""
    K = coeffs.tip
    count = len(c)
    xs, ys = [None] * count, [None] * count
    acc_x = acc_y = 0.0
    for k in reversed(range(count)):
        acc_x = acc_x - K[..., k] * s[k]
        acc_y = acc_y + K[..., k] * c[k]
        xs[k], ys[k] = acc_x, acc_y
    return xs, ys


def _momentum_terms(coeffs: DesignCoefficients, c, s):
    """h_l = I_l + sum_k W_kl cos(theta_k - theta_l): the angular momentum per absolute link rate."""
    W, inertia = coeffs.inertia_coupling, coeffs.inertia
    count = len(c)
    h = []
    for l in range(count):
        total = inertia[..., l] + W[..., l, l]
        for k in range(count):
            if k != l:
                # cos(theta_k - theta_l); W is symmetric, so each pair is used twice.
                total = total + W[..., k, l] * (c[k] * c[l] + s[k] * s[l])
        h.append(total)
    return h


def _momentum_rows(coeffs: DesignCoefficients, c, s):
    """Reverse sums H_j = sum_{l>=j} h_l: H_0 = I_S and H_1..H_n = I_M (eq. 5)."""
    h = _momentum_terms(coeffs, c, s)
    count = len(c)
    rows, acc = [None] * count, 0.0
    for j in reversed(range(count)):
        acc = acc + h[j]
        rows[j] = acc
    return rows


def _generalized_columns_and_momentum(coeffs: DesignCoefficients, c, s):
    """Columns of J* = J_M - J_S I_M / I_S (eq. 6) as lists (x_j, y_j), j = 1..n, and the
    momentum rows H_0 = I_S, H_1..H_n = I_M they were built from (eq. 5)."""
    xs, ys = _tip_columns(coeffs, c, s)
    H = _momentum_rows(coeffs, c, s)
    inv_is = 1.0 / H[0]
    gx = [xs[j] - xs[0] * (H[j] * inv_is) for j in range(1, len(c))]
    gy = [ys[j] - ys[0] * (H[j] * inv_is) for j in range(1, len(c))]
    return gx, gy, H


def _generalized_columns(coeffs: DesignCoefficients, c, s):
    """Columns of J* = J_M - J_S I_M / I_S (eq. 6) as lists (x_j, y_j), j = 1..n."""
    gx, gy, _ = _generalized_columns_and_momentum(coeffs, c, s)
    return gx, gy


def _manipulability_from_columns(gx, gy):
    """sqrt(det(J J^T)) of a 2 x n matrix by Cauchy-Binet: the norm of its 2 x 2 minors.

    Summing squares of minors avoids the cancellation of det(J J^T) near singular
    postures; the guarded square root keeps the gradient finite where w* = 0.
    """
    n = len(gx)
    minors = [gx[i] * gy[j] - gx[j] * gy[i] for i in range(n) for j in range(i + 1, n)]
    if len(minors) == 1:
        return jnp.abs(minors[0])
    squares = sum(m * m for m in minors)
    positive = squares > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, squares, 1.0)), 0.0)


# Public kernels -----------------------------------------------------------------------


@jax.jit
def tip_position(robot: PlanarRobot, phi: jax.Array) -> jax.Array:
    """Tip position in the inertial frame, origin at the system centroid (eq. 1).

    Args:
        robot: the design.
        phi: ``(..., n+1)`` posture [phi0, phi1..phin], rad.

    Returns:
        ``(..., 2)`` tip position, m.
    """
    c, s = _unit_vectors(phi)
    return _tip_from(design_coefficients(robot), c, s)


@jax.jit
def robot_frame_tip_position(robot: PlanarRobot, phi_arm: jax.Array) -> jax.Array:
    """Tip in the robot frame Sigma_R (origin at joint 1, axes along the base), m.

    Planar arms only (a `PlanarRobot`; another family raises TypeError).

    Args:
        phi_arm: ``(..., n)`` joint angles, rad.

    Returns:
        ``(..., 2)``; this is also the fixed-base (ground robot) tip.
    """
    require_family(robot, "planar", "robot_frame_tip_position")
    theta = jnp.cumsum(jnp.asarray(phi_arm), axis=-1)
    lengths = robot.link_length
    return jnp.stack([jnp.sum(lengths * jnp.cos(theta), -1), jnp.sum(lengths * jnp.sin(theta), -1)], axis=-1)


fixed_base_tip_position = robot_frame_tip_position


@jax.jit
def centroid_positions(robot: PlanarRobot, phi: jax.Array) -> jax.Array:
    """``(..., n+1, 2)`` centroids r_0..r_n in the inertial frame (origin at the system centroid), m.

    Planar arms only (a `PlanarRobot`; another family raises TypeError).
    """
    require_family(robot, "planar", "centroid_positions")
    theta = jnp.cumsum(jnp.asarray(phi), axis=-1)
    u = jnp.stack([jnp.cos(theta), jnp.sin(theta)], axis=-1)  # (..., n+1, 2)
    return jnp.einsum("...ik,...kd->...id", design_coefficients(robot).centroids, u)


@jax.jit
def base_jacobian(robot: PlanarRobot, phi: jax.Array) -> jax.Array:
    """J_S of eq. (2): ``(..., 2)`` tip velocity per unit base rate, m/rad.

    Planar arms only (a `PlanarRobot`; another family raises TypeError).
    """
    require_family(robot, "planar", "base_jacobian")
    c, s = _unit_vectors(phi)
    xs, ys = _tip_columns(design_coefficients(robot), c, s)
    return jnp.stack(jnp.broadcast_arrays(xs[0], ys[0]), axis=-1)


@jax.jit
def arm_jacobian(robot: PlanarRobot, phi: jax.Array) -> jax.Array:
    """J_M of eq. (2): ``(..., 2, n)`` tip velocity per unit joint rate (base held), m/rad.

    Planar arms only (a `PlanarRobot`; another family raises TypeError).
    """
    require_family(robot, "planar", "arm_jacobian")
    c, s = _unit_vectors(phi)
    xs, ys = _tip_columns(design_coefficients(robot), c, s)
    return _stack_matrix(xs[1:], ys[1:])


@jax.jit
def momentum_inertias(robot: PlanarRobot, phi: jax.Array) -> tuple[jax.Array, jax.Array]:
    """I_S ``(...)`` and I_M ``(..., n)`` of eq. (5), kg m^2.

    Planar arms only (a `PlanarRobot`; another family raises TypeError).

    Angular momentum about the system centroid is I_S dphi0 + I_M . dphi_M when the
    linear momentum is zero. Depends on the joint angles only, not on phi0.
    """
    require_family(robot, "planar", "momentum_inertias")
    c, s = _unit_vectors(phi, with_base=False)
    H = _momentum_rows(design_coefficients(robot), c, s)
    H = jnp.broadcast_arrays(*H)
    return H[0], jnp.stack(H[1:], axis=-1)


@jax.jit
def base_rate(robot: PlanarRobot, phi: jax.Array, joint_rates: jax.Array) -> jax.Array:
    """dphi0 = -(I_M . dphi_M) / I_S (eq. 5, zero angular momentum), rad per unit time.

    Args:
        phi: ``(..., n+1)`` posture, rad.
        joint_rates: ``(..., n)`` joint rates dphi_M.
    """
    i_s, i_m = momentum_inertias(robot, phi)
    return -jnp.sum(i_m * joint_rates, axis=-1) / i_s


@jax.jit
def angular_momentum(robot: PlanarRobot, phi: jax.Array, phi_rates: jax.Array) -> jax.Array:
    """``(...)`` angular momentum about the system centroid, I_S dphi0 + I_M . dphi_M (eq. 4, 5).

    Planar arms only (a `PlanarRobot`; another family raises TypeError).
    """
    require_family(robot, "planar", "angular_momentum")
    i_s, i_m = momentum_inertias(robot, phi)
    return i_s * phi_rates[..., 0] + jnp.sum(i_m * phi_rates[..., 1:], axis=-1)


def _stack_matrix(xs, ys):
    xs, ys = jnp.broadcast_arrays(*xs), jnp.broadcast_arrays(*ys)
    return jnp.stack([jnp.stack(xs, axis=-1), jnp.stack(ys, axis=-1)], axis=-2)


@jax.jit
def generalized_jacobian(robot: PlanarRobot, phi: jax.Array) -> jax.Array:
    """The Generalized Jacobian J* = J_M - J_S I_M / I_S (eq. 6), inertial frame.

    Args:
        robot: the design.
        phi: ``(..., n+1)`` posture, rad.

    Returns:
        ``(..., 2, n)``: tip velocity (m/s) per joint rate (rad/s) under zero momentum.
    """
    c, s = _unit_vectors(phi)
    return _stack_matrix(*_generalized_columns(design_coefficients(robot), c, s))


@jax.jit
def manipulability(robot: PlanarRobot, phi: jax.Array) -> jax.Array:
    """w* = sqrt(det(J* J*^T)) (eq. 10), m^2 (not normalized; divide by L^2 for eq. 11).

    Independent of phi0 (a rotation of the whole system), so it is evaluated in the
    robot frame. Exactly 0 at singular postures, with finite gradients there.

    Args:
        phi: ``(..., n+1)`` posture, rad (phi0 is accepted and ignored).
    """
    c, s = _unit_vectors(phi, with_base=False)
    return _manipulability_from_columns(*_generalized_columns(design_coefficients(robot), c, s))


def manipulability_from_angles(coeffs: DesignCoefficients, cos_theta, sin_theta) -> jax.Array:
    """w* from precomputed coefficients and absolute link angles (robot frame).

    Args:
        coeffs: from `design_coefficients` of one design.
        cos_theta, sin_theta: sequences of n arrays (links 1..n), broadcastable.

    The entry point for structured grids, where the unit vectors come from 1-D
    tables by angle addition rather than from a transcendental per posture.
    """
    c, s = [1.0] + list(cos_theta), [0.0] + list(sin_theta)
    return _manipulability_from_columns(*_generalized_columns(coeffs, c, s))


def grid_angle_tables(joint_axes: Sequence[jax.Array]) -> tuple[list, list]:
    """cos and sin of the absolute link angles on the outer-product grid of joint axes.

    Args:
        joint_axes: n 1-D arrays of joint angles phi_1..phi_n, rad.

    Returns:
        Two lists of n arrays, broadcastable to ``(A_1, ..., A_n)``: cos theta_k and
        sin theta_k with theta_k = phi_1 + ... + phi_k, built from the 1-D tables by
        angle addition, so no grid point needs its own transcendental.
    """
    n = len(joint_axes)
    cos_theta, sin_theta = [], []
    c_prev = s_prev = None
    for k, axis in enumerate(joint_axes):
        shape = [1] * n
        shape[k] = -1
        axis = jnp.reshape(jnp.asarray(axis), shape)
        ca, sa = jnp.cos(axis), jnp.sin(axis)
        if c_prev is None:
            c_k, s_k = ca, sa
        else:
            c_k, s_k = c_prev * ca - s_prev * sa, s_prev * ca + c_prev * sa
        cos_theta.append(c_k)
        sin_theta.append(s_k)
        c_prev, s_prev = c_k, s_k
    return cos_theta, sin_theta


@jax.jit
def manipulability_on_grid(robot: PlanarRobot, joint_axes: Sequence[jax.Array]) -> jax.Array:
    """w* on the outer-product grid of 1-D joint-angle axes, robot frame.

    Planar arms only (a `PlanarRobot`; another family raises TypeError).

    Args:
        joint_axes: n arrays of joint angles phi_1..phi_n, rad, of sizes (A_1, ..., A_n).

    Returns:
        ``(A_1, ..., A_n)`` w*, m^2. The absolute link angles come from the 1-D sine
        and cosine tables by angle addition: cos(a+b) = cos a cos b - sin a sin b.
    """
    require_family(robot, "planar", "manipulability_on_grid")
    w = manipulability_from_angles(design_coefficients(robot), *grid_angle_tables(joint_axes))
    return jnp.broadcast_to(w, tuple(jnp.shape(a)[0] for a in joint_axes))


@jax.jit
def manipulability_ellipse(robot: PlanarRobot, phi: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Principal axes of the manipulability ellipse {J* q : |q| <= 1} (section 4.1).

    Planar arms only (a `PlanarRobot`; another family raises TypeError).

    Args:
        phi: ``(..., n+1)`` posture, rad.

    Returns:
        ``(major, minor, angle)``: the singular values of J* (m/rad, major >= minor)
        and the inertial angle of the major axis, rad. major * minor = w*.
    """
    require_family(robot, "planar", "manipulability_ellipse")
    J = generalized_jacobian(robot, phi)
    a = jnp.sum(J[..., 0, :] ** 2, axis=-1)
    b = jnp.sum(J[..., 0, :] * J[..., 1, :], axis=-1)
    d = jnp.sum(J[..., 1, :] ** 2, axis=-1)
    mean, half = 0.5 * (a + d), jnp.sqrt(0.25 * (a - d) ** 2 + b * b)
    major = jnp.sqrt(mean + half)
    w = manipulability(robot, phi)
    # minor = w / major avoids the cancellation of sqrt(mean - half) near singularity.
    safe_major = jnp.where(major > 0, major, 1.0)
    minor = jnp.where(major > 0, w / safe_major, 0.0)
    angle = 0.5 * jnp.arctan2(2.0 * b, a - d)
    return major, minor, angle


@jax.jit
def fixed_base_jacobian(robot: PlanarRobot, phi_arm: jax.Array) -> jax.Array:
    """Jacobian of the same arm on a fixed (ground) base, robot frame (Fig. 7b).

    Args:
        phi_arm: ``(..., n)`` joint angles, rad.

    Returns:
        ``(..., 2, n)``, m/rad.
    """
    theta = jnp.cumsum(jnp.asarray(phi_arm), axis=-1)
    lengths = robot.link_length
    n = theta.shape[-1]
    xs, ys = [None] * n, [None] * n
    acc_x = acc_y = 0.0
    for k in reversed(range(n)):
        acc_x = acc_x - lengths[..., k] * jnp.sin(theta[..., k])
        acc_y = acc_y + lengths[..., k] * jnp.cos(theta[..., k])
        xs[k], ys[k] = acc_x, acc_y
    return _stack_matrix(xs, ys)


@jax.jit
def fixed_base_manipulability(robot: PlanarRobot, phi_arm: jax.Array) -> jax.Array:
    """Yoshikawa's w = sqrt(det(J J^T)) of the ground robot, m^2 (for n = 2, l1 l2 |sin phi2|).

    Args:
        phi_arm: ``(..., n)`` joint angles, rad.
    """
    J = fixed_base_jacobian(robot, phi_arm)
    n = J.shape[-1]
    return _manipulability_from_columns([J[..., 0, j] for j in range(n)], [J[..., 1, j] for j in range(n)])


def straight_path_field(robot: PlanarRobot, direction: jax.Array, sign0):
    """Closed form of the regularized straight-path field (one path), y = [phi0, phi_1..phi_n, s].

    The same field as the generic one in `spacearm.motion.straight_paths` (joint
    rates from `spacearm.kinematics.straight_path_rates`, base rate from eq. 5),
    written over the scalar columns of J* so that J* and the momentum rows share their
    sines, cosines and reverse sums: about twice as fast as the generic field, and equal
    to it to rounding (tests/test_seam.py).
    """
    coeffs = design_coefficients(robot)
    n = robot.n_links
    dx, dy = direction[0], direction[1]

    def field(y):
        c, s = _unit_vectors(y[: n + 1])
        gx, gy, H = _generalized_columns_and_momentum(coeffs, c, s)
        if n == 2:
            det = gx[0] * gy[1] - gx[1] * gy[0]
            v = [sign0 * (gy[1] * dx - gx[1] * dy), sign0 * (-gy[0] * dx + gx[0] * dy)]
            rate = sign0 * det
        else:
            a = sum(g * g for g in gx)
            b = sum(p * q for p, q in zip(gx, gy, strict=False))
            d = sum(g * g for g in gy)
            # det(J* J*^T) by Cauchy-Binet: no cancellation near singular postures.
            rate = sum((gx[i] * gy[j] - gx[j] * gy[i]) ** 2 for i in range(n) for j in range(i + 1, n))
            ax, ay = d * dx - b * dy, -b * dx + a * dy  # adj(J* J*^T) d
            v = [gx[j] * ax + gy[j] * ay for j in range(n)]
        norm_sq = sum(vj * vj for vj in v)
        positive = norm_sq > 0
        inv_norm = jnp.where(positive, 1.0 / jnp.sqrt(jnp.where(positive, norm_sq, 1.0)), 0.0)
        dq = [vj * inv_norm for vj in v]
        dphi0 = -sum(H[j + 1] * dq[j] for j in range(n)) / H[0]  # eq. (5)
        return jnp.stack([dphi0] + dq + [rate * inv_norm])

    return field
