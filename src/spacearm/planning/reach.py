"""Reaching point C: reorient the base by a cyclic maneuver, then a straight tip path.

Umetani & Yoshida 1990, section 3.2, Fig. 5: point C cannot be reached from the
current posture by a straight tip path, "but can be reached after reorienting the
base by a suitable cyclic maneuver" (planned in `spacearm.planning.reorientation`).

Reaching (`plan_reach`). Rotating the base by Delta rotates the whole system
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
from ..kinematics import tip_position
from ..models.family import family_of
from ..models.planar.robot import PlanarRobot
from ..models.spatial.robot import SpatialRobot
from ..motion import (
    REASON_MAX_LENGTH,
    compile_straight_tip_path_history,
    joint_path_history,
    straight_tip_path,
    straight_tip_path_history,
)
from .reorientation import (
    LoopSettings,
    ReorientationLoop,
    check_posture,
    compile_loop_optimizer,
    plan_reorientation_details,
)
from .spatial_reach import SpatialReachPlan, plan_spatial_reach
from .spatial_reorientation import SpatialLoopSettings

__all__ = [
    "MODE_REORIENT",
    "MODE_REPOSITION",
    "MODE_STRAIGHT",
    "PHASE_LOOP",
    "PHASE_REPOSITION",
    "PHASE_STRAIGHT",
    "ReachPlan",
    "plan_reach",
    "reachable_bounds",
]

MODE_STRAIGHT = "straight"
MODE_REORIENT = "reorient"
MODE_REPOSITION = "reposition"

PHASE_REPOSITION = 0
PHASE_LOOP = 1
PHASE_STRAIGHT = 2


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


def reachable_bounds(robot: PlanarRobot) -> tuple[float, float]:
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


def _loop_history(robot: PlanarRobot, phi_from: np.ndarray, loop: ReorientationLoop, samples: int = 4):
    """Postures ``(S, n+1)`` and inertial tips ``(S, 2)`` along the N passes of a loop.

    One pass is integrated (a fixed shape, compiled once); pass i is the first turned by
    i times the rotation of one pass, a rigid rotation of the whole system about the
    centroid (phi0 shifts, the tip rotates), because eq. (5) does not depend on phi0.
    """

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
    robot: PlanarRobot | SpatialRobot,
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

    One entry point for every robot family; the planner is the family's (planar below;
    spatial robots: `plan_spatial_reach`, a `SpatialReachPlan`, with the keyword options
    ``base_rotation``, ``rotations`` and ``loop_samples``). Every argument is honoured
    for every family or refused with a `ConfigError` naming it.

    1. A target outside the Maximum Reachable space (the family's
       `spacearm.models.family.RobotFamily.tip_shell`) is refused at once.
    2. Point B: if the straight tip path towards the target (J* inverted, base
       following eq. 5) gets there before a singularity of J* or a joint limit, that
       path is the plan.
    3. Point C: otherwise, turn the base first. A base rotation Delta turns the
       Straight-Path workspace about the system centroid, so the straight path from the
       current posture towards R(-Delta) target tells, for every Delta of a grid in one
       batched call, whether the target is reachable after the maneuver. The smallest
       such Delta (with margin) is planned with `plan_reorientation_details`, then
       the straight path runs from the posture after the loop.
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
            spatial 32).
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
    family = family_of(robot).name
    planner = _REACH_PLANNERS.get(family)
    if planner is None:
        raise ConfigError(f"robot: no reach planner for the {family!r} family")
    options = {
        "rotation_grid": rotation_grid,
        "history_samples": history_samples,
        "tolerance": tolerance,
        "settings": settings,
        "modes": modes,
    }
    return planner(robot, start, target, **{k: v for k, v in options.items() if v is not None}, **family_options)


def _plan_planar_reach(
    robot: PlanarRobot,
    phi_start,
    target,
    *,
    rotation_grid: int = 180,
    history_samples: int = 101,
    tolerance: float | None = None,
    settings: LoopSettings = LoopSettings(),
    modes: tuple[str, ...] = (MODE_STRAIGHT, MODE_REORIENT, MODE_REPOSITION),
    **spatial_options,
) -> ReachPlan:
    """The planar reach planner (`plan_reach`)."""
    if spatial_options:
        name = sorted(spatial_options)[0]
        raise ConfigError(
            f"{name}: not an option of planar reach plans (a planar posture starts with its base attitude phi0)"
        )
    if not isinstance(settings, LoopSettings):
        raise ConfigError(f"settings: expected LoopSettings for a planar robot, got {type(settings).__name__}")
    if int(rotation_grid) < 1:
        raise ConfigError(f"rotation_grid: expected a positive number of base rotations, got {rotation_grid!r}")
    if int(history_samples) < 2:
        raise ConfigError(f"history_samples: expected at least 2, got {history_samples!r}")
    if tolerance is not None and not float(tolerance) > 0:
        raise ConfigError(f"tolerance: expected a positive distance in m, got {tolerance!r}")
    phi = check_posture(robot, phi_start)
    if tolerance is None:
        tolerance = 1e-6 if jax.config.jax_enable_x64 else 1e-3
    target = np.asarray(target, dtype=float)
    if target.shape != (2,) or not np.all(np.isfinite(target)):
        raise ConfigError(f"target: expected two finite numbers (x, y) in m, got {np.asarray(target).tolist()!r}")
    inner, outer = family_of(robot).tip_shell(robot)
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
    # Compile ahead on a second core: XLA compiles outside the GIL, so the history sampler
    # (needed by every plan with a straight leg) and the loop optimizer (needed at point C)
    # compile while this thread compiles and integrates the straight paths. Each program
    # is still compiled once: the plan waits for them before it first calls them.
    ahead = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="spacearm-compile")
    history_ready = ahead.submit(compile_straight_tip_path_history, robot, 1, history_samples)
    loops_ready = ahead.submit(compile_loop_optimizer, robot, settings) if MODE_REORIENT in modes else None
    ahead.shutdown(wait=False)

    def wait(future):  # a failed compile ahead is only a missed head start
        if future is not None:
            concurrent.futures.wait([future])

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
            wait(history_ready)
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
        wait(loops_ready)
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
    wait(loops_ready)
    loop = plan_reorientation_details(robot, phi_mid, delta, settings=settings)
    postures, tips = _loop_history(robot, phi_mid, loop)
    waypoints = np.concatenate([segment, loop.waypoints[1:]])
    parts = [(PHASE_REPOSITION, move_postures, move_tips), (PHASE_LOOP, postures[1:], tips[1:])]
    return finish(MODE_REPOSITION, waypoints, parts, postures[-1], delta, loop.loops)


_REACH_PLANNERS = {"planar": _plan_planar_reach, "spatial": plan_spatial_reach}
