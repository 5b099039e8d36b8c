"""Turning the bus of a spatial arm by a target rotation with a closed joint loop.

Along a closed joint path the joints come back but the bus turns (the attitude ODE
R' = R [C_w(q) q']x is nonholonomic; `spacearm.motion.attitude`). In 3-D the net
rotation of a loop is a rotation, not an angle, and small loops turn the bus about
axes set by the curvature of C_w; three independent rotation components need loops
that use several joint planes at once. A loop repeated N times turns the bus by the
N-th power of its rotation (R_end = R0 D^N: the ODE does not depend on R), so a target
rotation exp([phi]x) is reached by any loop whose rotation is exp([phi/N]x), repeated
N times.

The planner, for candidate repetition counts N (all candidates in one batch, one jit):

1. parametrizes a loop through q0 by Fourier coefficients, q(s) = q0 + sum_h
   a_h (cos 2 pi h s - 1) + b_h sin 2 pi h s, sampled at ``segments + 1`` waypoints
   (straight joint segments between them); joints the robot holds (the family's
   ``moving_joints``: a tree focused on some arms) have no coefficients and stay at q0;
2. minimizes with optax Adam, through the integrator, the squared rotation error
   |log(D_N^T D(loop))|^2 (D_N = exp([phi/N]x)) plus a small joint-travel term and
   soft penalties keeping every waypoint inside the joint limits less a margin (the
   segments are straight, so the whole loop then stays inside the box);
3. finishes with minimum-norm Gauss-Newton steps on the 3-vector residual
   (dc = -J^T (J J^T + mu 1)^-1 r): 3 equations in 2 H n unknowns, quadratic
   convergence to rounding from the Adam result. Both phases run in one loop whose
   every step evaluates the residual and its 3-row Jacobian once (the Adam gradient
   is 2 J^T r plus the cheap terms), so the chain passes and their adjoints are
   compiled once;
4. checks each candidate with `spacearm.integrate_joint_path` at 4 times the
   optimizer's Magnus steps (converged to ~1e-14 rad for these loops):
   the rotation error of the repeated loop and the joint limits; returns the valid
   candidate with the least joint travel.

Reference: the closed-loop (cyclic) base reorientation of Vafa & Dubowsky (1990) and
Umetani & Yoshida (1990, section 3.2), here on SO(3).
"""

from __future__ import annotations

import dataclasses
import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax

from .._core.batching import shapes_of
from .._core.errors import ConfigError
from ..models.family import family_of
from ..motion.attitude import DEFAULT_ORDER, DEFAULT_STEPS, bus_rate_map, expm, log, path_rotation
from ..motion.joint_paths import integrate_joint_path
from ._loop_steps import LoopSteps, plan_loop

__all__ = [
    "SpatialLoopSettings",
    "SpatialReorientation",
    "compile_spatial_loop_optimizer",
    "plan_spatial_reorientation",
    "plan_spatial_reorientation_details",
    "repeat_loop",
]


@dataclasses.dataclass(frozen=True)
class SpatialLoopSettings:
    """Settings of the spatial reorientation planner.

    Only ``segments``, ``harmonics`` and the Magnus step counts fix the optimizer's
    shapes (a new value compiles once); the step counts of the optimizer, its rate,
    weights and margin are traced, the rest is host-side.

    Attributes:
        segments: straight joint segments per loop.
        harmonics: Fourier harmonics of the loop.
        loop_counts: candidate numbers of repetitions N.
        seeds: random starting loops per repetition count.
        initial_size: rms size of the random starting coefficients, rad.
        adam_steps, learning_rate: the optax Adam phase.
        newton_steps: Gauss-Newton steps that finish every candidate.
        travel_weight: weight of the joint travel (rad) against the squared rotation
            error (rad^2) in the Adam phase, per unit of |phi / N|^2.
        limit_margin: the loop keeps this far inside finite joint limits, rad (m).
        magnus_steps: Magnus steps per segment in the optimizer (the default of
            `spacearm.integrate_joint_path`); the final check uses 4 times as many.
        tolerance: accepted geodesic error of the final rotation, rad.
        seed: random seed of the starting loops.
    """

    segments: int = 24
    harmonics: int = 2
    loop_counts: tuple[int, ...] = (1, 2, 4, 8)
    seeds: int = 2
    initial_size: float = 0.3
    adam_steps: int = 100
    learning_rate: float = 0.02
    newton_steps: int = 12
    travel_weight: float = 1e-3
    limit_margin: float = 0.05
    magnus_steps: int = DEFAULT_STEPS
    tolerance: float = 1e-9
    seed: int = 0


