"""The exact hypervolume of 2, 3 or 4 objectives in JAX, and its gradient by autodiff.

All objectives are maximized: the hypervolume of a point set F above a reference point r
is the volume of the union of the boxes [r, f] over f in F. It is a piecewise
polynomial of the points' coordinates, so a sort-based formula written with
differentiable operations gives, where it is differentiable, the exact gradient
(Emmerich & Deutz, "Time complexity and zeros of the hypervolume indicator gradient
field", EVOLVE III, 2014): each non-dominated point's derivative in objective j is the
(m-1)-volume of the face of its exclusive region normal to axis j; dominated points and
points below the reference get zero.

* m = 2: sort by f1 descending; each point adds the strip (f1 - r1)(f2 - max f2 of the
  points before it), O(N log N).
* m > 2: sort by the last objective descending, z_1 >= z_2 >= ... >= z_N > r_m; between
  z_k and z_(k+1) the slice is the (m-1)-hypervolume of the first k points, so
  HV = sum_k (z_k - z_(k+1)) HV_(m-1)(points 1..k) (the slicing of While, Hingston,
  Barone & Huband, IEEE TEC 10(1), 2006). Written with masks and vmapped over k: O(N^2
  log N) for m = 3, O(N^3 log N) for m = 4, static shapes, no Python loop over points.

Each public function is jitted (one program per shape, not one per operation on
concrete data). Points outside the set (``mask`` False) and coordinates below the
reference are moved to the reference, where they add no volume; so a padded batch with a
mask gives the hypervolume of its valid rows, and the gradient of a masked row is zero.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

__all__ = ["exact_hypervolume", "hypervolume_contributions", "hypervolume_gradient", "layer_hypervolume_gradients"]


def _clipped(points: jax.Array, reference: jax.Array, mask: jax.Array) -> jax.Array:
    return jnp.where(mask[:, None], jnp.maximum(points, reference), reference)


def _hypervolume_2d(points: jax.Array, reference: jax.Array) -> jax.Array:
    """Points already clipped to the reference (rows at the reference add nothing)."""
    order = jnp.lexsort((-points[:, 1], -points[:, 0]))  # f1 descending, ties by f2 descending
    f = points[order]
    best_before = jnp.concatenate([reference[1:2], jax.lax.cummax(f[:-1, 1])])
    return jnp.sum((f[:, 0] - reference[0]) * jnp.maximum(f[:, 1] - jnp.maximum(best_before, reference[1]), 0.0))


def _hypervolume_sliced(points: jax.Array, reference: jax.Array) -> jax.Array:
    """Points clipped to the reference; any m >= 2 by slicing along the last objective."""
    m = points.shape[1]
    if m == 2:
        return _hypervolume_2d(points, reference)
    last = points[:, -1]
    order = jnp.argsort(-last)
    z = last[order]
    heights = z - jnp.concatenate([z[1:], reference[-1:]])  # (N,) slab heights, >= 0
    rank = jnp.empty_like(order).at[order].set(jnp.arange(order.size))
    lower = points[:, :-1]

    def slab(k):
        inside = rank <= k
        return _hypervolume_sliced(jnp.where(inside[:, None], lower, reference[:-1]), reference[:-1])

    return jnp.sum(heights * jax.vmap(slab)(jnp.arange(order.size)))


@jax.jit
def exact_hypervolume(points: jax.Array, reference: jax.Array, mask: jax.Array | None = None) -> jax.Array:
    """Exact hypervolume of a point set (all objectives maximized); differentiable.

    Args:
        points: ``(N, m)`` objective vectors, m = 2, 3 or 4 (any order; dominated
            points, duplicates and points below the reference allowed).
        reference: ``(m,)`` the reference point.
        mask: ``(N,)`` bool, the rows that belong to the set (default: all).

    Returns:
        The hypervolume, a scalar in the product of the objectives' units.
    """
    points = jnp.asarray(points)
    reference = jnp.asarray(reference, dtype=points.dtype)
    if points.ndim != 2 or points.shape[1] not in (2, 3, 4) or reference.shape != (points.shape[1],):
        raise ValueError(
            f"exact_hypervolume: points must be (N, m) with m in 2..4 and reference (m,); "
            f"got {points.shape} and {reference.shape}"
        )
    if points.shape[0] == 0:
        return jnp.zeros((), points.dtype)
    mask = jnp.ones(points.shape[0], dtype=bool) if mask is None else jnp.asarray(mask, dtype=bool)
    return _hypervolume_sliced(_clipped(points, reference, mask), reference)


@jax.jit
def hypervolume_gradient(points: jax.Array, reference: jax.Array, mask: jax.Array | None = None) -> jax.Array:
    """``(N, m)`` the derivative of `exact_hypervolume` with respect to every coordinate.

    Zero for dominated points, masked rows and coordinates below the reference. Where the
    hypervolume is not differentiable (ties between non-dominated points), autodiff returns
    one of the one-sided derivatives' convex combinations (a generalized gradient).

    A point below another in every objective lies inside that point's box under any small
    move, so its derivative is exactly zero; the slicing sums it as differences of slab
    volumes that cancel only up to rounding (about 1e-17 for 4 objectives), so such rows
    are set to zero.
    """
    points = jnp.asarray(points)
    mask = jnp.ones(points.shape[0], dtype=bool) if mask is None else jnp.asarray(mask, dtype=bool)
    below = jnp.all(points[:, None, :] < points[None, :, :], axis=-1) & mask[None, :]  # [i, j]: i below j
    gradient = jax.grad(exact_hypervolume)(points, reference, mask)
    return jnp.where(jnp.any(below, axis=1)[:, None], 0.0, gradient)


@jax.jit
def hypervolume_contributions(points: jax.Array, reference: jax.Array, mask: jax.Array | None = None) -> jax.Array:
    """``(N,)`` exclusive contributions: HV(set) - HV(set without point i).

    A duplicated or dominated point contributes zero (as ``moocore.hv_contributions``).
    """
    points = jnp.asarray(points)
    count = points.shape[0]
    mask = jnp.ones(count, dtype=bool) if mask is None else jnp.asarray(mask, dtype=bool)
    total = exact_hypervolume(points, reference, mask)
    without = jax.vmap(lambda i: exact_hypervolume(points, reference, mask & (jnp.arange(count) != i)))(
        jnp.arange(count)
    )
    return jnp.where(mask, total - without, 0.0)


@jax.jit
def layer_hypervolume_gradients(points: jax.Array, reference: jax.Array, layer: jax.Array) -> jax.Array:
    """``(N, m)`` each point's hypervolume gradient within its own non-dominated layer.

    The hypervolume gradient of a whole population is zero at every dominated point, which
    would freeze it; the gradient of each non-dominated-sorting layer's own hypervolume
    moves every layer towards the front (Wang, Deutz, Baeck & Emmerich, "Hypervolume
    indicator gradient ascent multi-objective optimization", EMO 2017).

    Args:
        points: ``(N, m)`` objective vectors.
        reference: ``(m,)`` the reference point.
        layer: ``(N,)`` int, the non-dominated-sorting rank of each point (0 = the front);
            a negative rank leaves the point out (zero gradient).
    """
    count = points.shape[0]

    def gradient_of(rank):
        inside = layer == rank
        return jnp.where(inside[:, None], hypervolume_gradient(points, reference, inside), 0.0)

    return jnp.sum(jax.vmap(gradient_of)(jnp.arange(count)), axis=0)
