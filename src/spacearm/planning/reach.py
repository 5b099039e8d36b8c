"""Reaching point C: reorient the base by a cyclic maneuver, then a straight tip path.

Umetani & Yoshida 1990, section 3.2, Fig. 5: point C cannot be reached from the
current posture by a straight tip path, "but can be reached after reorienting the
base by a suitable cyclic maneuver" (planned in `spacearm.planning.reorientation`).

`plan_reach` is the one reach planner of every family: its control flow runs over the
base-attitude group (`spacearm._core.groups`), with the numerics of each step supplied
per group (`spacearm.planning._reach_steps.ReachSteps`: the SO(2) steps below, the
SO(3) steps in `spacearm.planning.spatial_reach`). The SO(2) steps: rotating the base by Delta rotates the whole system
rigidly about the system centroid (joints unchanged), so the Straight-Path workspace
from (phi0 + Delta, q0) is the one from (phi0, q0) rotated by Delta. The target T is
reachable after the maneuver iff R(-Delta) T lies in the current Straight-Path
workspace: one batched call of `spacearm.motion.straight_tip_path` over a grid
of Delta finds the smallest useful reorientation. Targets whose distance from the
system centroid no rotation of the current workspace covers are reached by first
moving the joints to a posture whose tip lies at the target's radius (then the
maneuver brings the tip onto the target). Targets outside the Maximum Reachable
space (radius K0 + ... + Kn about the system centroid) are refused with
`ConfigError`.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from .._core.groups import SO2, SO3
from ..kinematics import tip_position
from ..models.family import family_of
from ..motion import (
    REASON_MAX_LENGTH,
    compile_straight_tip_path_history,
    joint_path_history,
    straight_tip_path,
    straight_tip_path_history,
)
from ._reach_steps import (
    MODE_REORIENT,
    MODE_REPOSITION,
    MODE_STRAIGHT,
    PHASE_LOOP,
    PHASE_REPOSITION,
    PHASE_STRAIGHT,
    ReachJob,
    ReachSteps,
)
from .reorientation import (
    LoopSettings,
    ReorientationLoop,
    check_posture,
    compile_loop_optimizer,
    plan_reorientation_details,
)
from .spatial_reach import SPATIAL_REACH_STEPS, SpatialReachPlan
from .spatial_reorientation import SpatialLoopSettings

__all__ = [
    "MODE_REORIENT",
    "MODE_REPOSITION",
    "MODE_STRAIGHT",
    "PHASE_LOOP",
    "PHASE_REPOSITION",
    "PHASE_STRAIGHT",
    "ReachPlan",
    "check_in_shell",
    "loop_settings",
    "plan_reach",
    "reachable_bounds",
]


@dataclasses.dataclass(frozen=True)
class ReachPlan:
    """A plan that brings the tip to a target (see `plan_reach`).

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


def reachable_bounds(robot) -> tuple[float, float]:
    """Inner and outer radius of the Maximum Reachable space (Area 3) about the system centroid, m.

    Outer K0 + .. + Kn (sec. 3.1 (3-a)); inner max(0, 2 max_k K_k - sum_k K_k), the hole
    when one coefficient outweighs the rest (the family's ``tip_shell``). Joint limits
    are not taken into account here (they can only shrink the space).
    """

    return family_of(robot).tip_shell(robot)


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


def _loop_history(robot, phi_from: np.ndarray, loop: ReorientationLoop, samples: int = 4):
    """Postures ``(S, n+1)`` and inertial tips ``(S, 2)`` along the N passes of a loop.

    One pass is integrated (a fixed shape, compiled once); pass i is the first turned by
    i times the rotation of one pass, a rigid rotation of the whole system about the
    centroid (phi0 shifts, the tip rotates), because eq. (5) does not depend on phi0.
    """

    if loop.loops == 0:
        return np.asarray(phi_from)[None], np.asarray(tip_position(robot, jnp.asarray(phi_from)))[None]
    phi0, joints, tips = joint_path_history(robot, jnp.asarray(phi_from), jnp.asarray(loop.loop), samples)
    postures, tips = np.concatenate([np.asarray(phi0)[..., None], np.asarray(joints)], axis=-1), np.asarray(tips)
    per_pass = postures[-1, 0] - postures[0, 0]
    turns = per_pass * np.arange(loop.loops)
    all_postures = np.concatenate(
        [postures[:1]] + [postures[1:] + np.r_[turn, np.zeros(postures.shape[1] - 1)] for turn in turns]
    )
    all_tips = np.concatenate([tips[:1]] + [_rotate(tips[1:], turn) for turn in turns])
    return all_postures, all_tips


