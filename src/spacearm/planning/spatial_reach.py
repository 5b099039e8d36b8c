"""Reaching an inertial point with a spatial arm: straight, or turn the bus first (3-D sec. 3.2).

0. A target outside the shell that holds every tip position (the virtual manipulator's
   radii about the system centroid, `spacearm.models.spatial.shell`) is refused at
   once, naming the radius: no motion of the arm reaches it.
1. If the straight tip path towards the target (translation, bus attitude integrated
   with the joints; `spacearm.motion.spatial_straight_tip_path`) gets there
   before J*_v loses rank or a joint limit, that path is the plan.
2. Otherwise turn the bus first. A closed joint loop leaves the joints at q0 and turns
   the bus by Q (bus frame): the tip moves to R0 Q p_bus(q0) and the straight paths
   start from (q0, R0 Q). For a set of candidate rotations (rotation vectors on a
   Fibonacci sphere of axes times a few angles, smallest first) the straight path
   towards the target is run from (q0, R0 Q); the smallest rotation whose path gets
   there is planned with `spacearm.planning.plan_spatial_reorientation_details`,
   then the straight path runs from the attitude actually reached.

Every straight path of a plan runs in one compiled program of ``history_samples``
lanes: the final straight leg is sampled by running its lanes to equal fractions of
its length (they sample its history), the candidate search runs the candidates that
many at a time, smallest rotations first, and stops at the first batch that reaches.
Once the straight path fails, the loop optimizer compiles on a second core while the
candidates run.

The target is about the system centroid, inertial axes (zero momentum fixes the
centroid: with no external force the system centroid does not move).
"""

from __future__ import annotations

import concurrent.futures
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from ..kinematics import tip_position
from ..models.family import family_of
from ..models.spatial.robot import SpatialRobot
from ..motion.attitude import expm, geodesic_distance, spatial_joint_path_history
from ..motion.path_ends import REASON_MAX_LENGTH
from ..motion.spatial_paths import spatial_straight_tip_path
from .spatial_reorientation import (
    SpatialLoopSettings,
    compile_spatial_loop_optimizer,
    plan_spatial_reorientation_details,
)

__all__ = ["MODE_REORIENT", "MODE_STRAIGHT", "SpatialReachPlan", "candidate_rotations", "plan_spatial_reach"]

MODE_STRAIGHT = "straight"
MODE_REORIENT = "reorient"

PHASE_LOOP = 1
PHASE_STRAIGHT = 2


@dataclasses.dataclass(frozen=True)
class SpatialReachPlan:
    """How the tip reaches the target, with the whole history.

    Attributes:
        mode: ``"straight"`` or ``"reorient"``.
        target: ``(3,)`` inertial target about the system centroid, m.
        joints: ``(S, n)`` joints along the plan (loop samples, then straight-path samples).
        base_rotation: ``(S, 3, 3)`` bus attitude along it (bus axes -> inertial axes).
        tips: ``(S, 3)`` inertial tip along it, m.
        phase: ``(S,)`` int, 1 = reorientation loop, 2 = straight tip path.
        loop_waypoints: ``(k, n)`` closed joint path turning the bus first (``(1, n)``: none).
        loop_rotation: ``(3, 3)`` the bus rotation planned for the loop (bus frame;
            the identity without a loop).
        loops: repetitions of the loop (0 without one).
        bus_turn: angle of R_start^T R_end over the whole plan, rad (the straight path
            turns the bus too).
        end_joints: ``(n,)``, end_rotation: ``(3, 3)``, end_tip: ``(3,)`` at the end.
        straight_length: tip distance of the final straight path, m.
        error: distance from the end tip to the target, m.
    """

    mode: str
    target: np.ndarray
    joints: np.ndarray
    base_rotation: np.ndarray
    tips: np.ndarray
    phase: np.ndarray
    loop_waypoints: np.ndarray
    loop_rotation: np.ndarray
    loops: int
    bus_turn: float
    end_joints: np.ndarray
    end_rotation: np.ndarray
    end_tip: np.ndarray
    straight_length: float
    error: float


