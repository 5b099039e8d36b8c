"""Averages of posture metrics over the joint box, with error estimates.

Each average is the mean of a per-posture metric under the uniform measure on the joint
box (`joint_box`: limits where given, one turn for a continuous joint):

- `average_manipulability`: translational w* = sqrt det(J*_v J*_v^T), m^2 planar,
  m^3 spatial (eq. 10; the paper's normalized eq. 12 is `spacearm.paper.normalized_wbar`);
- `global_conditioning_index`: 1 / kappa(J*_v) = sigma_min / sigma_max, in [0, 1]
  (Gosselin & Angeles 1991, over the joint box instead of the workspace);
- `average_base_disturbance`: ||C_w||_F, the Frobenius norm of the angular rows of
  C = -I_S^-1 I_M, rad per rad (Dubowsky & Torres 1991's disturbance, as a scalar);
- `average_dynamic_manipulability`: w_d = sqrt det(J*_v (H*^T H*)^-1 J*_v^T),
  (m / (kg m^2))^3 for revolute joints: tip acceleration per joint torque (Yoshikawa
  1985 applied to J*, with H* the arm inertia at zero momentum; spatial robots only);
- the impact metrics of `spacearm.analysis.impacts` (every family, given an `ImpactSetup`):
  the virtual mass of the tip along a direction, the bus angular-rate jump per unit tip
  impulse, and the bus rate after capturing a reference target.

Why Frobenius for the disturbance: ||C_w||_F^2 = sum of the squared singular values =
n times the mean of ||C_w u||^2 over unit joint-rate directions u, so it is the RMS
bus angular rate per unit joint rate (times sqrt n); it is smooth everywhere (the
spectral norm has kinks where singular values cross), which gradient search needs.

Why the translational rows for w_d: the spatial J* is 6 x n; for n < 6 the full Gram
determinant vanishes identically, so w_d uses J*_v, as w* does (and as
the spatial family's ``dynamic_manipulability``).

Estimator. Randomized quasi-Monte Carlo: R independent digital shifts of one Sobol
sequence (`joint_box`); points come in blocks of B per shift, and after 2^j
blocks (a power of two: the points form a net) the estimate is the mean of the R
shift means and the error estimate their standard error s_R / sqrt(R). Blocks are
added until error <= rtol |mean| (checked at powers of two) or ``max_samples`` is reached.
The loop is a ``lax.while_loop``, so it runs under ``jit`` and ``vmap`` (over designs:
each design stops at its own sample count). The mean is differentiable in the design
(a ``custom_vjp``: the backward pass sums the per-block gradients over exactly the
blocks the forward pass used, so the gradient is that of the returned estimate); the
error estimate and the sample count carry no gradient. The tolerance and the sample
budget are traced: a new value does not compile a new program.

Several metrics at once (`joint_averages`): one chain pass per posture gives J*, C
and H* (`posture_quantities`), and one estimator runs over the vector of metrics. On a
robot with several tips (a tree) w*, 1/kappa and w_d are per tip, ``manipulability[1]``
(`tip_metric`); ||C_w||_F is of the whole system and takes no tip.

Accuracy: tests/test_averages.py checks the estimate and its error estimate against
converged references (Table 1, the 3-DOF arm, the UR5). The integrands have kinks
where J*_v loses rank, so the error falls between N^-1/2 and N^-1, not at QMC's
N^-1 log^d N for smooth integrands; the error estimate follows the actual error within
a factor of about 1.5.
"""

from __future__ import annotations

import dataclasses
import functools
import re
from collections.abc import Sequence
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from .._core.linalg import gram_root_determinant, symmetric_eigenvalues
from .._core.schema import did_you_mean
from ..kinematics import base_rate_matrix, generalized_jacobian, manipulability
from ..models.family import family_of
from .impacts import IMPACT_METRICS, ImpactSetup, impact_metric
from .joint_box import box_postures, check_joint_box, digital_shifts, sobol_direction_numbers, sobol_points