@jax.jit
def _squared_radius_and_gradient(robot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """|tip|^2 about the centroid at phi = (0, q), and its gradient in q (one program per shape)."""

    def squared_radius(q):
        p = tip_position(robot, jnp.concatenate([jnp.zeros((1,), q.dtype), q]))
        return jnp.sum(p * p)

    return jax.value_and_grad(squared_radius)(q)


def _reposition_joints(robot, q0: np.ndarray, radius: float) -> np.ndarray:
    """Joint angles nearest q0 (minimum-norm Newton steps) whose tip is ``radius`` from the centroid."""

    def value_and_grad(q):
        return _squared_radius_and_gradient(robot, q)

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


def loop_settings(robot, **changes) -> LoopSettings | SpatialLoopSettings:
    """The reorientation loop's settings `plan_reach` uses for ``robot`` (its family's
    `LoopSettings` or `SpatialLoopSettings`), with ``changes`` (e.g. ``loop_counts``,
    ``harmonics``); `ConfigError` naming a setting the family does not have."""
    family = family_of(robot)
    steps = _REACH_STEPS.get(family.attitude.name)
    if steps is None:
        raise ConfigError(f"robot: no reach planner for the {family.name!r} family")
    known = {field.name for field in dataclasses.fields(steps.settings_type)}
    for name in changes:
        if name not in known:
            raise ConfigError(f"settings: {name} is not a loop setting of a {family.name} robot")
    return dataclasses.replace(steps.settings_type(), **changes)


def plan_reach(
    robot,
    start,
    target,
    *,
    rotation_grid: int | None = None,
    history_samples: int | None = None,
    tolerance: float | None = None,
    settings: LoopSettings | SpatialLoopSettings | None = None,
    modes: tuple[str, ...] | None = None,
    **family_options,
) -> ReachPlan | SpatialReachPlan:
    """Plan how the tip reaches an inertial target from a posture (sec. 3.2, points B and C).

    One control flow for every robot family, over its base-attitude group (SO(2) or
    SO(3)); the numerics of each step are the group's (`ReachSteps`). Spatial robots
    take the keyword options ``base_rotation`` (the start bus attitude, default the
    identity), ``rotations`` (``(c, 3)`` candidate rotation vectors instead of the
    default grid) and ``loop_samples`` (history samples per loop segment) and return a
    `SpatialReachPlan`. Every argument is honoured for every family or refused with a
    `ConfigError` naming it.

    1. A target outside the Maximum Reachable space (the family's
       `spacearm.models.family.RobotFamily.tip_shell`) is refused at once.
    2. Point B: if the straight tip path towards the target (J* inverted, base
       following eq. 5) gets there before a singularity of J* or a joint limit, that
       path is the plan.
    3. Point C: otherwise, turn the base first. A base rotation turns the Straight-Path
       workspace about the system centroid, so the straight path from the current
       posture towards the target turned back tells, for each candidate rotation of the
       group (`spacearm._core.groups.Group.candidates`, smallest first, batched),
       whether the target is reachable after the maneuver. The chosen rotation is
       planned as a closed joint loop (`plan_reorientation`), then the straight path
       runs from the posture after the loop.
    4. Planar: when no rotation of the current workspace covers the target's distance
       from the centroid, the joints first move straight in joint space to the nearest
       posture whose tip lies at that distance, and the loop turns the tip onto the target.

    Args:
        robot: one design.
        start: planar ``(n+1,)`` start posture [phi0, phi1..phin], rad; spatial ``(n,)`` joints.
        target: planar ``(2,)``, spatial ``(3,)`` inertial target (origin at the system centroid), m.
        rotation_grid: number of base rotations tried in step 3 (planar default 180 angles;
            spatial default 256 rotation vectors).
        history_samples: samples of the straight path in the history (planar default 101,
            spatial 32; spatial plans also try the candidates that many at a time).
        tolerance: accepted distance of the final tip from the target, m (default 1e-6
            in float64, 1e-3 in float32).
        settings: the reorientation loop's `LoopSettings` (planar) or
            `SpatialLoopSettings` (spatial).
        modes: the strategies allowed, tried in the order above ("straight",
            "reorient", and for planar robots "reposition"); e.g. ``("reposition",)``
            forces the third.

    Returns:
        a `ReachPlan` (planar) or `SpatialReachPlan` (spatial).

    Raises:
        ConfigError: bad input; the target outside the Maximum Reachable space; or no
            plan found.
    """
    family = family_of(robot)
    steps = _REACH_STEPS.get(family.attitude.name)
    if steps is None:
        raise ConfigError(f"robot: no reach planner for the {family.name!r} family")
    job = _check_request(
        robot, family, steps, start, target, rotation_grid, history_samples, tolerance, settings, modes, family_options
    )
    # Compile ahead on a second core: XLA compiles outside the GIL, so the programs the
    # later steps need compile while this thread runs the earlier ones. Each program is
    # still compiled once: a step waits for its program before it first calls it.
    ahead = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="spacearm-compile")
    try:
        if steps.compile_history is not None:
            job.ahead["history"] = ahead.submit(steps.compile_history, job)
        if MODE_STRAIGHT in job.modes:
            plan = steps.straight(job)
            if plan is not None:
                return plan
        searched = False
        if MODE_REORIENT in job.modes:
            job.ahead["loop"] = ahead.submit(steps.compile_loop, job)
            vectors = _candidates(family.attitude, job)
            rotation = steps.search(job, vectors)
            searched = True
            if rotation is not None:
                job.wait("loop")
                return steps.reorient(job, rotation)
        if MODE_REPOSITION in job.modes and steps.reposition is not None:
            job.wait("loop")
            return steps.reposition(job)
        for name in job.ahead:
            job.wait(name)
        raise ConfigError(steps.failure(job, searched))
    finally:
        ahead.shutdown(wait=False)


