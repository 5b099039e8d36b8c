"""The spatial (SO(3)) steps of `spacearm.planning.reach.plan_reach`: straight, or turn the bus first.

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

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from ..kinematics import tip_position
from ..motion.attitude import expm, so3_joint_path_history
from ..motion.path_ends import REASON_MAX_LENGTH
from ..motion.spatial_paths import spatial_straight_tip_path
from ._reach_steps import (
    MODE_REORIENT,
    MODE_STRAIGHT,
    PHASE_LOOP,
    PHASE_STRAIGHT,
    ReachJob,
    ReachSteps,
)
from .spatial_reorientation import (
    SpatialLoopSettings,
    compile_spatial_loop_optimizer,
    plan_spatial_reorientation_details,
)

__all__ = ["PHASE_LOOP", "PHASE_STRAIGHT", "SPATIAL_REACH_STEPS", "SpatialReachPlan"]


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


@jax.jit
def _rotations(vectors):
    return expm(vectors)


def _turn(R_start, R_end) -> float:
    """`geodesic_distance` of two concrete rotations, in NumPy on the host (no small program to compile)."""
    E = np.asarray(R_start).T @ np.asarray(R_end)
    s = 0.5 * np.linalg.norm([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]])
    return float(np.arctan2(s, 0.5 * (np.trace(E) - 1.0)))


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


def _check(robot, q_start, target, options):
    """Checked joints, start bus attitude, target and options (``base_rotation``,
    ``rotations``, ``loop_samples``) of a spatial reach request."""
    given_grid = options.pop("given_grid")
    base_rotation = options.pop("base_rotation", None)
    rotations = options.pop("rotations", None)
    loop_samples = options.pop("loop_samples", 4)
    if options:
        name = sorted(options)[0]
        raise ConfigError(f"{name}: not an option of spatial reach plans")
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
            f" ({robot.joint_names[j]})"
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
    if rotations is not None:
        if given_grid:
            raise ConfigError("rotation_grid: give either rotations or rotation_grid, not both")
        rotations = np.asarray(rotations, float)
        if rotations.ndim != 2 or rotations.shape[1] != 3 or not len(rotations) or not np.all(np.isfinite(rotations)):
            raise ConfigError(f"rotations: expected (c, 3) finite rotation vectors, got shape {rotations.shape}")
    if int(loop_samples) < 1:
        raise ConfigError(f"loop_samples: expected at least 1, got {loop_samples!r}")
    return q0, R0, target, {"rotations": rotations, "loop_samples": int(loop_samples)}


def _straight_leg(job: ReachJob, R_from):
    """The straight path from (q0, R_from), sampled at ``history_samples`` fractions of its length."""
    lanes, q0 = job.history_samples, job.start
    fractions = np.arange(lanes) / (lanes - 1)
    R = np.broadcast_to(R_from, (lanes, 3, 3))
    path, reached, distance = _lanes(
        job.robot, np.broadcast_to(q0, (lanes, q0.size)), R, job.target, fractions, job.tolerance
    )
    return path, bool(reached[-1]), float(distance[-1])


def _plan(job: ReachJob, mode, loop_waypoints, loop_rotation, loops, loop_history, path, length) -> SpatialReachPlan:
    """The plan: the loop's history (if any), then the straight leg's."""
    target, tolerance = job.target, job.tolerance
    joints, rotations_, tips = (np.asarray(x) for x in (path.end_joints, path.end_rotation, path.end_tip))
    phase = np.full(job.history_samples, PHASE_STRAIGHT)
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


def _straight(job: ReachJob) -> SpatialReachPlan | None:
    path, reached, length = _straight_leg(job, job.attitude)
    if not reached:
        return None
    return _plan(job, MODE_STRAIGHT, job.start[None], np.eye(3), 0, None, path, length)


def _search(job: ReachJob, vectors: np.ndarray):
    """The first candidate rotation vector (bus frame) after which the straight path
    reaches, the candidates ``history_samples`` at a time (one program), or None."""
    lanes, q0 = job.history_samples, job.start
    for first in range(0, len(vectors), lanes):
        chunk = vectors[first : first + lanes]
        padded = np.concatenate([chunk, np.repeat(chunk[-1:], lanes - len(chunk), axis=0)])
        starts = np.einsum("ij,cjk->cik", job.attitude, np.asarray(_rotations(jnp.asarray(padded))))
        _, reached, _ = _lanes(
            job.robot, np.broadcast_to(q0, (lanes, q0.size)), starts, job.target, None, job.tolerance
        )
        reached = reached[: len(chunk)]
        if reached.any():
            return chunk[int(np.argmax(reached))]
    job.options["searched"] = vectors
    return None


def _reorient(job: ReachJob, pick) -> SpatialReachPlan:
    """The loop turning the bus by exp(pick), its history, then the straight leg."""
    robot, q0, R0 = job.robot, job.start, job.attitude
    # The search's program (its lane count): no second compile for one vector.
    Q = np.asarray(_rotations(jnp.asarray(np.broadcast_to(pick, (job.history_samples, 3)))))[0]
    loop = plan_spatial_reorientation_details(robot, q0, Q, job.settings)
    # The loop's history: one pass sampled (a fixed shape), then pass i is pass 0 turned by
    # D^i on the left in bus axes (the attitude ODE does not depend on R).
    R_pass, q_pass = (
        np.asarray(x)
        for x in so3_joint_path_history(
            robot, q0, loop.loop, base_rotation=np.eye(3), samples_per_segment=job.options["loop_samples"], steps=1
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
    path, reached, length = _straight_leg(job, R_loop[-1])
    if not reached:
        raise ConfigError(
            f"target: after the planned loop the straight path stops {float(length - path.length[-1]):.3g} m short"
        )
    return _plan(job, MODE_REORIENT, loop.waypoints, Q, loop.repetitions, (q_loop, R_loop, tip_loop), path, length)


def _failure(job: ReachJob, searched: bool) -> str:
    target = job.target
    if searched:
        vectors = job.options["searched"]
        largest = np.degrees(np.max(np.linalg.norm(vectors, axis=1)))
        return (
            "target: the straight path does not reach the target, nor after any of the "
            f"{len(vectors)} candidate bus rotations (largest {largest:.3g} deg)"
        )
    return (
        f"target: ({target[0]:.6g}, {target[1]:.6g}, {target[2]:.6g}) m is not reachable from this "
        f"posture with the modes {job.modes!r}"
    )


SPATIAL_REACH_STEPS = ReachSteps(
    modes=(MODE_STRAIGHT, MODE_REORIENT),
    rotation_grid=256,
    history_samples=32,
    settings_type=SpatialLoopSettings,
    check=_check,
    compile_history=None,
    compile_loop=lambda job: compile_spatial_loop_optimizer(job.robot, job.settings),
    straight=_straight,
    search=_search,
    reorient=_reorient,
    reposition=None,
    failure=_failure,
)
