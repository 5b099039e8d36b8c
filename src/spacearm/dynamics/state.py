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
from ..models.dynamics import system_mass_matrix, tip_axes, tip_maps
from ..models.family import family_of

__all__ = ["DynamicState", "apply", "full_velocity", "solve", "solve_columns"]


class DynamicState:
    """One state of one robot design, checked and broadcast to one batch.

    Reads the posture as the family writes it (a planar posture leads with phi0; every other
    robot passes ``base_rotation``), checks each array's trailing size against the robot and
    names the argument that does not fit, and broadcasts everything to one batch shape.

    Held joints (a focused tree's, `spacearm.models.family.RobotFamily.moving_joints`) are
    held by their drives: their rates and accelerations are zero (`moving` masks them), the
    kernels that solve with H lock them (`locked`), and inverse dynamics gives the torque that
    holds them.

    Attributes:
        family, tree: the robot's family record and its dynamic tree (`RobotFamily.dynamic_tree`).
        keep: the family's ``twist_axes`` (the kept components of every 6-vector).
        tips: the family's tip weights (`RobotFamily.dynamic_tips`), or ``None``.
        n, batch: the joint count and the broadcast batch shape.
        q ``(*batch, n)``, R ``(*batch, 3, 3)``: joints and bus attitude (bus -> inertial).
        moving ``(n,)``: 1 for the moving joints, 0 for the held ones.
        joints: the joint arrays by name, ``(*batch, n)``, held joints' entries as given.
        momentum: the system momentum [P; L about the system centroid] ``(*batch, 6)``, BUS axes.
        twists: the 6-vectors by name ``(*batch, 6)``, inertial axes (all six components).
    """

    def __init__(self, robot, posture, base_rotation=None, *, joints=None, momentum=None, twists=None):
        family = family_of(robot)
        self.family, self.tree = family, family.dynamic_tree(robot)
        if jnp.ndim(self.tree.base_mass) != 0:
            raise ValueError("robot: one design per call; map a batch of designs with jax.vmap")
        self.keep, self.tips = np.asarray(family.twist_axes), family.dynamic_tips(robot)
        n = family.joint_count(robot)
        posture = _trailing("q", posture, (n + family.posture_offset,))
        if family.posture_offset:
            if base_rotation is not None:
                raise TypeError(f"base_rotation: a {family.name} posture carries its base attitude (phi0 first)")
            R, q = family.attitude.rotation(posture[..., 0]), posture[..., family.posture_offset :]
        else:
            q = posture
            R = (
                jnp.eye(3, dtype=q.dtype)
                if base_rotation is None
                else _trailing("base_rotation", base_rotation, (3, 3))
            )
        named = {name: _trailing(name, value, (n,)) for name, value in (joints or {}).items()}
        sizes = (len(self.keep),)
        vectors = {name: _trailing(name, value, sizes) for name, value in (twists or {}).items()}
        if momentum is not None:
            vectors["momentum"] = _trailing("momentum", momentum, sizes)
        shapes = [q.shape[:-1], R.shape[:-2]] + [a.shape[:-1] for a in (*named.values(), *vectors.values())]
        batch = self.batch = jnp.broadcast_shapes(*shapes)
        self.n, self.q, self.R = n, jnp.broadcast_to(q, batch + (n,)), jnp.broadcast_to(R, batch + (3, 3))
        self.moving = jnp.asarray(family.moving_joints(robot), self.q.dtype)
        self.joints = {name: jnp.broadcast_to(a, batch + (n,)) for name, a in named.items()}
        full = {name: self.embed(jnp.broadcast_to(a, batch + sizes)) for name, a in vectors.items()}
        zero = jnp.zeros(batch + (6,), self.q.dtype)
        self.momentum = self.unrotate(full.pop("momentum")) if momentum is not None else zero
        self.twists = full
        self.coords = np.concatenate([self.keep, 6 + np.arange(n)])

    def rates(self, name: str):
        """A joint array with the held joints' entries zero (rates and accelerations)."""
        return self.joints[name] * self.moving

    def locked(self, H):
        """H ``(..., 6 + n, 6 + n)`` with the held joints locked: their rows and columns zero and
        a one on the diagonal (they take no part in a solve)."""
        mask = jnp.concatenate([jnp.ones(6, H.dtype), self.moving.astype(H.dtype)])
        return H * (mask[:, None] * mask[None, :]) + jnp.diag(1.0 - mask)

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
        """``(*batch, [k,] 6, 6 + n)`` J of every tip, or of the chosen one, bus axes; the held
        joints' columns zero."""
        J = tip_maps(self.tree, self.q)
        J = J * jnp.concatenate([jnp.ones(6, J.dtype), self.moving.astype(J.dtype)])
        return self._weighted(J)

    def tip_axes(self):
        """``(*batch, [k,] 3, 3)`` the axes of every tip frame, or of the chosen one, INERTIAL axes."""
        axes = self._weighted(tip_axes(self.tree, self.q))
        R = self.R if self.tips is not None else self.R[..., None, :, :]
        return R @ axes

    def _weighted(self, per_tip):
        if self.tips is None:
            return per_tip
        return jnp.einsum("t,...tij->...ij", jnp.asarray(self.tips, per_tip.dtype), per_tip)

    @property
    def tip_count(self) -> int | None:
        """k, the tips on the tip axis of per-tip results; None when they have none (one tip, or
        a tree focused on one: then that tip is tip 0)."""
        return None if self.tips is not None else len(self.tree.tip_bodies)

    def pick_tip(self, per_tip, tip):
        """The ``tip``-th of per-tip results ``(*batch, k, ...)`` (``per_tip`` None: only the
        check). A robot without a tip axis takes only ``tip=0``; checked where ``tip`` is
        concrete, naming it."""
        k = self.tip_count
        if isinstance(tip, str):
            raise ValueError(f"tip: the index of a tip (0..{(k or 1) - 1}), got the name {tip!r}")
        if not isinstance(tip, jax.core.Tracer) and (
            isinstance(tip, bool) or int(tip) != tip or not 0 <= int(tip) < (k or 1)
        ):
            raise ValueError(f"tip: {tip!r} is not one of the robot's {k or 1} tip(s) (numbered from 0)")
        if per_tip is None or k is None:
            return per_tip
        return jnp.take(per_tip, tip, axis=len(self.batch))

    def tree_tip(self, tip: int) -> int:
        """The index among the tree's own tips of ``tip`` (a focused tree's tip 0 is its focus)."""
        self.pick_tip(None, tip)
        return int(np.argmax(np.asarray(self.tips))) if self.tips is not None else int(tip)