def _check_request(
    robot, family, steps, start, target, rotation_grid, history_samples, tolerance, settings, modes, family_options
) -> ReachJob:
    """The checked request of `plan_reach`, the target inside the family's tip shell."""
    settings = steps.settings_type() if settings is None else settings
    if not isinstance(settings, steps.settings_type):
        raise ConfigError(
            f"settings: expected {steps.settings_type.__name__} for a {family.name} robot, got {type(settings).__name__}"
        )
    given_grid = rotation_grid is not None
    rotation_grid = steps.rotation_grid if rotation_grid is None else rotation_grid
    if int(rotation_grid) < 1:
        raise ConfigError(f"rotation_grid: expected a positive number of base rotations, got {rotation_grid!r}")
    history_samples = steps.history_samples if history_samples is None else history_samples
    if int(history_samples) < 2:
        raise ConfigError(f"history_samples: expected at least 2, got {history_samples!r}")
    if tolerance is not None and not float(tolerance) > 0:
        raise ConfigError(f"tolerance: expected a positive distance in m, got {tolerance!r}")
    if tolerance is None:
        tolerance = 1e-6 if jax.config.jax_enable_x64 else 1e-3
    modes = steps.modes if modes is None else tuple(modes)
    if set(modes) - set(steps.modes) or not modes:
        expected = ", ".join(repr(m) for m in steps.modes)
        raise ConfigError(f"modes: expected some of {expected} for a {family.name} robot, got {modes!r}")
    start, attitude, target, options = steps.check(robot, start, target, dict(family_options, given_grid=given_grid))
    check_in_shell(robot, target)
    return ReachJob(
        robot=robot,
        family=family,
        start=start,
        attitude=attitude,
        target=target,
        tolerance=float(tolerance),
        rotation_grid=int(rotation_grid),
        history_samples=int(history_samples),
        settings=settings,
        modes=modes,
        options=options,
    )


