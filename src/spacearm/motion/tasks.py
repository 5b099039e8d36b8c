"""Timed tasks: joint waypoints and a duration, and the efforts a robot spends on them.

A task is k joint waypoints ``(k, n)`` and a duration. Each of its k - 1 straight joint
segments takes duration / (k - 1) s and follows the quintic time law

    s(u) = 10 u^3 - 15 u^4 + 6 u^5,    u = (t - t_i) / T in [0, 1],  T = duration / (k - 1),

so q = q_i + s(u) (q_{i+1} - q_i) starts and stops every segment at rest: s' = 30 u^2 (1 - u)^2
and s'' = 60 u (1 - u) (1 - 2 u) vanish at u = 0 and 1 (the minimum-jerk rest-to-rest profile,
Flash & Hogan 1985). Each segment is sampled at ``samples`` (default 101) evenly spaced u,
ends included, so an inner waypoint is sampled twice (as the end of one segment and the start
of the next, both at rest).

`task_peaks` evaluates `spacearm.dynamics.inverse_dynamics` at every sample at once, at zero
system momentum (the robot starts the task at rest), and takes the peaks over the samples:
the largest |tau_i| of each joint, and the largest force and torque that the bus's
actuators need to keep it at rest (the ``"held"`` wrench: force at the bus centroid, torque
about it, bus axes; planar robots [fx, fy, m]). At zero momentum these quantities do not
depend on the bus attitude (every one is in bus axes), so a task needs no attitude: the
attitude the bus drifts to along the task changes none of them.

`wheel_peaks` takes the same samples through `spacearm.dynamics.wheel_momentum` and the
``"attitude"`` inverse dynamics: the largest norm of the momentum h that reaction wheels must
hold for the bus not to turn (bus axes, N m s) and of the torque they apply to the bus
(-dh/dt, N m), what sizes a wheel assembly for the task.

A peak over samples is a maximum of smooth functions of the design: it is differentiable
wherever one sample attains it, which is almost everywhere, and its gradient there is the
gradient of that sample's value (where several samples tie, JAX splits the cotangent among
them, a subgradient). That is what the design objectives' gradient search needs; a smooth
maximum (log-sum-exp) would bias the value itself and is not used. The peak of a norm is
taken as the square root of the peak squared norm, whose gradient stays finite at the rest
samples where the wrench is zero.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from .._core.schema import check_keys, number
from ..dynamics import BASE_MODES, inverse_dynamics, wheel_momentum
from ..models.family import family_of

__all__ = [
    "MAX_WAYPOINTS",
    "SEGMENT_SAMPLES",
    "TaskPeaks",
    "TimedTask",
    "WheelPeaks",
    "peak_norm",
    "quintic_time_law",
    "task_from_mapping",
    "task_peaks",
    "task_states",
    "wheel_peaks",
]

SEGMENT_SAMPLES = 101  # samples per segment, both ends included
MAX_WAYPOINTS = 1024  # rows of a task read from a file (each segment is 101 states per design)


@dataclasses.dataclass(frozen=True, eq=False)
class TimedTask:
    """Joint waypoints visited in a given time, each segment on the quintic time law.

    Validated at construction (from concrete values); a pytree whose leaves are the
    waypoints and the duration, so a task passes through ``jit`` and ``vmap`` as data.

    Attributes:
        waypoints: ``(k, n)`` joint positions, rad (m for a prismatic joint), k >= 2.
        duration: the whole task's time, s (each segment takes duration / (k - 1)).
    """

    waypoints: Any
    duration: Any

    def __post_init__(self):
        waypoints = np.asarray(self.waypoints, dtype=np.float64)
        if waypoints.ndim != 2 or waypoints.shape[0] < 2 or waypoints.shape[1] < 1:
            raise ConfigError(
                f"task.waypoints: must be a (k, n) array of joint positions with k >= 2 waypoints, "
                f"got shape {waypoints.shape}"
            )
        if not np.all(np.isfinite(waypoints)):
            row = int(np.argwhere(~np.isfinite(waypoints))[0, 0])
            raise ConfigError(f"task.waypoints[{row}]: must be finite numbers, got {waypoints[row].tolist()}")
        duration = float(np.asarray(self.duration))
        if not math.isfinite(duration) or duration <= 0:
            raise ConfigError(f"task.duration: must be a positive number of seconds, got {duration!r}")
        object.__setattr__(self, "waypoints", waypoints)
        object.__setattr__(self, "duration", np.float64(duration))

    @property
    def n_joints(self) -> int:
        return int(np.shape(self.waypoints)[-1])

    @property
    def segment_duration(self):
        """duration / (k - 1), s."""
        return self.duration / (np.shape(self.waypoints)[-2] - 1)

    def to_mapping(self) -> dict:
        """The task as a sweep or problem file writes it (rad, s)."""
        return {"waypoints": np.asarray(self.waypoints).tolist(), "duration": float(self.duration)}


def _flatten(task: TimedTask):
    return (task.waypoints, task.duration), None


def _unflatten(_, leaves) -> TimedTask:
    task = object.__new__(TimedTask)  # leaves may be tracers: validated at construction only
    object.__setattr__(task, "waypoints", leaves[0])
    object.__setattr__(task, "duration", leaves[1])
    return task


jax.tree_util.register_pytree_node(TimedTask, _flatten, _unflatten)


def task_from_mapping(where: str, entry: Any, joint_kinds: tuple[str, ...]) -> TimedTask:
    """A task as a sweep or problem file gives it, checked against the robot's joints.

    ``{waypoints: [[...], ...], duration: 4.0}`` with the joints in rad (m for a prismatic
    joint), or ``waypoints_deg`` with the revolute joints in degrees (prismatic still in m).

    Raises:
        ConfigError: naming ``where`` (the file) and the field.
    """
    if not isinstance(entry, Mapping):
        raise ConfigError(f"{where}: task: must be a mapping {{waypoints: [[...], ...], duration: seconds}}")
    check_keys(f"{where}: task: ", entry, {"waypoints", "waypoints_deg", "duration"})
    if ("waypoints" in entry) == ("waypoints_deg" in entry):
        raise ConfigError(f"{where}: task: give exactly one of waypoints (rad) or waypoints_deg (degrees)")
    key = "waypoints" if "waypoints" in entry else "waypoints_deg"
    rows = entry[key]
    n = len(joint_kinds)
    if not isinstance(rows, (list, tuple)) or not 2 <= len(rows) <= MAX_WAYPOINTS:
        raise ConfigError(
            f"{where}: task.{key}: must be a list of 2 to {MAX_WAYPOINTS} waypoints, each a list of {n} joint positions"
        )
    for i, row in enumerate(rows):
        if not isinstance(row, (list, tuple)) or len(row) != n:
            got = len(row) if isinstance(row, (list, tuple)) else repr(row)
            raise ConfigError(f"{where}: task.{key}[{i}]: needs {n} joint positions (one per joint), got {got}")
    values = np.array(
        [[number(f"{where}: task.{key}[{i}][{j}]", v) for j, v in enumerate(row)] for i, row in enumerate(rows)]
    )
    if key == "waypoints_deg":
        revolute = np.array([kind != "prismatic" for kind in joint_kinds])
        values = np.where(revolute, np.radians(values), values)
    if "duration" not in entry:
        raise ConfigError(f"{where}: task.duration: missing required key (the task's time, s)")
    duration = number(f"{where}: task.duration", entry["duration"])
    if duration <= 0:
        raise ConfigError(f"{where}: task.duration: must be positive (seconds), got {duration:g}")
    return TimedTask(values, duration)


def quintic_time_law(u: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """``(s, ds/du, d2s/du2)`` of s = 10 u^3 - 15 u^4 + 6 u^5 at phases ``u`` in [0, 1] (any shape)."""
    s = u**3 * (10.0 + u * (-15.0 + 6.0 * u))
    ds = 30.0 * u**2 * (1.0 - u) ** 2
    dds = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u)
    return s, ds, dds


@functools.partial(jax.jit, static_argnames=("samples",))
def task_states(waypoints: jax.Array, duration, samples: int = SEGMENT_SAMPLES):
    """The states of a timed task at ``samples`` instants per segment, ends included.

    Args:
        waypoints: ``(..., k, n)`` joint positions, rad (m for a prismatic joint).
        duration: ``()`` the whole task's time, s; each segment takes duration / (k - 1).
        samples: instants per segment (>= 2), evenly spaced in u, both ends included.

    Returns:
        ``(t (S,), q (..., S, n), qd (..., S, n), qdd (..., S, n))`` with S = (k - 1) samples,
        segment after segment: time, s; joints, rad; rates, rad/s; accelerations, rad/s^2.
    """
    if samples < 2:
        raise ValueError(f"samples: at least 2 per segment (both ends), got {samples}")
    waypoints = jnp.asarray(waypoints)
    if not jnp.issubdtype(waypoints.dtype, jnp.floating):
        waypoints = waypoints.astype(float)
    k, n = waypoints.shape[-2:]
    T = jnp.asarray(duration, waypoints.dtype) / (k - 1)
    u = jnp.linspace(0.0, 1.0, samples, dtype=waypoints.dtype)
    s, ds, dds = quintic_time_law(u)
    start = waypoints[..., :-1, None, :]  # (..., k - 1, 1, n)
    step = waypoints[..., 1:, None, :] - start
    batch = waypoints.shape[:-2]
    shape = batch + ((k - 1) * samples, n)
    q = jnp.reshape(start + s[:, None] * step, shape)
    qd = jnp.reshape((ds[:, None] / T) * step, shape)
    qdd = jnp.reshape((dds[:, None] / T**2) * step, shape)
    t = jnp.reshape((jnp.arange(k - 1, dtype=u.dtype)[:, None] + u) * T, (-1,))
    return t, q, qd, qdd


class TaskPeaks(NamedTuple):
    """The peaks of a robot's efforts along a timed task (`task_peaks`).

    Attributes:
        joint_torque: ``(n,)`` the largest |tau_i| of each joint over the samples, N m (N for a
            prismatic joint), with the bus as `task_peaks`'s ``base`` says.
        held_force: ``()`` the largest norm of the force the bus's actuators apply to keep
            the bus at rest (at its centroid), N.
        held_torque: ``()`` the largest norm of the torque they apply about the bus centroid, N m.
    """

    joint_torque: jax.Array
    held_force: jax.Array
    held_torque: jax.Array

    @property
    def max_joint_torque(self) -> jax.Array:
        """``()`` the largest joint torque of any joint, N m."""
        return jnp.max(self.joint_torque, axis=-1)


def peak_norm(vectors: jax.Array) -> jax.Array:
    """``(...)`` the largest norm of ``(..., S, d)`` vectors over their samples S, as the square
    root of the peak squared norm: its gradient is finite wherever the peak is attained (a
    norm's is not at a zero vector, which every rest sample of a task has), and zero when
    every vector is zero."""
    peak = jnp.max(jnp.sum(vectors**2, axis=-1), axis=-1)
    positive = peak > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, peak, 1.0)), 0.0)


@functools.partial(jax.jit, static_argnames=("linear",))
def _peaks(tau: jax.Array, wrench: jax.Array, linear: tuple[bool, ...]) -> TaskPeaks:
    """`TaskPeaks` of ``(S, n)`` torques and ``(S, len(linear))`` held wrenches; ``linear``
    marks the force components of the wrench."""
    linear = np.asarray(linear)
    return TaskPeaks(
        joint_torque=jnp.max(jnp.abs(tau), axis=-2),
        held_force=peak_norm(wrench[..., linear]),
        held_torque=peak_norm(wrench[..., ~linear]),
    )


def _task_postures(family, task: TimedTask, samples: int):
    """``(q, qd, qdd)`` of the task's samples, q as the family writes a posture (a planar bus
    angle 0 first: at zero momentum nothing here depends on it)."""
    _, q, qd, qdd = task_states(task.waypoints, task.duration, samples)
    posture = jnp.concatenate([jnp.zeros(q.shape[:-1] + (family.posture_offset,), q.dtype), q], axis=-1)
    return posture, qd, qdd


def task_peaks(robot, task: TimedTask, *, base: str = "free", samples: int = SEGMENT_SAMPLES) -> TaskPeaks:
    """The peak joint torques and the peak held wrench of one design along a timed task.

    Every sample of `task_states` goes through `spacearm.dynamics.inverse_dynamics` at once,
    at zero momentum; the peaks are maxima over the samples (differentiable almost
    everywhere, see the module's docstring). Written as calls of those jitted kernels (not
    jitted as a whole), so a direct call of `inverse_dynamics` on the same samples reuses
    their compiled programs; under an outer ``jit`` or ``vmap`` it traces as one program.

    Args:
        robot: one design of any family (vmap over designs).
        task: the `TimedTask`; its waypoints are the joints (a planar robot's bus angle is
            not part of them: at zero momentum nothing here depends on it).
        base: the bus while the joint torques are computed: ``"free"`` (the free-floating
            system, the default), ``"held"`` or ``"attitude"``. The wrench is always the
            ``"held"`` one.
        samples: instants per segment, ends included (`SEGMENT_SAMPLES`).

    Returns:
        `TaskPeaks`: per-joint peak |tau|, N m; peak held force, N; peak held torque, N m.
    """
    if base not in BASE_MODES:
        raise ValueError(f"base: one of {', '.join(BASE_MODES)}, got {base!r}")
    family = family_of(robot)
    posture, qd, qdd = _task_postures(family, task, samples)
    tau, wrench = inverse_dynamics(robot, posture, qd, qdd, base="held")
    if base != "held":
        tau, _ = inverse_dynamics(robot, posture, qd, qdd, base=base)
    return _peaks(tau, wrench, tuple(bool(axis < 3) for axis in family.twist_axes))  # [x, y, z]: the force


class WheelPeaks(NamedTuple):
    """The reaction-wheel effort a timed task costs (`wheel_peaks`).

    Attributes:
        momentum: ``()`` the largest norm of the wheel momentum h over the samples, N m s.
        torque: ``()`` the largest norm of the torque the wheels apply to the bus, N m.
    """

    momentum: jax.Array
    torque: jax.Array


def wheel_peaks(robot, task: TimedTask, *, samples: int = SEGMENT_SAMPLES) -> WheelPeaks:
    """The peak wheel momentum and wheel torque of one design along a timed task.

    The bus attitude is held by reaction wheels alone (the bus translates freely) and the
    task starts at rest at zero momentum. At each sample the wheels hold
    h = `spacearm.dynamics.wheel_momentum` (q, qd) and apply the torque of the ``"attitude"``
    wrench of `spacearm.dynamics.inverse_dynamics` (q, qd, qdd), which is -dh/dt. Planar
    robots: both about the plane's normal. Peaks as in `task_peaks` (differentiable almost
    everywhere).

    Returns:
        `WheelPeaks`: peak ||h||, N m s; peak wheel torque, N m.
    """
    family = family_of(robot)
    posture, qd, qdd = _task_postures(family, task, samples)
    h = wheel_momentum(robot, posture, qd)
    _, wrench = inverse_dynamics(robot, posture, qd, qdd, base="attitude")
    angular = np.asarray(family.twist_axes) >= 3
    h = h if h.ndim == qd.ndim else h[..., None]  # planar: the one component about z
    return WheelPeaks(momentum=peak_norm(h), torque=peak_norm(wrench[..., angular]))
