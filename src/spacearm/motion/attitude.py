"""The bus attitude on SO(3) along joint-space paths of a spatial arm.

At zero momentum the bus angular velocity depends on the joint state only,
omega_B = C_w(q) q_dot (bus axes, C_w the angular rows of the base twist map C(q) =
-I_S^-1 I_M; Umetani & Yoshida 1990, eq. 5, in 3-D), so along a prescribed joint path
the attitude R (bus axes -> inertial axes) obeys the linear, driftless ODE

    R' = R [omega_B]x,

independent of the timing. Along a straight joint segment q(t) = a + t d, t in [0, 1],
the generator is a(t) = C_w(a + t d) d. Each segment is split into ``steps`` equal
sub-steps and each sub-step advanced by the 6th-order Magnus integrator on three
Gauss-Legendre nodes (Blanes, Casas & Ros, BIT 40, 2000; Blanes, Casas, Oteo & Ros,
Phys. Rep. 470, 2009, eq. 4.59)

    R_{k+1} = R_k expm([Omega_k]x),

with expm by Rodrigues' formula: the result stays on SO(3) to rounding whatever the
step. The 4th-order Magnus scheme on two Gauss nodes and RKMK4 are kept for the
measurements in docs/explanation/spatial-attitude.md, which chose the default: order
6, with steps of at most 0.15 rad of joint motion (3 evaluations of C_w per step;
about 6e-13 rad for UR5 loops of 0.6-rad segments at 4 steps, 1e-11 rad for 2-rad
segments at 16 steps).

The sub-step rotations of a whole path are independent once the nodes are known: all
C_w evaluations of all paths run in one batched call (for one design) and the ordered
product of the rotations is a balanced tree of 3x3 products (depth log2 of the step
count). The public entry points flatten paths, start attitudes and designs into one
batch inside one ``jit``.

The Magnus schemes live in `spacearm._core.magnus` (the spatial family's
``loop_holonomy``), the SO(3) helpers `hat`, `vee`, `expm` (Rodrigues), `log` and
`geodesic_distance` in `spacearm._core.groups`; both are re-exported here.
"""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from .._core.groups import expm, geodesic_distance, hat, log, vee
from .._core.magnus import (
    DEFAULT_ORDER,
    DEFAULT_STEPS,
    check_order,
    path_rotation,
    path_rotation_history,
    step_generators,
    step_nodes,
)
from ..models.family import family_of
from .batching import flatten_batch, is_traced, unpad

__all__ = [
    "DEFAULT_ORDER",
    "DEFAULT_STEPS",
    "MAX_STEP",
    "bus_rate_map",
    "choose_steps",
    "expm",
    "geodesic_distance",
    "hat",
    "integrate_so3_joint_path",
    "log",
    "path_rotation",
    "path_rotation_history",
    "so3_joint_path_history",
    "step_generators",
    "step_nodes",
    "vee",
]

# Largest joint move per Magnus step (infinity norm, rad or m) when the step count is
# chosen from the data: 6th-order steps of 0.15 rad keep UR5 errors near 1e-11 rad per
# 2-rad segment (docs/explanation/spatial-attitude.md).
MAX_STEP = 0.15

# The generator -----------------------------------------------------------------------------


def bus_rate_map(robot, q: jax.Array) -> jax.Array:
    """``(..., 3, n)`` C_w(q): bus angular velocity (bus axes) per joint rate.

    The angular rows of the base twist map C(q) = -I_S^-1 I_M (zero momentum), for
    ``q (..., n)`` with any leading batch (one batch-last pass over the chain).
    """
    return family_of(robot).attitude_rate_map(robot, q)


# Public entry points (spatial robots) ----------------------------------------------------


def _prepare(robot, q_start, joint_waypoints, base_rotation):
    n = robot.n_joints
    dtype = jnp.result_type(float)
    # Concrete inputs stay NumPy (jnp.asarray of one compiles a conversion program).
    xp = jnp if is_traced(q_start, joint_waypoints, base_rotation) else np
    q_start = xp.asarray(q_start, dtype)
    joint_waypoints = xp.asarray(joint_waypoints, dtype)
    if base_rotation is None:
        base_rotation = xp.eye(3, dtype=dtype)
    base_rotation = xp.asarray(base_rotation, dtype)
    if q_start.ndim < 1 or q_start.shape[-1] != n:
        raise ConfigError(f"q_start: expected shape (..., {n}) for a {n}-joint arm, got {q_start.shape}")
    if joint_waypoints.ndim < 2 or joint_waypoints.shape[-1] != n or joint_waypoints.shape[-2] < 2:
        raise ConfigError(f"joint_waypoints: expected shape (..., k, {n}) with k >= 2, got {joint_waypoints.shape}")
    if base_rotation.shape[-2:] != (3, 3):
        raise ConfigError(f"base_rotation: expected shape (..., 3, 3), got {base_rotation.shape}")
    if not is_traced(q_start, joint_waypoints):
        gap = np.max(np.abs(np.asarray(joint_waypoints[..., 0, :]) - np.asarray(q_start)), initial=0.0)
        if not gap <= 1e-9:
            raise ConfigError(f"joint_waypoints: the first row must equal q_start (largest gap {gap:.3g})")
        moving = family_of(robot).moving_joints(robot)
        held = np.zeros(np.shape(moving), bool) if is_traced(moving) else np.asarray(moving) == 0
        if np.any(held):  # a focused tree: its held joints have no columns in C_w
            moved = np.max(np.abs(np.asarray(joint_waypoints)[..., held] - np.asarray(q_start)[..., None, held]))
            if not moved <= 1e-12:
                raise ConfigError(
                    f"joint_waypoints: the path moves joints this robot holds (by up to {moved:.3g}); "
                    "integrate it on the whole robot, without the focus on some arms"
                )
    return q_start, joint_waypoints, base_rotation


