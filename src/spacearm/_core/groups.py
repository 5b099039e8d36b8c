"""The base-attitude groups SO(2) and SO(3): exp, log, compose, act, and reach candidates.

A free-floating base turns as the arm moves; its attitude is an element of SO(2) for a
planar arm (an angle phi0) and of SO(3) for a spatial arm (a rotation matrix, bus axes ->
inertial axes). The motion layer integrates the attitude as a flat coordinate vector
(``coords``: the angle, or the 9 entries of R row-major) driven by a body angular
velocity ``w`` in the group's Lie algebra (a scalar rate for SO(2), a 3-vector in bus
axes for SO(3)): d coords / dt = `Group.rate` (g, w), i.e. phi0' = w and R' = R [w]x.

SO(3) helpers (`hat`, `vee`, `expm` by Rodrigues' formula, `log`, `geodesic_distance`,
`polar_rotation`) live here once, batched over leading axes and safe to differentiate
at the identity; each is jitted, so a call on concrete arrays is one program, not one
per operation.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

__all__ = [
    "SO2",
    "SO3",
    "Group",
    "expm",
    "fibonacci_sphere",
    "geodesic_distance",
    "hat",
    "log",
    "polar_rotation",
    "rpy_matrix",
    "second_moment",
    "vee",
]


# SO(3) -----------------------------------------------------------------------------------


@jax.jit
def hat(v: jax.Array) -> jax.Array:
    """``(..., 3) -> (..., 3, 3)`` the skew matrix [v]x with [v]x w = v x w."""
    v = jnp.asarray(v)
    zero = jnp.zeros_like(v[..., 0])
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return jnp.stack(
        [jnp.stack([zero, -z, y], -1), jnp.stack([z, zero, -x], -1), jnp.stack([-y, x, zero], -1)], axis=-2
    )


@jax.jit
def vee(W: jax.Array) -> jax.Array:
    """``(..., 3, 3) -> (..., 3)`` the vector of the skew part of W (inverse of `hat`)."""
    return 0.5 * jnp.stack([W[..., 2, 1] - W[..., 1, 2], W[..., 0, 2] - W[..., 2, 0], W[..., 1, 0] - W[..., 0, 1]], -1)


def second_moment(c: jax.Array) -> jax.Array:
    """``(..., 3) -> (..., 3, 3)`` |c|^2 1 - c c^T = [c]x^T [c]x: the inertia of a unit point
    mass at c about the origin (the parallel-axis term per unit mass)."""
    return jnp.sum(c * c, -1)[..., None, None] * jnp.eye(3, dtype=c.dtype) - c[..., :, None] * c[..., None, :]


def safe_norm(v: jax.Array) -> tuple[jax.Array, jax.Array]:
    """|v| and |v|^2 over the last axis, with a finite gradient at v = 0 (the double-where idiom)."""
    sq = jnp.sum(v * v, axis=-1)
    positive = sq > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, sq, 1.0)), 0.0), sq


@jax.jit
def expm(v: jax.Array) -> jax.Array:
    """Rotation matrix of a rotation vector, Rodrigues' formula: ``(..., 3) -> (..., 3, 3)``.

    expm([v]x) = 1 + (sin t / t) [v]x + ((1 - cos t) / t^2) [v]x^2, t = |v|; the two
    coefficients switch to their Taylor series below t = 1e-3 (truncation < 1e-20), so
    the map is accurate and differentiable at v = 0.
    """
    v = jnp.asarray(v)
    theta, sq = safe_norm(v)
    small = theta < 1e-3
    t = jnp.where(small, 1.0, theta)
    sinc = jnp.where(small, 1.0 - sq / 6.0 + sq * sq / 120.0, jnp.sin(t) / t)
    cosc = jnp.where(small, 0.5 - sq / 24.0 + sq * sq / 720.0, (1.0 - jnp.cos(t)) / (t * t))
    K = hat(v)
    eye = jnp.eye(3, dtype=v.dtype)
    return eye + sinc[..., None, None] * K + cosc[..., None, None] * (K @ K)


@jax.jit
def log(R: jax.Array) -> jax.Array:
    """Rotation vector of a rotation matrix, angle in [0, pi]: ``(..., 3, 3) -> (..., 3)``.

    The angle comes from atan2(|vee(R - R^T)| / 2, (tr R - 1) / 2), accurate over the
    whole range. Below pi - 1e-3 the axis is vee(R - R^T) / (2 sin t); near pi, where
    that part vanishes, the axis comes from the symmetric part (R + R^T)/2 = cos t 1 +
    (1 - cos t) u u^T (its largest column), with the sign of the skew part.
    """
    R = jnp.asarray(R)
    w = vee(R)  # sin(t) u
    s, _ = safe_norm(w)
    c = 0.5 * (jnp.trace(R, axis1=-2, axis2=-1) - 1.0)
    theta = jnp.arctan2(s, c)
    small = theta < 1e-3
    # t / sin t, Taylor below 1e-3
    s_safe = jnp.where(small, 1.0, s)
    scale = jnp.where(small, 1.0 + theta * theta / 6.0, theta / s_safe)
    regular = scale[..., None] * w
    # near pi: u u^T = (S - c 1) / (1 - c), S the symmetric part
    near_pi = theta > math.pi - 1e-3
    S = 0.5 * (R + jnp.swapaxes(R, -1, -2))
    denominator = jnp.where(near_pi, 1.0 - c, 1.0)  # the unused branch stays finite (and its gradient)
    B = (S - c[..., None, None] * jnp.eye(3, dtype=R.dtype)) / denominator[..., None, None]
    column = jnp.argmax(jnp.diagonal(B, axis1=-2, axis2=-1), axis=-1)
    u = jnp.take_along_axis(B, column[..., None, None], axis=-1)[..., 0]
    u_norm, _ = safe_norm(u)
    u = u / jnp.where(u_norm > 0, u_norm, 1.0)[..., None]
    sign = jnp.where(jnp.sum(u * w, axis=-1) < 0, -1.0, 1.0)
    return jnp.where(near_pi[..., None], (sign * theta)[..., None] * u, regular)


@jax.jit
def geodesic_distance(R1: jax.Array, R2: jax.Array) -> jax.Array:
    """The angle of R1^T R2 in [0, pi], rad: the geodesic distance on SO(3), ``(...)``."""
    E = jnp.swapaxes(R1, -1, -2) @ R2
    s, _ = safe_norm(vee(E))
    c = 0.5 * (jnp.trace(E, axis1=-2, axis2=-1) - 1.0)
    return jnp.arctan2(s, c)


@jax.jit
def polar_rotation(M: jax.Array) -> jax.Array:
    """The rotation nearest to a ``(..., 3, 3)`` matrix close to one (polar factor by SVD)."""
    u, _, vt = jnp.linalg.svd(M)
    return u @ vt


def rpy_matrix(rpy) -> np.ndarray:
    """URDF roll-pitch-yaw (fixed axes x, y, z): R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = (float(v) for v in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def fibonacci_sphere(count: int) -> np.ndarray:
    """``(count, 3)`` unit vectors spread evenly over the sphere (a Fibonacci lattice)."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    phi = np.pi * (1.0 + 5.0**0.5) * k
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


# The groups ------------------------------------------------------------------------------


class Group:
    """A base-attitude group: elements ``g``, algebra vectors ``v`` (``(..., dim)``), flat coordinates.

    Attributes:
        name: ``"SO(2)"`` or ``"SO(3)"``.
        dim: dimension of the algebra (1 or 3): the size of a body angular velocity.
        space: dimension of the space it acts on (2 or 3).
        coords: length of the flat coordinate vector the integrators carry (1 or 9).
        abelian: whether elements commute (then the attitude along a joint path is a
            plain line integral of the rate, exact by quadrature).
        angular_axes: the components of a 3-D angular velocity the algebra keeps (SO(2): the
            z component, the plane's normal; SO(3): all three).
    """

    name = "abstract"
    dim = 0
    space = 0
    coords = 0
    abelian = False
    angular_axes: tuple[int, ...] = ()

    def identity(self, dtype=None) -> jax.Array:
        raise NotImplementedError

    def exp(self, v: jax.Array) -> jax.Array:
        """Algebra vector ``(..., dim)`` -> element."""
        raise NotImplementedError

    def log(self, g: jax.Array) -> jax.Array:
        """Element -> algebra vector ``(..., dim)`` (the principal one)."""
        raise NotImplementedError

    def compose(self, a: jax.Array, b: jax.Array) -> jax.Array:
        """The product a b (first b, then a, as maps)."""
        raise NotImplementedError

    def inverse(self, g: jax.Array) -> jax.Array:
        raise NotImplementedError

    def matrix(self, g: jax.Array) -> jax.Array:
        """``(..., space, space)`` rotation matrix of an element."""
        raise NotImplementedError

    def rotation(self, g: jax.Array) -> jax.Array:
        """``(..., 3, 3)`` the element as a rotation of space (SO(2): a turn about z)."""
        raise NotImplementedError

    def act(self, g: jax.Array, x: jax.Array) -> jax.Array:
        """The element applied to vectors ``x (..., space)`` (base axes -> inertial axes)."""
        return jnp.einsum("...ij,...j->...i", self.matrix(g), x)

    def act_inverse(self, g: jax.Array, x: jax.Array) -> jax.Array:
        """The inverse applied to ``x`` (inertial axes -> base axes)."""
        return jnp.einsum("...ji,...j->...i", self.matrix(g), x)

    def distance(self, a: jax.Array, b: jax.Array) -> jax.Array:
        """The angle of a^-1 b, rad (geodesic distance)."""
        return jnp.linalg.norm(self.log(self.compose(self.inverse(a), b)), axis=-1)

    def to_coords(self, g: jax.Array) -> jax.Array:
        """Element -> ``(..., coords)`` flat coordinates."""
        raise NotImplementedError

    def from_coords(self, c: jax.Array) -> jax.Array:
        """Flat coordinates (integrated, so slightly off the group for SO(3)) -> nearest element."""
        raise NotImplementedError

    def coords_matrix(self, c: jax.Array) -> jax.Array:
        """``(space, space)`` rotation matrix of coordinates as integrated (no projection; one element)."""
        raise NotImplementedError

    def rate(self, c: jax.Array, w: jax.Array) -> jax.Array:
        """d coords / dt for the body angular velocity ``w (dim,)`` at coordinates ``c`` (one element)."""
        raise NotImplementedError

    def candidates(self, count: int = 64, angles=(0.02, 0.05, 0.1, 0.2)) -> np.ndarray:
        """``(k, dim)`` algebra vectors a reach search tries as base rotations, smallest first."""
        raise NotImplementedError


class _SO2(Group):
    """Planar rotations, elements as angles ``(...)`` rad."""

    name = "SO(2)"
    dim = 1
    space = 2
    coords = 1
    abelian = True
    angular_axes = (2,)

    def identity(self, dtype=None):
        return jnp.zeros((), dtype or jnp.result_type(float))

    def exp(self, v):
        return jnp.asarray(v)[..., 0]

    def log(self, g):
        return ((jnp.asarray(g) + jnp.pi) % (2.0 * jnp.pi) - jnp.pi)[..., None]

    def compose(self, a, b):
        return jnp.asarray(a) + jnp.asarray(b)

    def inverse(self, g):
        return -jnp.asarray(g)

    def matrix(self, g):
        c, s = jnp.cos(g), jnp.sin(g)
        return jnp.stack([jnp.stack([c, -s], -1), jnp.stack([s, c], -1)], -2)

    def rotation(self, g):
        c, s = jnp.cos(g), jnp.sin(g)
        zero, one = jnp.zeros_like(c), jnp.ones_like(c)
        rows = [[c, -s, zero], [s, c, zero], [zero, zero, one]]
        return jnp.stack([jnp.stack(row, -1) for row in rows], -2)

    def act(self, g, x):
        c, s = jnp.cos(g), jnp.sin(g)
        return jnp.stack([c * x[..., 0] - s * x[..., 1], s * x[..., 0] + c * x[..., 1]], -1)

    def act_inverse(self, g, x):
        return self.act(-jnp.asarray(g), x)

    def to_coords(self, g):
        return jnp.asarray(g)[..., None]

    def from_coords(self, c):
        return c[..., 0]

    def coords_matrix(self, c):
        return self.matrix(c[0])

    def rate(self, c, w):
        return w

    def candidates(self, count: int = 64, angles=None) -> np.ndarray:
        """``count`` angles on a uniform circle grid, wrapped to [-pi, pi), the smallest first."""
        deltas = (2.0 * np.pi * np.arange(count) / count + np.pi) % (2.0 * np.pi) - np.pi
        return deltas[np.argsort(np.abs(deltas), kind="stable")][:, None]


class _SO3(Group):
    """Spatial rotations, elements as ``(..., 3, 3)`` matrices."""

    name = "SO(3)"
    dim = 3
    space = 3
    coords = 9
    abelian = False
    angular_axes = (0, 1, 2)

    def identity(self, dtype=None):
        return jnp.eye(3, dtype=dtype or jnp.result_type(float))

    def exp(self, v):
        return expm(v)

    def log(self, g):
        return log(g)

    def compose(self, a, b):
        return jnp.asarray(a) @ jnp.asarray(b)

    def inverse(self, g):
        return jnp.swapaxes(jnp.asarray(g), -1, -2)

    def matrix(self, g):
        return jnp.asarray(g)

    def rotation(self, g):
        return jnp.asarray(g)

    def distance(self, a, b):
        return geodesic_distance(a, b)

    def to_coords(self, g):
        g = jnp.asarray(g)
        return g.reshape(g.shape[:-2] + (9,))

    def from_coords(self, c):
        return polar_rotation(c.reshape(c.shape[:-1] + (3, 3)))

    def coords_matrix(self, c):
        return c.reshape(3, 3)

    def rate(self, c, w):
        return (c.reshape(3, 3) @ hat(w)).reshape(9)

    def candidates(self, count: int = 64, angles=(0.02, 0.05, 0.1, 0.2)) -> np.ndarray:
        """Rotation vectors: ``count`` axes on a Fibonacci sphere times each angle, smallest angles first."""
        unit = fibonacci_sphere(count)
        return np.concatenate([angle * unit for angle in angles], axis=0)


SO2 = _SO2()
SO3 = _SO3()
