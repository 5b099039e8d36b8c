"""Per-posture primitives of the spatial family: one design, one posture, no batch axes.

Everything is expressed in the bus frame (base_rotation = identity); the generic layer
rotates results by the bus attitude R (blkdiag(R, R) for twists, R for points).

Design-only work (`chain_constants`) happens once per design: the mount
rotation, each body re-expressed in a frame whose z axis is its joint axis (so a joint
rotation is Rz(q) and costs a sine, a cosine and 12 products), the bus and root body
folded into one constant body, subtree masses. The posture work is then one forward
pass over the chain (frames, joint axes, body centroids and inertias in bus axes) and
one backward pass (subtree mass moments), written entry by entry on scalars so that,
batched with ``vmap``, every operation is an elementwise loop over postures that XLA
fuses (no batched 3x3 matrix products).

Notation (all bus axes, origin of the bus frame). For arm joint k with unit axis a_k
through o_k, let bodies k..n move rigidly at unit joint rate, bus held still:

- p_k, their linear momentum: a_k x (h_k - M_k o_k) (revolute) or M_k a_k (prismatic),
  with M_k the subtree mass and h_k its first mass moment;
- L_k, their angular momentum about the bus-frame origin: K_k a_k - h_k x (a_k x o_k)
  (revolute) or h_k x a_k (prismatic), with K_k the subtree's inertia about the origin.

With G the system centroid, M the total mass and I~ = K - M S(G) the system inertia
about G (joints locked), zero linear and angular momentum give the bus angular
velocity omega_B = -I~^-1 I~_q qdot, with I~_q columns L_k - G x p_k (Yoshida's
inertia coupling; Umetani & Yoshida 1990, eq. 5, in 3-D), and the Generalized Jacobian

    J*_v = J_v - P / M + [r_t]x I~^-1 I~_q,    J*_w = J_w - I~^-1 I~_q,

with P = [p_1 .. p_n], r_t the tip about G, and J_v, J_w the fixed-base Jacobian
(Umetani & Yoshida 1990, eq. 6, in 3-D). It equals J_M - J_S I_S^-1 I_M for the
momentum map below; only a 3x3 system is solved.

Base twist coordinates of `momentum_map` and `jacobians`: b = [v; w], the
velocity of the bus centroid and the bus angular velocity, bus axes (J* does not
depend on this choice; ``-I_S^-1 I_M`` is then the bus centroid's twist per joint rate).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from .robot import SpatialRobot

__all__ = [
    "POSTURE_QUANTITIES",
    "ChainConstants",
    "arm_inertia",
    "base_twist_map",
    "chain_constants",
    "fixed_base_jacobian",
    "generalized_jacobian",
    "jacobians",
    "mass_matrix",
    "momentum_map",
    "posture_quantities",
    "rpy_to_matrix",
    "straight_maps_and_ends",
    "straight_path_maps",
    "tip",
    "tip_and_fixed_base_jacobian",
    "tip_and_generalized_jacobian",
    "tip_frame",
    "tip_pose",
]


# Scalar 3-vector and 3x3 helpers (tuples of arrays; Python floats are free constants) --


def _vec(array):
    return (array[0], array[1], array[2])


def _mat(array):
    return tuple((array[r, 0], array[r, 1], array[r, 2]) for r in range(3))


def _add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _scale(s, a):
    return (s * a[0], s * a[1], s * a[2])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _matvec(m, v):
    return tuple(m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2] for r in range(3))


def _matmul(a, b):
    return tuple(tuple(a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c] for c in range(3)) for r in range(3))


def _column(m, c):
    return (m[0][c], m[1][c], m[2][c])


def _from_columns(c0, c1, c2):
    return tuple((c0[r], c1[r], c2[r]) for r in range(3))


# Symmetric 3x3 as (xx, yy, zz, xy, xz, yz)


def _sym_rotate(rot, inertia):
    """R I R^T for a symmetric I given as a full 3x3 tuple; returns the 6 unique entries."""
    a = _matmul(rot, inertia)
    entry = lambda r, c: a[r][0] * rot[c][0] + a[r][1] * rot[c][1] + a[r][2] * rot[c][2]
    return (entry(0, 0), entry(1, 1), entry(2, 2), entry(0, 1), entry(0, 2), entry(1, 2))


def _sym_add(a, b):
    return tuple(x + y for x, y in zip(a, b, strict=False))


def _point_inertia(mass, c):
    """m S(c) = m (|c|^2 1 - c c^T) as 6 entries."""
    xx, yy, zz = c[0] * c[0], c[1] * c[1], c[2] * c[2]
    return (
        mass * (yy + zz),
        mass * (xx + zz),
        mass * (xx + yy),
        -mass * c[0] * c[1],
        -mass * c[0] * c[2],
        -mass * c[1] * c[2],
    )


def _sym_matvec(s, v):
    xx, yy, zz, xy, xz, yz = s
    return (xx * v[0] + xy * v[1] + xz * v[2], xy * v[0] + yy * v[1] + yz * v[2], xz * v[0] + yz * v[1] + zz * v[2])


def _sym_solve(s, columns):
    """Solve S X = B for symmetric positive definite S (6 entries) by the adjugate."""
    xx, yy, zz, xy, xz, yz = s
    c00 = yy * zz - yz * yz
    c01 = xz * yz - xy * zz
    c02 = xy * yz - xz * yy
    c11 = xx * zz - xz * xz
    c12 = xy * xz - xx * yz
    c22 = xx * yy - xy * xy
    inv_det = 1.0 / (xx * c00 + xy * c01 + xz * c02)
    adj = ((c00, c01, c02), (c01, c11, c12), (c02, c12, c22))
    return [_scale(inv_det, _matvec(adj, b)) for b in columns]


def _pack(nested):
    """Stack nested lists of scalars along new LEADING axes (batch axes stay last)."""
    if isinstance(nested, (list, tuple)):
        parts = [_pack(x) for x in nested]
        return jnp.stack(jnp.broadcast_arrays(*parts), axis=0)
    return jnp.asarray(nested)


# Design-only constants ---------------------------------------------------------------


def rpy_to_matrix(rpy: jax.Array) -> jax.Array:
    """URDF roll-pitch-yaw (fixed axes x, y, z) -> ``(3, 3)``: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = rpy[0], rpy[1], rpy[2]
    cr, sr, cp, sp, cy, sy = jnp.cos(r), jnp.sin(r), jnp.cos(p), jnp.sin(p), jnp.cos(y), jnp.sin(y)
    return jnp.stack(
        [
            jnp.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr]),
            jnp.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr]),
            jnp.stack([-sp, cp * sr, cp * cr]),
        ]
    )


