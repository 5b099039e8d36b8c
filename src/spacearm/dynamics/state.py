"""The state the dynamics kernels share: a robot's dynamic tree, joints, attitude and momentum.

`DynamicState` reads a posture the way every family writes it (a planar posture leads with
phi0; every other robot passes ``base_rotation``), broadcasts the other state arrays to one
batch and maps 6-vectors between inertial and bus axes and between the family's kept
components (``twist_axes``: [x, y, rz] in the plane) and all six. The base velocity a
momentum gives is eq. 4-5 of Umetani & Yoshida (1990) with its right side kept:
H_b [v; w] + H_bm qd = [R^T P; R^T L + (g - b) x R^T P] (g - b the system centroid about the
bus centroid, bus axes).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from .._core.groups import vee
from ..models.dynamics import system_mass_matrix, tip_maps
from ..models.family import family_of

__all__ = [
    "DynamicState",
    "apply",
    "base_from_momentum",
    "bus_momentum",
    "full_velocity",
    "momentum_array",
    "solve",
    "solve_columns",
]


class DynamicState:
    """One state of a robot: its dynamic tree, joints ``(*batch, n)``, attitude ``(*batch, 3, 3)``,
    the kept twist components and the tip weights, with the other arrays broadcast to the batch."""

    def __init__(self, robot, posture, base_rotation, *arrays):
        family = family_of(robot)
        self.family = family
        self.tree = family.dynamic_tree(robot)
        self.keep = np.asarray(family.twist_axes)
        self.tips = family.dynamic_tips(robot)
        posture = jnp.asarray(posture)
        offset = family.posture_offset
        if offset:
            if base_rotation is not None:
                raise TypeError(f"base_rotation: a {family.name} posture carries its base attitude (phi0 first)")
            R = family.attitude.rotation(posture[..., 0])
            q = posture[..., offset:]
        else:
            q = posture
            R = jnp.eye(3, dtype=q.dtype) if base_rotation is None else jnp.asarray(base_rotation)
        n = q.shape[-1]
        self.n = n
        shaped = [(jnp.asarray(a), core) for a, core in arrays]
        batch = jnp.broadcast_shapes(q.shape[:-1], R.shape[:-2], *[a.shape[: a.ndim - core] for a, core in shaped])
        self.batch = batch
        self.q = jnp.broadcast_to(q, batch + (n,))
        self.R = jnp.broadcast_to(R, batch + (3, 3))
        self.arrays = [jnp.broadcast_to(a, batch + a.shape[a.ndim - core :]) for a, core in shaped]
        self.coords = np.concatenate([self.keep, 6 + np.arange(n)])

    def embed(self, x):
        """A 6-vector's kept components ``(..., len(keep))`` -> ``(..., 6)`` (zeros elsewhere)."""
        x = jnp.asarray(x)
        if len(self.keep) == 6:
            return x
        return jnp.zeros(x.shape[:-1] + (6,), x.dtype).at[..., self.keep].set(x)

    def reduce(self, x):
        """``(..., 6)`` -> its kept components."""
        return x if len(self.keep) == 6 else x[..., self.keep]

    def rotate(self, x):
        """blkdiag(R, R) x for 6-vectors ``(*batch, [k,] 6)``: bus axes -> inertial axes."""
        R = self.R.reshape(self.batch + (1,) * (x.ndim - 1 - len(self.batch)) + (3, 3))
        return jnp.concatenate([apply(R, x[..., :3]), apply(R, x[..., 3:])], axis=-1)

    def unrotate(self, x):
        """blkdiag(R, R)^T x: inertial axes -> bus axes."""
        Rt = jnp.swapaxes(self.R, -1, -2).reshape(self.batch + (1,) * (x.ndim - 1 - len(self.batch)) + (3, 3))
        return jnp.concatenate([apply(Rt, x[..., :3]), apply(Rt, x[..., 3:])], axis=-1)

    def tip_maps(self):
        """``(*batch, [k,] 6, 6 + n)`` J of every tip, or of the chosen one, bus axes."""
        J = tip_maps(self.tree, self.q)
        if self.tips is None:
            return J
        return jnp.einsum("t,...tij->...ij", jnp.asarray(self.tips, J.dtype), J)


def apply(matrix, vector):
    return jnp.einsum("...ij,...j->...i", matrix, vector)


def solve(matrix, rhs):
    """Solve with a symmetric positive definite matrix (Cholesky) for one right-hand side ``(..., m)``."""
    factor = jax.scipy.linalg.cho_factor(matrix)
    return jax.scipy.linalg.cho_solve(factor, rhs[..., None])[..., 0]


def solve_columns(matrix, rhs):
    factor = jax.scipy.linalg.cho_factor(matrix)
    return jax.scipy.linalg.cho_solve(factor, rhs)


def base_from_momentum(H, qd, R, momentum):
    """``(..., 6)`` [v; w], bus axes, whose system momentum is ``momentum`` [P; L about the
    system centroid], inertial axes."""
    Rt = jnp.swapaxes(R, -1, -2)
    P, L = apply(Rt, momentum[..., :3]), apply(Rt, momentum[..., 3:])
    offset = vee(H[..., 3:6, 0:3]) / H[..., 0, 0, None]
    target = jnp.concatenate([P, L + jnp.cross(offset, P)], axis=-1)
    return solve(H[..., :6, :6], target - apply(H[..., :6, 6:], qd))


def full_velocity(system: DynamicState, qd, momentum):
    """nu = [v; w; qd] ``(..., 6 + n)`` for the momentum (zero when ``None``)."""
    H = system_mass_matrix(system.tree, system.q)
    m = jnp.zeros(system.batch + (6,), qd.dtype) if momentum is None else system.embed(momentum)
    return jnp.concatenate([base_from_momentum(H, qd, system.R, m), qd], axis=-1)


def momentum_array(momentum):
    return [] if momentum is None else [(momentum, 1)]


def bus_momentum(system: DynamicState, momentum, dtype):
    """``(*batch, 6)`` the system momentum [P; L about the system centroid] in BUS axes (zero
    when ``momentum`` is ``None``; else it is the state's last array)."""
    if momentum is None:
        return jnp.zeros(system.batch + (6,), dtype)
    return system.unrotate(system.embed(system.arrays[-1]))
