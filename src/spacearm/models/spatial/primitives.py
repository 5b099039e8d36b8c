"""Per-posture primitives of the spatial family: one design, one posture, no batch axes.

Everything is expressed in the bus frame (base_rotation = identity); the generic layer
rotates results by the bus attitude R (blkdiag(R, R) for twists, R for points).

Design-only work (:func:`chain_constants`) happens once per design: the mount
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

Base twist coordinates of :func:`momentum_map` and :func:`jacobians`: b = [v; w], the
velocity of the bus centroid and the bus angular velocity, bus axes (J* does not
depend on this choice; ``-I_S^-1 I_M`` is then the bus centroid's twist per joint rate).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from .robot import SpatialRobot

__all__ = [
    "ChainConstants",
    "chain_constants",
    "tip",
    "tip_pose",
    "jacobians",
    "momentum_map",
    "fixed_base_jacobian",
    "mass_matrix",
    "generalized_jacobian",
    "base_twist_map",
    "arm_inertia",
    "rpy_to_matrix",
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
    entry = lambda r, c: a[r][0] * rot[c][0] + a[r][1] * rot[c][1] + a[r][2] * rot[c][2]  # noqa: E731
    return (entry(0, 0), entry(1, 1), entry(2, 2), entry(0, 1), entry(0, 2), entry(1, 2))


def _sym_add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def _point_inertia(mass, c):
    """m S(c) = m (|c|^2 1 - c c^T) as 6 entries."""
    xx, yy, zz = c[0] * c[0], c[1] * c[1], c[2] * c[2]
    return (mass * (yy + zz), mass * (xx + zz), mass * (xx + yy), -mass * c[0] * c[1], -mass * c[0] * c[2], -mass * c[1] * c[2])


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


def _stack(rows):
    """A matrix from nested lists of scalars (arrays or Python floats)."""
    flat = jnp.broadcast_arrays(*[jnp.asarray(x) for row in rows for x in row])
    ncol = len(rows[0])
    return jnp.stack([jnp.stack(flat[r * ncol:(r + 1) * ncol], axis=-1) for r in range(len(rows))], axis=-2)


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

    Body i's frame here is its URDF frame turned by a constant rotation so that its
    joint axis is z; positions and inertias are re-expressed accordingly.

    Attributes:
        first_rotation: ``(3, 3)`` body 1 axes in the bus frame at q_1 = 0.
        first_origin: ``(3,)`` joint 1 origin in the bus frame, m.
        placement: ``(n, 3, 3)`` joint frame k in body k-1 (turned frames).
        offset: ``(n, 3)`` joint k origin in body k-1, m.
        link_mass: ``(n,)`` kg.  link_com: ``(n, 3)`` m.  link_inertia: ``(n, 3, 3)`` kg m^2.
        subtree_mass: ``(n,)`` M_k = mass of bodies k..n, kg.
        total_mass: ``()`` M, kg.
        fixed_moment: ``(3,)`` first mass moment of bus + root body, bus frame, kg m.
        fixed_inertia: ``(3, 3)`` inertia of bus + root body about the bus-frame origin.
        tip_offset: ``(3,)`` tip origin in body n, m.  tip_rotation: ``(3, 3)``.
        base_com: ``(3,)`` bus centroid, bus frame, m.
    """

    first_rotation: jax.Array
    first_origin: jax.Array
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


def _second_moment(c: jax.Array) -> jax.Array:
    return jnp.dot(c, c) * jnp.eye(3, dtype=c.dtype) - jnp.outer(c, c)