@dataclasses.dataclass(frozen=True)
class SpatialReorientation:
    """A planned reorientation.

    Attributes:
        waypoints: ``(N segments + 1, n)`` the closed joint path (first and last rows q0).
        loop: ``(segments + 1, n)`` one loop; ``waypoints`` repeats it ``repetitions`` times.
        repetitions: N.
        rotation_error: geodesic distance between the reached and the target rotation, rad.
        joint_travel: sum of the segment lengths in joint space, rad.
        candidates: ``(count, 3)`` per candidate: N, rotation error (rad), joint travel.
    """

    waypoints: np.ndarray
    loop: np.ndarray
    repetitions: int
    rotation_error: float
    joint_travel: float
    candidates: np.ndarray


def _basis(segments: int, harmonics: int) -> np.ndarray:
    """``(segments + 1, 2 H)``: cos(2 pi h s) - 1 and sin(2 pi h s) at the waypoints."""
    s = np.arange(segments + 1) / segments
    h = np.arange(1, harmonics + 1)
    basis = np.concatenate([np.cos(2 * np.pi * h * s[:, None]) - 1.0, np.sin(2 * np.pi * h * s[:, None])], axis=1)
    basis[-1] = 0.0  # closed exactly
    return basis


def repeat_loop(loop: np.ndarray, repetitions: int) -> np.ndarray:
    """``(k, n)`` closed loop -> ``(N (k - 1) + 1, n)``, the loop run N times."""
    loop = np.asarray(loop)
    return np.concatenate([np.tile(loop[:-1], (repetitions, 1)), loop[-1:]], axis=0)


def _travel(points):
    d = points[1:] - points[:-1]
    sq = jnp.sum(d * d, axis=-1)
    return jnp.sum(jnp.sqrt(sq + 1e-30))


class _LoopShape(NamedTuple):
    """The settings that fix the optimizer's array shapes (the only static part of its compile key)."""

    segments: int
    harmonics: int
    magnus_steps: int


def _split(settings: SpatialLoopSettings) -> tuple[_LoopShape, dict]:
    """Static shape settings, and the rest as host arrays (traced: new values do not recompile)."""
    shape = _LoopShape(settings.segments, settings.harmonics, settings.magnus_steps)
    options = {
        "learning_rate": np.asarray(settings.learning_rate, float),
        "travel_weight": np.asarray(settings.travel_weight, float),
        "limit_margin": np.asarray(settings.limit_margin, float),
        "adam_steps": np.asarray(settings.adam_steps, np.int32),
        "newton_steps": np.asarray(settings.newton_steps, np.int32),
    }
    return shape, options


@functools.partial(jax.jit, static_argnames=("shape",))
def _optimize(robot, q0, target, counts, coefficients, lower, upper, options, shape: _LoopShape):
    """Adam then Gauss-Newton for every candidate: per loop the rotation vector
    log(target) / N, ``counts (c,)`` the candidates' N.

    One loop of ``adam_steps + newton_steps`` iterations, each with one evaluation of the
    residual and its 3-row Jacobian (reverse mode): the Adam steps use the gradient
    2 J^T r / |phi / N|^2 plus the travel and limit terms, the Gauss-Newton steps J and r.
    The residual's chain passes and their adjoints are compiled once for both phases.
    Step counts, rates and weights are traced (``options``): only ``shape`` is static.
    """
    dtype = q0.dtype
    targets = log(target)[None, :] / counts[:, None]  # (c, 3)
    basis = jnp.asarray(_basis(shape.segments, shape.harmonics), dtype)
    omega_map = functools.partial(bus_rate_map, robot)
    margin = options["limit_margin"].astype(dtype)
    travel_weight = options["travel_weight"].astype(dtype)
    adam_steps = options["adam_steps"]
    optimizer = optax.adam(options["learning_rate"].astype(dtype))
    shape_c = coefficients.shape[1:]
    eye = jnp.eye(3, dtype=dtype)
    # Held joints (a focused tree) have no coefficients that act: they stay at q0 exactly.
    moving = jnp.asarray(family_of(robot).moving_joints(robot), dtype)

    def points(c):
        return q0 + basis @ (c.reshape(shape_c) * moving)  # (segments + 1, n)

    def penalty(c):
        p = points(c)
        over = jnp.maximum(p - (upper - margin), 0.0) + jnp.maximum((lower + margin) - p, 0.0)
        return travel_weight * _travel(p) + 100.0 * jnp.sum(over * over)

    def one(c, target):
        inverse = jnp.swapaxes(expm(target), -1, -2)
        scale = jnp.sum(target * target) + 1e-12

        def residual(c):
            return log(inverse @ path_rotation(omega_map, points(c), shape.magnus_steps, DEFAULT_ORDER))

        def step(k, carry):
            c, state = carry
            r, pullback = jax.vjp(residual, c)
            J = jax.vmap(pullback)(eye)[0]  # (3, 2 H n)
            g = 2.0 * (J.T @ r) / scale + jax.grad(penalty)(c)
            updates, moved = optimizer.update(g, state, c)
            JJ = J @ J.T
            gauss_newton = c - J.T @ jnp.linalg.solve(JJ + 1e-12 * jnp.trace(JJ) * eye, r)
            adam = k < adam_steps
            c = jnp.where(adam, optax.apply_updates(c, updates), gauss_newton)
            state = jax.tree_util.tree_map(lambda a, b: jnp.where(adam, a, b), moved, state)
            return c, state

        c = c.reshape(-1)
        c, _ = jax.lax.fori_loop(0, adam_steps + options["newton_steps"], step, (c, optimizer.init(c)))
        return c.reshape(shape_c), points(c)

    return jax.vmap(one)(coefficients, targets)


