"""Batching helpers: kernels are written for one posture and mapped over leading axes."""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["bucket_size", "map_leading", "pad_leading", "shapes_of"]


def shapes_of(tree):
    """``jax.ShapeDtypeStruct`` leaves for a pytree of concrete arrays, in JAX's dtypes
    (float32 without x64), to compile a program ahead of time with ``.lower(...).compile()``."""
    return jax.tree_util.tree_map(
        lambda x: jax.ShapeDtypeStruct(np.shape(x), jax.dtypes.canonicalize_dtype(np.result_type(x))), tree
    )


def bucket_size(count: int, minimum: int = 1) -> int:
    """The padded batch size of ``count`` items: the next power of two, at least ``minimum``.

    A compiled program is specialized to its shapes, so a kernel that took every batch
    size as it comes would compile once per size. Padding to a few bucket sizes (and
    masking the padding) keeps one program per bucket.
    """
    return max(int(minimum), 1 << max(int(count) - 1, 0).bit_length())


def pad_leading(tree, size: int):
    """Pad the leading axis of every leaf of ``tree`` to ``size`` by repeating its last row.

    The padding rows are valid inputs (copies of a real one), so a kernel runs on them
    without NaNs; the caller drops their results. NumPy leaves stay NumPy (no compiled
    program for the padding); traced or device leaves are padded with ``jnp``.
    """

    def pad(x):
        extra = size - x.shape[0]
        if extra <= 0:
            return x
        xp = np if isinstance(x, np.ndarray) else jnp
        return xp.concatenate([x, xp.repeat(x[-1:], extra, axis=0)], axis=0)

    return jax.tree_util.tree_map(pad, tree)


def map_leading(function: Callable, *arrays: jax.Array, core_ndims: tuple[int, ...]):
    """Apply a one-posture ``function`` over the leading batch axes of its arguments.

    Args:
        function: takes one unbatched array per argument and returns a pytree of arrays.
        arrays: arguments whose last ``core_ndims[i]`` axes belong to one posture; the
            leading axes are broadcast against each other.
        core_ndims: the number of trailing (per-posture) axes of each argument.

    Returns:
        The outputs with the broadcast leading batch shape in front.
    """
    arrays = [jnp.asarray(a) for a in arrays]
    batch_shapes = [a.shape[: a.ndim - k] for a, k in zip(arrays, core_ndims, strict=False)]
    batch = jnp.broadcast_shapes(*batch_shapes)
    flat = [
        jnp.broadcast_to(a, batch + a.shape[a.ndim - k :]).reshape((-1,) + a.shape[a.ndim - k :])
        for a, k in zip(arrays, core_ndims, strict=False)
    ]
    if not batch:
        return function(*[f[0] for f in flat])
    out = jax.vmap(function)(*flat)
    return jax.tree_util.tree_map(lambda y: y.reshape(batch + y.shape[1:]), out)