def chain_constants(robot: SpatialRobot) -> ChainConstants:
    """Design-only constants of one (unbatched) design; see :class:`ChainConstants`."""
    n = robot.n_joints
    frames = jax.vmap(_axis_frame)(jnp.asarray(robot.joint_axis))  # (n, 3, 3) Q_k
    identity = jnp.eye(3, dtype=frames.dtype)
    before = jnp.concatenate([identity[None], frames[:-1]], axis=0)  # Q_{k-1}, Q_0 = 1
    placement = jnp.einsum("kji,kjl,klm->kim", before, robot.joint_rotation, frames)
    offset = jnp.einsum("kji,kj->ki", before, robot.joint_translation)
    mount_rotation = rpy_to_matrix(robot.mount_rpy)
    mount_xyz = jnp.asarray(robot.mount_xyz)

    link_com = jnp.einsum("kji,kj->ki", frames, robot.link_com)
    link_inertia = jnp.einsum("kji,kjl,klm->kim", frames, robot.link_inertia, frames)
    link_mass = jnp.asarray(robot.link_mass)
    subtree_mass = jnp.cumsum(link_mass[::-1])[::-1]

    root_com = mount_xyz + mount_rotation @ robot.root_com
    root_inertia = mount_rotation @ robot.root_inertia @ mount_rotation.T
    fixed_moment = robot.base_mass * robot.base_com + robot.root_mass * root_com
    fixed_inertia = (
        robot.base_inertia
        + robot.base_mass * _second_moment(jnp.asarray(robot.base_com))
        + root_inertia
        + robot.root_mass * _second_moment(root_com)
    )
    total_mass = robot.base_mass + robot.root_mass + jnp.sum(link_mass)
    last = frames[n - 1]
    return ChainConstants(
        first_rotation=mount_rotation @ placement[0],
        first_origin=mount_xyz + mount_rotation @ offset[0],
        placement=placement,
        offset=offset,
        link_mass=link_mass,
        link_com=link_com,
        link_inertia=link_inertia,
        subtree_mass=subtree_mass,
        total_mass=total_mass,
        fixed_moment=fixed_moment,
        fixed_inertia=fixed_inertia,
        tip_offset=last.T @ robot.tip_translation,
        tip_rotation=last.T @ robot.tip_rotation,
        base_com=jnp.asarray(robot.base_com),
    )


# The per-posture pass ------------------------------------------------------------------


@dataclasses.dataclass
class _Pass:
    rotations: list  # body axes in the bus frame (turned frames), 3x3 tuples
    origins: list  # joint origins o_k
    axes: list  # unit joint axes a_k
    tip: tuple  # tip origin, bus frame
    momentum: list  # p_k
    angular: list  # L_k about the bus-frame origin
    centroid: tuple  # G
    mass: jax.Array  # M
    inertia_g: tuple  # I~ about G, 6 entries
    inertia_origin: tuple  # K about the origin, 6 entries


def _forward(cst: ChainConstants, kinds, q):
    """Body frames, joint origins and axes, and body centroids and inertias in bus axes."""
    rotations, origins, axes, centroids, inertias = [], [], [], [], []
    rot = None
    origin = _vec(cst.first_origin)
    for k, kind in enumerate(kinds):
        if k == 0:
            d = _mat(cst.first_rotation)
        else:
            d = _matmul(rot, _mat(cst.placement[k]))
            origin = _add(origin, _matvec(rot, _vec(cst.offset[k])))
        axis = _column(d, 2)
        if kind == "revolute":
            c, s = jnp.cos(q[k]), jnp.sin(q[k])
            d0, d1 = _column(d, 0), _column(d, 1)
            rot = _from_columns(_add(_scale(c, d0), _scale(s, d1)), _sub(_scale(c, d1), _scale(s, d0)), axis)
            body_origin = origin
        else:  # prismatic: the child frame slides along the axis
            rot = d
            body_origin = _add(origin, _scale(q[k], axis))
        rotations.append(rot)
        origins.append(origin)
        axes.append(axis)
        centroids.append(_add(body_origin, _matvec(rot, _vec(cst.link_com[k]))))
        inertias.append(_sym_rotate(rot, _mat(cst.link_inertia[k])))
        origin = body_origin
    tip = _add(origin, _matvec(rot, _vec(cst.tip_offset)))
    return rotations, origins, axes, centroids, inertias, tip