def compile_spatial_loop_optimizer(robot, settings: SpatialLoopSettings | None = None) -> None:
    """Compile, without running, the loop optimizer `plan_spatial_reorientation_details`
    runs for this design's shapes and ``settings``; a later plan finds the program.

    XLA compiles outside Python's GIL, so a caller can compile this on a second core (in
    a thread) while it does other work (``planning.plan_reach`` does).
    """
    settings = settings or SpatialLoopSettings()
    shape, options = _split(settings)
    n, count = robot.n_joints, len(settings.loop_counts) * settings.seeds
    dtype = jnp.result_type(float)
    s = lambda *dims: jax.ShapeDtypeStruct(dims, dtype)
    _optimize.lower(
        shapes_of(robot),
        s(n),
        s(3, 3),
        s(count),
        s(count, 2 * settings.harmonics, n),
        s(n),
        s(n),
        shapes_of(options),
        shape,
    ).compile()


@jax.jit
def _as_rotation(vector):
    return expm(vector)


def _rotation_errors(target: np.ndarray, reached: np.ndarray) -> np.ndarray:
    """`geodesic_distance` of concrete rotations, in NumPy on the host (no small program to compile)."""
    E = target.T @ reached
    s = 0.5 * np.linalg.norm(
        np.stack([E[..., 2, 1] - E[..., 1, 2], E[..., 0, 2] - E[..., 2, 0], E[..., 1, 0] - E[..., 0, 1]], -1), axis=-1
    )
    return np.arctan2(s, 0.5 * (np.trace(E, axis1=-2, axis2=-1) - 1.0))


def _check_inputs(robot, q_start, target_rotation):
    n = robot.n_joints
    if robot.batch_shape:
        raise ConfigError("plan_reorientation: one design at a time (got a batch of designs)")
    q0 = np.asarray(q_start, dtype=float)
    if q0.shape != (n,):
        raise ConfigError(f"q_start: expected shape ({n},) for a {n}-joint arm, got {q0.shape}")
    target = np.asarray(target_rotation, dtype=float)
    if target.shape == (3,) and np.all(np.isfinite(target)):  # a rotation vector
        target = np.asarray(_as_rotation(target))
    if target.shape != (3, 3) or not np.all(np.isfinite(target)):
        raise ConfigError(
            f"target_rotation: expected a (3, 3) rotation matrix or a (3,) rotation vector, got shape {target.shape}"
        )
    if np.max(np.abs(target.T @ target - np.eye(3))) > 1e-9 or np.linalg.det(target) < 0:
        raise ConfigError("target_rotation: not a rotation matrix (R^T R != 1 or det R < 0)")
    lower, upper = np.asarray(robot.joint_lower, float), np.asarray(robot.joint_upper, float)
    if np.any(q0 < lower) or np.any(q0 > upper):
        raise ConfigError("q_start: outside the joint limits")
    return q0, target, lower, upper


def plan_spatial_reorientation_details(
    robot, q_start, target_rotation, settings: SpatialLoopSettings | None = None
) -> SpatialReorientation:
    """Plan a closed joint path after which the bus attitude is R0 @ target_rotation.

    Args:
        robot: one spatial design.
        q_start: ``(n,)`` joints at the start (inside the limits).
        target_rotation: ``(3, 3)`` rotation in the bus frame (or a ``(3,)`` rotation
            vector), to be reached to ``settings.tolerance`` (1e-9 rad).
        settings: `SpatialLoopSettings`; only the segment, harmonic and Magnus step
            counts are compiled in, the other fields are traced or host-side.

    Raises:
        ConfigError: bad inputs, or no candidate loop reached the tolerance within the
            joint limits (the message gives the best error).
    """
    return plan_loop(_SPATIAL_LOOP_STEPS, robot, q_start, target_rotation, settings)


