"""Reaction-free motion of redundant spatial arms and trees of arms, and the bus-disturbance map.

The bus angular velocity at zero momentum is omega_B = C_w(q) q_dot (bus axes; C_w the
angular rows of C(q) = -I_S^-1 I_M). Joint rates in ker C_w turn the bus not at all:
the reaction null space (Nenchev, Umetani & Yoshida, IEEE TRA 8(1), 1992; flown on
ETS-VII, Yoshida, Hashizume & Abiko, ICRA 2001), of dimension n - 3 for an arm with
n > 3 joints where C_w has full rank.

- `reaction_null_space`: an orthonormal basis of ker C_w(q);
- `disturbance`, `disturbance_map`: ||C_w(q) u|| for unit joint rates u,
  its extreme values over u (the singular values of C_w) and the least-disturbing
  direction (the right singular vector of the smallest one; Dubowsky & Torres, ICRA
  1991), over any batch of postures (e.g. a joint grid);
- `reaction_free_tip_path`: a straight tip translation with zero bus rotation:
  q' solves [C_w; J*_v] q' = [0; R0^T d] (minimum norm for n > 6; least squares, with
  the tip residual reported, where the null space cannot produce the direction, n < 6).
  The bus attitude then stays R0, so the bus-frame direction is constant; the path is
  integrated in the tip distance with fixed DOP853 steps, and the reached bus rotation
  is measured independently by running the sampled joint path through the SO(3)
  integrator (`spacearm.motion.integrate_joint_path`).

Written over the robot-family seam (``attitude_rate_map``, ``straight_maps``, ``tip``,
``moving_joints``), so it serves a spatial arm and a tree of arms focused on one tip
(`spacearm.models.tree.robot.TreeRobot.focus`). On a tree whose every joint moves, the
reaction-free path of one tip is the "balance arm" (Huang, Xu & Liang, IJARS 2005;
Nenchev 2013): the minimum-norm rates of [C_w; J*_v] use the other arms to cancel the
bus rotation. Held joints of a focused tree take no part: their columns are zero, their
rates exactly zero, and the null space and disturbance extremes are over the moving
joints only.

Everything is batched over leading axes and written for one posture under ``vmap``.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from .._core.batching import bucket_size, pad_leading
from .._core.errors import ConfigError
from ..models.family import family_of
from ..motion import dop853
from ..motion.batching import flatten_batch, is_traced, unpad

__all__ = [
    "DisturbanceMap",
    "ReactionFreePath",
    "disturbance",
    "disturbance_map",
    "reaction_free_rates",
    "reaction_free_tip_path",
    "reaction_null_space",
]


def _moving_count(robot) -> int:
    """The number of joints that move (host: the shapes of the null space depend on it)."""
    mask = family_of(robot).moving_joints(robot)
    if isinstance(mask, jax.core.Tracer):
        raise TypeError(
            "the reaction null space of a focused tree has as many columns as the focus moves joints: "
            "pass the focused design to it concretely (outside jit), not traced"
        )
    return int(np.count_nonzero(np.asarray(mask)))


def _moving(robot, m: int) -> jax.Array:
    """Indices of the ``m`` joints that move (traced with the design's focus)."""
    return jnp.flatnonzero(jnp.asarray(family_of(robot).moving_joints(robot)), size=m)


def _bus_rate_map(robot, q: jax.Array, m: int) -> jax.Array:
    """``(..., 3, m)`` C_w over the moving joints."""
    return family_of(robot).attitude_rate_map(robot, q)[..., _moving(robot, m)]


def _embed(robot, rates: jax.Array, m: int) -> jax.Array:
    """``(..., m)`` -> ``(..., n)`` with zeros at the held joints."""
    n = family_of(robot).joint_count(robot)
    out = jnp.zeros(rates.shape[:-1] + (n,), rates.dtype)
    return out.at[..., _moving(robot, m)].set(rates)


def reaction_null_space(robot, q: jax.Array) -> jax.Array:
    """``(..., n, m - 3)`` orthonormal basis of ker C_w(q) (joint rates that do not turn the bus).

    m is the number of moving joints (all n, except in a focused tree); the rows of held
    joints are zero.

    Args:
        q: ``(..., n)`` joints, m > 3.
    """
    m = _moving_count(robot)
    if m <= 3:
        raise ConfigError(f"the reaction null space needs more than 3 moving joints, the robot has {m}")
    return _reaction_null_space(robot, q, m)


@functools.partial(jax.jit, static_argnums=2)
def _reaction_null_space(robot, q: jax.Array, m: int) -> jax.Array:
    _, _, vt = jnp.linalg.svd(_bus_rate_map(robot, q, m), full_matrices=True)
    return jnp.swapaxes(_embed(robot, vt[..., 3:, :], m), -1, -2)


@jax.jit
def disturbance(robot, q: jax.Array, joint_rates: jax.Array) -> jax.Array:
    """``(...)`` ||C_w(q) u|| / ||u||: bus angular speed per unit joint speed, rad/rad.

    Args:
        q: ``(..., n)`` joints; joint_rates: ``(..., n)`` directions u (any nonzero scale).
    """
    u = jnp.asarray(joint_rates)
    w = jnp.einsum("...ij,...j->...i", family_of(robot).attitude_rate_map(robot, q), u)
    return jnp.linalg.norm(w, axis=-1) / jnp.linalg.norm(u, axis=-1)


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class DisturbanceMap:
    """The bus disturbance per unit joint rate at a batch of postures.

    Attributes:
        largest: ``(...)`` max over unit u of ||C_w u||, rad/rad.
        smallest: ``(...)`` min over unit u (0 for n > 3 where C_w has full rank).
        singular_values: ``(..., min(3, n))`` of C_w, largest first.
        least_disturbing: ``(..., n)`` unit joint direction of the smallest disturbance
            (for n > 3 a direction of the reaction null space).
        most_disturbing: ``(..., n)`` unit joint direction of the largest disturbance.
    """

    largest: jax.Array
    smallest: jax.Array
    singular_values: jax.Array
    least_disturbing: jax.Array
    most_disturbing: jax.Array


def disturbance_map(robot, q: jax.Array) -> DisturbanceMap:
    """Extremes of ||C_w(q) u|| over unit joint rates u (Dubowsky & Torres 1991), ``q (..., n)``.

    Over a joint grid (e.g. `numpy.meshgrid` of two joints, the others fixed) this is
    the disturbance map; the least-disturbing direction is the right singular vector of
    the smallest singular value of C_w.
    """
    return _disturbance_map(robot, q, _moving_count(robot))


@functools.partial(jax.jit, static_argnums=2)
def _disturbance_map(robot, q: jax.Array, m: int) -> DisturbanceMap:
    _, s, vt = jnp.linalg.svd(_bus_rate_map(robot, q, m), full_matrices=True)
    smallest = s[..., -1] if m <= 3 else jnp.zeros_like(s[..., -1])
    return DisturbanceMap(
        largest=s[..., 0],
        smallest=smallest,
        singular_values=s,
        least_disturbing=_embed(robot, vt[..., -1, :], m),
        most_disturbing=_embed(robot, vt[..., 0, :], m),
    )


def reaction_free_rates(robot, q: jax.Array, tip_direction_bus: jax.Array):
    """Joint rates moving the tip at unit speed along a bus-frame direction without turning the bus.

    Solves [C_w; J*_v] q' = [0; d] (one posture) in the least-squares, minimum-norm sense
    (held joints of a focused tree have zero columns, hence zero rates).

    Returns:
        ``(q' (n,), tip residual ||J*_v q' - d|| (), bus rate ||C_w q'|| ())``.
    """
    J, C = family_of(robot).straight_maps(robot, q)  # one pass over the chain or tree
    return _rates_from_maps(J, C, tip_direction_bus)


def _rates_from_maps(J, C, tip_direction_bus):
    """`reaction_free_rates` from J*_v and C_w at the posture."""
    A = jnp.concatenate([C, J], axis=0)
    b = jnp.concatenate([jnp.zeros(3, J.dtype), tip_direction_bus])
    rates = jnp.linalg.pinv(A, rtol=1e-12) @ b
    return rates, jnp.linalg.norm(J @ rates - tip_direction_bus), jnp.linalg.norm(C @ rates)


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class ReactionFreePath:
    """A reaction-free straight tip translation, sampled.

    Attributes:
        joints: ``(..., steps + 1, n)`` joints along the path (tip distance 0..length).
        tip: ``(..., steps + 1, 3)`` tip about the system centroid, inertial axes, m.
        tip_residual: ``(...)`` largest ||J*_v q' - d|| along the path (0 where the
            null space produces the direction; > 0 where it cannot, n < 6).
        bus_rate: ``(...)`` largest ||C_w q'|| along the path, rad/m (rounding level).
        smallest_singular_value: ``(...)`` smallest singular value of [C_w; J*_v] met
            along the path (near 0: a singularity of reaction-free motion).
    """

    joints: jax.Array
    tip: jax.Array
    tip_residual: jax.Array
    bus_rate: jax.Array
    smallest_singular_value: jax.Array


@functools.partial(jax.jit, static_argnames=("steps",))
def _reaction_free_flat(robot, q0, R0, direction, length, steps):
    """A padded batch of reaction-free paths (the padding rows are copies of a real one)."""
    family = family_of(robot)
    # [J*_v; C_w] has zero columns at the held joints: over the m moving ones its smallest
    # singular value is the min(m, 6)-th of the whole matrix's.
    moving = jnp.sum(jnp.asarray(family.moving_joints(robot)) > 0)
    smallest = jnp.minimum(moving, min(6, family.joint_count(robot))) - 1

    def one(q0, R0, d, length):
        d_bus = R0.T @ (d / jnp.linalg.norm(d))

        def field(q):
            # The rates, and from the same pass the checks (tip residual, bus rate, smallest
            # singular value of [J*_v; C_w] over the moving joints) as the stage's aux.
            J, C = family.straight_maps(robot, q)
            rates, residual, bus = _rates_from_maps(J, C, d_bus)
            sv = jnp.linalg.svd(jnp.concatenate([J, C]), compute_uv=False)[smallest]
            return rates, jnp.stack([residual, bus, sv])

        h = length / steps
        zero = jnp.zeros((3,), q0.dtype)

        def step(q, _):
            # The field holds a scan over the chain: the stages run in a loop (one copy of
            # the field in the program), as for spatial straight paths; a 13th stage at the
            # step's end gives the checks at the next sample, the first at this one.
            q_new, checks = dop853.rk_step(field, q, h, rolled=True, end_slope=True, aux=zero)
            return q_new, (q_new, checks[0], checks[-1])

        _, (qs, at_start, at_end) = jax.lax.scan(step, q0, None, length=steps)
        joints = jnp.concatenate([q0[None], qs], axis=0)
        checks = jnp.concatenate([at_start[:1], at_end], axis=0)  # (steps + 1, 3), one row per sample
        tip = jnp.einsum("ij,sj->si", R0, jax.vmap(lambda q: family.tip(robot, q))(joints))
        return ReactionFreePath(joints, tip, jnp.max(checks[:, 0]), jnp.max(checks[:, 1]), jnp.min(checks[:, 2]))

    return jax.vmap(one)(q0, R0, direction, length)


def reaction_free_tip_path(
    robot,
    q_start: jax.Array,
    direction: jax.Array,
    length: jax.Array | float,
    *,
    base_rotation: jax.Array | None = None,
    steps: int = 200,
) -> ReactionFreePath:
    """Translate the tip along an inertial direction with joint rates in the reaction null space.

    On a tree of arms focused on one tip with every joint moving
    (``robot.focus(tip="left/tool0")``) this is the balance arm: the other arms cancel
    the bus rotation the tip's arm causes.

    Args:
        robot: one spatial design, or a tree focused on one tip, with at least 4 moving joints.
        q_start: ``(..., n)`` joints at the start.
        direction: ``(..., 3)`` inertial direction of the tip motion.
        length: ``(...)`` tip distance, m.
        base_rotation: ``(..., 3, 3)`` bus attitude (constant along the path), default identity.
        steps: fixed DOP853 steps in the tip distance (static).

    Returns:
        `ReactionFreePath` with the broadcast batch shape.
    """
    n = family_of(robot).joint_count(robot)
    m = _moving_count(robot)
    if m < 4:
        raise ConfigError(
            f"reaction-free tip motion needs at least 4 moving joints (a reaction null space), the robot has {m}"
        )
    if robot.batch_shape:
        raise ConfigError("reaction_free_tip_path: one design at a time")
    dtype = jnp.result_type(float)
    # Concrete inputs are prepared in NumPy (eager jnp would compile a program per operation).
    xp = jnp if is_traced(robot, q_start, direction, length, base_rotation) else np
    q_start = xp.asarray(q_start, dtype)
    direction = xp.asarray(direction, dtype)
    R0 = xp.eye(3, dtype=dtype) if base_rotation is None else xp.asarray(base_rotation, dtype)
    length = xp.asarray(length, dtype)
    if q_start.shape[-1:] != (n,) or direction.shape[-1:] != (3,):
        raise ConfigError(f"q_start (..., {n}) and direction (..., 3) expected, got {q_start.shape}, {direction.shape}")
    batch, _, _, flat = flatten_batch(robot, [(q_start, 1), (R0, 2), (direction, 1), (length, 0)])
    count = math.prod(batch)
    inputs = pad_leading(tuple(flat), bucket_size(count))  # one program per power of two of paths
    return unpad(_reaction_free_flat(robot, *inputs, int(steps)), count, batch)
