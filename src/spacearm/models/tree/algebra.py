"""The scalar algebra the pass over the tree is written in, and its forward and backward steps.

Posture arrays carry their batch axes LAST (q is ``(n, *batch)``), so every scalar of
the arithmetic is one contiguous array over postures: 3-vectors are 3-tuples of arrays,
3x3 matrices 3-tuples of rows, symmetric 3x3 matrices the 6 entries
(xx, yy, zz, xy, xz, yz). Batched with ``vmap`` or over trailing axes, every operation
is an elementwise loop over postures that XLA fuses (no batched 3x3 matrix products).

Notation of the steps (bus axes, origin of the bus frame). For joint k with unit axis
a_k through o_k, let the bodies of its subtree move rigidly at unit joint rate, bus held
still: p_k, their linear momentum, is a_k x (h_k - M_k o_k) (revolute) or M_k a_k
(prismatic), with M_k the subtree mass and h_k its first mass moment; L_k, their angular
momentum about the bus-frame origin, is K_k a_k - h_k x (a_k x o_k) (revolute) or
h_k x a_k (prismatic), with K_k the subtree's inertia about the origin.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

# 3-vectors and 3x3 matrices as tuples of arrays (Python floats are free constants) ------


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


def _motion_cross(twist, other):
    """Spatial motion cross product (Featherstone): [w; v] x [w'; v'] = [w x w'; w x v' + v x w'],
    twists as pairs of 3-tuples (angular; linear at one origin)."""
    (w, v), (w2, v2) = twist, other
    return (_cross(w, w2), _add(_cross(w, v2), _cross(v, w2)))


def _force_cross(twist, force):
    """Spatial force cross product (Featherstone): [w; v] x* [n; f] = [w x n + v x f; w x f]."""
    (w, v), (n, f) = twist, force
    return (_add(_cross(w, n), _cross(v, f)), _cross(w, f))


def _cholesky_solve(matrix, rhs):
    """``(n, *batch)`` x with S x = b, for S ``(n, n, *batch)`` symmetric positive definite (its
    lower triangle is read) and b ``(n, *batch)``.

    Cholesky S = L L^T, then L y = b and L^T x = y, each a scan over the columns whose step is
    elementwise over the batch: no LAPACK call per posture, and one step to compile (an
    unrolled factorization's program grows as n^3). The factorization is right-looking: step
    j scales column j of what is left and subtracts its outer product.
    """
    n = matrix.shape[0]
    rows = jnp.arange(n).reshape((n,) + (1,) * (matrix.ndim - 2))
    take = lambda x, i: jax.lax.dynamic_index_in_dim(x, i, axis=0, keepdims=False)

    def factor(rest, j):
        column = jax.lax.dynamic_index_in_dim(rest, j, axis=1, keepdims=False)
        column = jnp.where(rows >= j, column / jnp.sqrt(take(column, j)), 0.0)
        return rest - column[:, None] * column[None, :], column

    _, columns = jax.lax.scan(factor, matrix, jnp.arange(n))  # columns[j] = L[:, j]

    def forward(b, j):
        y = take(b, j) / take(columns[j], j)
        return jnp.where(rows > j, b - columns[j] * y, b), y

    _, y = jax.lax.scan(forward, rhs, jnp.arange(n))

    def backward(x, item):
        j, y_j = item
        column = columns[j]
        value = (y_j - jnp.sum(jnp.where(rows > j, column * x, 0.0), axis=0)) / take(column, j)
        return x.at[j].set(value), None

    x, _ = jax.lax.scan(backward, jnp.zeros_like(rhs), (jnp.arange(n)[::-1], y[::-1]))
    return x


def _pack(nested):
    """Stack nested lists of scalars along new LEADING axes (batch axes stay last)."""
    if isinstance(nested, (list, tuple)):
        parts = [_pack(x) for x in nested]
        return jnp.stack(jnp.broadcast_arrays(*parts), axis=0)
    return jnp.asarray(nested)


# Frames ----------------------------------------------------------------------------------


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


# The steps of the pass ------------------------------------------------------------------
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


def _coupling(state):
    """I~_q (angular momentum about G per joint rate) and A = I~^-1 I~_q, 3-tuples of ``(n, *batch)``,
    from a pass's momenta, centroid G and inertia about G (the bus angular velocity is -A qdot)."""
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


def _outer(a, b):
    """``(n, n, *batch)``: a_j . b_k for 3-tuples of ``(n, *batch)``."""
    return sum(a[c][:, None] * b[c][None, :] for c in range(3))


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


def _batch_first(matrix: jax.Array, axes: int) -> jax.Array:
    """``(a_1..a_axes, *batch)`` -> ``(*batch, a_1..a_axes)``."""
    return jnp.moveaxis(matrix, tuple(range(axes)), tuple(range(-axes, 0)))


# Postures per block: the arrays of one block stay in the core's cache
# (benchmarks/bench_spatial.py measures the block against one pass over every posture).
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

    def apply(robot, posture: jax.Array) -> jax.Array:
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
