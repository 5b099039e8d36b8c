"""The joint box and its uniform measure, with randomized Sobol points for averages over it.

The joint box of a design is the product of its joint ranges:

- a joint with finite limits covers [lower, upper];
- a revolute joint without limits (URDF ``continuous``, planar links without
  ``limit_deg``) covers one turn, [-pi, pi);
- a revolute joint limited on one side only covers one turn from its finite limit:
  [lower, lower + 2 pi) or [upper - 2 pi, upper);
- a revolute joint whose limits span more than a turn (the UR5's +-2 pi) covers one
  turn from its lower limit;

(the last three because every posture of a revolute joint then appears exactly once,
and every kinematic quantity is periodic in a revolute angle, so averages and extremes
are the same as over the full range);
- a prismatic joint must have finite limits (`ConfigError` otherwise).

The box is written for any robot family (planar postures get phi0 = 0 in front,
``family.posture_offset``). The limits are design leaves: averages and extremes over
the box are differentiable in them too (the points move with the box).

Quasi-Monte Carlo points: a Sobol sequence (Joe & Kuo's direction numbers,
``new-joe-kuo-6.21201``, for up to 32 joints; tests/test_averages.py checks them
against SciPy's generator) in its natural order, so the first 2^m points of any
block-aligned run form a (t, m, s)-net. Randomization by a random digital shift (an
XOR of every point with one random 32-bit word per dimension): each randomization is
an unbiased estimate, and the spread of independent randomizations estimates the
error.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from ..models.family import family_of

__all__ = [
    "MAX_SOBOL_DIMENSION",
    "box_postures",
    "check_joint_box",
    "digital_shifts",
    "joint_box",
    "joint_kinds",
    "periodic_joints",
    "sobol_direction_numbers",
    "sobol_points",
]

# Joe & Kuo (2008), new-joe-kuo-6.21201: (degree s, coefficients a, initial m_1..m_s)
# for dimensions 2..32 (dimension 1 is the van der Corput sequence, m_k = 1): enough for
# several arms on one bus (two 7-joint arms and a torso lift are 15 joints).
_JOE_KUO = (
    (1, 0, (1,)),
    (2, 1, (1, 3)),
    (3, 1, (1, 3, 1)),
    (3, 2, (1, 1, 1)),
    (4, 1, (1, 1, 3, 3)),
    (4, 4, (1, 3, 5, 13)),
    (5, 2, (1, 1, 5, 5, 17)),
    (5, 4, (1, 1, 5, 5, 5)),
    (5, 7, (1, 1, 7, 11, 19)),
    (5, 11, (1, 1, 5, 1, 1)),
    (5, 13, (1, 1, 1, 3, 11)),
    (5, 14, (1, 3, 5, 5, 31)),
    (6, 1, (1, 3, 3, 9, 7, 49)),
    (6, 13, (1, 1, 1, 15, 21, 21)),
    (6, 16, (1, 3, 1, 13, 27, 49)),
    (6, 19, (1, 1, 1, 15, 7, 5)),
    (6, 22, (1, 3, 1, 15, 13, 25)),
    (6, 25, (1, 1, 5, 5, 19, 61)),
    (7, 1, (1, 3, 7, 11, 23, 15, 103)),
    (7, 4, (1, 3, 7, 13, 13, 15, 69)),
    (7, 7, (1, 1, 3, 13, 7, 35, 63)),
    (7, 8, (1, 3, 5, 9, 1, 25, 53)),
    (7, 14, (1, 3, 1, 13, 9, 35, 107)),
    (7, 19, (1, 3, 1, 5, 27, 61, 31)),
    (7, 21, (1, 1, 5, 11, 19, 41, 61)),
    (7, 28, (1, 3, 5, 3, 3, 13, 69)),
    (7, 31, (1, 1, 7, 13, 1, 19, 1)),
    (7, 32, (1, 3, 7, 5, 13, 19, 59)),
    (7, 37, (1, 1, 3, 9, 25, 29, 41)),
    (7, 41, (1, 3, 5, 13, 23, 1, 55)),
    (7, 42, (1, 3, 7, 3, 13, 59, 17)),
)
MAX_SOBOL_DIMENSION = len(_JOE_KUO) + 1
_BITS = 32


def sobol_direction_numbers(dimension: int) -> np.ndarray:
    """``(dimension, 32)`` uint32 direction numbers v_{d,k} = m_{d,k} 2^(32-k), k = 1..32."""
    if not 1 <= dimension <= MAX_SOBOL_DIMENSION:
        raise ConfigError(f"joints: the joint-box averages support 1 to {MAX_SOBOL_DIMENSION} joints, got {dimension}")
    table = np.zeros((dimension, _BITS), dtype=np.uint64)
    table[0] = 1
    for d in range(1, dimension):
        s, a, initial = _JOE_KUO[d - 1]
        m = list(initial)
        for k in range(s, _BITS):
            value = m[k - s] ^ (m[k - s] << s)
            for i in range(1, s):
                if (a >> (s - 1 - i)) & 1:
                    value ^= m[k - i] << i
            m.append(value)
        table[d] = m[:_BITS]
    shifts = np.arange(_BITS - 1, -1, -1, dtype=np.uint64)  # 2^(32 - k) for k = 1..32
    return (table << shifts).astype(np.uint32)


def sobol_points(directions: jax.Array, start, count: int, shift: jax.Array) -> jax.Array:
    """Digitally shifted Sobol points of indices ``start .. start + count - 1`` (natural order).

    Args:
        directions: ``(d, 32)`` uint32 from `sobol_direction_numbers`.
        start: first index (a traced integer is fine).
        count: number of points (static).
        shift: ``(..., d)`` uint32 digital shifts (one row per randomization).

    Returns:
        ``(..., count, d)`` points in (0, 1): x = ((Sobol integer XOR shift) + 1/2) 2^-32.
    """
    index = (jnp.asarray(start, jnp.uint32) + jnp.arange(count, dtype=jnp.uint32))[:, None]
    bits = ((index >> jnp.arange(_BITS, dtype=jnp.uint32)) & 1).astype(bool)  # (count, 32)
    words = jnp.where(bits[:, None, :], directions[None, :, :], jnp.uint32(0))  # (count, d, 32)
    integer = jax.lax.reduce(words, jnp.uint32(0), jax.lax.bitwise_xor, (2,))  # (count, d)
    shifted = jnp.bitwise_xor(integer, jnp.asarray(shift, jnp.uint32)[..., None, :])
    dtype = jnp.result_type(float)
    return (shifted.astype(dtype) + 0.5) * (2.0**-_BITS)


_THREEFRY_ROTATIONS = ((13, 15, 26, 6), (17, 29, 16, 24))


def _threefry_2x32(key: tuple[int, int], x0: np.ndarray, x1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The Threefry-2x32 hash (20 rounds; Salmon et al., SC 2011) of counter pairs, in NumPy uint32."""
    k0, k1 = np.uint32(key[0]), np.uint32(key[1])
    ks = (k0, k1, k0 ^ k1 ^ np.uint32(0x1BD11BDA))
    x0, x1 = x0 + ks[0], x1 + ks[1]
    for group in range(5):
        for r in _THREEFRY_ROTATIONS[group % 2]:
            x0 = x0 + x1
            x1 = x0 ^ ((x1 << np.uint32(r)) | (x1 >> np.uint32(32 - r)))
        x0 = x0 + ks[(group + 1) % 3]
        x1 = x1 + ks[(group + 2) % 3] + np.uint32(group + 1)
    return x0, x1