def _axis_frame(axis: jax.Array) -> jax.Array:
    """A rotation Q whose third column is the unit joint axis a (Q e_z = a).

    The first column is a helper direction made orthogonal to a. Results do not
    depend on that choice (only a matters), so the branch is harmless for gradients.
    """
    a = axis / jnp.linalg.norm(axis)
    helper = jnp.where(jnp.abs(a[0]) < 0.9, jnp.array([1.0, 0.0, 0.0], a.dtype), jnp.array([0.0, 1.0, 0.0], a.dtype))
    x = helper - jnp.dot(helper, a) * a
    x = x / jnp.linalg.norm(x)
    y = jnp.cross(a, x)
    return jnp.stack([x, y, a], axis=-1)


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class ChainConstants:
    """Design-only arrays of one design (computed once per design).

    Body k's frame here is its URDF frame turned by a constant rotation so that its
    joint axis is z; positions and inertias are re-expressed accordingly.

    Attributes:
        mount_rotation: ``(3, 3)`` root body axes in the bus frame.
        mount_xyz: ``(3,)`` root body origin in the bus frame, m.
        placement: ``(n, 3, 3)`` joint frame k in body k-1 (turned frames; body 0 = root).
        offset: ``(n, 3)`` joint k origin in body k-1, m.
        prismatic: ``(n,)`` 1.0 for a prismatic joint, 0.0 for a revolute one.
        link_mass: ``(n,)`` kg.  link_com: ``(n, 3)`` m.
        link_inertia: ``(n, 3, 3)`` about the centroid, kg m^2.
        subtree_mass: ``(n,)`` M_k = mass of bodies k..n, kg.
        total_mass: ``()`` M, kg.
        fixed_moment: ``(3,)`` first mass moment of bus + root body, bus frame, kg m.
        fixed_inertia: ``(3, 3)`` inertia of bus + root body about the bus-frame origin.
        tip_offset: ``(3,)`` tip origin in body n, m.  tip_rotation: ``(3, 3)``.
        base_com: ``(3,)`` bus centroid, bus frame, m.
    """

    mount_rotation: jax.Array
    mount_xyz: jax.Array
    placement: jax.Array
    offset: jax.Array
    prismatic: jax.Array
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