def _chain_pass(robot: SpatialRobot, q, with_momentum: bool = True) -> _Pass:
    cst = chain_constants(robot)
    kinds = robot.joint_kinds
    q = jnp.asarray(q)
    rotations, origins, axes, centroids, inertias, tip = _forward(cst, kinds, q)
    if not with_momentum:
        return _Pass(rotations, origins, axes, tip, [], [], (), cst.total_mass, (), ())
    n = len(kinds)
    momentum, angular = [None] * n, [None] * n
    moment = (0.0, 0.0, 0.0)
    about_origin = (0.0,) * 6
    for k in reversed(range(n)):
        m = cst.link_mass[k]
        moment = _add(moment, _scale(m, centroids[k]))
        about_origin = _sym_add(about_origin, _sym_add(inertias[k], _point_inertia(m, centroids[k])))
        a, o, mk = axes[k], origins[k], cst.subtree_mass[k]
        if kinds[k] == "revolute":
            momentum[k] = _cross(a, _sub(moment, _scale(mk, o)))
            angular[k] = _sub(_sym_matvec(about_origin, a), _cross(moment, _cross(a, o)))
        else:
            momentum[k] = _scale(mk, a)
            angular[k] = _cross(moment, a)
    fixed = cst.fixed_inertia
    moment = _add(moment, _vec(cst.fixed_moment))
    about_origin = _sym_add(
        about_origin, (fixed[0, 0], fixed[1, 1], fixed[2, 2], fixed[0, 1], fixed[0, 2], fixed[1, 2])
    )
    mass = cst.total_mass
    centroid = _scale(1.0 / mass, moment)
    inertia_g = tuple(x - y for x, y in zip(about_origin, _point_inertia(mass, centroid)))
    return _Pass(rotations, origins, axes, tip, momentum, angular, centroid, mass, inertia_g, about_origin)


def _fixed_columns(state: _Pass, kinds):
    """Fixed-base Jacobian columns (v, w) of the tip origin, bus axes."""
    columns = []
    for k, kind in enumerate(kinds):
        a = state.axes[k]
        if kind == "revolute":
            columns.append((_cross(a, _sub(state.tip, state.origins[k])), a))
        else:
            columns.append((a, (0.0, 0.0, 0.0)))
    return columns


def _coupling(state: _Pass):
    """I~_q columns (angular momentum about G per joint rate) and A = I~^-1 I~_q."""
    coupling = [_sub(l, _cross(state.centroid, p)) for l, p in zip(state.angular, state.momentum)]
    return coupling, _sym_solve(state.inertia_g, coupling)


def _sym_full(s):
    xx, yy, zz, xy, xz, yz = s
    return ((xx, xy, xz), (xy, yy, yz), (xz, yz, zz))


def _skew(v):
    return ((0.0, -v[2], v[1]), (v[2], 0.0, -v[0]), (-v[1], v[0], 0.0))


# Primitives (one design, one posture) --------------------------------------------------