def _host_shifts(seed: int, randomizations: int, dimension: int) -> np.ndarray:
    """`digital_shifts` for a concrete seed, in NumPy: equal to ``jax.random.bits(jax.random.key(seed),
    (randomizations, dimension), uint32)`` (the partitionable Threefry counters, JAX's default),
    with no program to compile."""
    word = int(np.int64(seed).view(np.uint64))
    index = np.arange(randomizations * dimension, dtype=np.uint64)
    with np.errstate(over="ignore"):
        high, low = _threefry_2x32(
            (word >> 32, word & 0xFFFFFFFF), (index >> 32).astype(np.uint32), (index & 0xFFFFFFFF).astype(np.uint32)
        )
    return (high ^ low).reshape(randomizations, dimension)


@functools.partial(jax.jit, static_argnums=(1, 2))
def _traced_shifts(seed, randomizations: int, dimension: int) -> jax.Array:
    return jax.random.bits(jax.random.key(seed), (randomizations, dimension), jnp.uint32)


def digital_shifts(seed, randomizations: int, dimension: int):
    """``(randomizations, dimension)`` independent uniform uint32 words from ``seed``.

    JAX's Threefry bits of ``jax.random.key(seed)``: a traced seed (inside a compiled
    search) draws them in the program; a concrete one in NumPy on the host, the same
    words with no program to compile.
    """
    if isinstance(seed, (int, np.integer)):
        return _host_shifts(int(seed), randomizations, dimension)
    return _traced_shifts(seed, randomizations, dimension)