def _second_moment(c: jax.Array) -> jax.Array:
    return jnp.dot(c, c) * jnp.eye(3, dtype=c.dtype) - jnp.outer(c, c)


def chain_constants(robot: SpatialRobot) -> ChainConstants:
    """Design-only constants of one (unbatched) design; see `ChainConstants`."""
    n = robot.n_joints
    frames = jax.vmap(_axis_frame)(jnp.asarray(robot.joint_axis))  # (n, 3, 3) Q_k
    identity = jnp.eye(3, dtype=frames.dtype)
    before = jnp.concatenate([identity[None], frames[:-1]], axis=0)  # Q_{k-1}, Q_0 = 1
    placement = jnp.einsum("kji,kjl,klm->kim", before, robot.joint_rotation, frames)
    offset = jnp.einsum("kji,kj->ki", before, robot.joint_translation)
    mount_rotation = rpy_to_matrix(robot.mount_rpy)
    mount_xyz = jnp.asarray(robot.mount_xyz)

    link_mass = jnp.asarray(robot.link_mass)
    root_com = mount_xyz + mount_rotation @ robot.root_com
    root_inertia = mount_rotation @ robot.root_inertia @ mount_rotation.T
    last = frames[n - 1]
    return ChainConstants(
        mount_rotation=mount_rotation,
        mount_xyz=mount_xyz,
        placement=placement,
        offset=offset,
        prismatic=jnp.array([k == "prismatic" for k in robot.joint_kinds], dtype=placement.dtype),
        link_mass=link_mass,
        link_com=jnp.einsum("kji,kj->ki", frames, robot.link_com),
        link_inertia=jnp.einsum("kji,kjl,klm->kim", frames, robot.link_inertia, frames),
        subtree_mass=jnp.cumsum(link_mass[::-1])[::-1],
        total_mass=robot.base_mass + robot.root_mass + jnp.sum(link_mass),
        fixed_moment=robot.base_mass * robot.base_com + robot.root_mass * root_com,
        fixed_inertia=(
            robot.base_inertia
            + robot.base_mass * _second_moment(jnp.asarray(robot.base_com))
            + root_inertia
            + robot.root_mass * _second_moment(root_com)
        ),
        tip_offset=last.T @ robot.tip_translation,
        tip_rotation=last.T @ robot.tip_rotation,
        base_com=jnp.asarray(robot.base_com),
    )


# The pass over the chain ----------------------------------------------------------------
#
# Posture arrays carry their batch axes LAST here (q is (n, *batch)), so every scalar of
# the arithmetic below is one contiguous array over postures and every operation an
# elementwise loop over it. The chain is walked with lax.scan, one step per joint: a
# small block of scalar arithmetic whose outputs are stored. (Unrolled over the joints,
# XLA's CPU fusion copies cheap producers into every consumer and recomputes each sine
# some hundred times; the scan also compiles one step instead of n.)


def _forward_step(carry, x):
    rot, origin = carry
    placement, offset, c, s, slide, com, inertia = x
    rot_t = rot
    d = _matmul(rot_t, _mat(placement))
    joint_origin = _add(origin, _matvec(rot_t, _vec(offset)))
    axis = _column(d, 2)
    d0, d1 = _column(d, 0), _column(d, 1)
    new_rot = _from_columns(_add(_scale(c, d0), _scale(s, d1)), _sub(_scale(c, d1), _scale(s, d0)), axis)
    body_origin = _add(joint_origin, _scale(slide, axis))
    centroid = _add(body_origin, _matvec(new_rot, _vec(com)))
    inertia_bus = _sym_rotate(new_rot, _mat(inertia))
    # Tuples of scalar arrays throughout: no stacking (a concatenation per step) in the loop.
    return (new_rot, body_origin), (new_rot, joint_origin, axis, centroid, inertia_bus)