def tip(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """``(3,)`` tip origin about the system centroid, bus axes, m.

    Args:
        q: ``(n,)`` joint positions (rad or m), path order.
    """
    state = _chain_pass(robot, q)
    return jnp.stack(jnp.broadcast_arrays(*_sub(state.tip, state.centroid)))


def tip_pose(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Tip frame in the bus frame (bus held still): ``(3, 3)`` axes and ``(3,)`` origin (bus-frame origin)."""
    cst = chain_constants(robot)
    rotations, _, _, _, _, position = _forward(cst, robot.joint_kinds, jnp.asarray(q))
    rot = _matmul(rotations[-1], _mat(cst.tip_rotation))
    return _stack(rot), jnp.stack(jnp.broadcast_arrays(*position))


def fixed_base_jacobian(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """``(6, n)`` tip twist [v; w] per joint rate with the bus held fixed, bus axes."""
    state = _chain_pass(robot, q, with_momentum=False)
    columns = _fixed_columns(state, robot.joint_kinds)
    return _stack([[col[0][r] for col in columns] for r in range(3)] + [[col[1][r] for col in columns] for r in range(3)])


def jacobians(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """J_S ``(6, 6)`` (tip twist per bus twist [v of bus centroid; w]) and J_M ``(6, n)``, bus axes."""
    state = _chain_pass(robot, q, with_momentum=False)
    r = _sub(state.tip, _vec(chain_constants(robot).base_com))
    skew = _skew(r)
    j_s = [[1.0 if c == row else 0.0 for c in range(3)] + [-skew[row][c] for c in range(3)] for row in range(3)]
    j_s += [[0.0] * 3 + [1.0 if c == row else 0.0 for c in range(3)] for row in range(3)]
    return _stack(j_s), fixed_base_jacobian(robot, q)


def momentum_map(robot: SpatialRobot, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """I_S ``(6, 6)`` and I_M ``(6, n)``: total [linear; angular about the bus centroid] momentum
    is I_S [v; w] + I_M qdot (bus twist [v of bus centroid; w]), bus axes."""
    state = _chain_pass(robot, q)
    base_com = _vec(chain_constants(robot).base_com)
    mass = state.mass
    r_g = _sub(state.centroid, base_com)
    skew = _skew(r_g)
    about_com = _sym_full(_sym_add(state.inertia_g, _point_inertia(mass, r_g)))
    i_s = [[mass if c == row else 0.0 for c in range(3)] + [-mass * skew[row][c] for c in range(3)] for row in range(3)]
    i_s += [[mass * skew[row][c] for c in range(3)] + list(about_com[row]) for row in range(3)]
    angular = [_sub(l, _cross(base_com, p)) for l, p in zip(state.angular, state.momentum)]
    i_m = [[p[row] for p in state.momentum] for row in range(3)] + [[l[row] for l in angular] for row in range(3)]
    return _stack(i_s), _stack(i_m)


def generalized_jacobian(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """J* ``(6, n)``: tip twist [v; w] per joint rate at zero momentum, bus axes (closed form).

    Umetani & Yoshida 1990, eq. (6), in 3-D; only a 3x3 system is solved (module docstring).
    """
    state = _chain_pass(robot, q)
    _, solved = _coupling(state)
    r_t = _sub(state.tip, state.centroid)
    inv_mass = 1.0 / state.mass
    rows_v, rows_w = [[], [], []], [[], [], []]
    for (jv, jw), p, x in zip(_fixed_columns(state, robot.joint_kinds), state.momentum, solved):
        v = _add(_sub(jv, _scale(inv_mass, p)), _cross(r_t, x))
        w = _sub(jw, x)
        for r in range(3):
            rows_v[r].append(v[r])
            rows_w[r].append(w[r])
    return _stack(rows_v + rows_w)


def base_twist_map(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """C(q) ``(6, n)``: bus twist [v of bus centroid; w] per joint rate at zero momentum, bus axes."""
    state = _chain_pass(robot, q)
    _, solved = _coupling(state)
    r_g = _sub(state.centroid, _vec(chain_constants(robot).base_com))
    inv_mass = 1.0 / state.mass
    rows = [[] for _ in range(6)]
    for p, x in zip(state.momentum, solved):
        # v_bus = -P/M qdot - w x r_g with w = -x qdot.
        v = _sub(_scale(-inv_mass, p), _cross(r_g, x))
        for r in range(3):
            rows[r].append(v[r])
            rows[3 + r].append(-x[r])
    return _stack(rows)


def mass_matrix(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """H_m ``(n, n)``: the arm's joint-space inertia with the bus held fixed, kg m^2 (or kg)."""
    state = _chain_pass(robot, q)
    return _stack(_mass_rows(state, robot.joint_kinds))


def _mass_rows(state: _Pass, kinds):
    n = len(kinds)
    entries = [[None] * n for _ in range(n)]
    for j in range(n):
        a = state.axes[j]
        for k in range(j, n):
            if kinds[j] == "revolute":
                value = _dot(a, state.angular[k]) - _dot(_cross(a, state.origins[j]), state.momentum[k])
            else:
                value = _dot(a, state.momentum[k])
            entries[j][k] = entries[k][j] = value
    return entries


def arm_inertia(robot: SpatialRobot, q: jax.Array) -> jax.Array:
    """H* = H_m - H_bm^T H_b^-1 H_bm ``(n, n)``: the arm inertia at zero momentum.

    In system-centroid coordinates H_b = blkdiag(M 1, I~) and H_bm = [P; I~_q], so
    H* = H_m - P^T P / M - I~_q^T I~^-1 I~_q (Yoshida's generalized inertia).
    """
    state = _chain_pass(robot, q)
    coupling, solved = _coupling(state)
    h_m = _mass_rows(state, robot.joint_kinds)
    n = len(coupling)
    inv_mass = 1.0 / state.mass
    rows = [
        [h_m[j][k] - inv_mass * _dot(state.momentum[j], state.momentum[k]) - _dot(coupling[j], solved[k]) for k in range(n)]
        for j in range(n)
    ]
    return _stack(rows)