__all__ = [
    "METRICS",
    "PER_TIP_METRICS",
    "JointAverage",
    "average_base_disturbance",
    "average_dynamic_manipulability",
    "average_manipulability",
    "global_conditioning_index",
    "joint_average",
    "joint_average_manipulability",
    "joint_averages",
    "posture_metrics",
    "posture_quantities",
    "split_metric",
    "tip_count",
    "tip_metric",
]


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class JointAverage:
    """An average over the joint box with its error estimate.

    Attributes:
        value: ``(...)`` the estimate (mean over the R randomizations), the metric's unit.
        error: ``(...)`` its standard error, s_R / sqrt(R) (one sigma; same unit).
        samples: ``(...)`` postures used in all (R x points per randomization), int.
    """

    value: jax.Array
    error: jax.Array
    samples: jax.Array

    @property
    def relative_error(self) -> jax.Array:
        return self.error / jnp.abs(self.value)


# Per-posture metrics: (robot, postures (..., p)) -> (...). ---------------------------

# The per-posture matrices each metric reads; `posture_quantities` computes every
# requested one from one pass over the chain (spatial: one forward and one backward scan).
_NEEDS = {
    "manipulability": ("jacobian",),
    "conditioning": ("jacobian",),
    "base_disturbance": ("base_rate",),
    "dynamic_manipulability": ("jacobian", "arm_inertia"),
}


def posture_quantities(robot, posture: jax.Array, needs: tuple[str, ...]) -> dict[str, jax.Array]:
    """J* (``"jacobian"``), C = -I_S^-1 I_M (``"base_rate"``) and H* (``"arm_inertia"``) at postures.

    A family's ``posture_quantities`` fast path computes them together (the spatial one
    in one chain pass per posture); otherwise each comes from its own kernel (the
    planar closed forms). Spatial results are in bus axes.

    Args:
        robot: one design.
        posture: ``(..., p)`` postures of the family.
        needs: the names wanted (static).
    """
    family = family_of(robot)
    fast = family.fast_paths.posture_quantities
    if fast is not None:
        return fast(robot, posture, tuple(needs))
    out = {}
    if "arm_inertia" in needs:
        out["arm_inertia"] = family.arm_inertia(robot, posture)  # batched over postures; ConfigError where none
    if "jacobian" in needs:
        out["jacobian"] = generalized_jacobian(robot, posture)
    if "base_rate" in needs:
        out["base_rate"] = base_rate_matrix(robot, posture)
    return out


def _manipulability_of(family, quantities):
    return gram_root_determinant(quantities["jacobian"][..., : family.translational_rows, :])


def _conditioning_of(family, quantities):
    J = quantities["jacobian"][..., : family.translational_rows, :]
    gram = J @ jnp.swapaxes(J, -1, -2)
    eigenvalues = symmetric_eigenvalues(gram)  # ascending, closed form (no LAPACK per posture)
    ratio = eigenvalues[..., 0] / eigenvalues[..., -1]
    positive = ratio > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, ratio, 1.0)), 0.0)


def _disturbance_of(family, quantities):
    C = quantities["base_rate"]
    # Spatial base coordinates are [v of the bus centroid; w] (3 angular rows); the
    # planar base coordinate is the attitude phi0 alone.
    angular = C[..., -3:, :] if family.rotates_with_base else C
    return jnp.sqrt(jnp.sum(angular * angular, axis=(-2, -1)))


def _dynamic_of(family, quantities):
    J = quantities["jacobian"][..., :3, :]
    H = quantities["arm_inertia"]
    # J (H^T H)^-1 J^T = (J H^-1)(J H^-1)^T, with H symmetric positive definite.
    K = jnp.swapaxes(jnp.linalg.solve(H, jnp.swapaxes(J, -1, -2)), -1, -2)
    return gram_root_determinant(K)