def choose_steps(joint_waypoints, steps: int | None) -> int:
    """Magnus steps per segment: ``steps`` if given; else from the largest joint move of
    any segment (``MAX_STEP`` per step, rounded up to a power of two so that few step
    counts, hence few compilations, occur); `DEFAULT_STEPS` under tracing."""
    if steps is not None:
        if int(steps) < 1:
            raise ConfigError(f"steps: expected a positive number of Magnus steps per segment, got {steps}")
        return int(steps)
    if is_traced(joint_waypoints):
        return DEFAULT_STEPS
    wp = np.asarray(joint_waypoints)
    largest = float(np.max(np.abs(np.diff(wp, axis=-2)), initial=0.0))
    if not np.isfinite(largest):
        raise ConfigError("joint_waypoints: must be finite")
    needed = max(1, math.ceil(largest / MAX_STEP))
    return 1 << (needed - 1).bit_length()


@functools.partial(jax.jit, static_argnames=("robot_batched", "steps", "order"))
def _integrate_flat(robot, waypoints, base_rotation, robot_batched, steps, order):
    def rotate(robot, wp):
        return family_of(robot).loop_holonomy(robot, wp, steps=steps, order=order)

    if robot_batched:  # one design per path
        return base_rotation @ jax.vmap(rotate)(robot, waypoints)
    return base_rotation @ rotate(robot, waypoints)  # every node of every path in one batched pass


def integrate_so3_joint_path(
    robot,
    q_start: jax.Array,
    joint_waypoints: jax.Array,
    base_rotation: jax.Array | None = None,
    *,
    steps: int | None = None,
    order=DEFAULT_ORDER,
) -> tuple[jax.Array, jax.Array]:
    """Bus attitude and joints at the end of a joint-space polyline (zero momentum).

    Integrates R' = R [C_w(q) q']x along straight joint segments by the 6th-order
    Magnus scheme (module docstring), ``steps`` sub-steps per segment. By default the
    step count follows the largest joint move of any segment, at most ``MAX_STEP``
    (0.15 rad) per step, rounded up to a power of two (`choose_steps`): about
    1e-11 rad or better on the UR5 for segments up to 2 rad.

    Args:
        robot: a spatial design, or a batch of designs broadcasting with the paths.
        q_start: ``(..., n)`` joints at the start, rad (m for prismatic joints).
        joint_waypoints: ``(..., k, n)`` joints joined by straight segments; the first
            row equals ``q_start``.
        base_rotation: ``(..., 3, 3)`` bus attitude at the start (bus axes -> inertial
            axes); default identity.
        steps: sub-steps per segment (static); ``None`` chooses from the data (4 under tracing).
        order: ``6`` (default), ``4`` or ``"rkmk4"`` (static).

    Returns:
        ``(R_end (..., 3, 3), q_end (..., n))``: the attitude at the last waypoint and
        the last waypoint.
    """
    q_start, joint_waypoints, base_rotation = _prepare(robot, q_start, joint_waypoints, base_rotation)
    batch, flat_robot, batched, (wp_flat, R_flat, _q_flat) = flatten_batch(
        robot, [(joint_waypoints, 2), (base_rotation, 2), (q_start, 1)]
    )
    check_order(order)
    R_end = _integrate_flat(flat_robot, wp_flat, R_flat, batched, choose_steps(joint_waypoints, steps), order)
    # The joints at the end are the flattened last waypoints (NumPy when concrete).
    return unpad((R_end, wp_flat[:, -1, :]), wp_flat.shape[0], batch)


@functools.partial(jax.jit, static_argnames=("robot_batched", "samples", "steps", "order"))
def _history_flat(robot, waypoints, base_rotation, robot_batched, samples, steps, order):
    fractions = jnp.asarray(np.arange(samples) / samples, waypoints.dtype)

    def one(robot, wp, R0):
        starts, moves = wp[:-1], wp[1:] - wp[:-1]
        sub = (starts[:, None, :] + fractions[None, :, None] * moves[:, None, :]).reshape(-1, wp.shape[-1])
        points = jnp.concatenate([sub, wp[-1:]], axis=0)
        rotations = path_rotation_history(functools.partial(bus_rate_map, robot), points, steps, order)[::steps]
        return R0 @ rotations, points

    return jax.vmap(one, in_axes=(0 if robot_batched else None, 0, 0))(robot, waypoints, base_rotation)


def so3_joint_path_history(
    robot,
    q_start: jax.Array,
    joint_waypoints: jax.Array,
    base_rotation: jax.Array | None = None,
    samples_per_segment: int = 32,
    *,
    steps: int = 1,
    order=DEFAULT_ORDER,
) -> tuple[jax.Array, jax.Array]:
    """Bus attitudes and joints sampled along a joint polyline.

    Each segment is sampled at ``samples_per_segment`` equal intervals (each advanced
    by ``steps`` Magnus steps); the last sample is the last waypoint.

    Returns:
        ``(R (..., S, 3, 3), q (..., S, n))`` with S = (k - 1) samples_per_segment + 1;
        ``R[..., -1, :, :]`` equals `integrate_so3_joint_path`'s attitude.
    """
    q_start, joint_waypoints, base_rotation = _prepare(robot, q_start, joint_waypoints, base_rotation)
    batch, flat_robot, batched, (wp_flat, R_flat, _) = flatten_batch(
        robot, [(joint_waypoints, 2), (base_rotation, 2), (q_start, 1)]
    )
    R, q = _history_flat(flat_robot, wp_flat, R_flat, batched, int(samples_per_segment), int(steps), order)
    count = q.shape[1]
    return R.reshape(batch + (count, 3, 3)), q.reshape(batch + (count, robot.n_joints))