def check_in_shell(robot, target, what: str = "target") -> None:
    """Refuse a target outside the family's tip shell (`spacearm.models.family.RobotFamily.tip_shell`)
    before any integration.

    Raises:
        ConfigError: naming the target, its distance from the system centroid and the radius it passes.
    """
    inner, outer = family_of(robot).tip_shell(robot)
    distance = float(np.linalg.norm(target))
    # The shell's boundary is reachable (the stretched arm's tip lies on it): only a
    # target past it by more than rounding is refused.
    if distance > outer * (1.0 + 1e-12) or distance < inner * (1.0 - 1e-12):
        where = (
            f"beyond the Maximum Reachable radius {outer:.6g} m"
            if distance > outer * (1.0 + 1e-12)
            else f"inside the unreachable hole of radius {inner:.6g} m"
        )
        point = ", ".join(f"{x:.6g}" for x in target)
        raise ConfigError(
            f"{what}: ({point}) m is {distance:.6g} m from the system centroid, {where} (from the link "
            "coefficients: no posture or base attitude gets past it); no motion of this robot can reach it"
        )


def _candidates(group, job: ReachJob) -> np.ndarray:
    """``(c, dim)`` candidate base rotations (algebra vectors), the smallest first.

    The caller's ``rotations`` when given, else ``rotation_grid`` of the group's
    candidates (which come in blocks of ``len(group.candidates(1))`` per count).
    """
    vectors = job.options.get("rotations")
    if vectors is None:
        block = len(group.candidates(1))
        vectors = group.candidates(-(-job.rotation_grid // block))[: job.rotation_grid]
    return vectors[np.argsort(np.linalg.norm(vectors, axis=1), kind="stable")]


# The planar steps ---------------------------------------------------------------------------


def _planar_check(robot, phi_start, target, options):
    options.pop("given_grid")
    if options:
        name = sorted(options)[0]
        raise ConfigError(
            f"{name}: not an option of planar reach plans (a planar posture starts with its base attitude phi0)"
        )
    phi = check_posture(robot, phi_start)
    target = np.asarray(target, dtype=float)
    if target.shape != (2,) or not np.all(np.isfinite(target)):
        raise ConfigError(f"target: expected two finite numbers (x, y) in m, got {np.asarray(target).tolist()!r}")
    return phi, phi[0], target, {}


def _planar_straight_path(job: ReachJob, phi_from, max_length=None, directions=None):
    dtype = jnp.result_type(float)
    tip_from = np.asarray(tip_position(job.robot, jnp.asarray(phi_from, dtype)))
    offset = job.target - tip_from if directions is None else directions
    return straight_tip_path(job.robot, jnp.asarray(phi_from, dtype), jnp.asarray(offset, dtype), max_length=max_length)


def _planar_finish(job: ReachJob, mode, joint_waypoints, joint_parts, phi_after, delta, loops) -> ReachPlan:
    """The plan: the joint-space parts, then the straight leg from ``phi_after`` to the target."""
    robot, target, phi, history_samples = job.robot, job.target, job.start, job.history_samples
    dtype = jnp.result_type(float)
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
        path = _planar_straight_path(job, phi_after, max_length=length)
        if int(path.reason) != REASON_MAX_LENGTH:
            raise ConfigError(
                f"target: the straight tip path from the planned posture stops after {float(path.length):.6g} m "
                f"of {length:.6g} m (reason {int(path.reason)})"
            )
        job.wait("history")
        postures, tips = straight_tip_path_history(
            robot, jnp.asarray(phi_after, dtype), jnp.asarray(offset, dtype), history_samples, max_length=length
        )
        parts_postures.append(np.asarray(postures)[1:])
        parts_tips.append(np.asarray(tips)[1:])
        parts_phase.append(np.full(history_samples - 1, PHASE_STRAIGHT))
        end_posture, end_tip = np.asarray(path.end_posture), np.asarray(path.end_tip)
    error = float(np.linalg.norm(end_tip - target))
    if not error <= job.tolerance:
        raise ConfigError(f"target: the plan ends {error:.3g} m from the target (tolerance {job.tolerance:.3g} m)")
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


def _planar_straight(job: ReachJob) -> ReachPlan | None:
    phi = job.start
    still = np.stack([phi[1:], phi[1:]])
    tip0 = np.asarray(tip_position(job.robot, jnp.asarray(phi)))
    distance = float(np.linalg.norm(job.target - tip0))
    if distance <= 1e-12 or int(_planar_straight_path(job, phi, max_length=distance).reason) == REASON_MAX_LENGTH:
        return _planar_finish(job, MODE_STRAIGHT, still, [], phi, 0.0, 0)
    return None


def _planar_search(job: ReachJob, vectors: np.ndarray) -> float | None:
    """The smallest useful base rotation (with margin, `_choose_rotation`), or None.

    The candidates are put back in their circular order for the run search.
    """
    phi = job.start
    deltas = vectors[:, 0]
    deltas = deltas[np.argsort(np.mod(deltas, 2.0 * np.pi), kind="stable")]
    tip0 = np.asarray(tip_position(job.robot, jnp.asarray(phi)))
    turned = _rotate(job.target, -deltas)  # (G, 2): the target seen from the unrotated system
    offsets = turned - tip0
    lengths = np.linalg.norm(offsets, axis=-1)
    ends = _planar_straight_path(job, np.broadcast_to(phi, (len(deltas), phi.size)), directions=offsets)
    slack = np.asarray(ends.length) - lengths
    feasible = (slack > 1e-6 * float(job.robot.reach)) & (np.asarray(ends.reason) != 3)
    if not np.any(feasible):
        return None
    return _choose_rotation(deltas, slack, feasible)


def _planar_reorient(job: ReachJob, delta) -> ReachPlan:
    delta = float(np.asarray(delta).reshape(()))
    loop = plan_reorientation_details(job.robot, job.start, delta, settings=job.settings)
    postures, tips = _loop_history(job.robot, job.start, loop)
    return _planar_finish(
        job, MODE_REORIENT, loop.waypoints, [(PHASE_LOOP, postures, tips)], postures[-1], delta, loop.loops
    )


def _planar_reposition(job: ReachJob) -> ReachPlan:
    """Move the joints to a posture whose tip lies at the target's radius, then loop."""
    robot, phi, target = job.robot, job.start, job.target
    q0 = phi[1:]
    q1 = _reposition_joints(robot, q0, float(np.linalg.norm(target)))
    segment = np.stack([q0, q1])
    phi0, joints, move_tips = (np.asarray(x) for x in joint_path_history(robot, phi, segment, 16))
    move_postures = np.concatenate([np.asarray(phi0)[..., None], np.asarray(joints)], axis=-1)
    phi_mid = move_postures[-1]
    tip_mid = move_tips[-1]
    delta = float(_wrap(np.arctan2(target[1], target[0]) - np.arctan2(tip_mid[1], tip_mid[0])))
    loop = plan_reorientation_details(robot, phi_mid, delta, settings=job.settings)
    postures, tips = _loop_history(robot, phi_mid, loop)
    waypoints = np.concatenate([segment, loop.waypoints[1:]])
    parts = [(PHASE_REPOSITION, move_postures, move_tips), (PHASE_LOOP, postures[1:], tips[1:])]
    return _planar_finish(job, MODE_REPOSITION, waypoints, parts, postures[-1], delta, loop.loops)


def _planar_failure(job: ReachJob, searched: bool) -> str:
    target = job.target
    return (
        f"target: ({target[0]:.6g}, {target[1]:.6g}) m is not reachable from this posture with the modes {job.modes!r}"
    )


_PLANAR_REACH_STEPS = ReachSteps(
    modes=(MODE_STRAIGHT, MODE_REORIENT, MODE_REPOSITION),
    rotation_grid=180,
    history_samples=101,
    settings_type=LoopSettings,
    check=_planar_check,
    compile_history=lambda job: compile_straight_tip_path_history(job.robot, 1, job.history_samples),
    compile_loop=lambda job: compile_loop_optimizer(job.robot, job.settings),
    straight=_planar_straight,
    search=_planar_search,
    reorient=_planar_reorient,
    reposition=_planar_reposition,
    failure=_planar_failure,
)

# The steps of each base-attitude group.
_REACH_STEPS = {SO2.name: _PLANAR_REACH_STEPS, SO3.name: SPATIAL_REACH_STEPS}