def _backward_step(carry, x):
    moment, about = carry
    mass, centroid, inertia, axis, origin, subtree_mass, prismatic = x
    c, a, o = centroid, axis, origin
    moment = _add(moment, _scale(mass, c))
    about = _sym_add(_sym_add(about, inertia), _point_inertia(mass, c))
    revolute = 1.0 - prismatic
    p_rev = _cross(a, _sub(moment, _scale(subtree_mass, o)))
    l_rev = _sub(_sym_matvec(about, a), _cross(moment, _cross(a, o)))
    p = _add(_scale(revolute, p_rev), _scale(prismatic * subtree_mass, a))
    l = _add(_scale(revolute, l_rev), _scale(prismatic, _cross(moment, a)))
    return (moment, about), (p, l)


@dataclasses.dataclass
class _Pass:
    """One pass over the chain, as tuples of components.

    Per-joint quantities are 3-tuples of ``(n, *batch)`` arrays (the joint axis leading,
    so the post-processing is written once for all joints); per-posture ones are
    3-tuples of ``(*batch)`` arrays.
    """

    last_rotation: tuple  # body n axes (turned frame), 3x3 tuple
    origins: tuple  # joint origins o_k
    axes: tuple  # unit joint axes a_k
    tip: tuple  # tip origin, bus frame
    prismatic: jax.Array  # (n, 1, ...) 1.0 for prismatic joints, broadcastable
    momentum: tuple = None  # p_k
    angular: tuple = None  # L_k about the bus-frame origin
    centroid: tuple = None  # G
    mass: jax.Array = None  # M
    inertia_g: tuple = None  # I~ about G, 6 entries (xx, yy, zz, xy, xz, yz)


def _chain_pass(robot: SpatialRobot, q, with_momentum: bool = True) -> _Pass:
    """Forward and backward pass for joint positions ``q (n, *batch)`` (batch axes last)."""
    cst = chain_constants(robot)
    q = jnp.asarray(q)
    batch = q.shape[1:]
    flags = jnp.asarray([k == "prismatic" for k in robot.joint_kinds], dtype=q.dtype)
    flags = flags.reshape((-1,) + (1,) * len(batch))
    angle = q * (1.0 - flags)  # prismatic joints turn by 0 and slide by q
    xs = (cst.placement, cst.offset, jnp.cos(angle), jnp.sin(angle), q * flags, cst.link_com, cst.link_inertia)
    spread = lambda x: jnp.broadcast_to(x, batch)
    start = (
        tuple(tuple(spread(cst.mount_rotation[r, c]) for c in range(3)) for r in range(3)),
        tuple(spread(cst.mount_xyz[r]) for r in range(3)),
    )
    (rot, origin), (_, origins, axes, centroids, inertias) = jax.lax.scan(_forward_step, start, xs)
    tip = _add(origin, _matvec(rot, _vec(cst.tip_offset)))
    state = _Pass(last_rotation=rot, origins=origins, axes=axes, tip=tip, prismatic=flags)
    if not with_momentum:
        return state
    xs = (cst.link_mass, centroids, inertias, axes, origins, cst.subtree_mass, flags.reshape(-1))
    zero = jnp.zeros(batch, q.dtype)
    (moment, about), (momentum, angular) = jax.lax.scan(_backward_step, ((zero,) * 3, (zero,) * 6), xs, reverse=True)
    fixed = cst.fixed_inertia
    moment = _add(moment, _vec(cst.fixed_moment))
    about = _sym_add(about, (fixed[0, 0], fixed[1, 1], fixed[2, 2], fixed[0, 1], fixed[0, 2], fixed[1, 2]))
    mass = cst.total_mass
    centroid = _scale(1.0 / mass, moment)
    state.momentum, state.angular = momentum, angular
    state.centroid, state.mass = centroid, mass
    state.inertia_g = tuple(x - y for x, y in zip(about, _point_inertia(mass, centroid), strict=False))
    return state


