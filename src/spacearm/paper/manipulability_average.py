"""The average manipulability w-bar of eq. (12): the planar family's adaptive quadrature (section 5, eq. 11, 12).

Everything here lives in the robot frame Sigma_R (origin at joint 1, axes along the
base): w* does not depend on the base attitude phi0, so phi0 = 0 throughout.

The average w-bar of eq. (12)
-----------------------------
For n = 2 the map (phi1, phi2) -> tip in Sigma_R covers the reachable annulus
l1 - l2 <= |x| <= l1 + l2 once with the elbow-down sheet phi2 in [0, pi] (and once
more with the elbow-up sheet), with area element ds = l1 l2 |sin phi2| dphi1 dphi2.
So

    w-bar = int w*/L^2 l1 l2 |sin phi2| dphi1 dphi2  /  int l1 l2 |sin phi2| dphi1 dphi2,

the denominator being 4 pi l1 l2 = pi ((l1 + l2)^2 - (l1 - l2)^2), the annulus area.
Mirroring the whole robot about the base x axis maps (phi1, phi2) to (-phi1, -phi2)
and keeps w*, so the elbow-down, elbow-up and two-sheet averages are equal.

Quadrature. w* = |det J*| is smooth except where det J* changes sign: the zero set
(dynamic singularities) is two curves phi2 = g(phi1) winding around phi2 = 0 and
phi2 = pi, crossing into the elbow-down strip (Papadopoulos & Dubowsky's dynamic
singularities; the paper's "phi2 = 0" is only the b0 = 0 case). A plain product
rule sees kinks and converges at second order. Here phi2 uses composite
Gauss-Legendre panels, each split at the root of det J* when the panel brackets one
(found by a fixed number of bisection and Newton steps), so each sub-panel integrates
a smooth function; phi1 uses Gauss-Legendre panels split where the zero curves cross
the strip's edges phi2 = 0, pi (there the inner integral has a jump in its third
derivative; a periodic trapezoid in phi1 converges at fourth order for that reason).
The split positions need no derivative: at a phi2 split the integrand vanishes, and
a phi1 split only divides one integral into two (Leibniz boundary terms cancel).
The convergence is spectral: see tests/test_metrics.py and the README.

Cost. The nodes depend on the design, so nothing is shared across a batch of designs
the way the product rule shares its sin/cos tables; the rule avoids transcendental
calls at data-dependent angles instead. At fixed phi1, det J* = N / H with N a
trigonometric polynomial of degree 2 and H > 0 of degree 1 in phi2; rotated to a
panel's center c, N is a quartic in t = tan((phi2 - c) / 2), so the phi2 roots are
polynomial root finding; at the nodes, cos and sin of phi2 - c are Taylor
polynomials. On the strip's edges (sin phi2 = 0) det J* factors into K0 sin phi1
times a bracket linear in cos phi1, so the phi1 splits are in closed form.

For n > 2 the posture -> tip map is many-to-one and an area average needs a choice
of measure on each self-motion manifold, which the paper does not make; the area
reading raises `ConfigError` and ``measure="joint"`` (uniform average over the
joint torus) is offered for any n.
"""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from .._core.schema import integer
from ..models.planar.closed_forms import (
    DesignCoefficients,
    design_coefficients,
)
from ..models.planar.robot import PlanarRobot
from .manipulability_maps import grid_average

__all__ = ["check_average_options", "fixed_base_average_manipulability", "normalized_wbar"]

_MEASURES = ("area", "joint")
_ELBOWS = ("down", "up", "both")
_RULES = ("adaptive", "product")
# Smallest allowed value of each integer option of normalized_wbar.
_INTEGER_OPTIONS = {
    "phi1_panels": 2,
    "phi2_panels": 1,
    "order": 1,
    "newton_steps": 0,
    "designs_per_chunk": 1,
    "n_points_joint": 2,
}


# Areas (Table 2) ---------------------------------------------------------------------


# The average w-bar (eq. 12) ---------------------------------------------------------


