"""Batching helpers of the motion layer: designs and paths flattened to one batch axis."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError

__all__ = ["check_arm_axis", "flatten_batch", "is_traced", "unpad"]


def is_traced(*xs) -> bool:
    return any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(xs))


def flatten_batch(robot, arrays: list[tuple[jax.Array, int]]):
    """Broadcast the design batch and the leading axes of ``arrays`` together and flatten them.

    Args:
        arrays: pairs (array, number of trailing core axes).

    Returns:
        (batch_shape, flat robot, robot_batched flag, list of flat arrays (size, *core)).
    """
    robot_batch = robot.batch_shape
    shapes = [robot_batch] + [tuple(jnp.shape(a))[: jnp.ndim(a) - core] for a, core in arrays]
    try:
        batch = tuple(np.broadcast_shapes(*shapes))
    except ValueError:
        raise ConfigError(f"batch axes do not broadcast together: {shapes}") from None
    size = math.prod(batch)
    # Concrete inputs are flattened in NumPy: eager jnp.broadcast_to / reshape would each
    # compile a small program per shape, before the kernel's own.
    xp = jnp if is_traced(robot, [a for a, _ in arrays]) else np
    flat = []
    for a, core in arrays:
        a = xp.asarray(a)
        core_shape = a.shape[a.ndim - core :]
        flat.append(xp.broadcast_to(a, batch + core_shape).reshape((size,) + core_shape))
    if robot_batch:
        nb = len(robot_batch)

        def spread(x):
            x = xp.asarray(x)
            core_shape = x.shape[nb:]
            return xp.broadcast_to(x, batch + core_shape).reshape((size,) + core_shape)

        robot = jax.tree_util.tree_map(spread, robot)
    return batch, robot, bool(robot_batch), flat


def unpad(tree, count: int, batch: tuple[int, ...]):
    """The first ``count`` rows of each leaf of a flat (padded) result, reshaped to ``batch``;
    in NumPy when concrete (eager slicing and reshaping would compile a small program per
    shape), the inverse of `flatten_batch` and a padding to a bucket size."""
    if is_traced(tree):
        return jax.tree_util.tree_map(lambda x: x[:count].reshape(batch + x.shape[1:]), tree)
    return jax.tree_util.tree_map(lambda x: jax.device_put(np.asarray(x)[:count].reshape(batch + x.shape[1:])), tree)


def check_arm_axis(robot, name: str, array, expected: int) -> None:
    if jnp.ndim(array) < 1 or jnp.shape(array)[-1] != expected:
        raise ConfigError(
            f"{name}: expected a trailing axis of {expected} for a {robot.n_links}-link arm, "
            f"got shape {jnp.shape(array)}"
        )


# Joint-space paths -----------------------------------------------------------------------
