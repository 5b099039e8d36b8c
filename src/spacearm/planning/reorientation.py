"""Reorienting the base by cyclic joint maneuvers (Umetani & Yoshida 1990, section 3.2).

Fig. 5 of the paper: point C "can be reached after reorienting the base by a suitable
cyclic maneuver". This module plans that maneuver.

Reorientation (`plan_reorientation`). Along a closed joint-space loop the
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
   (`spacearm.motion.integrate_joint_path`): squared rotation error, total
   joint travel, soft penalties on joint limits and on the excursion from q0; all
   candidates in one vmapped, jitted call;
3. finishes each candidate with Newton steps on a scale factor of the loop about q0,
   so that the integrated rotation is delta_phi0, and keeps the valid candidate (inside
   the joint limits and the excursion bound) with the least joint travel.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax

from .._core.batching import shapes_of
from .._core.errors import ConfigError
from .._core.groups import SO2, SO3
from ..models.family import family_of
from ..motion import integrate_joint_path
from ._loop_steps import LoopSteps, plan_loop
from .spatial_reorientation import plan_spatial_reorientation

__all__ = [
    "LoopSettings",
    "ReorientationLoop",
    "check_posture",
    "compile_loop_optimizer",
    "plan_reorientation",
    "plan_reorientation_details",
    "rotation_curl",
]


@dataclasses.dataclass(frozen=True)
class LoopSettings:
    """Settings of the reorientation planner (only the counts that fix shapes are compiled in).

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


def _connection(robot, q: jax.Array) -> jax.Array:
    """The one-form of eq. (5): d phi0 = omega(q) . dq with omega = -I_M / I_S, ``(n,)`` (the
    family's attitude-rate map of its SO(2) attitude)."""
    return family_of(robot).attitude_rate_map(robot, q)[0]


def rotation_curl(robot, joint_angles: jax.Array) -> jax.Array:
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


def _loop_basis(settings) -> np.ndarray:
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


def _loop_rotation(robot, q0: jax.Array, points: jax.Array) -> jax.Array:
    """Base rotation of one pass over the closed polygon ``points`` ``(k+1, n)``, rad."""

    phi_start = jnp.concatenate([jnp.zeros((1,), q0.dtype), q0])
    # Loop segments are short (~0.1 rad): 10 Gauss points per segment are exact to rounding
    # there; the returned waypoints are checked with the integrator's defaults.
    return integrate_joint_path(robot, phi_start, points, nodes=10, pieces=1)[0]


class _LoopShape(NamedTuple):
    """The settings that fix the optimizer's shapes (the only static part of its compile key)."""

    samples_per_loop: int
    harmonics: int
    loop_counts: tuple[int, ...]
    directions: int


def _split(settings: LoopSettings) -> tuple[_LoopShape, dict]:
    """Static shape settings, and the rest as host arrays (traced: new values do not recompile)."""
    shape = _LoopShape(settings.samples_per_loop, settings.harmonics, tuple(settings.loop_counts), settings.directions)
    floats = ("learning_rate", "max_excursion", "limit_margin", "room_fraction", "travel_weight")
    options = {name: np.asarray(getattr(settings, name), float) for name in floats}
    options.update(steps=np.asarray(settings.steps, np.int32), newton_steps=np.asarray(settings.newton_steps, np.int32))
    return shape, options


class _LoopProblem(NamedTuple):
    """What every candidate loop of one request shares (traced arrays, `_loop_problem`)."""

    robot: Any  # one design
    q0: jax.Array  # (n,) start joints, rad
    delta: jax.Array  # the requested base rotation, rad
    magnitude: jax.Array  # |delta|, at least 1e-9, rad
    sigma: jax.Array  # the curl's top singular value at q0, rad / rad^2
    e1: jax.Array  # (n,) its left singular vector
    e2: jax.Array  # (n,) its right singular vector
    sign: jax.Array  # -1 for delta >= 0, else +1: the orientation of the initial circles
    basis: jax.Array  # (k+1, 2 M) the loop basis (`_loop_basis`)
    lower: jax.Array  # (n,) joint limits, rad
    upper: jax.Array
    room_up: jax.Array  # (n,) allowed displacement from q0 upwards, rad
    room_down: jax.Array  # (n,) and downwards
    travel_weight: jax.Array