def joint_kinds(robot) -> tuple[str, ...]:
    """Static joint kinds, ``"revolute"`` or ``"prismatic"`` (the family's `RobotFamily.joint_kinds`)."""
    return family_of(robot).joint_kinds(robot)


def periodic_joints(robot) -> np.ndarray:
    """``(n,)`` static bools: revolute joints (kinematics periodic in the angle)."""
    return np.array([kind == "revolute" for kind in joint_kinds(robot)])


def joint_box(robot) -> tuple[jax.Array, jax.Array]:
    """``(lower, upper)``, each ``(..., n)``: the box the joint-uniform measure covers.

    The one rule for every search and average over the joints (module docstring).
    Revolute joints: free ones [-pi, pi), one-sided ones one turn from the finite limit,
    wider ones one turn from the lower limit; prismatic joints: their limits (m), which
    must be finite (`check_joint_box`).
    """
    revolute = jnp.asarray(periodic_joints(robot))
    lower = jnp.asarray(robot.joint_lower)
    upper = jnp.asarray(robot.joint_upper)
    turn = 2.0 * jnp.pi
    low_ok, high_ok = jnp.isfinite(lower), jnp.isfinite(upper)
    box_lower = jnp.where(low_ok, lower, jnp.where(high_ok, upper - turn, -jnp.pi))
    box_upper = jnp.where(high_ok, upper, box_lower + turn)
    box_upper = jnp.where(revolute, jnp.minimum(box_upper, box_lower + turn), box_upper)
    return box_lower, box_upper


def check_joint_box(robot) -> None:
    """Raise `ConfigError` naming the joint when a prismatic joint has an infinite limit.

    Skipped under tracing (the limits are then unknown); an infinite prismatic range
    would give NaN there.
    """
    if isinstance(robot.joint_lower, jax.core.Tracer) or isinstance(robot.joint_upper, jax.core.Tracer):
        return
    kinds = joint_kinds(robot)
    if not 1 <= len(kinds) <= MAX_SOBOL_DIMENSION:
        raise ConfigError(
            f"joints: the joint-box averages support 1 to {MAX_SOBOL_DIMENSION} joints, the robot has {len(kinds)}"
        )
    lower, upper = np.asarray(robot.joint_lower), np.asarray(robot.joint_upper)
    names = family_of(robot).joint_names(robot)
    for i, kind in enumerate(kinds):
        if kind == "prismatic" and not (np.all(np.isfinite(lower[..., i])) and np.all(np.isfinite(upper[..., i]))):
            label = f"'{names[i]}'" if i < len(names) else f"{i}"
            raise ConfigError(
                f"joints[{i}] {label}: a prismatic joint needs finite limits for a joint-box average or search"
            )


def box_postures(robot, unit: jax.Array) -> jax.Array:
    """Map points of the unit cube to postures of the family.

    Args:
        robot: one design (no batch axes).
        unit: ``(..., n)`` points in [0, 1]^n.

    Returns:
        ``(..., posture_offset + n)``: planar [phi0 = 0, phi1..phin]; spatial q.
    """
    lower, upper = joint_box(robot)
    joints = lower + (upper - lower) * unit
    offset = family_of(robot).posture_offset
    if offset:
        joints = jnp.concatenate([jnp.zeros(joints.shape[:-1] + (offset,), joints.dtype), joints], axis=-1)
    return joints