_FROM_QUANTITIES = {
    "manipulability": _manipulability_of,
    "conditioning": _conditioning_of,
    "base_disturbance": _disturbance_of,
    "dynamic_manipulability": _dynamic_of,
}


# Metrics of one tip: on a robot with several tips (J* of shape (..., k, 6, n)) they are
# named with the tip's index, ``manipulability[1]``, and read that tip's rows of J*.
PER_TIP_METRICS = ("manipulability", "conditioning", "dynamic_manipulability", *IMPACT_METRICS)
_TIP_METRIC = re.compile(r"^(\w+)\[(\d+)\]$")


def split_metric(metric: str) -> tuple[str, int | None]:
    """``("manipulability", 1)`` for ``"manipulability[1]"``; ``(metric, None)`` without a tip."""
    match = _TIP_METRIC.match(metric)
    return (match.group(1), int(match.group(2))) if match else (metric, None)


def tip_count(robot) -> int | None:
    """The number of tips k of a robot whose per-tip quantities carry a tip axis, else None
    (the family's `RobotFamily.tip_count`)."""
    return family_of(robot).tip_count(robot)


def tip_metric(where: str, robot, metric: str, tip: str | int | None = None, label: str | None = None) -> str:
    """The metric name `joint_averages` takes for ``metric`` at tip ``tip`` of ``robot``.

    Args:
        where: names the file and field in messages.
        robot: the design (a robot with several tips names them in ``labels.tip_names``).
        metric: a name from `METRICS`.
        tip: a tip's name or index (robots with several tips); None for a one-tip robot
            or a whole-system metric.
        label: the metric's name in messages (a sweep's or problem's name for it; default ``metric``).

    Raises:
        ConfigError: a per-tip metric without a tip on a robot with several, an unknown tip
            (with a did-you-mean), or a tip on a whole-system metric or a one-arm robot.
    """
    count = tip_count(robot)
    label = label or metric
    if tip is None:
        if count is None or metric not in PER_TIP_METRICS:
            return metric
        if count == 1:
            return f"{metric}[0]"
        names = ", ".join(robot.labels.tip_names) or ", ".join(map(str, range(count)))
        raise ConfigError(f"{where}: {label} is per tip and the robot has {count} ({names}); name one with tip:")
    if metric not in PER_TIP_METRICS:
        raise ConfigError(f"{where}.tip: {label} is a quantity of the whole system (every joint); it takes no tip")
    if count is None:
        raise ConfigError(f"{where}.tip: the robot has one tip (a single arm); leave tip out")
    names = tuple(robot.labels.tip_names)
    if isinstance(tip, int) and not isinstance(tip, bool):
        if not 0 <= tip < count:
            raise ConfigError(f"{where}.tip: index {tip} out of range; the robot has {count} tips (0..{count - 1})")
        return f"{metric}[{tip}]"
    if isinstance(tip, str) and tip in names:
        return f"{metric}[{names.index(tip)}]"
    raise ConfigError(
        f"{where}.tip: unknown tip {tip!r}{did_you_mean(str(tip), names)}; the tips: {', '.join(names)} "
        f"(or an index 0..{count - 1})"
    )


def _tip_rows(quantities: dict, tip: int | None) -> dict:
    """The quantities as one tip sees them: its rows of J* (the whole-system C and H* as they are)."""
    if tip is None or "jacobian" not in quantities:
        return quantities
    return {**quantities, "jacobian": quantities["jacobian"][..., tip, :, :]}