def _fixed_columns(state: _Pass):
    """Fixed-base Jacobian of the tip origin, all joints at once: (v, w) 3-tuples of ``(n, *batch)``."""
    revolute = 1.0 - state.prismatic
    lever = _cross(state.axes, _sub(state.tip, state.origins))
    v = _add(_scale(revolute, lever), _scale(state.prismatic, state.axes))
    return v, _scale(revolute, state.axes)


def _coupling(state: _Pass):
    """I~_q (angular momentum about G per joint rate) and A = I~^-1 I~_q, 3-tuples of ``(n, *batch)``."""
    coupling = _sub(state.angular, _cross(state.centroid, state.momentum))
    return coupling, _sym_solve(state.inertia_g, [coupling])[0]


def _skew(v):
    return ((0.0, -v[2], v[1]), (v[2], 0.0, -v[0]), (-v[1], v[0], 0.0))


def _sym_full(s):
    xx, yy, zz, xy, xz, yz = s
    return ((xx, xy, xz), (xy, yy, yz), (xz, yz, zz))


def _rows(*vectors):
    """``(3 * len(vectors), n, *batch)``: the components of 3-tuples of ``(n, *batch)`` as rows."""
    return _pack([component for vector in vectors for component in vector])


def _batch_last(posture: jax.Array) -> jax.Array:
    return jnp.moveaxis(jnp.asarray(posture), -1, 0)


def _batch_first(matrix: jax.Array, axes: int) -> jax.Array:
    """``(a_1..a_axes, *batch)`` -> ``(*batch, a_1..a_axes)``."""
    return jnp.moveaxis(matrix, tuple(range(axes)), tuple(range(-axes, 0)))


# Kernels in batch-last form (q (n, *batch)) ----------------------------------------------


def _tip_minor(robot, q):
    state = _chain_pass(robot, q)
    return _pack(_sub(state.tip, state.centroid))


def _fixed_minor(robot, q):
    return _rows(*_fixed_columns(_chain_pass(robot, q, with_momentum=False)))


def _generalized_columns(state: _Pass):
    """From one chain pass: the bus rotation per joint rate A (``solved``), the fixed-base
    columns (v, w), the tip about the system centroid r_t, and J*'s translational columns
    v* = v - P/M + r_t x A (the bus reaction, eq. 5's spatial form)."""
    _, solved = _coupling(state)
    v, w = _fixed_columns(state)
    r_t = _sub(state.tip, state.centroid)
    v_star = _add(_sub(v, _scale(1.0 / state.mass, state.momentum)), _cross(r_t, solved))
    return solved, v, w, r_t, v_star


def _jstar_minor(robot, q):
    state = _chain_pass(robot, q)
    solved, _, w, _, v_star = _generalized_columns(state)
    return _rows(v_star, _sub(w, solved))


def _jstar_tip_minor(robot, q):
    """J* (rows 0-5) and the tip about the centroid (rows 6-8, the same in every column) from ONE chain pass."""
    state = _chain_pass(robot, q)
    solved, _, w, r_t, v_star = _generalized_columns(state)
    tip_rows = tuple(jnp.broadcast_to(component, q.shape) for component in r_t)
    return _rows(v_star, _sub(w, solved), tip_rows)


def _fixed_tip_minor(robot, q):
    """Fixed-base J (rows 0-5) and the tip about the centroid (rows 6-8, the same in every column), one chain pass."""
    state = _chain_pass(robot, q)
    tip_rows = tuple(jnp.broadcast_to(component, q.shape) for component in _sub(state.tip, state.centroid))
    return _rows(*_fixed_columns(state), tip_rows)


def _base_twist_minor(robot, q):
    state = _chain_pass(robot, q)
    _, solved = _coupling(state)
    r_g = _sub(state.centroid, _vec(jnp.asarray(robot.base_com)))
    # w_bus = -A qdot; v_bus = -P/M qdot - w_bus x r_g.
    v = _sub(_scale(-1.0 / state.mass, state.momentum), _cross(r_g, solved))
    return _rows(v, _scale(-1.0, solved))


