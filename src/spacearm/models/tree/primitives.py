"""Per-posture primitives of the tree family: one design, one posture, no batch axes.

One forward and one backward pass over the tree, written in the scalar algebra of
`spacearm.models.tree.algebra` (its forward and backward steps per joint): the joints
split into segments, maximal runs where joint j hangs from body j-1. The
forward pass scans each segment from its parent frame (a root's mount frame, or a
body of an earlier segment); the backward pass walks the segments in reverse order,
each body adding the totals (first mass moment, inertia about the bus-frame origin)
of the segments that hang from it, so every joint sees its whole subtree.

Everything is in the bus frame; the generic layer rotates results by the bus attitude.
With p_j, L_j the linear and angular momentum (about the bus-frame origin) of joint
j's subtree moving at unit rate, G the system centroid, M the total mass, I~ the
system inertia about G and A = I~^-1 I~_q (I~_q columns L_j - G x p_j), the bus
angular velocity is -A qdot and the Generalized Jacobian of tip t is

    J*_v,t = J_v,t - P / M + [r_t]x A,    J*_w,t = J_w,t - A

(Umetani & Yoshida 1990, eq. 6, in 3-D), with J_v,t, J_w,t the fixed-base Jacobian
of tip t (zero in the columns of joints off its path) and r_t the tip about G. The
terms in P and A are not masked: moving one arm turns and shifts the bus, and with it
every other tip. It equals J_M - J_S I_S^-1 I_M for `jacobians` and `momentum_map`.

Base twist coordinates: b = [v; w], the velocity of the bus centroid and the bus
angular velocity, bus axes (as the spatial family).
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np

from ..._core.groups import second_moment
from .algebra import (
    _add,
    _axis_frame,
    _backward_step,
    _bus_momentum_matrix,
    _coupling,
    _cross,
    _dot,
    _forward_step,
    _matmul,
    _matvec,
    _outer,
    _pack,
    _point_inertia,
    _point_twist_map,
    _rows,
    _scale,
    _sub,
    _sym_add,
    _vec,
    batched,
    rpy_to_matrix,
)
from .robot import TreeRobot

__all__ = [
    "POSTURE_QUANTITIES",
    "TreeConstants",
    "base_twist_map",
    "body_frames",
    "fixed_base_jacobian",
    "fixed_base_jacobian_and_tips",
    "generalized_jacobian",
    "jacobians",
    "joint_points",
    "manipulability",
    "momentum_map",
    "posture_quantities",
    "segments",
    "straight_maps_and_ends",
    "straight_path_maps",
    "tip",
    "tip_and_fixed_base_jacobian",
    "tip_and_generalized_jacobian",
    "tip_frames",
    "tip_pose",
    "tree_constants",
]

# Static topology ----------------------------------------------------------------------


@functools.lru_cache(maxsize=256)
def segments(parents: tuple[int, ...]) -> tuple[tuple[int, int, int], ...]:
    """``(start, stop, parent)`` per segment: joints start..stop-1 form a chain
    (``parents[j] == j - 1`` inside), hanging from ``parent`` (a body index or ``-1 - r``)."""
    out, start = [], 0
    for j in range(1, len(parents) + 1):
        if j == len(parents) or parents[j] != j - 1:
            out.append((start, j, parents[start]))
            start = j
    return tuple(out)


@functools.lru_cache(maxsize=256)
def descendants(parents: tuple[int, ...]) -> np.ndarray:
    """``(n, n)`` booleans: body k is in the subtree of joint j (k == j included)."""
    n = len(parents)
    mask = np.eye(n, dtype=bool)
    for k in range(n - 1, -1, -1):
        p = parents[k]
        if p >= 0:
            mask[p] |= mask[k]
    return mask


# Design-only constants -----------------------------------------------------------------


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class TreeConstants:
    """Design-only arrays of one tree design (body frames turned so each joint axis is z).

    Attributes:
        mount_rotation: ``(r, 3, 3)`` root axes in the bus frame.  mount_xyz: ``(r, 3)``.
        placement: ``(n, 3, 3)`` joint frame j in its parent's (turned) frame.
        offset: ``(n, 3)`` joint j origin in its parent's frame, m.
        link_mass: ``(n,)``.  link_com: ``(n, 3)``.  link_inertia: ``(n, 3, 3)`` (turned frames).
        subtree_mass: ``(n,)`` mass of joint j's subtree, kg.
        total_mass: ``()`` M, kg.
        fixed_moment: ``(3,)`` first mass moment of the bus and all roots, bus frame.
        fixed_inertia: ``(3, 3)`` their inertia about the bus-frame origin.
        tip_offset: ``(k, 3)`` tip origins in their bodies' turned frames.
        tip_rotation: ``(k, 3, 3)`` tip axes in those frames.
        base_com: ``(3,)`` bus centroid, bus frame.
    """

    mount_rotation: jax.Array
    mount_xyz: jax.Array
    placement: jax.Array
    offset: jax.Array
    link_mass: jax.Array
    link_com: jax.Array
    link_inertia: jax.Array
    subtree_mass: jax.Array
    total_mass: jax.Array
    fixed_moment: jax.Array
    fixed_inertia: jax.Array
    tip_offset: jax.Array
    tip_rotation: jax.Array
    base_com: jax.Array


def tree_constants(robot: TreeRobot) -> TreeConstants:
    """Design-only constants of one (unbatched) tree design; see `TreeConstants`."""
    parents = np.asarray(robot.parents)
    frames = jax.vmap(_axis_frame)(jnp.asarray(robot.joint_axis))  # (n, 3, 3) Q_j
    identity = jnp.eye(3, dtype=frames.dtype)
    before = jnp.where((parents >= 0)[:, None, None], frames[np.maximum(parents, 0)], identity)
    placement = jnp.einsum("kji,kjl,klm->kim", before, robot.joint_rotation, frames)
    offset = jnp.einsum("kji,kj->ki", before, robot.joint_translation)
    mount_rotation = jax.vmap(rpy_to_matrix)(jnp.asarray(robot.mount_rpy))
    mount_xyz = jnp.asarray(robot.mount_xyz)
    root_mass = jnp.asarray(robot.root_mass)
    root_com = mount_xyz + jnp.einsum("rij,rj->ri", mount_rotation, robot.root_com)
    root_inertia = jnp.einsum("rij,rjk,rlk->ril", mount_rotation, robot.root_inertia, mount_rotation)
    link_mass = jnp.asarray(robot.link_mass)
    tips = np.asarray(robot.tip_bodies)
    base_com = jnp.asarray(robot.base_com)
    return TreeConstants(
        mount_rotation=mount_rotation,
        mount_xyz=mount_xyz,
        placement=placement,
        offset=offset,
        link_mass=link_mass,
        link_com=jnp.einsum("kji,kj->ki", frames, robot.link_com),
        link_inertia=jnp.einsum("kji,kjl,klm->kim", frames, robot.link_inertia, frames),
        subtree_mass=jnp.asarray(descendants(robot.parents), link_mass.dtype) @ link_mass,
        total_mass=robot.base_mass + jnp.sum(root_mass) + jnp.sum(link_mass),
        fixed_moment=robot.base_mass * base_com + root_mass @ root_com,
        fixed_inertia=(
            robot.base_inertia
            + robot.base_mass * second_moment(base_com)
            + jnp.sum(root_inertia, axis=0)
            + jnp.sum(root_mass[:, None, None] * second_moment(root_com), axis=0)
        ),
        tip_offset=jnp.einsum("kji,kj->ki", frames[tips], robot.tip_translation),
        tip_rotation=jnp.einsum("kji,kjl->kil", frames[tips], robot.tip_rotation),
        base_com=base_com,
    )


# The pass over the tree -----------------------------------------------------------------


@dataclasses.dataclass
class _TreePass:
    """One pass over the tree; per-joint 3-tuples of ``(n, *batch)``, per-tip of ``(k, *batch)``."""

    origins: tuple  # joint origins o_j
    axes: tuple  # unit joint axes a_j
    tips: tuple  # tip origins, bus frame, (k, *batch) components
    tip_rotations: tuple  # tip axes, 3x3 tuple of (k, *batch)
    prismatic: jax.Array  # (n, 1, ...)
    momentum: tuple = None
    angular: tuple = None
    centroid: tuple = None
    mass: jax.Array = None
    inertia_g: tuple = None


def _cat(parts):
    """Concatenate per-segment component tuples (nested) along the leading joint axis."""
    if isinstance(parts[0], tuple):
        return tuple(_cat([p[i] for p in parts]) for i in range(len(parts[0])))
    return jnp.concatenate(parts, axis=0)


def _index(nested, i):
    if isinstance(nested, tuple):
        return tuple(_index(x, i) for x in nested)
    return nested[i]


def _lean_forward_step(carry, x):
    """`_forward_step` without the body axes among its outputs (the carry still has them)."""
    carry, out = _forward_step(carry, x)
    return carry, out[1:]


def _tree_backward_step(carry, x):
    """`_backward_step` after adding the totals of the segments hanging from this body."""
    (extra_moment, extra_about), rest = x[:2], x[2:]
    moment, about = carry
    return _backward_step((_add(moment, extra_moment), _sym_add(about, extra_about)), rest)


def _tree_pass(robot: TreeRobot, q, with_momentum: bool = True) -> _TreePass:
    """Forward and backward pass for joint positions ``q (n, *batch)`` (batch axes last)."""
    cst = tree_constants(robot)
    state, centroids, inertias = _forward_pass(robot, cst, q)
    if with_momentum:
        _backward_pass(robot, cst, state, centroids, inertias)
    return state


def _forward_pass(robot: TreeRobot, cst: TreeConstants, q):
    """Frames down the tree: the state without momenta, and the body centroids and inertias (bus axes)."""
    q = jnp.asarray(q)
    batch = q.shape[1:]
    flags = jnp.asarray([k == "prismatic" for k in robot.joint_kinds], dtype=q.dtype)
    flags = flags.reshape((-1,) + (1,) * len(batch))
    angle = q * (1.0 - flags)
    slide = q * flags
    cos, sin = jnp.cos(angle), jnp.sin(angle)
    spread = lambda x: jnp.broadcast_to(x, batch)
    segs = segments(robot.parents)
    # When every body whose frame is needed (tips, branch points) ends a segment, its
    # frame is that segment's last carry, and the scans need not store every body's axes.
    ends = {stop - 1: s for s, (_, stop, _) in enumerate(segs)}
    needed = {int(b) for b in robot.tip_bodies} | {p for _, _, p in segs if p >= 0}
    lean = needed <= ends.keys()
    where = {}  # body index -> (segment number, local index)
    outs, lasts = [], []
    for s, (start, stop, parent) in enumerate(segs):
        if parent < 0:
            r = -1 - parent
            carry = (
                tuple(tuple(spread(cst.mount_rotation[r, i, c]) for c in range(3)) for i in range(3)),
                tuple(spread(cst.mount_xyz[r, i]) for i in range(3)),
            )
        elif lean:
            carry = lasts[ends[parent]]
        else:
            seg, local = where[parent]
            rot, joint_origin, axis = (_index(outs[seg][i], local) for i in range(3))
            carry = (rot, _add(joint_origin, _scale(slide[parent], axis)))
        part = slice(start, stop)
        xs = (
            cst.placement[part],
            cst.offset[part],
            cos[part],
            sin[part],
            slide[part],
            cst.link_com[part],
            cst.link_inertia[part],
        )
        last, out = jax.lax.scan(_lean_forward_step if lean else _forward_step, carry, xs)
        outs.append((None, *out) if lean else out)
        lasts.append(last)
        for j in range(start, stop):
            where[j] = (s, j - start)
    origins, axes, centroids, inertias = (_cat([o[i] for o in outs]) for i in range(1, 5))
    bodies = np.asarray(robot.tip_bodies)
    if lean:
        frames = [lasts[ends[int(b)]] for b in bodies]
        body_rot = tuple(tuple(jnp.stack([f[0][i][c] for f in frames]) for c in range(3)) for i in range(3))
        body_origin = tuple(jnp.stack([f[1][i] for f in frames]) for i in range(3))
    else:
        body_rot = _index(_cat([o[0] for o in outs]), bodies)
        body_origin = _add(_index(origins, bodies), _scale(slide[bodies], _index(axes, bodies)))
    offset = tuple(cst.tip_offset[:, i].reshape((-1,) + (1,) * len(batch)) for i in range(3))
    tips = _add(body_origin, _matvec(body_rot, offset))
    tip_rot = tuple(
        tuple(cst.tip_rotation[:, i, c].reshape((-1,) + (1,) * len(batch)) for c in range(3)) for i in range(3)
    )
    state = _TreePass(
        origins=origins,
        axes=axes,
        tips=tips,
        tip_rotations=_matmul(body_rot, tip_rot),
        prismatic=flags,
    )
    return state, centroids, inertias


def _backward_pass(robot: TreeRobot, cst: TreeConstants, state: _TreePass, centroids, inertias) -> None:
    """Subtree momenta up the tree, then the system centroid, mass and inertia about it, into ``state``."""
    segs = segments(robot.parents)
    flags = state.prismatic
    axes, origins = state.axes, state.origins
    batch = axes[0].shape[1:]
    zero = jnp.zeros(batch, flags.dtype)
    totals: dict[int, list] = {}  # parent body/root -> totals of the segments hanging from it
    momentum_parts, angular_parts = [None] * len(segs), [None] * len(segs)
    flat_flags = flags.reshape(-1)
    for s in range(len(segs) - 1, -1, -1):
        start, stop, parent = segs[s]
        part = slice(start, stop)
        xs = (
            cst.link_mass[part],
            _index(centroids, part),
            _index(inertias, part),
            _index(axes, part),
            _index(origins, part),
            cst.subtree_mass[part],
            flat_flags[part],
        )
        init = ((zero,) * 3, (zero,) * 6)
        children = [j for j in range(start, stop) if j in totals]
        if children:
            extra = []
            for j in range(start, stop):
                hanging = totals.get(j, [init])
                moment = functools.reduce(_add, [h[0] for h in hanging])
                about = functools.reduce(_sym_add, [h[1] for h in hanging])
                extra.append((moment, about))
            extra_moment = tuple(jnp.stack([e[0][i] for e in extra]) for i in range(3))
            extra_about = tuple(jnp.stack([e[1][i] for e in extra]) for i in range(6))
            total, (p, l) = jax.lax.scan(_tree_backward_step, init, (extra_moment, extra_about, *xs), reverse=True)
        else:
            total, (p, l) = jax.lax.scan(_backward_step, init, xs, reverse=True)
        momentum_parts[s], angular_parts[s] = p, l
        totals.setdefault(parent, []).append(total)
    roots = [t for key, group in totals.items() if key < 0 for t in group]
    fixed = cst.fixed_inertia
    moment = functools.reduce(_add, [t[0] for t in roots], _vec(cst.fixed_moment))
    about = functools.reduce(
        _sym_add, [t[1] for t in roots], (fixed[0, 0], fixed[1, 1], fixed[2, 2], fixed[0, 1], fixed[0, 2], fixed[1, 2])
    )
    mass = cst.total_mass
    centroid = _scale(1.0 / mass, moment)
    state.momentum, state.angular = _cat(momentum_parts), _cat(angular_parts)
    state.centroid, state.mass = centroid, mass
    state.inertia_g = tuple(x - y for x, y in zip(about, _point_inertia(mass, centroid), strict=False))


def _expand(x, batch_ndim):
    return x.reshape(x.shape + (1,) * batch_ndim)


def _fixed_columns(robot: TreeRobot, state: _TreePass):
    """Fixed-base Jacobian of every tip: (v, w) 3-tuples of ``(k, n, *batch)`` (zero off each tip's path)."""
    batch_ndim = state.prismatic.ndim - 1
    mask = jnp.asarray(_expand(robot.support, batch_ndim), state.prismatic.dtype)  # (k, n, 1..)
    revolute = 1.0 - state.prismatic
    axes = tuple(a[None] for a in state.axes)
    tips = tuple(t[:, None] for t in state.tips)
    lever = _cross(axes, _sub(tips, tuple(o[None] for o in state.origins)))
    v = _add(_scale(revolute, lever), _scale(state.prismatic, axes))
    return _scale(mask, v), _scale(mask * revolute, axes)


def _tip_rows(*vectors):
    """``(k, 3 * len(vectors), n, *batch)`` from 3-tuples of ``(k, n, *batch)``."""
    return jnp.stack([component for vector in vectors for component in vector], axis=1)


def _jstar_from(robot, state):
    """``(k, 6, n, *batch)`` J* of every tip, the module docstring's closed form regrouped.

    With w*_t = S_t a - A (S_t the support mask; a zero for prismatic joints) and
    r_t = tip_t - G: J*_v,t = w*_t x tip_t + S_t (prismatic a - revolute a x o) - P/M - G x A,
    so the per-tip work is one cross product per column (the rest is shared by the tips).
    """
    _, solved = _coupling(state)
    batch_ndim = state.prismatic.ndim - 1
    mask = jnp.asarray(_expand(robot.support, batch_ndim), state.prismatic.dtype)  # (k, n, 1..)
    revolute = 1.0 - state.prismatic
    own = _sub(_scale(state.prismatic, state.axes), _scale(revolute, _cross(state.axes, state.origins)))
    shared = _sub(_scale(-1.0 / state.mass, state.momentum), _cross(state.centroid, solved))
    turning = _scale(revolute, state.axes)
    w_star = tuple(mask * x[None] - y[None] for x, y in zip(turning, solved, strict=True))
    tips = tuple(t[:, None] for t in state.tips)
    lever = _cross(w_star, tips)
    v_star = tuple(l + mask * o[None] + c[None] for l, o, c in zip(lever, own, shared, strict=True))
    return _tip_rows(v_star, w_star)


# Kernels in batch-last form (q (n, *batch)) ----------------------------------------------


def _jstar_first(robot, q):
    """``(batch, k, 6, n)`` J* of every tip for ``q (n, batch)``: `_jstar_from`'s closed form,
    assembled batch-first.

    The pass runs batch-last (every scalar one contiguous array over postures); the
    per-joint terms w = revolute a, A, own and shared (12 numbers per joint) and the tips
    are turned batch-first, and the 6k x n entries of each posture are formed there, so
    the result is written in its final order (forming them batch-last and transposing
    the result was slower on XLA's CPU backend: the transposed write is not vectorized).
    """
    state = _tree_pass(robot, q)
    _, solved = _coupling(state)
    revolute = 1.0 - state.prismatic
    own = _sub(_scale(state.prismatic, state.axes), _scale(revolute, _cross(state.axes, state.origins)))
    shared = _sub(_scale(-1.0 / state.mass, state.momentum), _cross(state.centroid, solved))
    turning = _scale(revolute, state.axes)
    per_joint = jnp.transpose(jnp.stack([*turning, *solved, *own, *shared]), (2, 0, 1))  # (batch, 12, n)
    tips = jnp.transpose(jnp.stack(state.tips), (2, 1, 0))  # (batch, k, 3)
    term = lambda i: tuple(per_joint[:, None, 3 * i + c] for c in range(3))  # (batch, 1, n)
    turning, solved, own, shared = (term(i) for i in range(4))
    mask = jnp.asarray(robot.support, q.dtype)  # (k, n)
    w_star = tuple(mask * t - a for t, a in zip(turning, solved, strict=True))
    lever = _cross(w_star, tuple(tips[:, :, c, None] for c in range(3)))
    v_star = tuple(l + mask * o + c for l, o, c in zip(lever, own, shared, strict=True))
    return jnp.stack([*v_star, *w_star], axis=2)


def _tip_minor(robot, q):
    state = _tree_pass(robot, q)
    return jnp.stack(_sub(state.tips, tuple(c[None] for c in state.centroid)), axis=1)


def _fixed_minor(robot, q):
    return _tip_rows(*_fixed_columns(robot, _tree_pass(robot, q, with_momentum=False)))


def _fixed_tips_minor(robot, q):
    """Fixed-base twists of every tip (rows 0-5) and the tip origins about the bus frame
    (rows 6-8, the same in every column), from one pass without momenta."""
    state = _tree_pass(robot, q, with_momentum=False)
    v, w = _fixed_columns(robot, state)
    tips = tuple(jnp.broadcast_to(t[:, None], v[0].shape) for t in state.tips)
    return _tip_rows(v, w, tips)


def _jstar_minor(robot, q):
    return _jstar_from(robot, _tree_pass(robot, q))


def _wstar_minor(robot, q):
    """``(k, *batch)`` translational w* of every tip: sqrt of the sum of squared 3x3 minors
    of J*_v (Cauchy-Binet; no cancellation near rank loss). Minor (i, j, l), i < j < l, is
    (c_i x c_j) . c_l: one step per middle column j over contiguous slices (no gathers)."""
    J = _jstar_minor(robot, q)[:, :3]  # (k, 3, n, *batch)
    n = robot.n_joints
    cols = tuple(J[:, c] for c in range(3))  # (k, n, *batch)
    squares = jnp.zeros((J.shape[0],) + J.shape[3:], J.dtype)
    for j in range(1, n - 1):
        middle = tuple(c[:, j : j + 1] for c in cols)  # (k, 1, *batch)
        cross = _cross(tuple(c[:, :j] for c in cols), middle)  # (k, j, *batch): c_i x c_j, i < j
        after = tuple(c[:, None, j + 1 :] for c in cols)  # (k, 1, n-j-1, *batch)
        minors = _dot(tuple(x[:, :, None] for x in cross), after)  # (k, j, n-j-1, *batch)
        squares = squares + jnp.sum(minors * minors, axis=(1, 2))
    positive = squares > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, squares, 1.0)), 0.0)