def posture_metrics(
    robot, posture: jax.Array, metrics: tuple[str, ...], impact: ImpactSetup | None = None
) -> jax.Array:
    """``(..., k)`` the metrics named in ``metrics`` (of `METRICS` or `IMPACT_METRICS`, per-tip
    ones with their tip, ``manipulability[1]``) at postures ``(..., p)``.

    Every kinematic metric is read off one `posture_quantities` call: J*, C and H* are
    computed once per posture however many metrics (and tips) use them. The impact metrics
    read ``impact`` (`ImpactSetup`).
    """
    family = family_of(robot)
    parsed = [split_metric(name) for name in metrics]
    needs = tuple(dict.fromkeys(need for name, _ in parsed if name in _NEEDS for need in _NEEDS[name]))
    quantities = posture_quantities(robot, posture, needs) if needs else {}
    values = [
        impact_metric(name, robot, posture, impact, tip)
        if name in IMPACT_METRICS
        else _FROM_QUANTITIES[name](family, _tip_rows(quantities, tip))
        for name, tip in parsed
    ]
    return jnp.stack(values, axis=-1)


def manipulability_metric(robot, posture):
    """Translational w* (m^2 planar, m^3 spatial)."""
    return manipulability(robot, posture)


def inverse_condition_metric(robot, posture):
    """1 / kappa(J*_v) = sigma_min / sigma_max, in [0, 1]; 0 at singular postures."""
    return posture_metrics(robot, posture, ("conditioning",))[..., 0]


def base_disturbance_metric(robot, posture):
    """||C_w||_F: bus angular rate per joint rate (Frobenius), rad/rad (m/rad rows excluded)."""
    return posture_metrics(robot, posture, ("base_disturbance",))[..., 0]


def dynamic_manipulability_metric(robot, posture):
    """w_d = sqrt det(J*_v (H*^T H*)^-1 J*_v^T) (families that give the arm inertia H*)."""
    return posture_metrics(robot, posture, ("dynamic_manipulability",))[..., 0]


METRICS = {
    "manipulability": manipulability_metric,
    "conditioning": inverse_condition_metric,
    "base_disturbance": base_disturbance_metric,
    "dynamic_manipulability": dynamic_manipulability_metric,
}
_KNOWN = (*METRICS, *IMPACT_METRICS)  # every name `joint_averages` takes


# The estimator ------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class _Plan:
    """What fixes the shapes of one estimator program (a static argument): the metrics,
    R, the block size B, and for a fixed rule its points per randomization (None: adaptive)."""

    metrics: tuple[str, ...]
    randomizations: int
    block: int
    points: int | None = None


class _Budget(NamedTuple):
    """Traced options of the adaptive estimator: a new tolerance or sample budget does not recompile."""

    rtol: jax.Array  # (k,) relative standard error per metric
    min_blocks: jax.Array  # int32
    max_blocks: jax.Array  # int32, a power of two


def _block_sums(plan: _Plan, robot, shifts, block_index, impact):
    """``(R, k)`` sums of the metrics over block ``block_index`` of each randomization."""
    n = family_of(robot).joint_count(robot)
    directions = jnp.asarray(sobol_direction_numbers(n))
    unit = sobol_points(directions, block_index * plan.block, plan.block, shifts)  # (R, B, n)
    values = posture_metrics(robot, box_postures(robot, unit), plan.metrics, impact)  # (R, B, k)
    return jnp.sum(values, axis=-2)


def _summary(plan: _Plan, sums, blocks):
    means = sums / (blocks * plan.block).astype(sums.dtype)  # (R, k)
    value = jnp.mean(means, axis=0)
    error = jnp.std(means, axis=0, ddof=1) / jnp.sqrt(plan.randomizations)
    return value, error


def _is_power_of_two(k):
    return (k & (k - 1)) == 0


def _forward(plan: _Plan, robot, shifts, budget: _Budget, impact):
    dtype = jnp.result_type(float)

    def cond(state):
        _blocks, _, done = state
        return ~done

    def body(state):
        blocks, sums, _ = state
        sums = sums + _block_sums(plan, robot, shifts, blocks, impact)
        blocks = blocks + 1
        value, error = _summary(plan, sums, blocks)
        checkpoint = _is_power_of_two(blocks) & (blocks >= budget.min_blocks)
        met = jnp.all(error <= budget.rtol * jnp.abs(value))  # every metric meets its tolerance
        done = (checkpoint & met) | (blocks >= budget.max_blocks)
        return blocks, sums, done

    state = (jnp.asarray(0, jnp.int32), jnp.zeros((plan.randomizations, len(plan.metrics)), dtype), jnp.asarray(False))
    blocks, sums, _ = jax.lax.while_loop(cond, body, state)
    value, error = _summary(plan, sums, blocks)
    return value, error, blocks


