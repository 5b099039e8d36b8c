"""Small dense linear algebra for the kernels: Gram and square determinants, adjugates.

Written out for the small sizes of robot Jacobians (t <= 3 task rows) so that they stay
accurate and differentiable where a matrix loses rank: Cauchy-Binet instead of
det(J J^T), cofactors instead of det(A) inv(A).
"""

from __future__ import annotations

import itertools

import jax
import jax.numpy as jnp

__all__ = ["adjugate", "gram_determinant", "gram_root_determinant", "square_determinant", "symmetric_eigenvalues"]


def gram_determinant(J: jax.Array) -> jax.Array:
    """det(J J^T) of ``(..., t, n)`` matrices (t <= n).

    For t = 2 and 3 it is the sum of squared t x t minors (Cauchy-Binet), which avoids the
    cancellation of det(J J^T) near singular postures.
    """
    t, n = J.shape[-2], J.shape[-1]
    if t == 1:
        return jnp.sum(J[..., 0, :] ** 2, axis=-1)
    if t == 2:
        x, y = J[..., 0, :], J[..., 1, :]
        minors = x[..., :, None] * y[..., None, :] - x[..., None, :] * y[..., :, None]
        return 0.5 * jnp.sum(minors * minors, axis=(-2, -1))
    if t == 3 and n >= 3:
        columns = jnp.asarray(list(itertools.combinations(range(n), 3)))  # (C(n, 3), 3), static
        minors = square_determinant(jnp.swapaxes(J[..., :, columns], -3, -2))  # (..., C(n, 3))
        return jnp.sum(minors * minors, axis=-1)
    return jnp.linalg.det(J @ jnp.swapaxes(J, -1, -2))


def gram_root_determinant(J: jax.Array) -> jax.Array:
    """sqrt(det(J J^T)) of ``(..., t, n)`` matrices: 0 at rank loss, with finite gradients there."""
    if J.shape[-2] == 2 and J.shape[-1] == 2:
        return jnp.abs(J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0])
    squares = gram_determinant(J)
    positive = squares > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, squares, 1.0)), 0.0)


def square_determinant(J: jax.Array) -> jax.Array:
    """det J of ``(..., t, t)`` matrices, t <= 3, written out (no LU pivoting: smooth everywhere)."""
    t = J.shape[-1]
    if t == 1:
        return J[..., 0, 0]
    if t == 2:
        return J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    return jnp.sum(J[..., :, 0] * jnp.cross(J[..., :, 1], J[..., :, 2]), axis=-1)


def adjugate(A: jax.Array) -> jax.Array:
    """adj(A) of a 1x1, 2x2 or 3x3 matrix by cofactors: finite and smooth where det A = 0."""
    t = A.shape[-1]
    if t == 1:
        return jnp.ones_like(A)
    if t == 2:
        return jnp.array([[A[1, 1], -A[0, 1]], [-A[1, 0], A[0, 0]]])
    if t == 3:
        rows = [jnp.cross(A[:, (i + 1) % 3], A[:, (i + 2) % 3]) for i in range(3)]
        return jnp.stack(rows)  # row i of adj(A) = column (i+1) x column (i+2)
    raise ValueError(f"straight paths need 1 to 3 task rows, got {t}")


def symmetric_eigenvalues(S: jax.Array) -> jax.Array:
    """Eigenvalues of symmetric ``(..., t, t)`` matrices, t <= 3, ascending, in closed form.

    The characteristic polynomial solved directly (the trigonometric form of the cubic
    for t = 3), so no LAPACK call runs per posture: cheaper under ``vmap`` for these
    sizes, and free of the two-device hang of LAPACK custom calls seen with
    jaxlib 0.10.2 on CPU (benchmarks/repro_two_device_hang.py). Accurate to a few ulps of
    the largest eigenvalue.
    """
    t = S.shape[-1]
    if t == 1:
        return S[..., 0:1, 0]
    if t == 2:
        a, b, d = S[..., 0, 0], S[..., 0, 1], S[..., 1, 1]
        mean, half = 0.5 * (a + d), jnp.sqrt(0.25 * (a - d) ** 2 + b * b)
        return jnp.stack([mean - half, mean + half], axis=-1)
    if t != 3:
        return jnp.linalg.eigvalsh(S)
    q = (S[..., 0, 0] + S[..., 1, 1] + S[..., 2, 2]) / 3.0
    off = S[..., 0, 1] ** 2 + S[..., 0, 2] ** 2 + S[..., 1, 2] ** 2
    diag = (S[..., 0, 0] - q) ** 2 + (S[..., 1, 1] - q) ** 2 + (S[..., 2, 2] - q) ** 2
    p = jnp.sqrt((diag + 2.0 * off) / 6.0)
    safe_p = jnp.where(p > 0, p, 1.0)
    B = (S - q[..., None, None] * jnp.eye(3, dtype=S.dtype)) / safe_p[..., None, None]
    r = jnp.clip(0.5 * square_determinant(B), -1.0, 1.0)
    phi = jnp.arccos(r) / 3.0
    largest = q + 2.0 * p * jnp.cos(phi)
    smallest = q + 2.0 * p * jnp.cos(phi + 2.0 * jnp.pi / 3.0)
    middle = 3.0 * q - largest - smallest
    values = jnp.stack([smallest, middle, largest], axis=-1)
    return jnp.where((p > 0)[..., None], values, q[..., None])