def _base_twist_minor(robot, q):
    state = _tree_pass(robot, q)
    _, solved = _coupling(state)
    r_g = _sub(state.centroid, _vec(jnp.asarray(robot.base_com)))
    v = _sub(_scale(-1.0 / state.mass, state.momentum), _cross(r_g, solved))
    return _rows(v, _scale(-1.0, solved))


def _straight_maps_minor(robot, q):
    state = _tree_pass(robot, q)
    jstar = _jstar_from(robot, state)  # (k, 6, n, *batch)
    _, solved = _coupling(state)
    return jnp.concatenate([jstar.reshape((-1,) + jstar.shape[2:]), _rows(_scale(-1.0, solved))], axis=0)


def _mass_from(robot, state):
    """H_m over the tree: joint j and k interact only when one is in the other's subtree."""
    revolute = 1.0 - state.prismatic
    lever = _cross(state.axes, state.origins)
    upper = revolute[:, None] * (_outer(state.axes, state.angular) - _outer(lever, state.momentum))
    upper = upper + state.prismatic[:, None] * _outer(state.axes, state.momentum)
    down = _expand(descendants(robot.parents), upper.ndim - 2)
    zero = jnp.zeros((), upper.dtype)
    return jnp.where(down, upper, jnp.where(np.swapaxes(down, 0, 1), jnp.swapaxes(upper, 0, 1), zero))


