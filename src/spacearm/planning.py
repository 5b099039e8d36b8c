"""Reaching point C: cyclic joint maneuvers that reorient the base, then a straight path.

Umetani & Yoshida 1990, section 3.2, Fig. 5: point C cannot be reached from the
current posture by a straight tip path, "but can be reached after reorienting the
base by a suitable cyclic maneuver". The paper stops there; this module plans it.

Reorientation (:func:`plan_reorientation`). Along a closed joint-space loop the
joints come back but the base turns by the line integral of eq. (5),

    delta_phi0 = -(loop integral) (I_M / I_S) . dq,

which by Stokes is the curl of the one-form -I_M/I_S times the enclosed (signed)
joint-space area. I_S and I_M do not depend on phi0, so a loop repeated N times turns
the base N times as much, and the base attitude at the start of the loop does not
matter. The planner

1. takes the curl at the start q0 = phi_start[1:] (an antisymmetric n x n matrix
   Omega; its top singular pair spans the joint plane where small loops turn the base
   most, with rotation ~ sigma_max * area), which sizes a circle through q0 for each
   candidate number of repetitions N;
2. refines every candidate loop (Fourier coefficients of a closed curve through q0,
   sampled into waypoints) with optax Adam through the integrator
   (:func:`spacearm.motion.integrate_joint_path`): squared rotation error, total
   joint travel, soft penalties on joint limits and on the excursion from q0; all
   candidates in one vmapped, jitted call;
3. finishes each candidate with Newton steps on a scale factor of the loop about q0,
   so the waypoints turn the base by the requested angle to rounding;
4. keeps the feasible candidate (within joint limits and the excursion bound) with the
   least joint travel.

Reaching (:func:`plan_reach`). Rotating the base by Delta rotates the whole system
rigidly about the system centroid (joints unchanged), so the Straight-Path workspace
from (phi0 + Delta, q0) is the one from (phi0, q0) rotated by Delta. The target T is
reachable after the maneuver iff R(-Delta) T lies in the current Straight-Path
workspace: one batched call of :func:`spacearm.motion.straight_tip_path` over a grid
of Delta finds the smallest useful reorientation. Targets whose distance from the
system centroid no rotation of the current workspace covers are reached by first
moving the joints to a posture whose tip lies at the target's radius (then the
maneuver brings the tip onto the target). Targets outside the Maximum Reachable
space (radius K0 + ... + Kn about the system centroid) are refused with
:class:`~spacearm.robot.ConfigError`.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
import optax

from .kinematics import momentum_inertias, tip_position
from .robot import ConfigError, PlanarRobot

__all__ = [
    "LoopSettings",
    "ReachPlan",
    "plan_reorientation",
    "plan_reorientation_details",
    "ReorientationLoop",
    "rotation_curl",
    "plan_reach",
    "reachable_bounds",
    "MODE_STRAIGHT",
    "MODE_REORIENT",
    "MODE_REPOSITION",
    "add_reach_command",
]


# Settings -----------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class LoopSettings:
    """Static settings of the reorientation planner (hashable: part of the compile key).

    Attributes:
        samples_per_loop: waypoints per loop (straight joint-space segments between them).
        harmonics: Fourier harmonics of the closed loop curve.
        loop_counts: candidate numbers of repetitions N, all tried in one batch.
        directions: candidate directions of the loop centre from q0, in the curl plane.
        steps: Adam steps.
        learning_rate: Adam step size, in units of the initial loop radius.
        max_excursion: bound on |q_j - q0_j| for every joint along the loop, rad.
        limit_margin: the optimizer keeps the loop this far inside finite joint limits, rad.
        room_fraction: the optimizer uses this fraction of the allowed excursion, leaving
            the rest for the final scaling.
        travel_weight: weight of the (normalized) joint travel against the rotation error.
        newton_steps: Newton steps on the loop scale factor after the optimizer.
    """

    samples_per_loop: int = 48
    harmonics: int = 3
    loop_counts: tuple[int, ...] = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64)
    directions: int = 4
    steps: int = 300
    learning_rate: float = 0.03
    max_excursion: float = 1.5
    limit_margin: float = 0.02
    room_fraction: float = 0.95
    travel_weight: float = 0.005
    newton_steps: int = 12


# Curl of eq. (5) ------------------------------------------------------------------------


def _connection(robot: PlanarRobot, q: jax.Array) -> jax.Array:
    """The one-form of eq. (5): d phi0 = omega(q) . dq with omega = -I_M / I_S, ``(n,)``."""
    phi = jnp.concatenate([jnp.zeros((1,), q.dtype), q])
    i_s, i_m = momentum_inertias(robot, phi)
    return -i_m / i_s


def rotation_curl(robot: PlanarRobot, joint_angles: jax.Array) -> jax.Array:
    """Curl of the base-rotation one-form of eq. (5) at a joint posture.

    A small closed joint loop q0 + x(s) turns the base by sum_{i<j} Omega_ij A_ij, where
    A_ij is the signed area the loop encloses in the (q_i, q_j) plane (counter-clockwise
    positive). For n = 2 that is Omega_12 times the signed area.

    Args:
        robot: one design.
        joint_angles: ``(n,)`` joint angles q, rad.

    Returns:
        ``(n, n)`` antisymmetric Omega_ij = d omega_j / d q_i - d omega_i / d q_j,
        rad of base rotation per rad^2 of enclosed joint area.
    """
    q = jnp.asarray(joint_angles)
    jac = jax.jacfwd(functools.partial(_connection, robot))(q)  # [j, i] = d omega_j / d q_i
    return jac.T - jac


# Loop parametrization ------------------------------------------------------------------


def _loop_basis(settings: LoopSettings) -> np.ndarray:
    """``(samples_per_loop + 1, 2 M)``: (1 - cos 2 pi m s), sin 2 pi m s at s = j / k.

    Every basis function is zero at s = 0 and s = 1, so q(s) = q0 + basis @ C is a
    closed curve through q0 for any coefficients C.
    """
    s = np.arange(settings.samples_per_loop + 1) / settings.samples_per_loop
    m = np.arange(1, settings.harmonics + 1)
    angle = 2.0 * np.pi * s[:, None] * m[None, :]
    basis = np.concatenate([1.0 - np.cos(angle), np.sin(angle)], axis=1)
    basis[-1] = 0.0  # exactly closed (cos 2 pi m = 1 up to rounding otherwise)
    return basis


def _path_length(points: jax.Array) -> jax.Array:
    """Joint-space length of a polygon ``(k, n)``, rad (smooth at zero-length segments)."""
    steps = jnp.diff(points, axis=0)
    return jnp.sum(jnp.sqrt(jnp.sum(steps * steps, axis=-1) + 1e-30))


def _loop_rotation(robot: PlanarRobot, q0: jax.Array, points: jax.Array) -> jax.Array:
    """Base rotation of one pass over the closed polygon ``points`` ``(k+1, n)``, rad."""
    from .motion import integrate_joint_path

    phi_start = jnp.concatenate([jnp.zeros((1,), q0.dtype), q0])
    # Loop segments are short (~0.1 rad): 10 Gauss points per segment are exact to rounding
    # there; the returned waypoints are checked with the integrator's defaults.
    return integrate_joint_path(robot, phi_start, points, nodes=10, pieces=1)[0]


@functools.partial(jax.jit, static_argnames=("settings",))
def _optimize_loops(robot: PlanarRobot, q0: jax.Array, delta: jax.Array, settings: LoopSettings):
    """Optimize one loop per (repetition count, centre direction) candidate.

    Returns a dict of per-candidate arrays (leading axis: candidates): ``points``
    ``(C, k+1, n)``, ``loops`` ``(C,)``, ``rotation`` (total, rad), ``travel`` (total, rad),
    ``excursion`` (max |q - q0|, rad), ``limit_violation`` (rad, 0 when inside).
    """
    n = q0.shape[0]
    dtype = q0.dtype
    basis = jnp.asarray(_loop_basis(settings), dtype)
    lower = jnp.asarray(robot.joint_lower, dtype)
    upper = jnp.asarray(robot.joint_upper, dtype)

    # The plane and strength of the curl at q0 (top singular pair of Omega).
    omega = rotation_curl(robot, q0)
    u_mat, sig, vt = jnp.linalg.svd(omega)
    sigma = jnp.maximum(sig[0], 1e-12)
    e1, e2 = u_mat[:, 0], vt[0]  # Omega e2 = sigma e1; e1 . e2 = 0 (Omega antisymmetric)
    # A loop q0 + r[(1 - cos t) c + sin t c_perp] with (c, c_perp) a rotation of (e1, e2)
    # encloses area pi r^2 clockwise in the (c, c_perp) orientation: its rotation is about
    # -sigma pi r^2. Flip c_perp for the requested sign.
    sign = jnp.where(delta >= 0, -1.0, 1.0).astype(dtype)

    counts = np.repeat(np.asarray(settings.loop_counts), settings.directions)
    alphas = np.tile(2.0 * np.pi * np.arange(settings.directions) / settings.directions, len(settings.loop_counts))
    counts_j = jnp.asarray(counts, dtype)
    magnitude = jnp.maximum(jnp.abs(delta), 1e-9)
    radius = jnp.sqrt(magnitude / (counts_j * jnp.pi * sigma))
    radius = jnp.minimum(radius, 0.5 * settings.max_excursion)

    def initial(alpha, r):
        c = jnp.cos(alpha) * e1 + jnp.sin(alpha) * e2
        c_perp = sign * (-jnp.sin(alpha) * e1 + jnp.cos(alpha) * e2)
        coeffs = jnp.zeros((2 * settings.harmonics, n), dtype)
        coeffs = coeffs.at[0].set(r * c).at[settings.harmonics].set(r * c_perp)
        return coeffs / r  # normalized by r

    def points_of(normalized, r, scale=1.0):
        return q0 + scale * r * (basis @ normalized)

    # Allowed displacement from q0 per joint and direction: the excursion bound and the
    # joint limits, shrunk by `room_fraction` so the final Newton scaling has room. The box
    # contains q0 and is convex, so the loop q0 + c x(s) stays inside for every scale c
    # up to largest_scale(x).
    room_up = settings.room_fraction * jnp.clip(upper - settings.limit_margin - q0, 0.0, settings.max_excursion)
    room_down = settings.room_fraction * jnp.clip(q0 - (lower + settings.limit_margin), 0.0, settings.max_excursion)

    def largest_scale(offsets):
        ratio_up = jnp.where(offsets > 0, room_up / jnp.where(offsets > 0, offsets, 1.0), jnp.inf)
        ratio_down = jnp.where(offsets < 0, room_down / jnp.where(offsets < 0, -offsets, 1.0), jnp.inf)
        return jnp.min(jnp.minimum(ratio_up, ratio_down))

    def project(normalized, r):
        # Projection onto the allowed box by shrinking the loop about q0.
        return normalized * jnp.minimum(1.0, largest_scale(r * (basis @ normalized)))

    def objective(normalized, r, count):
        points = points_of(normalized, r)
        rotation = count * _loop_rotation(robot, q0, points)
        rot_err = (rotation - delta) / magnitude
        travel = count * _path_length(points) / (2.0 * jnp.pi * jnp.sqrt(magnitude / (jnp.pi * sigma)))
        return rot_err**2 + settings.travel_weight * travel**2

    schedule = optax.cosine_decay_schedule(settings.learning_rate, settings.steps, alpha=0.02)
    optimizer = optax.adam(schedule)

    def solve(alpha, r, count):
        params = project(initial(alpha, r), r)
        state = optimizer.init(params)
        grad_fn = jax.grad(objective)

        def step(carry, _):
            params, state = carry
            grad = grad_fn(params, r, count)
            updates, state = optimizer.update(grad, state, params)
            return (project(optax.apply_updates(params, updates), r), state), None

        (params, _), _ = jax.lax.scan(step, (params, state), None, length=settings.steps)

        # Newton on the scale factor c of the loop about q0: count * R(c) = delta.
        def rotation_at(scale):
            return count * _loop_rotation(robot, q0, points_of(params, r, scale))

        def newton(scale, _):
            value, slope = jax.value_and_grad(rotation_at)(scale)
            safe = jnp.where(jnp.abs(slope) > 1e-300, slope, 1.0)
            return jnp.clip(scale - (value - delta) / safe, 0.25, 4.0), None

        scale, _ = jax.lax.scan(newton, jnp.asarray(1.0, dtype), None, length=settings.newton_steps)
        points = points_of(params, r, scale)
        rotation = count * _loop_rotation(robot, q0, points)
        violation = jnp.max(
            jnp.concatenate([jax.nn.relu(points - upper).ravel(), jax.nn.relu(lower - points).ravel()])
        )
        return dict(
            points=points,
            rotation=rotation,
            travel=count * _path_length(points),
            excursion=jnp.max(jnp.abs(points - q0)),
            limit_violation=violation,
        )

    result = jax.vmap(solve)(jnp.asarray(alphas, dtype), radius, counts_j)
    result["loops"] = jnp.asarray(counts)
    return result


@dataclasses.dataclass(frozen=True)
class ReorientationLoop:
    """A planned reorientation maneuver (see :func:`plan_reorientation_details`).

    Attributes:
        waypoints: ``(N k + 1, n)`` joint waypoints, rad; the loop repeated N times,
            first and last rows equal to q0.
        loop: ``(k + 1, n)`` one pass of the loop, rad.
        loops: N, the number of repetitions.
        rotation: base rotation of the whole maneuver integrated along ``waypoints``, rad.
        rotation_error: ``rotation - delta_phi0``, rad.
        travel: joint-space length of the whole maneuver, rad.
        excursion: largest |q_j - q0_j| along the loop, rad.
    """

    waypoints: np.ndarray
    loop: np.ndarray
    loops: int
    rotation: float
    rotation_error: float
    travel: float
    excursion: float


def _check_posture(robot: PlanarRobot, phi_start) -> np.ndarray:
    if robot.batch_shape:
        raise ConfigError("robot: plan one design at a time (got a batch of designs)")
    phi = np.asarray(phi_start, dtype=float)
    n = robot.n_links
    if phi.shape != (n + 1,):
        raise ConfigError(f"phi_start: expected shape ({n + 1},) = [phi0, phi1..phi{n}], got {phi.shape}")
    if not np.all(np.isfinite(phi)):
        raise ConfigError(f"phi_start: must be finite, got {phi}")
    lower, upper = np.asarray(robot.joint_lower), np.asarray(robot.joint_upper)
    outside = (phi[1:] < lower) | (phi[1:] > upper)
    if np.any(outside):
        j = int(np.argmax(outside)) + 1
        raise ConfigError(
            f"phi_start: joint {j} = {phi[j]:.6g} rad is outside its limits [{lower[j - 1]:.6g}, {upper[j - 1]:.6g}]"
        )
    return phi


def plan_reorientation_details(
    robot: PlanarRobot,
    phi_start,
    delta_phi0: float,
    *,
    settings: LoopSettings = LoopSettings(),
    tolerance: float | None = None,
) -> ReorientationLoop:
    """Plan a closed joint maneuver that turns the base by ``delta_phi0``, with diagnostics.

    Args:
        robot: one design.
        phi_start: ``(n+1,)`` start posture [phi0, q0], rad (phi0 does not matter).
        delta_phi0: requested base rotation, rad (any sign and size).
        settings: :class:`LoopSettings` (static; a new value compiles once).
        tolerance: largest accepted |rotation error| of the integrated waypoints, rad
            (default 1e-9 in float64, 1e-4 in float32).

    Returns:
        a :class:`ReorientationLoop`.

    Raises:
        ConfigError: bad input, or no candidate loop reaches the rotation within the
            joint limits and the excursion bound (raise ``loop_counts`` or
            ``max_excursion``).
    """
    from .motion import integrate_joint_path

    phi = _check_posture(robot, phi_start)
    delta = float(delta_phi0)
    if not math.isfinite(delta):
        raise ConfigError(f"delta_phi0: must be finite, got {delta_phi0!r}")
    if tolerance is None:
        tolerance = 1e-9 if jax.config.jax_enable_x64 else 1e-4
    q0 = phi[1:]
    if delta == 0.0:
        still = np.stack([q0, q0])
        return ReorientationLoop(still, still, 0, 0.0, 0.0, 0.0, 0.0)
    dtype = jnp.result_type(float)
    result = _optimize_loops(robot, jnp.asarray(q0, dtype), jnp.asarray(delta, dtype), settings)
    result = jax.tree_util.tree_map(np.asarray, result)
    error = np.abs(result["rotation"] - delta)
    feasible = (
        (error <= tolerance)
        & (result["limit_violation"] <= 0.0)
        & (result["excursion"] <= settings.max_excursion)
        & np.isfinite(result["travel"])
    )
    if not np.any(feasible):
        raise ConfigError(
            f"delta_phi0: no loop turns the base by {math.degrees(delta):.6g} deg within the joint limits, "
            f"max_excursion = {settings.max_excursion:.3g} rad and at most {max(settings.loop_counts)} repetitions "
            f"(best rotation error {np.min(error):.3g} rad); allow more repetitions or a larger excursion"
        )
    best = int(np.argmin(np.where(feasible, result["travel"], np.inf)))
    loop = result["points"][best]
    loops = int(result["loops"][best])
    waypoints = np.concatenate([loop[:1]] + [loop[1:]] * loops, axis=0)
    waypoints[-1] = q0
    # One pass with the integrator's full accuracy; the passes are identical and eq. (5) does
    # not depend on phi0, so N passes turn the base N times as far (one compiled shape for
    # every N; tests integrate the whole waypoint array independently).
    loop_start = np.r_[0.0, q0]
    rotation = loops * float(integrate_joint_path(robot, jnp.asarray(loop_start), jnp.asarray(loop))[0])
    if not abs(rotation - delta) <= tolerance:
        raise ConfigError(
            f"delta_phi0: the planned loop turns the base by {rotation!r} rad instead of {delta!r} rad "
            f"(error {rotation - delta:.3g} rad above tolerance {tolerance:.3g})"
        )
    return ReorientationLoop(
        waypoints=waypoints,
        loop=loop,
        loops=loops,
        rotation=rotation,
        rotation_error=rotation - delta,
        travel=float(result["travel"][best]),
        excursion=float(result["excursion"][best]),
    )


def plan_reorientation(robot: PlanarRobot, phi_start, delta_phi0: float, **options) -> np.ndarray:
    """Joint waypoints of a closed maneuver that turns the base by ``delta_phi0``.

    A closed joint-space loop through q0 = phi_start[1:], repeated N times where one
    loop within the joint limits and ``max_excursion`` cannot turn the base far enough,
    found by optax through the integrator of eq. (5) and finished by Newton steps on
    the loop's scale, so that ``integrate_joint_path(robot, phi_start, waypoints)``
    ends at [phi0 + delta_phi0, q0] to ~1e-12 rad (accepted at 1e-9).

    Args:
        robot: one design.
        phi_start: ``(n+1,)`` start posture [phi0, phi1..phin], rad.
        delta_phi0: base rotation, rad.
        **options: ``settings`` (:class:`LoopSettings`), ``tolerance`` (rad).

    Returns:
        ``(k, n)`` joint waypoints, rad, joined by straight joint-space segments; the
        first and last rows equal phi_start[1:].
    """
    return plan_reorientation_details(robot, phi_start, delta_phi0, **options).waypoints


# Reaching a target ---------------------------------------------------------------------

MODE_STRAIGHT = "straight"
MODE_REORIENT = "reorient"
MODE_REPOSITION = "reposition"

PHASE_REPOSITION = 0
PHASE_LOOP = 1
PHASE_STRAIGHT = 2


@dataclasses.dataclass(frozen=True)
class ReachPlan:
    """A plan that brings the tip to a target (see :func:`plan_reach`).

    Attributes:
        mode: "straight" (a straight tip path from the start), "reorient" (a
            reorientation loop, then a straight tip path), or "reposition" (a straight
            joint-space move to a posture whose tip lies at the target's radius, a
            reorientation loop, then the remaining straight tip path, usually of zero length).
        target: ``(2,)`` inertial target, m.
        postures: ``(S, n+1)`` the whole history [phi0, phi1..phin], rad.
        tips: ``(S, 2)`` inertial tip along it, m.
        phase: ``(S,)`` int, 0 = repositioning move, 1 = reorientation loop, 2 = straight tip path.
        joint_waypoints: ``(k, n)`` the joint-space part (repositioning and loop), rad;
            a single row q0 repeated when there is none.
        delta_phi0: base rotation requested from the loop, rad (0 without a loop).
        loops: repetitions of the loop (0 without one).
        joint_travel: joint-space length of the joint-space part, rad.
        straight_length: length of the final straight tip path, m.
        end_posture: ``(n+1,)`` final posture, rad.
        end_tip: ``(2,)`` final tip, inertial, m.
        error: |end_tip - target|, m.
    """

    mode: str
    target: np.ndarray
    postures: np.ndarray
    tips: np.ndarray
    phase: np.ndarray
    joint_waypoints: np.ndarray
    delta_phi0: float
    loops: int
    joint_travel: float
    straight_length: float
    end_posture: np.ndarray
    end_tip: np.ndarray
    error: float


def reachable_bounds(robot: PlanarRobot) -> tuple[float, float]:
    """Inner and outer radius of the Maximum Reachable space (Area 3) about the system centroid, m.

    Outer K0 + .. + Kn (sec. 3.1 (3-a)); inner max(0, 2 max_k K_k - sum_k K_k), the hole
    when one coefficient outweighs the rest (both from :mod:`spacearm.workspace`). Joint
    limits are not taken into account here (they can only shrink the space).
    """
    from .workspace import maximum_reachable_inner_radius, maximum_reachable_radius

    return float(maximum_reachable_inner_radius(robot)), float(maximum_reachable_radius(robot))


def _rotate(points: np.ndarray, angle) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    x, y = points[..., 0], points[..., 1]
    return np.stack([c * x - s * y, s * x + c * y], axis=-1)


def _wrap(angle):
    return (np.asarray(angle) + np.pi) % (2.0 * np.pi) - np.pi


def _choose_rotation(deltas: np.ndarray, slack: np.ndarray, feasible: np.ndarray) -> float:
    """The smallest useful base rotation, moved inward from the edge of its feasible run.

    Among the grid rotations whose straight path passes the target (``feasible``), keep
    those with at least half the largest slack of their contiguous (circular) run, then
    take the one nearest zero: the straight path then ends with a margin before the
    singularity instead of grazing it.
    """
    count = len(deltas)
    keep = np.zeros(count, bool)
    if np.all(feasible):
        runs = [np.arange(count)]
    else:
        start = int(np.argmin(feasible))  # a gap; runs begin after gaps
        order = (start + np.arange(count)) % count
        runs, current = [], []
        for i in order:
            if feasible[i]:
                current.append(i)
            elif current:
                runs.append(np.array(current))
                current = []
        if current:
            runs.append(np.array(current))
    for run in runs:
        best = np.max(slack[run])
        keep[run[slack[run] >= 0.5 * best]] = True
    candidates = np.flatnonzero(keep)
    return float(deltas[candidates[np.argmin(np.abs(deltas[candidates]))]])


def _loop_history(robot: PlanarRobot, phi_from: np.ndarray, loop: ReorientationLoop, samples: int = 4):
    """Postures ``(S, n+1)`` and inertial tips ``(S, 2)`` along the N passes of a loop.

    One pass is integrated (a fixed shape, compiled once); pass i is the first turned by
    i times the rotation of one pass, a rigid rotation of the whole system about the
    centroid (phi0 shifts, the tip rotates), because eq. (5) does not depend on phi0.
    """
    from .motion import joint_path_history

    if loop.loops == 0:
        return np.asarray(phi_from)[None], np.asarray(tip_position(robot, jnp.asarray(phi_from)))[None]
    postures, tips = joint_path_history(robot, jnp.asarray(phi_from), jnp.asarray(loop.loop), samples)
    postures, tips = np.asarray(postures), np.asarray(tips)
    per_pass = postures[-1, 0] - postures[0, 0]
    turns = per_pass * np.arange(loop.loops)
    all_postures = np.concatenate(
        [postures[:1]] + [postures[1:] + np.r_[turn, np.zeros(postures.shape[1] - 1)] for turn in turns]
    )
    all_tips = np.concatenate([tips[:1]] + [_rotate(tips[1:], turn) for turn in turns])
    return all_postures, all_tips


def _reposition_joints(robot: PlanarRobot, q0: np.ndarray, radius: float) -> np.ndarray:
    """Joint angles nearest q0 (minimum-norm Newton steps) whose tip is ``radius`` from the centroid."""

    def squared_radius(q):
        phi = jnp.concatenate([jnp.zeros((1,), q.dtype), q])
        p = tip_position(robot, phi)
        return jnp.sum(p * p)

    value_and_grad = jax.jit(jax.value_and_grad(squared_radius))
    lower, upper = np.asarray(robot.joint_lower), np.asarray(robot.joint_upper)
    q = np.array(q0, float)
    eps = float(jnp.finfo(jnp.result_type(float)).eps)
    for _ in range(60):
        value, grad = value_and_grad(jnp.asarray(q))
        residual = float(value) - radius**2
        if abs(residual) <= 100.0 * eps * max(radius**2, 1.0):
            break
        grad = np.asarray(grad)
        norm2 = float(grad @ grad)
        if norm2 < 1e-24:  # stationary (stretched or folded arm): nudge off it
            q = q + 1e-3
            continue
        step = -residual * grad / norm2
        q = np.clip(q + np.clip(step, -0.3, 0.3), lower, upper)
    value, _ = value_and_grad(jnp.asarray(q))
    if not abs(float(value) - radius**2) <= 1e4 * eps * max(radius**2, 1.0):
        raise ConfigError(
            f"target: no joint posture within the limits puts the tip {radius:.6g} m from the system centroid"
        )
    return q


def plan_reach(
    robot: PlanarRobot,
    phi_start,
    target,
    *,
    rotation_grid: int = 180,
    history_samples: int = 101,
    tolerance: float | None = None,
    settings: LoopSettings = LoopSettings(),
    modes: tuple[str, ...] = (MODE_STRAIGHT, MODE_REORIENT, MODE_REPOSITION),
) -> ReachPlan:
    """Plan how the tip reaches an inertial target from a posture (sec. 3.2, points B and C).

    1. Point B: if the straight tip path towards the target (J* inverted, base
       following eq. 5) gets there before a singularity of J* or a joint limit, that
       path is the plan.
    2. Point C: otherwise, turn the base first. A base rotation Delta turns the
       Straight-Path workspace about the system centroid, so the straight path from the
       current posture towards R(-Delta) target tells, for every Delta of a grid in one
       batched call, whether the target is reachable after the maneuver. The smallest
       such Delta (with margin) is planned with :func:`plan_reorientation_details`, then
       the straight path runs from the posture after the loop.
    3. When no rotation of the current workspace covers the target's distance from the
       centroid, the joints first move straight in joint space to the nearest posture
       whose tip lies at that distance, and the loop turns the tip onto the target.

    Args:
        robot: one design.
        phi_start: ``(n+1,)`` start posture, rad.
        target: ``(2,)`` inertial target (origin at the system centroid), m.
        rotation_grid: number of base rotations tried in step 2.
        history_samples: samples of the straight path in the history.
        tolerance: accepted distance of the final tip from the target, m (default 1e-6
            in float64, 1e-3 in float32).
        settings: :class:`LoopSettings` for the reorientation loop.
        modes: the strategies allowed, tried in the order above ("straight",
            "reorient", "reposition"); e.g. ``("reposition",)`` forces the third.

    Returns:
        a :class:`ReachPlan`.

    Raises:
        ConfigError: bad input; the target outside the Maximum Reachable space (radius
            K0 + .. + Kn about the system centroid); or no plan found.
    """
    from .motion import (
        REASON_MAX_LENGTH,
        joint_path_history,
        straight_tip_path,
        straight_tip_path_history,
    )

    phi = _check_posture(robot, phi_start)
    if tolerance is None:
        tolerance = 1e-6 if jax.config.jax_enable_x64 else 1e-3
    target = np.asarray(target, dtype=float)
    if target.shape != (2,) or not np.all(np.isfinite(target)):
        raise ConfigError(f"target: expected two finite numbers (x, y) in m, got {np.asarray(target).tolist()!r}")
    inner, outer = reachable_bounds(robot)
    distance_from_centroid = float(np.linalg.norm(target))
    if distance_from_centroid > outer * (1.0 - 1e-12) or distance_from_centroid < inner * (1.0 + 1e-12):
        hole = f", outside its hole of radius {inner:.6g} m" if inner > 0 else ""
        raise ConfigError(
            f"target: ({target[0]:.6g}, {target[1]:.6g}) m is {distance_from_centroid:.6g} m from the system "
            f"centroid, outside the Maximum Reachable space (radius {outer:.6g} m = K0 + .. + Kn{hole}); "
            "no motion of this robot can reach it"
        )
    q0 = phi[1:]
    dtype = jnp.result_type(float)

    def straight(phi_from, max_length=None, directions=None):
        tip_from = np.asarray(tip_position(robot, jnp.asarray(phi_from, dtype)))
        offset = target - tip_from if directions is None else directions
        return straight_tip_path(robot, jnp.asarray(phi_from, dtype), jnp.asarray(offset, dtype), max_length=max_length)

    def finish(mode, joint_waypoints, joint_parts, phi_after, delta, loops):
        tip_after = np.asarray(tip_position(robot, jnp.asarray(phi_after, dtype)))
        offset = target - tip_after
        length = float(np.linalg.norm(offset))
        parts_postures, parts_tips, parts_phase = [], [], []
        for phase, postures, tips in joint_parts:
            parts_postures.append(postures)
            parts_tips.append(tips)
            parts_phase.append(np.full(len(postures), phase))
        if not parts_postures:
            parts_postures.append(phi[None])
            parts_tips.append(np.asarray(tip_position(robot, jnp.asarray(phi)))[None])
            parts_phase.append(np.array([PHASE_STRAIGHT]))
        end_posture, end_tip = np.asarray(phi_after), tip_after
        if length > 1e-12:
            path = straight(phi_after, max_length=length)
            if int(path.reason) != REASON_MAX_LENGTH:
                raise ConfigError(
                    f"target: the straight tip path from the planned posture stops after {float(path.length):.6g} m "
                    f"of {length:.6g} m (reason {int(path.reason)})"
                )
            postures, tips = straight_tip_path_history(
                robot, jnp.asarray(phi_after, dtype), jnp.asarray(offset, dtype), history_samples, max_length=length
            )
            parts_postures.append(np.asarray(postures)[1:])
            parts_tips.append(np.asarray(tips)[1:])
            parts_phase.append(np.full(history_samples - 1, PHASE_STRAIGHT))
            end_posture, end_tip = np.asarray(path.end_posture), np.asarray(path.end_tip)
        error = float(np.linalg.norm(end_tip - target))
        if not error <= tolerance:
            raise ConfigError(f"target: the plan ends {error:.3g} m from the target (tolerance {tolerance:.3g} m)")
        steps = np.diff(joint_waypoints, axis=0)
        return ReachPlan(
            mode=mode,
            target=target,
            postures=np.concatenate(parts_postures),
            tips=np.concatenate(parts_tips),
            phase=np.concatenate(parts_phase),
            joint_waypoints=joint_waypoints,
            delta_phi0=float(delta),
            loops=int(loops),
            joint_travel=float(np.sum(np.linalg.norm(steps, axis=-1))),
            straight_length=length,
            end_posture=end_posture,
            end_tip=end_tip,
            error=error,
        )

    unknown = set(modes) - {MODE_STRAIGHT, MODE_REORIENT, MODE_REPOSITION}
    if unknown or not modes:
        raise ConfigError(f"modes: expected some of 'straight', 'reorient', 'reposition', got {modes!r}")
    still = np.stack([q0, q0])
    tip0 = np.asarray(tip_position(robot, jnp.asarray(phi)))
    distance = float(np.linalg.norm(target - tip0))
    if MODE_STRAIGHT in modes:
        if distance <= 1e-12:
            return finish(MODE_STRAIGHT, still, [], phi, 0.0, 0)
        if int(straight(phi, max_length=distance).reason) == REASON_MAX_LENGTH:
            return finish(MODE_STRAIGHT, still, [], phi, 0.0, 0)

    # Point C: which base rotations Delta put the target inside the Straight-Path workspace?
    deltas = _wrap(2.0 * np.pi * np.arange(rotation_grid) / rotation_grid)
    turned = _rotate(target, -deltas)  # (G, 2): the target seen from the unrotated system
    offsets = turned - tip0
    lengths = np.linalg.norm(offsets, axis=-1)
    feasible = np.zeros(rotation_grid, bool)
    if MODE_REORIENT in modes:
        ends = straight(np.broadcast_to(phi, (rotation_grid, phi.size)), directions=offsets)
        slack = np.asarray(ends.length) - lengths
        feasible = (slack > 1e-6 * float(robot.reach)) & (np.asarray(ends.reason) != 3)
    if np.any(feasible):
        delta = _choose_rotation(deltas, slack, feasible)
        loop = plan_reorientation_details(robot, phi, delta, settings=settings)
        postures, tips = _loop_history(robot, phi, loop)
        return finish(MODE_REORIENT, loop.waypoints, [(PHASE_LOOP, postures, tips)], postures[-1], delta, loop.loops)

    # No rotation of the current workspace covers the target's radius: move the joints.
    if MODE_REPOSITION not in modes:
        raise ConfigError(
            f"target: ({target[0]:.6g}, {target[1]:.6g}) m is not reachable from this posture with the modes {modes!r}"
        )
    q1 = _reposition_joints(robot, q0, distance_from_centroid)
    segment = np.stack([q0, q1])
    move_postures, move_tips = (np.asarray(x) for x in joint_path_history(robot, phi, segment, 16))
    phi_mid = move_postures[-1]
    tip_mid = move_tips[-1]
    delta = float(_wrap(np.arctan2(target[1], target[0]) - np.arctan2(tip_mid[1], tip_mid[0])))
    loop = plan_reorientation_details(robot, phi_mid, delta, settings=settings)
    postures, tips = _loop_history(robot, phi_mid, loop)
    waypoints = np.concatenate([segment, loop.waypoints[1:]])
    parts = [(PHASE_REPOSITION, move_postures, move_tips), (PHASE_LOOP, postures[1:], tips[1:])]
    return finish(MODE_REPOSITION, waypoints, parts, postures[-1], delta, loop.loops)


# Command line --------------------------------------------------------------------------


def _numbers(text: str, count: int, what: str) -> np.ndarray:
    try:
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise ConfigError(f"{what}: expected {count} comma-separated numbers, got {text!r}") from None
    if values.size != count or not np.all(np.isfinite(values)):
        raise ConfigError(f"{what}: expected {count} finite comma-separated numbers, got {text!r}")
    return values


def _cmd_reach(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .figures.planning import animate_reach, draw_reach
    from .robot import load_robot

    robot = load_robot(args.robot)
    phi = _numbers(args.start, robot.n_links + 1, "--from")
    if not args.radians:
        phi = np.radians(phi)
    target = _numbers(args.target, 2, "--to")
    plan = plan_reach(robot, phi, target)
    out = Path(args.out)
    figure_path = draw_reach(robot, phi, plan, out / "reach.png")
    lines = [
        f"mode           {plan.mode}",
        f"start tip      ({plan.tips[0, 0]:.6f}, {plan.tips[0, 1]:.6f}) m",
        f"target         ({target[0]:.6f}, {target[1]:.6f}) m",
        f"base rotation  {np.degrees(plan.delta_phi0):.6f} deg by {plan.loops} loop(s)",
        f"joint travel   {plan.joint_travel:.6f} rad",
        f"straight path  {plan.straight_length:.6f} m",
        "end posture    " + ", ".join(f"{v:.6f}" for v in np.degrees(plan.end_posture)) + " deg",
        f"tip error      {plan.error:.3e} m",
        f"figure         {figure_path}",
    ]
    if args.animate:
        lines.append(f"animation      {animate_reach(robot, plan, out / 'reach.gif')}")
    from .results import write_npz

    write_npz(
        out / "reach.npz",
        postures_rad=plan.postures,
        tips_m=plan.tips,
        phase=plan.phase,
        joint_waypoints_rad=plan.joint_waypoints,
        target_m=plan.target,
    )
    print("\n".join(lines))
    return 0


def add_reach_command(subparsers) -> None:
    """Register ``spacearm reach ROBOT.yaml --from PHI0,PHI1,..,PHIn --to X,Y``."""
    parser = subparsers.add_parser(
        "reach",
        help="plan how the tip reaches an inertial point (straight path, or base reorientation first)",
        description=(
            "Plan a motion that brings the tip to an inertial target (Umetani & Yoshida 1990, sec. 3.2, "
            "points B and C): a straight tip path when the target is in the current Straight-Path "
            "workspace, otherwise a cyclic joint maneuver that turns the base first. Writes reach.png "
            "(and reach.npz with the whole history) into --out. Exit 2 for a target outside the "
            "Maximum Reachable space."
        ),
    )
    parser.add_argument("robot", help="robot YAML file, e.g. configs/umetani1990.yaml")
    parser.add_argument(
        "--from",
        dest="start",
        required=True,
        metavar="PHI0,PHI1,..",
        help="start posture: base attitude then joint angles, in DEGREES (radians with --radians); "
        "write --from=-10,20,30 when the first value is negative",
    )
    parser.add_argument(
        "--to", dest="target", required=True, metavar="X,Y",
        help="target in the inertial frame, m, origin at the system centroid (--to=-2,1 for a negative x)",
    )
    parser.add_argument("--radians", action="store_true", help="read --from in radians")
    parser.add_argument("--out", default="results/reach", help="output folder (default results/reach)")
    parser.add_argument("--animate", action="store_true", help="also write reach.gif")
    parser.set_defaults(func=_cmd_reach)
