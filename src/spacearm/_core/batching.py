"""Batching helpers: kernels are written for one posture and mapped over leading axes."""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp

__all__ = ["map_leading"]


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
    batch_shapes = [a.shape[: a.ndim - k] for a, k in zip(arrays, core_ndims)]
    batch = jnp.broadcast_shapes(*batch_shapes)
    flat = [
        jnp.broadcast_to(a, batch + a.shape[a.ndim - k :]).reshape((-1,) + a.shape[a.ndim - k :])
        for a, k in zip(arrays, core_ndims)
    ]
    if not batch:
        return function(*[f[0] for f in flat])
    out = jax.vmap(function)(*flat)
    return jax.tree_util.tree_map(lambda y: y.reshape(batch + y.shape[1:]), out)