def candidate_rotations(axes: int = 64, angles=(0.02, 0.05, 0.1, 0.2)) -> np.ndarray:
    """``(axes * len(angles), 3)`` rotation vectors, smallest angles first (Fibonacci sphere of axes)."""
    k = np.arange(axes) + 0.5
    z = 1.0 - 2.0 * k / axes
    phi = np.pi * (1.0 + 5.0**0.5) * k
    r = np.sqrt(1.0 - z * z)
    unit = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    return np.concatenate([angle * unit for angle in angles], axis=0)


@jax.jit
def _rotations(vectors):
    return expm(vectors)


@jax.jit
def _turn(R_start, R_end):
    return geodesic_distance(R_start, R_end)


def _lanes(robot, q, R, target, fractions, tolerance):
    """Straight paths from ``(q (S, n), R (S, 3, 3))`` towards ``target``, lane i stopped
    after ``fractions[i]`` of its distance to the target (``None``: all of it).

    Returns the path, per lane whether it reached ``start + fraction * offset`` within
    ``tolerance``, and the distances to the target ``(S,)``.
    """
    dtype = jnp.result_type(float)
    start = np.asarray(tip_position(robot, jnp.asarray(q, dtype), jnp.asarray(R, dtype)))
    offset = target[None] - start
    distance = np.linalg.norm(offset, axis=1)
    direction = offset / np.where(distance > 0, distance, 1.0)[:, None]
    direction[distance == 0] = (1.0, 0.0, 0.0)  # any: the lane stops at once
    lengths = distance if fractions is None else distance * fractions
    path = spatial_straight_tip_path(
        robot,
        jnp.asarray(q, dtype),
        jnp.asarray(direction, dtype),
        jnp.asarray(lengths, dtype),
        base_rotation=jnp.asarray(R, dtype),
    )
    aim = start + lengths[:, None] * direction
    error = np.linalg.norm(np.asarray(path.end_tip) - aim, axis=1)
    reached = (np.asarray(path.reason) == REASON_MAX_LENGTH) & (error <= tolerance)
    return path, reached, distance


def _check(robot: SpatialRobot, q_start, target, base_rotation):
    if robot.batch_shape:
        raise ConfigError("robot: plan one design at a time (got a batch of designs)")
    n = robot.n_joints
    q0 = np.asarray(q_start, float)
    if q0.shape != (n,) or not np.all(np.isfinite(q0)):
        raise ConfigError(f"q_start: expected {n} finite joint positions, got shape {q0.shape}")
    lower, upper = np.asarray(robot.joint_lower, float), np.asarray(robot.joint_upper, float)
    outside = (q0 < lower) | (q0 > upper)
    if np.any(outside):
        j = int(np.argmax(outside))
        raise ConfigError(
            f"q_start: joint {j + 1} = {q0[j]:.6g} is outside its limits [{lower[j]:.6g}, {upper[j]:.6g}]"
        )
    target = np.asarray(target, float)
    if target.shape != (3,) or not np.all(np.isfinite(target)):
        raise ConfigError(f"target: expected three finite numbers (x, y, z) in m, got {np.asarray(target).tolist()!r}")
    R0 = np.eye(3) if base_rotation is None else np.asarray(base_rotation, float)
    if (
        R0.shape != (3, 3)
        or not np.all(np.isfinite(R0))
        or np.max(np.abs(R0.T @ R0 - np.eye(3))) > 1e-9
        or np.linalg.det(R0) < 0
    ):
        raise ConfigError("base_rotation: expected a (3, 3) rotation matrix")
    inner, outer = family_of(robot).tip_shell(robot)
    distance = float(np.linalg.norm(target))
    if distance > outer or distance < inner:
        where = (
            f"beyond the Maximum Reachable radius {outer:.6g} m"
            if distance > outer
            else f"inside the unreachable hole of radius {inner:.6g} m"
        )
        raise ConfigError(
            f"target: ({target[0]:.6g}, {target[1]:.6g}, {target[2]:.6g}) m is {distance:.6g} m from the system centroid, "
            f"{where} (from the virtual link lengths: no posture or bus attitude gets past it); "
            "no motion of this robot can reach it"
        )
    return q0, target, R0