@functools.partial(jax.custom_vjp, nondiff_argnums=(0,))
def _estimate(plan: _Plan, robot, shifts, budget: _Budget, impact):
    return _forward(plan, robot, shifts, budget, impact)


def _estimate_fwd(plan: _Plan, robot, shifts, budget: _Budget, impact):
    value, error, blocks = _forward(plan, robot, shifts, budget, impact)
    return (value, error, blocks), (robot, shifts, blocks, impact)


def _estimate_bwd(plan: _Plan, residuals, cotangents):
    robot, shifts, blocks, impact = residuals
    g = cotangents[0]  # (k,); the error estimates and the block count carry no gradient
    scale = g / (plan.randomizations * blocks * plan.block).astype(g.dtype)

    def body(state):
        k, accumulated = state
        _, pullback = jax.vjp(lambda r: jnp.sum(_block_sums(plan, r, shifts, k, impact) * scale), robot)
        (grad,) = pullback(jnp.ones((), scale.dtype))
        return k + 1, jax.tree_util.tree_map(jnp.add, accumulated, grad)

    zeros = jax.tree_util.tree_map(jnp.zeros_like, robot)
    _, gradient = jax.lax.while_loop(lambda s: s[0] < blocks, body, (jnp.asarray(0, jnp.int32), zeros))
    # The shifts are integers; the budget and the impact settings carry no gradient.
    return gradient, None, None, jax.tree_util.tree_map(jnp.zeros_like, impact)


_estimate.defvjp(_estimate_fwd, _estimate_bwd)


