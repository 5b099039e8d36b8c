"""Derivation variants of the free-floating model, for the readings of Table 2's w-bar.

Table 2 of Umetani & Yoshida (1990) prints w-bar = 5.59 ... 8.08 (x1e-2) for b0/B0 =
0 ... 2; the faithful model (eq. 1-12, `spacearm.kinematics`) gives 8.77 ... 10.23,
and no rule of averaging the exact w* changes its growth (x1.17 against the printed
x1.45). The paper prints the tip kinematics (eq. 1, 2; S_M and S_G confirm them) but
not I_S and I_M of eq. 5, so this module asks which *derivation* of the momentum
equation a hand calculation in 1990 could have made instead.

A `Derivation` is one such model: a choice, without a free parameter, of the
reference point of the angular momentum, the terms it keeps, the inertias it uses and
the point the tip is measured from. Every variant is written in the same
virtual-manipulator form as the faithful model,

    L = sum_l h_l(theta) dtheta_l,   h_l = I_l + sum_k W_kl cos(theta_k - theta_l),
    W_kl = sum_i m_i R_ik R_il,       tip = sum_k K_k u(theta_k),

with design-only coefficients (`derivation_coefficients`), then per posture
I_S = H_0, I_M = (H_1..H_n) with H_j = sum_{l>=j} h_l (eq. 5), J* = J_M - J_S I_M / I_S
(eq. 6) and w* = sqrt(det J* J*^T) (eq. 10). `FAITHFUL` reproduces
`spacearm.kinematics` exactly; nothing here changes the package's defaults.

`grid_averages` evaluates w*/L^2 of any batch of (derivation, design) pairs on one
midpoint grid of the elbow-down strip and returns every averaging rule of
`AVERAGES`; `wbar_readings` crosses the departures of `DEPARTURES`
(alone and in pairs) with those rules for the Table 2 report.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import jax
import jax.numpy as jnp
import numpy as np

from .._core.batching import pad_leading
from ..paper import PlanarRobot, umetani1990
from ..paper.planar_parts import (
    DesignCoefficients,
    grid_angle_tables,
    manipulability_from_columns as _manipulability_from_columns,
    momentum_rows as _faithful_momentum_rows,
    momentum_terms as _momentum_terms,
    stack_robots,
    tip_columns as _tip_columns,
)

__all__ = [
    "AVERAGES",
    "DEPARTURES",
    "FAITHFUL",
    "Derivation",
    "chance_level",
    "derivation_coefficients",
    "generalized_jacobian",
    "grid_averages",
    "manipulability",
    "model_variants",
    "momentum_inertias",
    "relative_errors",
    "wbar_readings",
]

B0 = 1.4  # m, Table 1's b0 (Table 2's B0)


@dataclasses.dataclass(frozen=True)
class Derivation:
    """One way of deriving I_S, I_M (eq. 5) and J_S, J_M (eq. 2); no free parameter.

    Attributes:
        momentum_origin: the point the angular momentum is taken about, velocities
            relative to it: "system" (the system centroid: exact with zero linear
            momentum), "base" (the base centroid, as if it did not translate) or
            "joint1" (joint 1, as if the base were pinned there).
        tip_origin: the point the tip is measured from in eq. 1: "system" (eq. 1 as
            printed), "base" (base centroid) or "joint1".
        base_orbital: keep the base's orbital term m_0 r_0 x dr_0 of eq. 4.
        base_inertia: I_0 about "centroid" (Table 1), about "joint1" (I_0 + m_0 b_0^2)
            or "zero" (the base a point mass).
        link_inertia: I_i about "centroid" (Table 1), about "joint" (I_i + m_i a_i^2)
            or "zero" (point-mass links).
        cross_terms: keep the posture-dependent terms W_kl cos(theta_k - theta_l), k != l
            (True), drop them all (False), or "arm": drop only the base-arm ones (k or l
            = 0: D01 cos phi1 and D02 cos(phi1 + phi2) for n = 2) and keep the arm's own
            (D12 cos phi2).
        link_rates: read L = sum h_l dtheta_l (absolute link rates) as if its
            coefficients multiplied the joint rates: I_S = h_0, I_M = (h_1..h_n).
        sign: +1 for J* = J_M - J_S I_M / I_S (eq. 6), -1 for the slipped sign.
    """

    momentum_origin: str = "system"
    tip_origin: str = "system"
    base_orbital: bool = True
    base_inertia: str = "centroid"
    link_inertia: str = "centroid"
    cross_terms: bool = True
    link_rates: bool = False
    sign: int = 1

    def __post_init__(self):
        for field, allowed in (
            ("momentum_origin", ("system", "base", "joint1")),
            ("tip_origin", ("system", "base", "joint1")),
            ("base_inertia", ("centroid", "joint1", "zero")),
            ("link_inertia", ("centroid", "joint", "zero")),
            ("sign", (1, -1)),
            ("cross_terms", (True, False, "arm")),
        ):
            if getattr(self, field) not in allowed:
                raise ValueError(f"{field}: must be one of {allowed}, got {getattr(self, field)!r}")

    def departures(self) -> tuple[str, ...]:
        """The fields that differ from the faithful derivation."""
        return tuple(f.name for f in dataclasses.fields(self) if getattr(self, f.name) != getattr(FAITHFUL, f.name))


FAITHFUL = Derivation()

# Single departures from the faithful derivation: name -> (the change, a one-line reason
# a 1990 derivation could have made it). Each changes one field of Derivation, so two
# departures combine when they change different fields.
DEPARTURES: dict[str, tuple[dict, str]] = {
    "momentum about base centroid": (
        {"momentum_origin": "base"},
        "eq. 4 about the base centroid with velocities relative to it: base translation neglected (m0 = 5 x arm mass)",
    ),
    "momentum about joint 1": (
        {"momentum_origin": "joint1"},
        "eq. 4 about the shoulder with velocities relative to it: the base as if pinned at joint 1",
    ),
    "no base orbital term": (
        {"base_orbital": False},
        "m0 r0 x dr0 dropped from eq. 4: the base centroid taken as (nearly) the system centroid",
    ),
    "I0 about joint 1": (
        {"base_inertia": "joint1"},
        "base inertia taken about the attachment point, I0 + m0 b0^2",
    ),
    "no base inertia": (
        {"base_inertia": "zero"},
        "I0 dtheta0 dropped: the base as a point mass",
    ),
    "I_i about joint i": (
        {"link_inertia": "joint"},
        "link inertias about their joints, I_i + m_i a_i^2 (a rod's m l^2/3)",
    ),
    "point-mass links": (
        {"link_inertia": "zero"},
        "link rotational inertias dropped, I_i = 0",
    ),
    "no cross terms": (
        {"cross_terms": False},
        "the cos(theta_k - theta_l) terms of I_S, I_M dropped: inertias averaged over the posture, constant",
    ),
    "no base-arm cross terms": (
        {"cross_terms": "arm"},
        "D01 cos phi1 and D02 cos(phi1 + phi2) dropped, the arm's own D12 cos phi2 kept: the base's share of "
        "the momentum a constant inertia that grows with b0 ('the moment of inertia of the base increases')",
    ),
    "link-rate slip": (
        {"link_rates": True},
        "L = sum h_l dtheta_l (absolute link rates) read as joint rates: I_S = h0, I_M = (h1, h2)",
    ),
    "sign slip": (
        {"sign": -1},
        "J* = J_M + J_S I_M / I_S: the base reaction added instead of subtracted",
    ),
    "tip from base centroid": (
        {"tip_origin": "base"},
        "p = b0 u0 + l1 u1 + l2 u2 from the base centroid (contradicts eq. 1's K_k)",
    ),
    "tip from joint 1": (
        {"tip_origin": "joint1"},
        "p = l1 u1 + l2 u2 from the shoulder, ground kinematics in inertial axes (contradicts eq. 1)",
    ),
}

# Pairs that are the same model as one of their parts (left out of model_variants).
_DEGENERATE = {
    frozenset({"momentum about base centroid", "no base orbital term"})
}  # base term is 0 about its own centroid

# Averaging rules of w*/L^2 over the elbow-down strip (the grid of grid_averages).
AVERAGES: dict[str, str] = {
    "area": "eq. 12: ds = l1 l2 abs(sin phi2) dphi1 dphi2, the reachable area of the robot frame",
    "joint": "ds read as dphi1 dphi2, uniform over the joint angles",
    "area / joint volume": "int w* ds divided by l1 l2 x 2 pi x pi, the joint-space volume (abs(sin phi2) forgotten below)",
    "square": "average over the square [-L, L]^2 of the contour-map grid, unreachable points as 0",
    "area of w^2": "det(J* J*^T)/L^4 averaged instead of its square root",
    "inertial area": "ds = w* dphi1 dphi2, the area the tip sweeps in the inertial frame",
    "(b0+L)^2": "w* normalized by (b0 + L)^2, L read as the reach from the base centroid",
}


def _array_module(robot: PlanarRobot):
    """NumPy for a concrete design (no XLA program for host-side arithmetic), else jax.numpy."""
    traced = any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(robot))
    return jnp if traced else np


def _spans(robot: PlanarRobot, xp=jnp) -> jax.Array:
    """``(..., n+1)``: b0, l1..ln, the lengths passed along u(theta_k) on the way out."""
    length = xp.asarray(robot.link_a) + xp.asarray(robot.link_b)
    return xp.concatenate([xp.asarray(robot.base_attach)[..., None], length], axis=-1)


def derivation_coefficients(derivation: Derivation, robot: PlanarRobot) -> DesignCoefficients:
    """K (tip), R (centroids about the momentum origin), W and the inertias of a variant.

    Body centroids from the base centroid: body i = sum_{k<i} s_k u_k + a_i u_i with
    s = (b0, l1..ln) (a_0 = 0); the tip = sum_k s_k u_k. The momentum and tip origins
    are subtracted as coefficient rows (the system centroid is the mass-weighted mean).
    Works on batched designs and inside jit (the derivation is static data); a concrete
    design is computed in NumPy on the host, so it compiles nothing.
    """
    xp = _array_module(robot)
    if xp is np:
        robot = jax.tree_util.tree_map(np.asarray, robot)
    spans = _spans(robot, xp)
    n1 = spans.shape[-1]
    k = xp.arange(n1)
    before = (k[None, :] < k[:, None]).astype(spans.dtype)  # [i, k]: k < i
    own = xp.concatenate([xp.zeros_like(spans[..., :1]), xp.asarray(robot.link_a)], axis=-1)
    rows = spans[..., None, :] * before + xp.eye(n1, dtype=spans.dtype) * own[..., None, :]
    masses = xp.concatenate([xp.asarray(robot.base_mass)[..., None], xp.asarray(robot.link_mass)], axis=-1)
    joint1 = spans * (k == 0)

    def origin(which):
        if which == "system":
            return xp.einsum("...i,...ik->...k", masses, rows) / xp.sum(masses, axis=-1)[..., None]
        if which == "base":
            return xp.zeros_like(spans)
        return joint1

    centroids = rows - origin(derivation.momentum_origin)[..., None, :]
    tip = spans - origin(derivation.tip_origin)
    weights = masses if derivation.base_orbital else masses * (k > 0)
    coupling = xp.einsum("...i,...ik,...il->...kl", weights, centroids, centroids)
    if derivation.cross_terms is False:
        coupling = coupling * xp.eye(n1, dtype=spans.dtype)
    elif derivation.cross_terms == "arm":  # zero W_0l and W_k0 off the diagonal: the base-arm terms
        coupling = coupling * (1.0 - ((k[:, None] == 0) != (k[None, :] == 0)).astype(spans.dtype))
    base_inertia = xp.asarray(robot.base_inertia, spans.dtype)
    if derivation.base_inertia == "joint1":
        base_inertia = base_inertia + robot.base_mass * robot.base_attach**2
    elif derivation.base_inertia == "zero":
        base_inertia = xp.zeros_like(base_inertia)
    link_inertia = robot.link_inertia
    if derivation.link_inertia == "joint":
        link_inertia = link_inertia + robot.link_mass * robot.link_a**2
    elif derivation.link_inertia == "zero":
        link_inertia = xp.zeros_like(link_inertia)
    inertia = xp.concatenate([base_inertia[..., None], link_inertia], axis=-1)
    return DesignCoefficients(tip=tip, centroids=centroids, inertia_coupling=coupling, inertia=inertia)


# Per posture: I_S, I_M -> J* -> w* ------------------------------------------------------


def _momentum_rows(coeffs: DesignCoefficients, c, s, link_rates):
    """[I_S, I_M_1..I_M_n] per posture: H_j = sum_{l>=j} h_l, or h_j for the link-rate slip.

    ``link_rates`` is a Python bool or a 0/1 array (blended, for batches mixing both).
    """
    h = _momentum_terms(coeffs, c, s)
    H = _faithful_momentum_rows(coeffs, c, s)
    if link_rates is False:
        return H
    if link_rates is True:
        return h
    return [jnp.where(link_rates, hj, Hj) for hj, Hj in zip(h, H, strict=False)]


def _columns(coeffs, c, s, link_rates, sign):
    xs, ys = _tip_columns(coeffs, c, s)
    H = _momentum_rows(coeffs, c, s, link_rates)
    ratio = [sign * H[j] / H[0] for j in range(1, len(c))]
    return [xs[j] - xs[0] * r for j, r in zip(range(1, len(c)), ratio, strict=False)], [
        ys[j] - ys[0] * r for j, r in zip(range(1, len(c)), ratio, strict=False)
    ]


def _angles(phi):
    theta = jnp.cumsum(jnp.asarray(phi), axis=-1)
    cos, sin = jnp.cos(theta), jnp.sin(theta)
    return [cos[..., k] for k in range(theta.shape[-1])], [sin[..., k] for k in range(theta.shape[-1])]


def momentum_inertias(derivation: Derivation, robot: PlanarRobot, phi: jax.Array) -> tuple[jax.Array, jax.Array]:
    """I_S ``(...)`` and I_M ``(..., n)`` of eq. 5 under ``derivation``, kg m^2.

    Args:
        phi: ``(..., n+1)`` posture [phi0, phi1..phin], rad.
    """
    c, s = _angles(phi)
    H = jnp.broadcast_arrays(*_momentum_rows(derivation_coefficients(derivation, robot), c, s, derivation.link_rates))
    return H[0], jnp.stack(H[1:], axis=-1)


def generalized_jacobian(derivation: Derivation, robot: PlanarRobot, phi: jax.Array) -> jax.Array:
    """J* = J_M - sign J_S I_M / I_S under ``derivation``, ``(..., 2, n)``, inertial frame."""
    c, s = _angles(phi)
    gx, gy = _columns(derivation_coefficients(derivation, robot), c, s, derivation.link_rates, derivation.sign)
    gx, gy = jnp.broadcast_arrays(*gx), jnp.broadcast_arrays(*gy)
    return jnp.stack([jnp.stack(gx, axis=-1), jnp.stack(gy, axis=-1)], axis=-2)


def manipulability(derivation: Derivation, robot: PlanarRobot, phi: jax.Array) -> jax.Array:
    """w* = sqrt(det(J* J*^T)) under ``derivation``, m^2 (``(...)``)."""
    c, s = _angles(phi)
    return _manipulability_from_columns(
        *_columns(derivation_coefficients(derivation, robot), c, s, derivation.link_rates, derivation.sign)
    )


# Averages over the elbow-down strip ------------------------------------------------------

_GRID_PHI1, _GRID_PHI2 = 512, 256  # midpoint grid (second order at the kinks: under 1e-5 relative)
GRID_CHUNK = 64  # (derivation, design) pairs per call of the compiled grid program


@jax.jit
def _grid_statistics(coeffs: DesignCoefficients, link_rates, sign, reach, l1l2, b0, count):
    """Every rule of AVERAGES for a batch of coefficient sets (leading axis), one grid.

    Only the first ``count`` (traced) rows are computed, one by one; the padding rows
    after them come out as zeros, so a chunk that is mostly padding costs no more than
    its real rows."""
    phi1 = -jnp.pi + 2 * jnp.pi * (jnp.arange(_GRID_PHI1) + 0.5) / _GRID_PHI1
    phi2 = jnp.pi * (jnp.arange(_GRID_PHI2) + 0.5) / _GRID_PHI2
    cos_theta, sin_theta = grid_angle_tables([phi1, phi2])
    c, s = [1.0] + cos_theta, [0.0] + sin_theta

    def single(args):
        co, lr, sg, L, ll, b = args
        w = _manipulability_from_columns(*_columns(co, c, s, lr, sg))
        w = jnp.broadcast_to(w, (_GRID_PHI1, _GRID_PHI2)) / L**2
        i_s = _momentum_rows(co, c, s, lr)[0]
        # I_S changing sign on the strip: w* has a pole there and no finite average.
        w = jnp.where(jnp.min(i_s) * jnp.max(i_s) > 0, w, jnp.nan)
        area = jnp.broadcast_to(jnp.sin(phi2), w.shape)  # l1 l2 cancels in the ratios
        mean = jnp.sum(w * area) / jnp.sum(area)
        return {
            "area": mean,
            "joint": jnp.mean(w),
            "area / joint volume": mean * 2.0 / math.pi,  # int_0^pi sin = 2 against pi
            # the annulus pi ((l1 + l2)^2 - (l1 - l2)^2) = 4 pi l1 l2 inside the square (2L)^2
            "square": mean * math.pi * ll / L**2,
            "area of w^2": jnp.sum(w * w * area) / jnp.sum(area),
            # w* = 0 on the whole strip (no base inertia at b0 = 0): the weighted mean is its limit 0
            "inertial area": jnp.sum(w * w) / jnp.where(jnp.sum(w) > 0, jnp.sum(w), 1.0),
            "(b0+L)^2": mean * L**2 / (b + L) ** 2,
        }

    args = (coeffs, link_rates, sign, reach, l1l2, b0)
    first = jax.tree_util.tree_map(lambda x: x[0], args)
    size = jax.tree_util.tree_leaves(args)[0].shape[0]
    out = jax.tree_util.tree_map(lambda v: jnp.zeros((size, *v.shape), v.dtype), jax.eval_shape(single, first))

    def row(i, out):
        values = single(jax.tree_util.tree_map(lambda x: x[i], args))
        return jax.tree_util.tree_map(lambda o, v: o.at[i].set(v), out, values)

    return jax.lax.fori_loop(0, count, row, out)


def grid_averages(derivations: list[Derivation], robots: PlanarRobot) -> dict[str, np.ndarray]:
    """w-bar of every (derivation, design) pair by every rule of `AVERAGES`.

    Args:
        derivations: the variants.
        robots: a batch of n = 2 designs (one leading axis).

    Returns:
        ``{rule: (len(derivations), designs)}``, dimensionless; NaN where I_S vanishes
        somewhere on the strip (w* has a pole, the average diverges). Computed on a 512 x 256
        midpoint grid of the elbow-down strip (under 1e-5 relative to the adaptive rule
        of `spacearm.paper.normalized_wbar` for the faithful model).
    """
    if robots.n_links != 2 or len(robots.batch_shape) != 1:
        raise ValueError("grid_averages takes a one-axis batch of n = 2 designs")
    designs = robots.batch_shape[0]
    # Host-side set-up in NumPy (eager jax.numpy would compile a program per operation and shape).
    robots = jax.tree_util.tree_map(np.asarray, robots)
    parts = [derivation_coefficients(d, robots) for d in derivations]
    coeffs = jax.tree_util.tree_map(lambda *xs: np.concatenate(xs, axis=0), *parts)
    repeat = lambda x: np.tile(np.asarray(x), len(derivations))
    link_rates = np.repeat(np.asarray([d.link_rates for d in derivations]), designs)
    sign = np.repeat(np.asarray([float(d.sign) for d in derivations]), designs)
    lengths = robots.link_a + robots.link_b
    args = (
        coeffs,
        link_rates,
        sign,
        repeat(np.sum(lengths, axis=-1)),
        repeat(lengths[:, 0] * lengths[:, 1]),
        repeat(robots.base_attach),
    )
    # Fixed chunks of GRID_CHUNK pairs, the last padded but its padding not computed (the
    # program runs the pairs one by one anyway): one compiled program for any number of
    # pairs, instead of one per count.
    # Sliced in NumPy, so the chunks compile no slicing programs either.
    count = len(derivations) * designs
    args = pad_leading(jax.tree_util.tree_map(np.asarray, args), -(-count // GRID_CHUNK) * GRID_CHUNK)
    chunks = [
        _grid_statistics(
            *jax.tree_util.tree_map(lambda x, start=start: x[start : start + GRID_CHUNK], args),
            np.int32(min(GRID_CHUNK, count - start)),
        )
        for start in range(0, count, GRID_CHUNK)
    ]
    return {
        k: np.concatenate([np.asarray(chunk[k]) for chunk in chunks])[:count].reshape(len(derivations), designs)
        for k in chunks[0]
    }


# The readings of Table 2 -------------------------------------------------------------------


def _combine(names: tuple[str, ...]) -> Derivation:
    changes: dict = {}
    for name in names:
        changes.update(DEPARTURES[name][0])
    return Derivation(**changes)


def model_variants(max_departures: int = 2) -> list[tuple[tuple[str, ...], Derivation]]:
    """The faithful model, every single departure and (up to ``max_departures``) every
    combination of departures changing different fields, without degenerate pairs."""
    out = [((), FAITHFUL)]
    names = list(DEPARTURES)
    for size in range(1, max_departures + 1):
        for combo in itertools.combinations(names, size):
            fields = [next(iter(DEPARTURES[n][0])) for n in combo]
            if len(set(fields)) < size:
                continue  # two choices of the same field
            if any(pair <= set(combo) for pair in _DEGENERATE):
                continue
            out.append((combo, _combine(combo)))
    return out


def wbar_readings(
    base: PlanarRobot | None = None, ratios=(0.0, 0.5, 1.0, 1.5, 2.0), *, max_departures: int = 2
) -> list[dict]:
    """Every reading: each model variant of `model_variants` by each rule of AVERAGES.

    Returns:
        dicts with ``model`` (tuple of departure names, () = faithful), ``average``
        (a key of AVERAGES), ``derivation`` and ``values`` (w-bar x 1e-2 at ``ratios``).
    """
    base = umetani1990() if base is None else base
    robots = stack_robots([base.replace(base_attach=np.float64(B0 * r)) for r in ratios])
    variants = model_variants(max_departures)
    stats = grid_averages([d for _, d in variants], robots)
    readings = []
    for index, (names, derivation) in enumerate(variants):
        for rule in AVERAGES:
            readings.append(
                {"model": names, "average": rule, "derivation": derivation, "values": 100 * stats[rule][index]}
            )
    return readings


def relative_errors(values, printed) -> tuple[float, float]:
    """(max |ours / printed - 1|, rms of ours / printed - 1) over the rows; NaN if undefined."""
    rel = np.asarray(values, float) / np.asarray(printed, float) - 1.0
    return float(np.max(np.abs(rel))), float(np.sqrt(np.mean(rel**2)))


def shape_error(values, printed) -> float:
    """max over the rows of |(ours_i / ours_0) / (printed_i / printed_0) - 1|.

    The column relative to its first row: blind to any constant factor (a misread
    normalization or measure that scales every row alike), so it tests the derivation.
    NaN when the first value is 0 or undefined.
    """
    values, printed = np.asarray(values, float), np.asarray(printed, float)
    if not np.isfinite(values[0]) or values[0] == 0:
        return float("nan")
    return float(np.max(np.abs((values / values[0]) / (printed / printed[0]) - 1.0)))


def chance_level(
    values: np.ndarray, printed, *, trials: int = 1000, seed: int = 0, statistic: str = "rms"
) -> tuple[float, float]:
    """How well the same set of readings fits columns that are not the paper's.

    Draws ``trials`` random increasing columns with the printed first and last values
    (interior steps uniform on the simplex) and finds each one's best reading.

    Args:
        values: ``(readings, rows)`` the readings' values (rows with NaN or a zero first value are skipped).
        printed: ``(rows,)`` the printed column.
        statistic: "rms" (rms relative error) or "shape" (`shape_error`).

    Returns:
        ``(fraction, median)``: the fraction of random columns fitted at least as well as
        the printed one, and the median of their best scores.
    """
    values = np.asarray(values, float)
    values = values[np.all(np.isfinite(values), axis=1) & (values[:, 0] != 0)]
    printed = np.asarray(printed, float)

    def best(target):
        if statistic == "shape":
            shapes = values / values[:, :1]
            return float(np.min(np.max(np.abs(shapes / (target / target[0]) - 1.0), axis=1)))
        return float(np.min(np.sqrt(np.mean((values / target - 1.0) ** 2, axis=1))))

    rng = np.random.default_rng(seed)
    steps = rng.dirichlet(np.ones(len(printed) - 1), size=trials)
    fractions = np.concatenate([np.zeros((trials, 1)), np.cumsum(steps, axis=1)], axis=1)
    targets = printed[0] + (printed[-1] - printed[0]) * fractions
    scores = np.array([best(t) for t in targets])
    return float(np.mean(scores <= best(printed))), float(np.median(scores))