def _gauss_legendre(order: int) -> tuple[np.ndarray, np.ndarray]:
    nodes, weights = np.polynomial.legendre.leggauss(order)
    return 0.5 * (nodes + 1.0), 0.5 * weights  # on [0, 1]


def _signed_determinant(coeffs: DesignCoefficients, cos1, sin1, phi2):
    """det J* (n = 2) at phi0 = 0, phi1 given by its cosine and sine, phi2 in rad.

    The 2 x 2 case of eq. (6) written out (tested against the generic kernel): with
    t_j the tip columns of eq. (2) and H_j the momentum rows of eq. (5),
    det J* = det(t1, t2) + (H2 det(t0, t1) - H1 det(t0, t2)) / H0, where
    det(t1, t2) = K1 K2 sin phi2, det(t0, t1) = K0 (K1 sin phi1 + K2 sin phi12) and
    det(t0, t2) = K2 (K0 sin phi12 + K1 sin phi2). Few operations keep compilation short.
    """
    K, W, inertia = coeffs.tip, coeffs.inertia_coupling, coeffs.inertia
    cos2, sin2 = jnp.cos(phi2), jnp.sin(phi2)
    cos12, sin12 = cos1 * cos2 - sin1 * sin2, sin1 * cos2 + cos1 * sin2
    h0 = inertia[0] + W[0, 0] + W[0, 1] * cos1 + W[0, 2] * cos12
    h1 = inertia[1] + W[1, 1] + W[0, 1] * cos1 + W[1, 2] * cos2
    h2 = inertia[2] + W[2, 2] + W[0, 2] * cos12 + W[1, 2] * cos2
    coupled = h2 * K[0] * (K[1] * sin1 + K[2] * sin12) - (h1 + h2) * K[2] * (K[0] * sin12 + K[1] * sin2)
    return K[1] * K[2] * sin2 + coupled / (h0 + h1 + h2)


def _fourier_forms(coeffs: DesignCoefficients, cos1, sin1):
    """det J* at fixed phi1 as trigonometric polynomials in phi2: N / H.

    Every factor of `_signed_determinant` is linear in (1, cos phi2, sin phi2), so
    with H = h0 + h1 + h2 > 0 the numerator N = det J* H is a trigonometric polynomial
    of degree 2.

    Args:
        coeffs: one design's coefficients.
        cos1, sin1: cosine and sine of phi1, any (common) shape S.

    Returns:
        ``(N, H)``: ``(S..., 5)`` coefficients of (1, cos, sin, cos 2phi2, sin 2phi2) and
        ``(S..., 3)`` of (1, cos phi2, sin phi2).
    """
    K, W, inertia = coeffs.tip, coeffs.inertia_coupling, coeffs.inertia

    def product(a, b):  # (a0 + a1 cos + a2 sin)(b0 + b1 cos + b2 sin)
        return (
            a[0] * b[0] + 0.5 * (a[1] * b[1] + a[2] * b[2]),
            a[0] * b[1] + a[1] * b[0],
            a[0] * b[2] + a[2] * b[0],
            0.5 * (a[1] * b[1] - a[2] * b[2]),
            0.5 * (a[1] * b[2] + a[2] * b[1]),
        )

    # h_j and the two sums of eq. (6) as in _signed_determinant, with
    # cos phi12 = cos1 cos2 - sin1 sin2 and sin phi12 = sin1 cos2 + cos1 sin2.
    h0 = (inertia[0] + W[0, 0] + W[0, 1] * cos1, W[0, 2] * cos1, -W[0, 2] * sin1)
    h1 = (inertia[1] + W[1, 1] + W[0, 1] * cos1, W[1, 2], 0.0)
    h2 = (inertia[2] + W[2, 2], W[0, 2] * cos1 + W[1, 2], -W[0, 2] * sin1)
    tip1 = (K[1] * sin1, K[2] * sin1, K[2] * cos1)  # K1 sin1 + K2 sin12
    tip2 = (0.0, K[0] * sin1, K[0] * cos1 + K[1])  # K0 sin12 + K1 sin2
    total = tuple(a + b + c for a, b, c in zip(h0, h1, h2, strict=False))
    h12 = tuple(a + b for a, b in zip(h1, h2, strict=False))
    free = product(total, (0.0, 0.0, 1.0))  # sin2 (h0 + h1 + h2)
    first, second = product(h2, tip1), product(h12, tip2)
    numerator = [K[1] * K[2] * f + K[0] * a - K[2] * b for f, a, b in zip(free, first, second, strict=False)]
    shape = jnp.shape(cos1)
    return (
        jnp.stack([jnp.broadcast_to(c, shape) for c in numerator], axis=-1),
        jnp.stack([jnp.broadcast_to(c, shape) for c in total], axis=-1),
    )