def _trailing(name: str, value, shape: tuple[int, ...]):
    """``value`` as an array whose trailing axes are ``shape``, else ValueError naming the argument."""
    array = jnp.asarray(value)
    if array.shape[array.ndim - len(shape) :] != shape or array.ndim < len(shape):
        raise ValueError(f"{name}: expected trailing axes {shape}, got shape {array.shape}")
    if not jnp.issubdtype(array.dtype, jnp.inexact):
        array = array.astype(float)
    return array


def apply(matrix, vector):
    return jnp.einsum("...ij,...j->...i", matrix, vector)


def solve(matrix, rhs):
    """Solve with a symmetric positive definite matrix (Cholesky) for one right-hand side ``(..., m)``."""
    factor = jax.scipy.linalg.cho_factor(matrix)
    return jax.scipy.linalg.cho_solve(factor, rhs[..., None])[..., 0]


def solve_columns(matrix, rhs):
    factor = jax.scipy.linalg.cho_factor(matrix)
    return jax.scipy.linalg.cho_solve(factor, rhs)


def full_velocity(system: DynamicState, qd):
    """nu = [v; w; qd] ``(..., 6 + n)``: the bus velocity the state's momentum gives with the
    joint rates ``qd`` (held joints' rates zero)."""
    H = system_mass_matrix(system.tree, system.q)
    P, L = system.momentum[..., :3], system.momentum[..., 3:]
    offset = vee(H[..., 3:6, 0:3]) / H[..., 0, 0, None]  # the system centroid about the bus centroid
    target = jnp.concatenate([P, L + jnp.cross(offset, P)], axis=-1)
    return jnp.concatenate([solve(H[..., :6, :6], target - apply(H[..., :6, 6:], qd)), qd], axis=-1)