def _centred_tip_rows(state, shape):
    """``(k, 3, *shape)``: the tips about the system centroid, repeated over the columns."""
    tips = _sub(state.tips, tuple(c[None] for c in state.centroid))  # (k, *batch)
    return jnp.stack([jnp.broadcast_to(t[:, None], shape[:1] + shape[2:]) for t in tips], axis=1)


def _jstar_tips_minor(robot, q):
    """J* of every tip (rows 0-5) and the tips about the centroid (rows 6-8, the same in every
    column), ``(k, 9, n, *batch)``, from one pass."""
    state = _tree_pass(robot, q)
    jstar = _jstar_from(robot, state)
    return jnp.concatenate([jstar, _centred_tip_rows(state, jstar.shape)], axis=1)


def _fixed_centred_minor(robot, q):
    """Fixed-base twists of every tip (rows 0-5) and the tips about the centroid (rows 6-8),
    ``(k, 9, n, *batch)``, from one pass."""
    state = _tree_pass(robot, q)
    fixed = _tip_rows(*_fixed_columns(robot, state))
    return jnp.concatenate([fixed, _centred_tip_rows(state, fixed.shape)], axis=1)


def _straight_ends_minor(robot, q):
    """`_straight_maps_minor`'s rows (6k + 3), then every tip's fixed-base J_v (3k rows) and the
    tips about the centroid (3k rows, the same in every column), from one pass."""
    state = _tree_pass(robot, q)
    jstar = _jstar_from(robot, state)
    _, solved = _coupling(state)
    fixed_v = _tip_rows(_fixed_columns(robot, state)[0])
    flat = lambda x: x.reshape((-1,) + x.shape[2:])
    parts = [flat(jstar), _rows(_scale(-1.0, solved)), flat(fixed_v), flat(_centred_tip_rows(state, fixed_v.shape))]
    return jnp.concatenate(parts, axis=0)