# (1 + t^2)^2 (1, cos, sin, cos 2d, sin 2d) as quartics in t = tan(d / 2), rows ascending:
# cos d = (1 - t^2) / (1 + t^2), sin d = 2t / (1 + t^2). Small integers: well conditioned.
_TO_QUARTIC = np.array([[1, 0, 2, 0, 1], [1, 0, 0, 0, -1], [0, 2, 0, 2, 0], [1, 0, -6, 0, 1], [0, 4, 0, -4, 0]], float)


def _panel_rotations(centers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Constant maps of `_fourier_forms`'s coefficients in phi2 to coefficients in
    d = phi2 - c for each panel center c (orthogonal: rotations by c and 2c).

    Returns:
        ``(5, panels * 5)`` and ``(3, panels * 3)``, right-multiplying N's and H's coefficients.
    """
    numerator, denominator = [], []
    for c in centers:
        cos, sin, cos2, sin2 = math.cos(c), math.sin(c), math.cos(2 * c), math.sin(2 * c)
        # Rows: coefficients in phi2; columns: in d (cos phi2 = cos c cos d - sin c sin d, ...).
        rotate = np.array(
            [[1, 0, 0, 0, 0], [0, cos, -sin, 0, 0], [0, sin, cos, 0, 0], [0, 0, 0, cos2, -sin2], [0, 0, 0, sin2, cos2]]
        )
        numerator.append(rotate)
        denominator.append(rotate[:3, :3])
    return np.concatenate(numerator, axis=1), np.concatenate(denominator, axis=1)


def _cos_sin(theta, bound: float):
    """cos and sin of |theta| <= bound by their Taylor polynomials (Horner in theta^2).

    The degree is fixed by ``bound`` so the truncation error is below 1e-18 max(1, bound)
    on the whole range: no transcendental call at data-dependent angles, and no range
    reduction (degree 14 for the default panels, |theta| <= pi/8).
    """
    degree = 2
    while bound ** (degree + 1) / math.factorial(degree + 1) > 1e-18 * max(1.0, bound):
        degree += 2
    square = theta * theta
    cos = jnp.full_like(theta, (-1) ** (degree // 2) / math.factorial(degree))
    sin = jnp.full_like(theta, (-1) ** (degree // 2) / math.factorial(degree + 1))
    for k in range(degree - 2, -1, -2):
        cos = cos * square + (-1) ** (k // 2) / math.factorial(k)
        sin = sin * square + (-1) ** (k // 2) / math.factorial(k + 1)
    return cos, sin * theta


def _polynomial(coefficients, t, slope: bool = False):
    """Horner: p(t) (and p'(t)) for ``(..., k)`` ascending coefficients broadcast against t."""
    value = coefficients[..., -1]
    derivative = jnp.zeros_like(value)
    for k in range(coefficients.shape[-1] - 2, -1, -1):
        if slope:
            derivative = derivative * t + value
        value = value * t + coefficients[..., k]
    return (value, derivative) if slope else value


def _polynomial_roots(coefficients, left, right, newton_steps: int, bisection_steps: int = 6):
    """Where the polynomial changes sign inside [left, right] (else the midpoint); no gradient.

    ``coefficients``: ``(..., k)`` ascending, broadcast against the brackets. A few
    bisection steps shrink the bracket (only its lower end is carried: the width halves
    each step), then Newton steps from the regula falsi point, clipped to the bracket.
    The loops are unrolled: a quartic is a few operations, and one fused kernel beats a
    ``while`` loop that writes its state to memory every step.
    """
    coefficients = jax.lax.stop_gradient(coefficients)
    left, right = jax.lax.stop_gradient(left), jax.lax.stop_gradient(right)

    def value(x):
        return _polynomial(coefficients, x)

    d_left, d_right = value(left), value(right)
    brackets = d_left * d_right < 0
    width = right - left
    lo = left
    for k in range(1, bisection_steps + 1):  # the root stays in [lo, lo + width / 2^k]
        mid = lo + width * 0.5**k
        lo = jnp.where(value(mid) * d_left > 0, mid, lo)
    hi = lo + width * 0.5**bisection_steps
    d_lo, d_hi = value(lo), value(hi)
    denom = jnp.where(brackets, d_lo - d_hi, 1.0)
    x = jnp.clip(lo + (hi - lo) * d_lo / denom, lo, hi)
    for _ in range(newton_steps):
        d, slope = _polynomial(coefficients, x, slope=True)
        step = jnp.where(slope != 0, d / jnp.where(slope != 0, slope, 1.0), 0.0)
        x = jnp.clip(x - step, lo, hi)
    return jax.lax.stop_gradient(jnp.where(brackets, x, 0.5 * (left + right)))


def _edge_crossings(coeffs: DesignCoefficients):
    """cos phi1 where det J* = 0 on the strip edges phi2 = 0 and phi2 = +-pi, besides sin phi1 = 0.

    There sin phi2 = 0, and det J* (numerator of _signed_determinant) reduces to
    K0 sin(phi1) (K1 h2 - K2 h1) at phi2 = 0 and K0 sin(phi1) (K1 h2 + K2 h1) at
    phi2 = pi, with h1, h2 linear in cos phi1: each bracket vanishes at one cos phi1.

    Returns:
        ``(cosines, valid)``: ``(2,)`` each; valid where a crossing exists (|cos| < 1,
        K0 != 0: with K0 = 0 det J* vanishes on the whole edge and nothing is split).
    """
    K, W, inertia = coeffs.tip, coeffs.inertia_coupling, coeffs.inertia
    a1, a2 = inertia[1] + W[1, 1], inertia[2] + W[2, 2]
    # phi2 = 0: h1 = a1 + W12 + W01 c1, h2 = a2 + W12 + W02 c1.
    # phi2 = pi: h1 = a1 - W12 + W01 c1, h2 = a2 - W12 - W02 c1.
    constant = jnp.stack([K[1] * (a2 + W[1, 2]) - K[2] * (a1 + W[1, 2]), K[1] * (a2 - W[1, 2]) + K[2] * (a1 - W[1, 2])])
    slope = jnp.stack([K[1] * W[0, 2] - K[2] * W[0, 1], K[2] * W[0, 1] - K[1] * W[0, 2]])
    constant, slope = jax.lax.stop_gradient(constant), jax.lax.stop_gradient(slope)
    cosines = -constant / jnp.where(slope != 0, slope, 1.0)
    valid = (slope != 0) & (jnp.abs(cosines) < 1.0) & (jax.lax.stop_gradient(K[0]) != 0)
    return jnp.where(valid, cosines, 0.0), valid


def _wbar_two_link(
    robot: PlanarRobot,
    measure: str,
    elbow: str,
    phi1_panels: int,
    phi2_panels: int,
    order: int,
    newton_steps: int,
    rule: str,
):
    """w-bar of one n = 2 design (see the module docstring for the rule)."""
    coeffs = design_coefficients(robot)
    lengths = robot.link_length
    l1, l2 = lengths[0], lengths[1]
    dtype = coeffs.tip.dtype
    nodes, weights = _gauss_legendre(order)
    nodes, weights = jnp.asarray(nodes, dtype), jnp.asarray(weights, dtype)
    lo, hi = {"down": (0.0, math.pi), "up": (-math.pi, 0.0), "both": (-math.pi, math.pi)}[elbow]
    if rule == "adaptive":
        # Gauss-Legendre panels in phi1, halved, and split where the zero set of det J*
        # meets the strip's edges phi2 = 0, +-pi (phi1 = 0, +-pi, which are panel edges, and
        # +-arccos of _edge_crossings, elsewhere only for long b0): across those phi1 the
        # inner integral has a jump in its third derivative. An absent crossing gives a
        # zero-width sub-panel (static shapes).
        halves = jnp.linspace(-jnp.pi, jnp.pi, 2 * phi1_panels + 1, dtype=dtype)
        cosines, valid = _edge_crossings(coeffs)
        angles = jnp.arccos(cosines)
        crossings = jnp.where(jnp.concatenate([valid, valid]), jnp.concatenate([angles, -angles]), -jnp.pi)
        breaks = jax.lax.stop_gradient(jnp.sort(jnp.concatenate([halves, crossings])))
        starts, widths = breaks[:-1], breaks[1:] - breaks[:-1]  # (2 phi1_panels + 4,)
        phi1 = (starts[:, None] + widths[:, None] * nodes).reshape(-1)
        phi1_weights = (widths[:, None] * weights).reshape(-1)
    else:
        count = phi1_panels * order
        phi1 = -jnp.pi + 2.0 * jnp.pi * jnp.arange(count, dtype=dtype) / count
        phi1_weights = jnp.full((count,), 2.0 * jnp.pi / count, dtype)
    cos1, sin1 = jnp.cos(phi1), jnp.sin(phi1)

    if rule == "adaptive":
        # phi2 panels of width pi / phi2_panels (as the product rule's), each split where
        # det J* changes sign (when it brackets a root), so each sub-panel integrates a
        # smooth function. No sin or cos at data-dependent angles: det J* = N / H is a
        # trigonometric polynomial (_fourier_forms) rotated to each panel's center c; the
        # root is that of a quartic in t = tan((phi2 - c) / 2) (_TO_QUARTIC); at the
        # Gauss-Legendre nodes cos and sin of phi2 - c come from
        # Taylor polynomials (|phi2 - c| <= half the panel width).
        half = (hi - lo) / (2 * phi2_panels)
        centers = lo + half * (2 * np.arange(phi2_panels) + 1)
        rotate_numerator, rotate_denominator = (jnp.asarray(m, dtype) for m in _panel_rotations(centers))
        fourier_numerator, fourier_denominator = _fourier_forms(coeffs, cos1, sin1)  # (n1, 5), (n1, 3)
        numerator = (fourier_numerator @ rotate_numerator).reshape(-1, phi2_panels, 5)
        denominator = (fourier_denominator @ rotate_denominator).reshape(-1, phi2_panels, 3)
        tau = math.tan(half / 2)
        bracket = jnp.full(numerator.shape[:2], tau, dtype)
        root = _polynomial_roots(numerator @ jnp.asarray(_TO_QUARTIC, dtype), -bracket, bracket, newton_steps)
        middle = 2.0 * jnp.arctan(root)  # (n1, panels), offset from the center; 0 without a root
        starts = jnp.stack([jnp.full_like(middle, -half), middle], axis=-1)[..., None]  # (n1, panels, 2, 1)
        widths = jnp.stack([middle + half, half - middle], axis=-1)[..., None]
        offset = starts + widths * nodes  # (n1, panels, 2, order): phi2 - c
        cos, sin = _cos_sin(offset, half)
        basis = (cos, sin, cos * cos - sin * sin, 2.0 * sin * cos)
        coefficient = [numerator[:, :, None, None, k] for k in range(5)]
        values = coefficient[0] + sum(c * b for c, b in zip(coefficient[1:], basis, strict=False))
        coefficient = [denominator[:, :, None, None, k] for k in range(3)]
        values = jnp.abs(values) / (coefficient[0] + coefficient[1] * cos + coefficient[2] * sin)
        if measure == "area":
            sin_c, cos_c = (jnp.asarray(f(centers), dtype)[:, None, None] for f in (np.sin, np.cos))
            values = values * (l1 * l2) * jnp.abs(sin_c * cos + cos_c * sin)  # |sin phi2|
        # The node sum as a product with the weights: a reduction fused with the integrand
        # runs several times slower on CPU than this elementwise pass and a matrix-vector product.
        inner = jnp.sum((values @ weights) * widths[..., 0], axis=(-2, -1))
    else:

        def integrand(phi2):
            w = jnp.abs(_signed_determinant(coeffs, cos1[:, None], sin1[:, None], phi2))
            if measure == "area":
                w = w * (l1 * l2) * jnp.abs(jnp.sin(phi2))
            return w

        count = phi2_panels * order
        step = (hi - lo) / count
        phi2 = lo + step * (jnp.arange(count, dtype=dtype) + 0.5)
        inner = jnp.sum(integrand(jnp.broadcast_to(phi2, (phi1.shape[0], count))), axis=-1) * step
    total = jnp.sum(inner * phi1_weights)
    span = hi - lo
    # Area: int l1 l2 |sin phi2| over the strip, 2 pi l1 l2 * (2 per sheet of width pi).
    denominator = 2.0 * jnp.pi * l1 * l2 * 2.0 * (span / math.pi) if measure == "area" else 2.0 * jnp.pi * span
    return total / denominator / robot.reach**2


def check_average_options(*, where: str = "", **options) -> None:
    """Raise `ConfigError` naming the first bad option of `normalized_wbar`.

    Shared with the sweep files' ``wbar`` metric, so ``spacearm validate`` catches what a
    run would reject. ``where`` prefixes the field names (``"metrics[0]."``).
    """
    measure, elbow, rule = options.get("measure", "area"), options.get("elbow", "down"), options.get("rule", "adaptive")
    if measure not in _MEASURES:
        raise ConfigError(f"{where}measure: must be one of {', '.join(_MEASURES)}, got {measure!r}")
    if elbow not in _ELBOWS:
        raise ConfigError(f"{where}elbow: must be one of {', '.join(_ELBOWS)}, got {elbow!r}")
    if rule not in _RULES:
        raise ConfigError(f"{where}rule: must be one of {', '.join(_RULES)}, got {rule!r}")
    for name, least in _INTEGER_OPTIONS.items():
        integer(f"{where}{name}", options.get(name, least), least=least)  # bounded by SIZE_LIMITS too
    if options.get("phi1_panels", 2) % 2:
        raise ConfigError(
            f"{where}phi1_panels: must be even so that phi1 = 0 is a panel edge, got {options['phi1_panels']}"
        )


def normalized_wbar(
    robot: PlanarRobot,
    *,
    measure: str = "area",
    elbow: str = "down",
    phi1_panels: int = 8,
    phi2_panels: int = 4,
    order: int = 8,
    newton_steps: int = 4,
    rule: str = "adaptive",
    designs_per_chunk: int = 16,
    n_points_joint: int = 48,
) -> jax.Array:
    """Normalized average manipulability w-bar (Umetani & Yoshida 1990, eq. 12).

    The faithful reading (the default): w*/L^2 (eq. 11) averaged over the elbow-down
    reachable area of the robot frame, ds = l1 l2 |sin phi2| dphi1 dphi2 for n = 2.
    Joint limits are ignored (the paper's assumption 3). Differentiable with respect
    to every design leaf; batched designs are processed ``designs_per_chunk`` at a
    time under ``jax.lax.map``. Compiled once per option set and shape (the options
    are static); works inside ``jit``, ``vmap`` and ``grad``.

    The default rule reaches about 1e-13 relative error on the Table 2 designs
    (see tests/test_metrics.py for the convergence study).

    Args:
        robot: a design or a batch of designs (leading axes on every leaf).
        measure: "area" (eq. 12, n = 2 only) or "joint" (uniform dphi measure over
            the joint angles; any n: for n = 2 over the chosen elbow strip by the
            same quadrature, for n > 2 over the whole joint torus by a periodic
            grid of ``n_points_joint`` points per joint).
        elbow: "down" (phi2 in [0, pi], the paper's choice), "up" or "both". The three
            give the same value up to rounding (mirror symmetry); kept as a check.
        phi1_panels: panels over phi1 in [-pi, pi) (even, so 0 is an edge).
        phi2_panels: panels over the phi2 strip of width pi (twice as many for "both").
        order: Gauss-Legendre points per sub-panel ("adaptive": each phi1 panel is
            halved and split at the crossings, each phi2 panel split at its root).
        newton_steps: Newton steps (after 6 bisections) locating det J* = 0 in a phi2
            panel (on a quartic polynomial, see the module docstring).
        rule: "adaptive" (Gauss-Legendre, split at the sign changes of det J*) or
            "product" (periodic trapezoid x midpoint on phi1_panels*order by
            phi2_panels*order points; second order at the kinks), for comparison.
        designs_per_chunk: designs evaluated together in a batch.
        n_points_joint: grid points per joint for measure="joint" with n > 2.

    Returns:
        ``(...)`` w-bar, dimensionless (Table 2 prints it x 1e-2).

    Raises:
        ConfigError: for an unknown option, or measure="area" with n != 2.
    """
    check_average_options(
        measure=measure,
        elbow=elbow,
        phi1_panels=phi1_panels,
        phi2_panels=phi2_panels,
        order=order,
        newton_steps=newton_steps,
        rule=rule,
        designs_per_chunk=designs_per_chunk,
        n_points_joint=n_points_joint,
    )
    n = robot.n_links
    if n != 2 and measure == "area":
        raise ConfigError(
            f"links: the area average of eq. 12 is defined here for n = 2 (got n = {n}); for n > 2 the "
            "posture -> tip map is many-to-one and the paper gives no measure on the self-motions; "
            "use measure='joint' (uniform over the joint torus)"
        )
    return _average_jit(
        robot,
        measure=measure,
        elbow=elbow,
        phi1_panels=phi1_panels,
        phi2_panels=phi2_panels * (2 if elbow == "both" else 1),
        order=order,
        newton_steps=newton_steps,
        rule=rule,
        designs_per_chunk=designs_per_chunk,
        n_points_joint=n_points_joint,
    )


@functools.partial(
    jax.jit,
    static_argnames=(
        "measure",
        "elbow",
        "phi1_panels",
        "phi2_panels",
        "order",
        "newton_steps",
        "rule",
        "designs_per_chunk",
        "n_points_joint",
    ),
)
def _average_jit(
    robot, *, measure, elbow, phi1_panels, phi2_panels, order, newton_steps, rule, designs_per_chunk, n_points_joint
):
    n = robot.n_links

    def single(design: PlanarRobot):
        if n == 2:
            return _wbar_two_link(design, measure, elbow, phi1_panels, phi2_panels, order, newton_steps, rule)
        return grid_average(design, n_points_joint)

    batch = robot.batch_shape
    if not batch:
        return single(robot)
    flat = jax.tree_util.tree_map(lambda x: jnp.reshape(jnp.asarray(x), (-1, *jnp.shape(x)[len(batch) :])), robot)
    size = int(np.prod(batch))
    values = jax.lax.map(single, flat, batch_size=min(designs_per_chunk, size))
    return jnp.reshape(values, batch)


def fixed_base_average_manipulability(robot: PlanarRobot, *, measure: str = "area") -> jax.Array:
    """The ground robot's w-bar in closed form (n = 2), for comparison with Table 2.

    With w = l1 l2 |sin phi2|: the area average is (l1 l2 / L^2) (pi / 4) and the
    joint-space average (l1 l2 / L^2) (2 / pi).

    Returns:
        ``(...)`` dimensionless.
    """
    if robot.n_links != 2:
        raise ConfigError(f"links: the closed form is for n = 2, got n = {robot.n_links}")
    if measure not in _MEASURES:
        raise ConfigError(f"measure: must be one of {', '.join(_MEASURES)}, got {measure!r}")
    l1, l2 = robot.link_length[..., 0], robot.link_length[..., 1]
    factor = {"area": math.pi / 4.0, "joint": 2.0 / math.pi}[measure]
    return l1 * l2 / robot.reach**2 * factor