def _fixed_rule(plan: _Plan, robot, shifts, impact):
    """A fixed QMC rule: one pass over all R x points postures and plain means (ordinary AD)."""
    n = family_of(robot).joint_count(robot)
    unit = sobol_points(jnp.asarray(sobol_direction_numbers(n)), 0, plan.points, shifts)  # (R, P, n)
    values = posture_metrics(robot, box_postures(robot, unit), plan.metrics, impact)  # (R, P, k)
    means = jnp.mean(values, axis=-2)
    value = jnp.mean(means, axis=0)
    error = jnp.std(means, axis=0, ddof=1) / jnp.sqrt(plan.randomizations)
    return value, error, jnp.asarray(plan.points // plan.block, jnp.int32)


def _estimate_one(plan: _Plan, robot, shifts, budget: _Budget, impact):
    if plan.points is not None:
        value, error, blocks = _fixed_rule(plan, robot, shifts, impact)
    else:
        value, error, blocks = _estimate(plan, robot, shifts, budget, impact)
    samples = jnp.broadcast_to(blocks * plan.block * plan.randomizations, value.shape)
    return JointAverage(value, error, samples)


@functools.partial(jax.jit, static_argnames=("plan", "designs_per_chunk"))
def _estimate_batched(robot, shifts, budget: _Budget, impact, plan: _Plan, designs_per_chunk: int):
    """One `JointAverage` per metric of ``plan`` (split inside the program: no eager slicing)."""
    batch = robot.batch_shape
    if not batch:
        out = _estimate_one(plan, robot, shifts, budget, impact)
    else:
        size = 1
        for s in batch:
            size *= s
        flat = jax.tree_util.tree_map(lambda x: jnp.reshape(jnp.asarray(x), (size, *jnp.shape(x)[len(batch) :])), robot)
        out = jax.lax.map(
            lambda design: _estimate_one(plan, design, shifts, budget, impact),
            flat,
            batch_size=min(designs_per_chunk, size),
        )
        out = jax.tree_util.tree_map(lambda y: jnp.reshape(y, batch + y.shape[1:]), out)
    return tuple(
        JointAverage(out.value[..., i], out.error[..., i], out.samples[..., i]) for i in range(len(plan.metrics))
    )


def joint_averages(
    robot,
    metrics: Sequence[str],
    *,
    rtol: float | Sequence[float] = 1e-4,
    randomizations: int = 8,
    block: int = 1024,
    min_samples: int = 2**14,
    max_samples: int = 2**24,
    seed: int = 0,
    designs_per_chunk: int = 8,
    impact: ImpactSetup | None = None,
) -> dict[str, JointAverage]:
    """Means of several posture metrics over the joint box from ONE set of postures.

    One chain pass per posture feeds every metric (`posture_metrics`); one randomized
    QMC estimator runs over the vector of metrics and stops when every metric meets
    its tolerance (so each is at least as accurate as alone, on the same points).

    A fixed rule (``min_samples`` and ``max_samples`` round to the same block count,
    as design problems use) is one pass over all its points and plain means: no loop,
    no custom VJP, ordinary AD. Otherwise the adaptive loop of `joint_average` runs
    with ``rtol`` and the sample budget as traced values (new values do not recompile).

    Args:
        robot: a design of either family, or a batch of designs.
        metrics: names from `METRICS`, each at most once.
        rtol: target relative standard error, one for all or one per metric.
        randomizations, block, min_samples, max_samples, seed, designs_per_chunk: as
            in `joint_average`.
        impact: the settings of the impact metrics (`ImpactSetup`: direction, joints,
            target); required when one is listed (traced: a new target does not recompile).

    Returns:
        ``{metric: JointAverage}`` with ``(...)`` fields (the batch shape).
    """
    metrics = tuple(metrics)
    if not metrics or len(set(metrics)) != len(metrics):
        raise ConfigError(f"metrics: a non-empty list of distinct names from {', '.join(_KNOWN)} is required")
    count = tip_count(robot)
    for metric in metrics:
        name, tip = split_metric(metric)
        if name not in _KNOWN:
            raise ConfigError(f"metric: must be one of {', '.join(_KNOWN)}, got {metric!r}")
        if name in IMPACT_METRICS and impact is None:
            raise ConfigError(f"metric: {name} needs its impact settings: pass impact=ImpactSetup(...)")
        if (tip is None) != (count is None or name not in PER_TIP_METRICS) or (tip is not None and tip >= count):
            tips = f"one of {name}[0] .. {name}[{count - 1}]" if count else name
            raise ConfigError(f"metric: {metric!r} for a robot with {count or 1} tip(s): use {tips}")
    if "dynamic_manipulability" in {split_metric(m)[0] for m in metrics} and not family_of(robot).rotates_with_base:
        raise ConfigError("metric: dynamic_manipulability needs the arm inertia H*, which only spatial robots provide")
    if randomizations < 2:
        raise ConfigError(f"randomizations: must be at least 2 for an error estimate, got {randomizations}")
    if block < 1 or block & (block - 1):
        raise ConfigError(f"block: must be a power of two, got {block}")
    tolerances = np.broadcast_to(np.asarray(rtol, dtype=np.float64), (len(metrics),))
    if not np.all(tolerances > 0):
        raise ConfigError(f"rtol: must be positive, got {rtol}")
    check_joint_box(robot)
    per_block = block * randomizations
    max_blocks = max(1, max_samples // per_block)
    max_blocks = 1 << (max_blocks.bit_length() - 1)  # a power of two: the last estimate is on a net
    min_blocks = min(max_blocks, max(1, -(-min_samples // per_block)))
    points = max_blocks * block if min_blocks == max_blocks else None
    plan = _Plan(metrics, int(randomizations), int(block), points)
    budget = _Budget(  # NumPy: traced by the program, no eager conversion programs
        np.asarray(tolerances, jnp.result_type(float)),
        np.asarray(min_blocks, np.int32),
        np.asarray(max_blocks, np.int32),
    )
    shifts = digital_shifts(seed, randomizations, family_of(robot).joint_count(robot))
    out = _estimate_batched(robot, shifts, budget, impact, plan, designs_per_chunk)
    return dict(zip(metrics, out, strict=True))


def joint_average(
    robot,
    metric: str = "manipulability",
    *,
    rtol: float = 1e-4,
    randomizations: int = 8,
    block: int = 1024,
    min_samples: int = 2**14,
    max_samples: int = 2**24,
    seed: int = 0,
    designs_per_chunk: int = 8,
    impact: ImpactSetup | None = None,
) -> JointAverage:
    """The mean of a posture metric over the joint box, to a relative standard error ``rtol``.

    Args:
        robot: a design of either family, or a batch of designs (leading axes on every
            leaf; each design stops at its own sample count).
        metric: one of `METRICS` ("manipulability", "conditioning",
            "base_disturbance", "dynamic_manipulability") or of `IMPACT_METRICS`
            ("virtual_mass", "bus_rate_jump", "capture_bus_rate", with ``impact``).
        rtol: target relative standard error (one sigma) of the mean (traced: a new
            value does not recompile).
        randomizations: R independent digital shifts (>= 2; the error estimate has
            R - 1 degrees of freedom).
        block: Sobol points per randomization per loop step (a power of two).
        min_samples, max_samples: bounds on the postures used in all (R x points);
            when ``max_samples`` is hit first the returned error says how far it got.
            Equal bounds give a fixed rule (one pass, no loop).
        seed: seed of the digital shifts (a new seed does not recompile).
        designs_per_chunk: designs evaluated together under ``lax.map`` for batches.
        impact: the settings of an impact metric (`spacearm.analysis.impacts.ImpactSetup`).

    Returns:
        `JointAverage` with ``(...)`` fields. ``value`` is differentiable in the
        design (``jax.grad``); under ``vmap`` or ``jit`` it works as well.
    """
    return joint_averages(
        robot,
        (metric,),
        rtol=rtol,
        randomizations=randomizations,
        block=block,
        min_samples=min_samples,
        max_samples=max_samples,
        seed=seed,
        designs_per_chunk=designs_per_chunk,
        impact=impact,
    )[metric]


def joint_average_manipulability(robot, **options) -> JointAverage:
    """Mean translational w* over the joint box (m^2 planar, m^3 spatial), not normalized, with its error."""
    return joint_average(robot, "manipulability", **options)


def average_manipulability(robot, **options):
    """The mean translational w* over the joint box, not normalized: m^2 planar, m^3 spatial, ``(...)``.

    The same quantity for every robot (eq. 10 averaged under the uniform measure of the
    joint box), to relative standard error ``rtol`` (default 1e-4); the options are those
    of `joint_average`, which also returns the error estimate and the sample count. The
    paper's normalized w-bar of eq. 12 (an average over the workspace area, divided by
    L^2) is `spacearm.paper.normalized_wbar`.
    """
    return joint_average(robot, "manipulability", **options).value


def global_conditioning_index(robot, **options) -> JointAverage:
    """Gosselin & Angeles' global conditioning index: the mean of 1/kappa(J*_v) over the joint box (dimensionless)."""
    return joint_average(robot, "conditioning", **options)


def average_base_disturbance(robot, **options) -> JointAverage:
    """The mean of ||C_w||_F (bus angular rate per joint rate, Frobenius) over the joint box, rad/rad."""
    return joint_average(robot, "base_disturbance", **options)


def average_dynamic_manipulability(robot, **options) -> JointAverage:
    """The mean of w_d = sqrt det(J*_v (H*^T H*)^-1 J*_v^T) over the joint box (spatial robots)."""
    return joint_average(robot, "dynamic_manipulability", **options)


__all__ += [
    "base_disturbance_metric",
    "dynamic_manipulability_metric",
    "inverse_condition_metric",
    "manipulability_metric",
]