def _curl_plane(robot, q0: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """The plane and strength of the curl at q0 (top singular pair of Omega): ``(sigma, e1, e2)``."""
    omega = rotation_curl(robot, q0)
    u_mat, sig, vt = jnp.linalg.svd(omega)
    sigma = jnp.maximum(sig[0], 1e-12)
    return sigma, u_mat[:, 0], vt[0]  # Omega e2 = sigma e1; e1 . e2 = 0 (Omega antisymmetric)


def _loop_problem(robot, q0: jax.Array, delta: jax.Array, opt: dict, settings: _LoopShape) -> _LoopProblem:
    """The curl plane at q0, the loop basis, and the box the loops must stay in."""
    dtype = q0.dtype
    basis = jnp.asarray(_loop_basis(settings), dtype)
    lower = jnp.asarray(robot.joint_lower, dtype)
    upper = jnp.asarray(robot.joint_upper, dtype)
    sigma, e1, e2 = _curl_plane(robot, q0)
    # A loop q0 + r[(1 - cos t) c + sin t c_perp] with (c, c_perp) a rotation of (e1, e2)
    # encloses area pi r^2 clockwise in the (c, c_perp) orientation: its rotation is about
    # -sigma pi r^2. Flip c_perp for the requested sign.
    sign = jnp.where(delta >= 0, -1.0, 1.0).astype(dtype)
    magnitude = jnp.maximum(jnp.abs(delta), 1e-9)
    # Allowed displacement from q0 per joint and direction: the excursion bound and the
    # joint limits, shrunk by `room_fraction` so the final Newton scaling has room. The box
    # contains q0 and is convex, so the loop q0 + c x(s) stays inside for every scale c
    # up to `_largest_scale` (x).
    room_up = opt["room_fraction"] * jnp.clip(upper - opt["limit_margin"] - q0, 0.0, opt["max_excursion"])
    room_down = opt["room_fraction"] * jnp.clip(q0 - (lower + opt["limit_margin"]), 0.0, opt["max_excursion"])
    return _LoopProblem(
        robot, q0, delta, magnitude, sigma, e1, e2, sign, basis, lower, upper, room_up, room_down, opt["travel_weight"]
    )


def _initial_loop(problem: _LoopProblem, harmonics: int, alpha, r) -> jax.Array:
    """``(2 M, n)`` Fourier coefficients, normalized by r, of the circle of radius r about
    q0 + r c, c at angle ``alpha`` from e1 in the curl plane, turning the requested way."""
    e1, e2 = problem.e1, problem.e2
    c = jnp.cos(alpha) * e1 + jnp.sin(alpha) * e2
    c_perp = problem.sign * (-jnp.sin(alpha) * e1 + jnp.cos(alpha) * e2)
    coeffs = jnp.zeros((2 * harmonics, problem.q0.shape[0]), problem.q0.dtype)
    coeffs = coeffs.at[0].set(r * c).at[harmonics].set(r * c_perp)
    return coeffs / r  # normalized by r


def _loop_points(problem: _LoopProblem, normalized, r, scale=1.0) -> jax.Array:
    """``(k+1, n)`` waypoints of the loop with coefficients ``r * normalized``, scaled about q0."""
    return problem.q0 + scale * r * (problem.basis @ normalized)


def _largest_scale(problem: _LoopProblem, offsets) -> jax.Array:
    """The largest c for which q0 + c ``offsets`` ``(k+1, n)`` stays in the allowed box."""
    ratio_up = jnp.where(offsets > 0, problem.room_up / jnp.where(offsets > 0, offsets, 1.0), jnp.inf)
    ratio_down = jnp.where(offsets < 0, problem.room_down / jnp.where(offsets < 0, -offsets, 1.0), jnp.inf)
    return jnp.min(jnp.minimum(ratio_up, ratio_down))


def _project(problem: _LoopProblem, normalized, r) -> jax.Array:
    """Projection onto the allowed box by shrinking the loop about q0."""
    return normalized * jnp.minimum(1.0, _largest_scale(problem, r * (problem.basis @ normalized)))


def _loop_objective(problem: _LoopProblem, normalized, r, count) -> jax.Array:
    """Squared rotation error (relative to the request) plus the weighted squared joint travel
    of ``count`` passes (relative to the circle that would turn the base by the request)."""
    points = _loop_points(problem, normalized, r)
    rotation = count * _loop_rotation(problem.robot, problem.q0, points)
    rot_err = (rotation - problem.delta) / problem.magnitude
    travel = count * _path_length(points) / (2.0 * jnp.pi * jnp.sqrt(problem.magnitude / (jnp.pi * problem.sigma)))
    return rot_err**2 + problem.travel_weight * travel**2


def _cosine_schedule(learning_rate, steps, dtype):
    """optax.cosine_decay_schedule(learning_rate, steps, alpha=0.02), with ``steps`` traced."""

    def schedule(count):
        decay_steps = jnp.maximum(steps, 1).astype(dtype)
        fraction = jnp.minimum(count.astype(dtype), decay_steps) / decay_steps
        return learning_rate * (0.98 * 0.5 * (1.0 + jnp.cos(jnp.pi * fraction)) + 0.02)

    return schedule


def _refine_loop(problem: _LoopProblem, optimizer, steps, params, r, count) -> jax.Array:
    """``steps`` projected Adam steps on `_loop_objective` from ``params``."""
    state = optimizer.init(params)
    grad_fn = jax.grad(functools.partial(_loop_objective, problem))

    def step(_, carry):
        params, state = carry
        grad = grad_fn(params, r, count)
        updates, state = optimizer.update(grad, state, params)
        return _project(problem, optax.apply_updates(params, updates), r), state

    params, _ = jax.lax.fori_loop(0, steps, step, (params, state))
    return params


def _rotation_scale(problem: _LoopProblem, params, r, count, newton_steps) -> jax.Array:
    """Newton on the scale factor c of the loop about q0: count * R(c) = delta (c in [0.25, 4])."""

    def rotation_at(scale):
        return count * _loop_rotation(problem.robot, problem.q0, _loop_points(problem, params, r, scale))

    def newton(_, scale):
        value, slope = jax.value_and_grad(rotation_at)(scale)
        safe = jnp.where(jnp.abs(slope) > 1e-300, slope, 1.0)
        return jnp.clip(scale - (value - problem.delta) / safe, 0.25, 4.0)

    return jax.lax.fori_loop(0, newton_steps, newton, jnp.asarray(1.0, problem.q0.dtype))


def _candidate_record(problem: _LoopProblem, points, count) -> dict:
    """The candidate's loop ``points`` with its total rotation, travel, excursion and limit violation."""
    rotation = count * _loop_rotation(problem.robot, problem.q0, points)
    upper, lower = problem.upper, problem.lower
    violation = jnp.max(jnp.concatenate([jax.nn.relu(points - upper).ravel(), jax.nn.relu(lower - points).ravel()]))
    return dict(
        points=points,
        rotation=rotation,
        travel=count * _path_length(points),
        excursion=jnp.max(jnp.abs(points - problem.q0)),
        limit_violation=violation,
    )


def _solve_candidate(problem: _LoopProblem, optimizer, options: dict, harmonics: int, alpha, r, count) -> dict:
    """One candidate: the circle at ``alpha`` of radius ``r``, refined, then scaled to the request."""
    params = _project(problem, _initial_loop(problem, harmonics, alpha, r), r)
    params = _refine_loop(problem, optimizer, options["steps"], params, r, count)
    scale = _rotation_scale(problem, params, r, count, options["newton_steps"])
    return _candidate_record(problem, _loop_points(problem, params, r, scale), count)


@functools.partial(jax.jit, static_argnames=("settings",))
def _optimize_loops(robot, q0: jax.Array, delta: jax.Array, options: dict, settings: _LoopShape):
    """Optimize one loop per (repetition count, centre direction) candidate.

    ``settings`` holds the shape settings (static); ``options`` the step counts, rate,
    bounds and weights (traced: new values do not recompile).

    Returns a dict of per-candidate arrays (leading axis: candidates): ``points``
    ``(C, k+1, n)``, ``loops`` ``(C,)``, ``rotation`` (total, rad), ``travel`` (total, rad),
    ``excursion`` (max |q - q0|, rad), ``limit_violation`` (rad, 0 when inside).
    """
    dtype = q0.dtype
    opt = {
        name: value.astype(dtype) if name not in ("steps", "newton_steps") else value for name, value in options.items()
    }
    problem = _loop_problem(robot, q0, delta, opt, settings)
    counts = np.repeat(np.asarray(settings.loop_counts), settings.directions)
    alphas = np.tile(2.0 * np.pi * np.arange(settings.directions) / settings.directions, len(settings.loop_counts))
    counts_j = jnp.asarray(counts, dtype)
    radius = jnp.sqrt(problem.magnitude / (counts_j * jnp.pi * problem.sigma))
    radius = jnp.minimum(radius, 0.5 * opt["max_excursion"])
    optimizer = optax.adam(_cosine_schedule(opt["learning_rate"], options["steps"], dtype))
    solve = functools.partial(_solve_candidate, problem, optimizer, options, settings.harmonics)
    result = jax.vmap(solve)(jnp.asarray(alphas, dtype), radius, counts_j)
    result["loops"] = jnp.asarray(counts)
    return result


@dataclasses.dataclass(frozen=True)
class ReorientationLoop:
    """A planned reorientation maneuver (see `plan_reorientation_details`).

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


def check_posture(robot, phi_start) -> np.ndarray:
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


def compile_loop_optimizer(robot, settings: LoopSettings = LoopSettings()) -> None:
    """Compile, without running, the loop optimizer `plan_reorientation_details`
    runs for this design's shapes and ``settings``; a later plan finds the program.

    XLA compiles outside Python's GIL, so a caller can compile this on a second core (in
    a thread) while it does other work (``planning.plan_reach`` does).
    """
    dtype = jnp.result_type(float)
    q0, delta = jax.ShapeDtypeStruct((robot.n_links,), dtype), jax.ShapeDtypeStruct((), dtype)
    shape, options = _split(settings)
    _optimize_loops.lower(shapes_of(robot), q0, delta, shapes_of(options), shape).compile()


def plan_reorientation_details(
    robot,
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
        settings: `LoopSettings` (only the loop's sample, harmonic, repetition and
            direction counts are compiled in; the rest is traced).
        tolerance: largest accepted |rotation error| of the integrated waypoints, rad
            (default 1e-9 in float64, 1e-4 in float32).

    Returns:
        a `ReorientationLoop`.

    Raises:
        ConfigError: bad input, or no candidate loop reaches the rotation within the
            joint limits and the excursion bound (raise ``loop_counts`` or
            ``max_excursion``).
    """

    return plan_loop(_PLANAR_LOOP_STEPS, robot, phi_start, delta_phi0, settings, tolerance=tolerance)