def _straight_maps_minor(robot, q):
    """J*_v and C_w rows from ONE chain pass: what a straight-path field needs per evaluation."""
    state = _chain_pass(robot, q)
    solved, _, _, _, v_star = _generalized_columns(state)
    return _rows(v_star, _scale(-1.0, solved))


def _straight_ends_minor(robot, q):
    """`_straight_maps_minor`'s rows, then the fixed-base J_v (rows 6-8) and the tip about
    the centroid (rows 9-11, the same in every column), from the same ONE chain pass."""
    state = _chain_pass(robot, q)
    solved, v, _, r_t, v_star = _generalized_columns(state)
    tip_rows = tuple(jnp.broadcast_to(component, q.shape) for component in r_t)
    return _rows(v_star, _scale(-1.0, solved), v, tip_rows)


def _outer(a, b):
    """``(n, n, *batch)``: a_j . b_k for 3-tuples of ``(n, *batch)``."""
    return sum(a[c][:, None] * b[c][None, :] for c in range(3))


def _symmetric_from_upper(upper):
    n = upper.shape[0]
    mask = (jnp.arange(n)[:, None] <= jnp.arange(n)[None, :]).reshape((n, n) + (1,) * (upper.ndim - 2))
    return jnp.where(mask, upper, jnp.swapaxes(upper, 0, 1))


def _mass_from(state: _Pass):
    # Row j, column k >= j: the generalized force of joint j from subtree k moving at unit rate.
    revolute = 1.0 - state.prismatic
    lever = _cross(state.axes, state.origins)
    upper = revolute[:, None] * (_outer(state.axes, state.angular) - _outer(lever, state.momentum))
    upper = upper + state.prismatic[:, None] * _outer(state.axes, state.momentum)
    return _symmetric_from_upper(upper)


def _mass_minor(robot, q):
    return _mass_from(_chain_pass(robot, q))


def _arm_inertia_minor(robot, q):
    state = _chain_pass(robot, q)
    coupling, solved = _coupling(state)
    return _mass_from(state) - _outer(state.momentum, state.momentum) / state.mass - _outer(coupling, solved)


# Postures per block: the arrays of one block stay in the core's cache (measured on the
# UR5 J*: ~2k postures per block runs 5x faster than one pass over 10^5).
BLOCK = 2048


