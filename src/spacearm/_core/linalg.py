"""Small dense linear algebra for the kernels: Gram and square determinants, adjugates.

Written out for the small sizes of robot Jacobians (t <= 3 task rows) so that they stay
accurate and differentiable where a matrix loses rank: Cauchy-Binet instead of
det(J J^T), cofactors instead of det(A) inv(A).
"""

from __future__ import annotations

import itertools

import jax
import jax.numpy as jnp

__all__ = ["gram_determinant", "gram_root_determinant", "square_determinant", "adjugate"]


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