def plan_spatial_reach(
    robot: SpatialRobot,
    q_start,
    target,
    *,
    base_rotation=None,
    rotations: np.ndarray | None = None,
    rotation_grid: int | None = None,
    tolerance: float | None = None,
    settings: SpatialLoopSettings | None = None,
    history_samples: int = 32,
    loop_samples: int = 4,
    modes: tuple[str, ...] = (MODE_STRAIGHT, MODE_REORIENT),
) -> SpatialReachPlan:
    """Plan how the tip of a spatial arm reaches an inertial point.

    Args:
        robot: one spatial design.
        q_start: ``(n,)`` joints at the start.
        target: ``(3,)`` inertial point about the system centroid, m.
        base_rotation: ``(3, 3)`` bus attitude at the start (default identity).
        rotations: ``(c, 3)`` candidate bus rotation vectors, bus frame (default
            ``rotation_grid`` of `candidate_rotations`); tried smallest first.
        rotation_grid: how many default candidates (default 256: axes on a Fibonacci
            sphere times four angles, 0.02 to 0.2 rad); not together with ``rotations``.
        tolerance: accepted tip error at the end, m (default 1e-6 in float64, 1e-3 in float32).
        settings: `SpatialLoopSettings` of the reorientation loop.
        history_samples: samples of the final straight path in the history; also the
            lane count of the one straight-path program (candidates run that many at a time).
        loop_samples: history samples per loop segment.
        modes: the strategies allowed, in this order: ``"straight"``, ``"reorient"``.

    Raises:
        ConfigError: bad input, a target outside the Maximum Reachable shell, or no
            strategy reaches it.
    """
    q0, target, R0 = _check(robot, q_start, target, base_rotation)
    if rotations is not None and rotation_grid is not None:
        raise ConfigError("rotation_grid: give either rotations or rotation_grid, not both")
    rotation_grid = 256 if rotation_grid is None else rotation_grid
    if int(rotation_grid) < 1:
        raise ConfigError(f"rotation_grid: expected a positive number of candidate rotations, got {rotation_grid!r}")
    unknown = set(modes) - {MODE_STRAIGHT, MODE_REORIENT}
    if unknown or not modes:
        raise ConfigError(f"modes: expected some of 'straight', 'reorient' for a spatial robot, got {modes!r}")
    if tolerance is None:
        tolerance = 1e-6 if jax.config.jax_enable_x64 else 1e-3
    if not float(tolerance) > 0:
        raise ConfigError(f"tolerance: expected a positive distance in m, got {tolerance!r}")
    settings = SpatialLoopSettings() if settings is None else settings
    if not isinstance(settings, SpatialLoopSettings):
        raise ConfigError(f"settings: expected SpatialLoopSettings for a spatial robot, got {type(settings).__name__}")
    lanes = int(history_samples)
    if lanes < 2:
        raise ConfigError(f"history_samples: expected at least 2, got {history_samples!r}")
    if int(loop_samples) < 1:
        raise ConfigError(f"loop_samples: expected at least 1, got {loop_samples!r}")
    vectors = (
        candidate_rotations(axes=-(-int(rotation_grid) // 4))[: int(rotation_grid)]
        if rotations is None
        else np.asarray(rotations, float)
    )
    if vectors.ndim != 2 or vectors.shape[1] != 3 or not len(vectors) or not np.all(np.isfinite(vectors)):
        raise ConfigError(f"rotations: expected (c, 3) finite rotation vectors, got shape {vectors.shape}")
    n = q0.size
    fractions = np.arange(lanes) / (lanes - 1)

    def straight_leg(R_from):
        """The straight path from (q0, R_from), sampled at ``lanes`` fractions of its length."""
        R = np.broadcast_to(R_from, (lanes, 3, 3))
        path, reached, distance = _lanes(robot, np.broadcast_to(q0, (lanes, n)), R, target, fractions, tolerance)
        return path, bool(reached[-1]), float(distance[-1])

    def plan(mode, loop_waypoints, loop_rotation, loops, loop_history, path, length):
        joints, rotations_, tips = (np.asarray(x) for x in (path.end_joints, path.end_rotation, path.end_tip))
        phase = np.full(lanes, PHASE_STRAIGHT)
        if loop_history is not None:
            q_loop, R_loop, tip_loop = loop_history
            joints = np.concatenate([q_loop, joints[1:]])
            rotations_ = np.concatenate([R_loop, rotations_[1:]])
            tips = np.concatenate([tip_loop, tips[1:]])
            phase = np.concatenate([np.full(len(q_loop), PHASE_LOOP), phase[1:]])
        error = float(np.linalg.norm(tips[-1] - target))
        if not error <= tolerance:
            raise ConfigError(f"target: the plan ends {error:.3g} m from the target (tolerance {tolerance:.3g} m)")
        return SpatialReachPlan(
            mode=mode,
            target=target,
            joints=joints,
            base_rotation=rotations_,
            tips=tips,
            phase=phase,
            loop_waypoints=loop_waypoints,
            loop_rotation=loop_rotation,
            loops=int(loops),
            bus_turn=float(_turn(rotations_[0], rotations_[-1])),
            end_joints=joints[-1],
            end_rotation=rotations_[-1],
            end_tip=tips[-1],
            straight_length=length,
            error=error,
        )

    none = q0[None]
    if MODE_STRAIGHT in modes:
        path, reached, length = straight_leg(R0)
        if reached:
            return plan(MODE_STRAIGHT, none, np.eye(3), 0, None, path, length)
    if MODE_REORIENT not in modes:
        raise ConfigError(
            f"target: ({target[0]:.6g}, {target[1]:.6g}, {target[2]:.6g}) m is not reachable from this "
            f"posture with the modes {modes!r}"
        )
    # Compile the loop optimizer on a second core while the candidates run (XLA compiles
    # outside the GIL); the program is still compiled once: the plan waits for it.
    ahead = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="spacearm-compile")
    optimizer_ready = ahead.submit(compile_spatial_loop_optimizer, robot, settings)
    ahead.shutdown(wait=False)

    vectors = vectors[np.argsort(np.linalg.norm(vectors, axis=1), kind="stable")]
    pick = None
    for first in range(0, len(vectors), lanes):
        chunk = vectors[first : first + lanes]
        padded = np.concatenate([chunk, np.repeat(chunk[-1:], lanes - len(chunk), axis=0)])
        starts = np.einsum("ij,cjk->cik", R0, np.asarray(_rotations(jnp.asarray(padded))))
        _, reached, _ = _lanes(robot, np.broadcast_to(q0, (lanes, n)), starts, target, None, tolerance)
        reached = reached[: len(chunk)]
        if reached.any():
            pick = chunk[int(np.argmax(reached))]
            break
    if pick is None:
        concurrent.futures.wait([optimizer_ready])
        raise ConfigError(
            "target: the straight path does not reach the target, nor after any of the "
            f"{len(vectors)} candidate bus rotations (largest {np.degrees(np.max(np.linalg.norm(vectors, axis=1))):.3g} deg)"
        )
    concurrent.futures.wait([optimizer_ready])  # a failed compile ahead is only a missed head start
    Q = np.asarray(_rotations(jnp.asarray(pick)))
    loop = plan_spatial_reorientation_details(robot, q0, Q, settings)
    # The loop's history: one pass sampled (a fixed shape), then pass i is pass 0 turned by
    # D^i on the left in bus axes (the attitude ODE does not depend on R).
    R_pass, q_pass = (
        np.asarray(x)
        for x in spatial_joint_path_history(
            robot, q0, loop.loop, base_rotation=np.eye(3), samples_per_segment=int(loop_samples), steps=1
        )
    )
    D = R_pass[-1]
    power, R_loop, q_loop = np.eye(3), [np.eye(3)[None]], [q0[None]]
    for _ in range(loop.repetitions):
        R_loop.append(power @ R_pass[1:])
        q_loop.append(q_pass[1:])
        power = power @ D
    R_loop = np.einsum("ij,sjk->sik", R0, np.concatenate(R_loop))
    q_loop = np.concatenate(q_loop)
    tip_loop = np.asarray(tip_position(robot, jnp.asarray(q_loop), jnp.asarray(R_loop)))
    R_after = R_loop[-1]
    path, reached, length = straight_leg(R_after)
    if not reached:
        raise ConfigError(
            f"target: after the planned loop the straight path stops {float(length - path.length[-1]):.3g} m short"
        )
    return plan(MODE_REORIENT, loop.waypoints, Q, loop.repetitions, (q_loop, R_loop, tip_loop), path, length)