def batched(kernel, axes: int):
    """A batch-last kernel as a function of ``(robot, q (..., n))`` -> ``(..., *result)``.

    Large batches run in blocks of `BLOCK` postures in a loop that writes each block's
    result in place into the whole result, so memory stays bounded and each block's arrays
    stay in cache. The last block is shifted back to end at the last posture (it repeats
    a few postures, with the same values), so nothing is padded and the result is never
    copied to slice padding off. ``axes=0`` takes a kernel that already returns
    ``(batch, *result)``.
    """

    def one(robot, block):
        return _batch_first(kernel(robot, block.T), axes)

    def apply(robot: SpatialRobot, posture: jax.Array) -> jax.Array:
        posture = jnp.asarray(posture)
        batch, n = posture.shape[:-1], posture.shape[-1]
        flat = posture.reshape((-1, n))
        count = flat.shape[0]
        if count <= BLOCK:
            out = one(robot, flat)
        else:
            result = jax.eval_shape(one, robot, flat[:BLOCK])

            def step(i, out):
                start = jnp.minimum(i * BLOCK, count - BLOCK)
                part = one(robot, jax.lax.dynamic_slice_in_dim(flat, start, BLOCK))
                return jax.lax.dynamic_update_slice_in_dim(out, part, start, 0)

            empty = jnp.zeros((count,) + result.shape[1:], result.dtype)
            out = jax.lax.fori_loop(0, -(-count // BLOCK), step, empty)
        return out.reshape(batch + out.shape[1:])

    apply.__name__ = kernel.__name__.strip("_").replace("_minor", "")
    return apply


# Primitives (one design, one posture; also any leading batch of postures) -----------------

tip = batched(_tip_minor, 1)
tip.__doc__ = """``(..., 3)`` tip origin about the system centroid, bus axes, m, for ``q (..., n)``."""

fixed_base_jacobian = batched(_fixed_minor, 2)
fixed_base_jacobian.__doc__ = """``(..., 6, n)`` tip twist [v; w] per joint rate with the bus held fixed, bus axes."""

generalized_jacobian = batched(_jstar_minor, 2)
generalized_jacobian.__doc__ = """``(..., 6, n)`` J*: tip twist [v; w] per joint rate at zero momentum, bus axes.

The closed form of the module docstring (Umetani & Yoshida 1990, eq. 6, in 3-D):
only a 3x3 system is solved, one pass over the chain per posture."""

base_twist_map = batched(_base_twist_minor, 2)
base_twist_map.__doc__ = (
    """``(..., 6, n)`` C(q): bus twist [v of bus centroid; w] per joint rate at zero momentum, bus axes."""
)

straight_path_maps = batched(_straight_maps_minor, 2)
straight_path_maps.__doc__ = """``(..., 6, n)``: rows 0-2 J*_v (tip velocity per joint rate at zero momentum) and
rows 3-5 C_w (bus angular velocity per joint rate), bus axes, from one pass over the chain
(the rows of `generalized_jacobian` and `base_twist_map` a straight tip path needs)."""

_jstar_tip = batched(_jstar_tip_minor, 2)
_straight_ends = batched(_straight_ends_minor, 2)


def straight_maps_and_ends(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """`straight_path_maps` ``(..., 6, n)``, the fixed-base J_v ``(..., 3, n)`` and the tip about
    the system centroid ``(..., 3)``, bus axes, from one chain pass per posture: a straight
    path's field and its end quantities (equal to `straight_path_maps`,
    `fixed_base_jacobian` rows 0-2 and `tip`)."""
    stacked = _straight_ends(robot, q)
    return stacked[..., :6, :], stacked[..., 6:9, :], stacked[..., 9:, 0]


def tip_and_generalized_jacobian(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(..., 6, n)`` J* and ``(..., 3)`` tip about the system centroid, bus axes, from one chain pass per posture.

    Equal to `generalized_jacobian` and `tip`; for code that needs both (and their
    derivatives) at the same postures, such as the singular-set search."""
    stacked = _jstar_tip(robot, q)
    return stacked[..., :6, :], stacked[..., 6:, 0]


_fixed_tip = batched(_fixed_tip_minor, 2)


def tip_and_fixed_base_jacobian(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(..., 6, n)`` fixed-base Jacobian and ``(..., 3)`` tip about the system centroid, bus axes,
    from one chain pass per posture (equal to `fixed_base_jacobian` and `tip`)."""
    stacked = _fixed_tip(robot, q)
    return stacked[..., :6, :], stacked[..., 6:, 0]


mass_matrix = batched(_mass_minor, 2)
mass_matrix.__doc__ = """``(..., n, n)`` H_m: the arm's joint-space inertia with the bus held fixed."""

arm_inertia = batched(_arm_inertia_minor, 2)
arm_inertia.__doc__ = """``(..., n, n)`` H* = H_m - H_bm^T H_b^-1 H_bm: the arm inertia at zero momentum.

In system-centroid coordinates H_b = blkdiag(M 1, I~) and H_bm = [P; I~_q], so
H* = H_m - P^T P / M - I~_q^T I~^-1 I~_q (Yoshida's generalized inertia)."""


def tip_pose(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Tip frame with the bus frame fixed, one posture: ``(3, 3)`` axes and ``(3,)`` origin."""
    cst = chain_constants(robot)
    state = _chain_pass(robot, jnp.asarray(q), with_momentum=False)
    return _pack(_matmul(state.last_rotation, _mat(cst.tip_rotation))), _pack(state.tip)


def tip_frame(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """One posture: the tip origin about the system centroid ``(3,)`` and the tip axes
    ``(3, 3)``, bus axes, from one chain pass (equal to `tip` and `tip_pose`'s axes)."""
    cst = chain_constants(robot)
    state = _chain_pass(robot, jnp.asarray(q))
    return _pack(_sub(state.tip, state.centroid)), _pack(_matmul(state.last_rotation, _mat(cst.tip_rotation)))


def _point_twist_map(point, base_com):
    """``(6, 6)`` J_S: the twist [v; w] of a point fixed to the bus per bus twist [v of the bus
    centroid; w], bus axes."""
    skew = _skew(_sub(point, base_com))
    j_s = [[1.0 if c == r else 0.0 for c in range(3)] + [-skew[r][c] for c in range(3)] for r in range(3)]
    j_s += [[0.0] * 3 + [1.0 if c == r else 0.0 for c in range(3)] for r in range(3)]
    return _pack(j_s)


def _bus_momentum_matrix(state, base_com):
    """``(6, 6)`` I_S: [linear; angular about the bus centroid] momentum per bus twist, joints
    locked, from a pass's total mass, centroid and inertia about it (``state.mass``,
    ``state.centroid``, ``state.inertia_g``)."""
    mass = state.mass
    r_g = _sub(state.centroid, base_com)
    skew = _skew(r_g)
    about_com = _sym_full(_sym_add(state.inertia_g, _point_inertia(mass, r_g)))
    i_s = [[mass if c == r else 0.0 for c in range(3)] + [-mass * skew[r][c] for c in range(3)] for r in range(3)]
    i_s += [[mass * skew[r][c] for c in range(3)] + list(about_com[r]) for r in range(3)]
    return _pack(i_s)


def jacobians(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """One posture: J_S ``(6, 6)`` (tip twist per bus twist [v of bus centroid; w]) and J_M ``(6, n)``, bus axes."""
    state = _chain_pass(robot, jnp.asarray(q), with_momentum=False)
    return _point_twist_map(state.tip, _vec(jnp.asarray(robot.base_com))), _rows(*_fixed_columns(state))


def momentum_map(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """One posture: I_S ``(6, 6)`` and I_M ``(6, n)``; total [linear; angular about the bus
    centroid] momentum is I_S [v; w] + I_M qdot (bus twist [v of bus centroid; w]), bus axes."""
    state = _chain_pass(robot, jnp.asarray(q))
    base_com = _vec(jnp.asarray(robot.base_com))
    angular = _sub(state.angular, _cross(base_com, state.momentum))
    return _bus_momentum_matrix(state, base_com), _rows(state.momentum, angular)


def _posture_quantities_minor(robot, q, needs):
    """J*, C and H* stacked by rows ``(rows, n, *batch)`` from ONE chain pass (only those in ``needs``)."""
    state = _chain_pass(robot, q)
    coupling, solved = _coupling(state)
    parts = []
    if "jacobian" in needs:
        _, _, w, _, v_star = _generalized_columns(state)
        parts.append(_rows(v_star, _sub(w, solved)))
    if "base_rate" in needs:
        r_g = _sub(state.centroid, _vec(jnp.asarray(robot.base_com)))
        v_bus = _sub(_scale(-1.0 / state.mass, state.momentum), _cross(r_g, solved))
        parts.append(_rows(v_bus, _scale(-1.0, solved)))
    if "arm_inertia" in needs:
        parts.append(_mass_from(state) - _outer(state.momentum, state.momentum) / state.mass - _outer(coupling, solved))
    return jnp.concatenate(parts, axis=0)


POSTURE_QUANTITIES = ("jacobian", "base_rate", "arm_inertia")


def posture_quantities(robot: SpatialRobot, q: jax.Array, needs: tuple[str, ...]) -> dict[str, jax.Array]:
    """The per-posture matrices posture metrics need, from one chain pass per posture.

    Args:
        robot: one design.
        q: ``(..., n)`` joint positions.
        needs: a subset of `POSTURE_QUANTITIES` (static): ``"jacobian"`` J* ``(..., 6, n)``,
            ``"base_rate"`` C ``(..., 6, n)`` (bus twist per joint rate), ``"arm_inertia"``
            H* ``(..., n, n)``; bus axes, each equal to its own kernel above.

    Returns:
        ``{name: array}`` for the names in ``needs``.
    """
    wanted = tuple(name for name in POSTURE_QUANTITIES if name in needs)
    stacked = batched(lambda r, x: _posture_quantities_minor(r, x, wanted), 2)(robot, q)
    rows = {"jacobian": 6, "base_rate": 6, "arm_inertia": robot.n_joints}
    out, start = {}, 0
    for name in wanted:
        out[name] = stacked[..., start : start + rows[name], :]
        start += rows[name]
    return out