def _planar_check(robot, phi_start, delta_phi0, settings, tolerance=None) -> dict:
    phi = check_posture(robot, phi_start)
    delta = float(delta_phi0)
    if not math.isfinite(delta):
        raise ConfigError(f"delta_phi0: must be finite, got {delta_phi0!r}")
    if tolerance is None:
        tolerance = 1e-9 if jax.config.jax_enable_x64 else 1e-4
    return {"robot": robot, "q0": phi[1:], "delta": delta, "settings": settings, "tolerance": tolerance}


def _planar_still(job: dict) -> ReorientationLoop | None:
    if job["delta"] != 0.0:
        return None
    still = np.stack([job["q0"], job["q0"]])
    return ReorientationLoop(still, still, 0, 0.0, 0.0, 0.0, 0.0)


def _planar_candidates(job: dict) -> dict:
    """The optimized loops; ``error`` is inf where a loop leaves the limits or the excursion bound."""
    dtype = jnp.result_type(float)
    settings, delta = job["settings"], job["delta"]
    shape, options = _split(settings)
    result = _optimize_loops(job["robot"], jnp.asarray(job["q0"], dtype), jnp.asarray(delta, dtype), options, shape)
    result = jax.tree_util.tree_map(np.asarray, result)
    result["raw_error"] = np.abs(result["rotation"] - delta)
    inside = (
        (result["limit_violation"] <= 0.0)
        & (result["excursion"] <= settings.max_excursion)
        & np.isfinite(result["travel"])
    )
    result["error"] = np.where(inside, result["raw_error"], np.inf)
    return result