# Primitives (one design, one posture; also any leading batch of postures) -----------------

tip = batched(_tip_minor, 2)
tip.__doc__ = """``(..., k, 3)`` tip origins about the system centroid, bus axes, m, for ``q (..., n)``."""

fixed_base_jacobian = batched(_fixed_minor, 3)
fixed_base_jacobian.__doc__ = """``(..., k, 6, n)`` tip twists [v; w] per joint rate, bus held fixed, bus axes
(zero in the columns of joints off each tip's path)."""

_fixed_tips = batched(_fixed_tips_minor, 3)


def fixed_base_jacobian_and_tips(robot: TreeRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """`fixed_base_jacobian` ``(..., k, 6, n)`` and the tip origins ``(..., k, 3)`` about the
    bus frame origin, bus axes, from one pass over the tree without momenta (what the
    relative Jacobian of two tips needs: the bus twist drops out of it)."""
    stacked = _fixed_tips(robot, q)
    return stacked[..., :6, :], stacked[..., 6:, 0]


generalized_jacobian = batched(_jstar_first, 0)
generalized_jacobian.__doc__ = """``(..., k, 6, n)`` J* of every tip over all joints at zero momentum, bus axes.

The closed form of the module docstring: one pass over the tree and one 3x3 solve per posture."""

manipulability = batched(_wstar_minor, 1)
manipulability.__doc__ = """``(..., k)`` translational w* = sqrt det(J*_v J*_v^T) of every tip, m^3."""

base_twist_map = batched(_base_twist_minor, 2)
base_twist_map.__doc__ = """``(..., 6, n)`` C(q): bus twist [v of bus centroid; w] per joint rate, bus axes."""

straight_path_maps = batched(_straight_maps_minor, 2)
straight_path_maps.__doc__ = """``(..., 6k + 3, n)``: rows 6t..6t+5 J* [v; w] of tip t, the last 3 rows C_w (bus
angular velocity per joint rate), bus axes, from one pass over the tree (what straight tip and pose paths need)."""

_jstar_tips = batched(_jstar_tips_minor, 3)
_fixed_centred = batched(_fixed_centred_minor, 3)
_straight_ends = batched(_straight_ends_minor, 2)


def tip_and_generalized_jacobian(robot: TreeRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(..., k, 6, n)`` J* and ``(..., k, 3)`` tips about the system centroid, bus axes, from one
    pass per posture (equal to `generalized_jacobian` and `tip`; for code that needs both)."""
    stacked = _jstar_tips(robot, q)
    return stacked[..., :6, :], stacked[..., 6:, 0]


def tip_and_fixed_base_jacobian(robot: TreeRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(..., k, 6, n)`` fixed-base Jacobians and ``(..., k, 3)`` tips about the system centroid,
    bus axes, from one pass per posture (equal to `fixed_base_jacobian` and `tip`)."""
    stacked = _fixed_centred(robot, q)
    return stacked[..., :6, :], stacked[..., 6:, 0]


def straight_maps_and_ends(robot: TreeRobot, q: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """`straight_path_maps` ``(..., 6k + 3, n)``, every tip's fixed-base J_v ``(..., k, 3, n)`` and
    the tips about the system centroid ``(..., k, 3)``, bus axes, from one pass per posture: a
    straight path's field and its end quantities."""
    k, n = robot.n_tips, robot.n_joints
    stacked = _straight_ends(robot, q)
    maps, fixed_v, tips = (
        stacked[..., : 6 * k + 3, :],
        stacked[..., 6 * k + 3 : 9 * k + 3, :],
        stacked[..., 9 * k + 3 :, 0],
    )
    return maps, fixed_v.reshape(fixed_v.shape[:-2] + (k, 3, n)), tips.reshape(tips.shape[:-1] + (k, 3))


def joint_points(robot: TreeRobot, q: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """One posture: the system centroid ``(3,)``, the joint origins ``(n, 3)`` and the tip origins
    ``(k, 3)``, bus frame, m, from the kernels' pass (what a drawing of the robot needs)."""
    state = _tree_pass(robot, jnp.asarray(q))
    return jnp.stack(state.centroid), jnp.stack(state.origins, axis=-1), jnp.stack(state.tips, axis=-1)


POSTURE_QUANTITIES = ("jacobian", "base_rate", "arm_inertia")


def _posture_quantities_minor(robot, q, needs):
    """J* rows of all tips (6k), C (6) and H* (n) stacked by rows ``(rows, n, *batch)`` from ONE pass."""
    state = _tree_pass(robot, q)
    coupling, solved = _coupling(state)
    parts = []
    if "jacobian" in needs:
        J = _jstar_from(robot, state)
        parts.append(J.reshape((-1,) + J.shape[2:]))
    if "base_rate" in needs:
        r_g = _sub(state.centroid, _vec(jnp.asarray(robot.base_com)))
        v_bus = _sub(_scale(-1.0 / state.mass, state.momentum), _cross(r_g, solved))
        parts.append(_rows(v_bus, _scale(-1.0, solved)))
    if "arm_inertia" in needs:
        H = _mass_from(robot, state) - _outer(state.momentum, state.momentum) / state.mass
        parts.append(H - _outer(coupling, solved))
    return jnp.concatenate(parts, axis=0)


def posture_quantities(robot: TreeRobot, q: jax.Array, needs: tuple[str, ...]) -> dict[str, jax.Array]:
    """The per-posture matrices posture metrics need, from one pass over the tree per posture.

    Args:
        robot: one design.
        q: ``(..., n)`` joint positions.
        needs: a subset of `POSTURE_QUANTITIES` (static): ``"jacobian"`` J* ``(..., k, 6, n)``,
            ``"base_rate"`` C ``(..., 6, n)``, ``"arm_inertia"`` H* ``(..., n, n)``; bus axes,
            each equal to its own kernel above.
    """
    wanted = tuple(name for name in POSTURE_QUANTITIES if name in needs)
    stacked = batched(lambda r, x: _posture_quantities_minor(r, x, wanted), 2)(robot, q)
    k, n = robot.n_tips, robot.n_joints
    rows = {"jacobian": 6 * k, "base_rate": 6, "arm_inertia": n}
    out, start = {}, 0
    for name in wanted:
        out[name] = stacked[..., start : start + rows[name], :]
        start += rows[name]
    if "jacobian" in out:
        out["jacobian"] = out["jacobian"].reshape(out["jacobian"].shape[:-2] + (k, 6, n))
    return out


def tip_pose(robot: TreeRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Tip frames with the bus frame fixed, one posture: ``(k, 3, 3)`` axes and ``(k, 3)`` origins."""
    state = _tree_pass(robot, jnp.asarray(q), with_momentum=False)
    rotation = jnp.moveaxis(_pack(state.tip_rotations), -1, 0)
    return rotation, jnp.stack(state.tips, axis=-1)


def tip_frames(robot: TreeRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """One posture: the tip origins about the system centroid ``(k, 3)`` and the tip axes
    ``(k, 3, 3)``, bus axes, from one pass over the tree (equal to `tip` and `tip_pose`'s axes)."""
    state = _tree_pass(robot, jnp.asarray(q))
    origins = jnp.stack(_sub(state.tips, tuple(c[None] for c in state.centroid)), axis=1)
    return origins, jnp.moveaxis(_pack(state.tip_rotations), -1, 0)


def body_frames(robot: TreeRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Body frames with the bus frame fixed, one posture ``q (n,)``: ``(n, 3, 3)`` axes of
    each body's URDF link frame (the child frame of joint j) and ``(n, 3)`` its origin, bus
    frame, m (a prismatic joint's body origin is its joint origin slid by q_j along the axis).

    A plain walk down the parents (joint frame in the parent body, then turned about or slid
    along the unit axis, Rodrigues' formula): for drawing, not for the kernels' hot path."""
    q = jnp.asarray(q)
    mounts = jax.vmap(rpy_to_matrix)(jnp.asarray(robot.mount_rpy))
    eye = jnp.eye(3, dtype=mounts.dtype)
    rotations, origins = [], []
    for j, parent in enumerate(robot.parents):
        if parent < 0:
            rotation, origin = mounts[-1 - parent], jnp.asarray(robot.mount_xyz)[-1 - parent]
        else:
            rotation, origin = rotations[parent], origins[parent]
        frame = rotation @ jnp.asarray(robot.joint_rotation)[j]
        origin = origin + rotation @ jnp.asarray(robot.joint_translation)[j]
        axis = jnp.asarray(robot.joint_axis)[j]
        axis = axis / jnp.linalg.norm(axis)
        if robot.joint_kinds[j] == "prismatic":
            origin = origin + q[j] * (frame @ axis)
        else:
            k = jnp.cross(eye, axis)  # [axis]x: row i is e_i x axis
            frame = frame @ (eye + jnp.sin(q[j]) * k + (1.0 - jnp.cos(q[j])) * (k @ k))
        rotations.append(frame)
        origins.append(origin)
    return jnp.stack(rotations), jnp.stack(origins)


def jacobians(robot: TreeRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """One posture: J_S ``(6k, 6)`` (tip twists per bus twist [v of bus centroid; w]) and
    J_M ``(6k, n)``, tip by tip, bus axes."""
    state = _tree_pass(robot, jnp.asarray(q), with_momentum=False)
    base_com = _vec(jnp.asarray(robot.base_com))
    blocks = [_point_twist_map(_index(state.tips, t), base_com) for t in range(robot.n_tips)]
    J_M = _tip_rows(*_fixed_columns(robot, state))
    return jnp.concatenate(blocks, axis=0), J_M.reshape((-1,) + J_M.shape[2:])


def momentum_map(robot: TreeRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """One posture: I_S ``(6, 6)`` and I_M ``(6, n)``; total [linear; angular about the bus
    centroid] momentum is I_S [v; w] + I_M qdot (bus twist [v of bus centroid; w]), bus axes."""
    state = _tree_pass(robot, jnp.asarray(q))
    base_com = _vec(jnp.asarray(robot.base_com))
    angular = _sub(state.angular, _cross(base_com, state.momentum))
    return _bus_momentum_matrix(state, base_com), _rows(state.momentum, angular)