def _spatial_check(robot, q_start, target_rotation, settings) -> dict:
    settings = settings or SpatialLoopSettings()
    if not isinstance(settings, SpatialLoopSettings):
        raise ConfigError(f"settings: expected SpatialLoopSettings for a spatial robot, got {type(settings).__name__}")
    q0, target, lower, upper = _check_inputs(robot, q_start, target_rotation)
    return {
        "robot": robot,
        "q0": q0,
        "target": target,
        "lower": lower,
        "upper": upper,
        "settings": settings,
        "tolerance": settings.tolerance,
    }


def _spatial_candidates(job: dict) -> dict:
    """The optimized loops, checked through the public integrator at 4 times the Magnus steps."""
    robot, q0, target, settings = job["robot"], job["q0"], job["target"], job["settings"]
    lower, upper = job["lower"], job["upper"]
    n = robot.n_joints
    dtype = jnp.result_type(float)
    counts = np.repeat(np.asarray(settings.loop_counts), settings.seeds)
    rng = np.random.default_rng(settings.seed)
    coefficients = settings.initial_size * rng.normal(size=(len(counts), 2 * settings.harmonics, n))
    coefficients = coefficients * family_of(robot).moving_joints(robot)  # held joints stay at q0
    finite = lambda x: np.where(np.isfinite(x), x, np.sign(x) * 1e3)
    shape, options = _split(settings)
    _, loops = _optimize(
        robot,
        jnp.asarray(q0, dtype),
        jnp.asarray(target, dtype),
        jnp.asarray(counts, dtype),
        jnp.asarray(coefficients, dtype),
        jnp.asarray(finite(lower), dtype),
        jnp.asarray(finite(upper), dtype),
        options,
        shape,
    )
    loops = np.array(loops)
    # Check every candidate through the public integrator, converged (one batch):
    # the loop's rotation D, then D^N (the repeated loop turns the bus by D^N).
    loops[:, 0] = loops[:, -1] = q0
    D, _ = integrate_joint_path(robot, loops[:, 0], loops, steps=4 * settings.magnus_steps)
    reached = np.asarray(D)
    for power in range(2, int(counts.max()) + 1):
        reached = np.where((counts >= power)[:, None, None], reached @ np.asarray(D), reached)
    errors = _rotation_errors(target, reached)
    inside = np.all((loops >= lower) & (loops <= upper), axis=(1, 2))
    travel = counts * np.sum(np.linalg.norm(np.diff(loops, axis=1), axis=2), axis=1)
    error = np.where(inside, errors, np.inf)
    return {"loops": loops, "counts": counts, "error": error, "overall_error": errors, "travel": travel}


def _spatial_failure(job: dict, candidates: dict) -> str:
    error, overall = candidates["error"], candidates["overall_error"]
    inside = np.isfinite(error)
    best = f"best inside them {float(np.min(error)):.3g} rad" if inside.any() else "none stayed inside them"
    return (
        f"plan_reorientation: no loop reached the target rotation to {job['settings'].tolerance:g} rad inside the "
        f"joint limits ({best}; best of all {len(error)} loops {float(np.nanmin(overall)):.3g} rad, "
        f"{int((~inside).sum())} left the limits); try more loop_counts or harmonics"
    )


def _spatial_record(job: dict, candidates: dict, best: int) -> SpatialReorientation:
    loop = candidates["loops"][best]
    repetitions = int(candidates["counts"][best])
    table = np.stack([candidates["counts"], candidates["error"], candidates["travel"]], axis=1)
    return SpatialReorientation(
        waypoints=repeat_loop(loop, repetitions),
        loop=loop,
        repetitions=repetitions,
        rotation_error=float(table[best, 1]),
        joint_travel=float(table[best, 2]),
        candidates=table,
    )


_SPATIAL_LOOP_STEPS = LoopSteps(
    check=_spatial_check,
    still=lambda job: None,
    candidates=_spatial_candidates,
    failure=_spatial_failure,
    record=_spatial_record,
)


def plan_spatial_reorientation(robot, q_start, target_rotation, **options) -> np.ndarray:
    """``(k, n)`` closed joint path (first and last rows ``q_start``) turning the bus by
    ``target_rotation`` (bus frame): after it the attitude is ``R0 @ target_rotation``
    to 1e-9 rad. Options are `SpatialLoopSettings` fields."""
    return plan_spatial_reorientation_details(robot, q_start, target_rotation, SpatialLoopSettings(**options)).waypoints