def _planar_failure(job: dict, result: dict) -> str:
    settings, delta = job["settings"], job["delta"]
    return (
        f"delta_phi0: no loop turns the base by {math.degrees(delta):.6g} deg within the joint limits, "
        f"max_excursion = {settings.max_excursion:.3g} rad and at most {max(settings.loop_counts)} repetitions "
        f"(best rotation error {np.min(result['raw_error']):.3g} rad); allow more repetitions or a larger excursion"
    )


def _planar_record(job: dict, result: dict, best: int) -> ReorientationLoop:
    q0, delta, tolerance = job["q0"], job["delta"], job["tolerance"]
    loop = result["points"][best]
    loops = int(result["loops"][best])
    waypoints = np.concatenate([loop[:1]] + [loop[1:]] * loops, axis=0)
    waypoints[-1] = q0
    # One pass with the integrator's full accuracy; the passes are identical and eq. (5) does
    # not depend on phi0, so N passes turn the base N times as far (one compiled shape for
    # every N; tests integrate the whole waypoint array independently).
    loop_start = np.r_[0.0, q0]
    rotation = loops * float(integrate_joint_path(job["robot"], jnp.asarray(loop_start), jnp.asarray(loop))[0])
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


_PLANAR_LOOP_STEPS = LoopSteps(
    check=_planar_check,
    still=_planar_still,
    candidates=_planar_candidates,
    failure=_planar_failure,
    record=_planar_record,
)


def plan_reorientation(robot, phi_start, delta_phi0, **options) -> np.ndarray:
    """Joint waypoints of a closed maneuver that turns the base by ``delta_phi0``.

    Spatial robots: ``plan_reorientation(robot, q_start, target_rotation)`` returns a
    closed joint path after which the bus attitude is ``R0 @ target_rotation`` to
    1e-9 rad (`spacearm.planning.spatial_reorientation.plan_spatial_reorientation`;
    options are its settings). The rest of this docstring is the planar case.

    A closed joint-space loop through q0 = phi_start[1:], repeated N times where one
    loop within the joint limits and ``max_excursion`` cannot turn the base far enough,
    found by optax through the integrator of eq. (5) and finished by Newton steps on
    the loop's scale, so that ``integrate_joint_path(robot, phi_start, waypoints)``
    ends at [phi0 + delta_phi0, q0] to ~1e-12 rad (accepted at 1e-9).

    Args:
        robot: one design.
        phi_start: ``(n+1,)`` start posture [phi0, phi1..phin], rad.
        delta_phi0: base rotation, rad.
        **options: ``settings`` (`LoopSettings`), ``tolerance`` (rad).

    Returns:
        ``(k, n)`` joint waypoints, rad, joined by straight joint-space segments; the
        first and last rows equal phi_start[1:].
    """
    planner = _REORIENTATION_PLANNERS.get(family_of(robot).attitude.name)
    if planner is None:
        raise ConfigError(f"robot: no reorientation planner for the {family_of(robot).name!r} family")
    return planner(robot, phi_start, delta_phi0, **options)


def _plan_planar_reorientation(robot, phi_start, delta_phi0, **options) -> np.ndarray:
    return plan_reorientation_details(robot, phi_start, delta_phi0, **options).waypoints


# The loop planner of each base-attitude group.
_REORIENTATION_PLANNERS = {SO2.name: _plan_planar_reorientation, SO3.name: plan_spatial_reorientation}
