"""Free-floating dynamics on the tree pass: the system mass matrix, the bias forces, the tip maps.

Coordinates nu = [v; w; qdot]: v the velocity of the bus centroid and w the bus angular
velocity, both in bus axes, then the joint rates. The kinetic energy is
T = 1/2 nu^T H(q) nu with

    H = [[H_b, H_bm], [H_bm^T, H_m]],

H_b = I_S and H_bm = I_M the momentum map of one pass over the tree (so H nu is the
momentum [P; L_c] in bus axes, L_c about the bus centroid, then the joint momenta) and
H_m the joint-space inertia (Umetani & Yoshida 1990, eq. 4-5, in 3-D; Yoshida's
generalized inertia).

The bias forces follow from the same H. The bus coordinates are body-fixed, so the bus
rows are Kirchhoff's equations and the joint rows Lagrange's (the Euler-Poincare
equations of SE(3) x joints, gravity zero):

    d/dt P + w x P = f,   d/dt L_c + w x L_c + v x P = n,   d/dt p_q - dT/dq = tau,

with f the force at the bus centroid and n the torque about it (bus axes). Hence
H nu' + c(q, nu) = [f; n; tau] with

    c = (dH/dq . qdot) nu + [w x P; w x L_c + v x P; -1/2 nu^T (dH/dq) nu].

c is the generalized force of the motion nu at nu' = 0, so it is computed as that inverse
dynamics, by Newton-Euler on the same pass's frames (`_bias_from`; it equals the form
above, the derivatives of the pass that builds H, to rounding).
With the bus free (no wrench) the bus rows are solved through the system centroid, where
H_b is blkdiag(M, I~) (`free_dynamics`).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .tree.algebra import (
    _add,
    _bus_momentum_matrix,
    _cholesky_solve,
    _coupling,
    _cross,
    _dot,
    _force_cross,
    _mat,
    _matvec,
    _motion_cross,
    _outer,
    _rows,
    _scale,
    _sub,
    _sym_matvec,
    _sym_solve,
    _vec,
    batched,
)
from .tree.primitives import (
    _backward_pass,
    _fixed_columns,
    _forward_pass,
    _mass_from,
    _tip_rows,
    _tree_pass,
    descendants,
    tip_frames,
    tree_constants,
)
from .tree.robot import TreeRobot

__all__ = ["free_dynamics", "mass_and_bias", "system_mass_matrix", "tip_axes", "tip_maps"]


def _mass_from_pass(robot: TreeRobot, state, batch):
    """``(6 + n, 6 + n, *batch)`` H from a pass's momenta, centroid and inertia."""
    base_com = _vec(jnp.asarray(robot.base_com))
    angular = _sub(state.angular, _cross(base_com, state.momentum))
    h_b = jnp.broadcast_to(_bus_momentum_matrix(state, base_com), (6, 6) + batch)
    h_bm = _rows(state.momentum, angular)
    top = jnp.concatenate([h_b, h_bm], axis=1)
    bottom = jnp.concatenate([jnp.swapaxes(h_bm, 0, 1), _mass_from(robot, state)], axis=1)
    return jnp.concatenate([top, bottom], axis=0)


def _system_mass_minor(robot: TreeRobot, q):
    """``(6 + n, 6 + n, *batch)`` H for ``q (n, *batch)``, from one pass."""
    return _mass_from_pass(robot, _tree_pass(robot, q), q.shape[1:])


def _bias_from(robot: TreeRobot, cst, state, centroids, inertias, nu):
    """``(6 + n, *batch)`` c for ``nu (6 + n, *batch)``: Newton-Euler at nu' = 0.

    Twists and wrenches are Plucker pairs (angular; linear) at the bus-frame origin in bus
    axes, the frame frozen at this instant. nu' = 0 holds the bus's body-fixed twist, so
    its spatial acceleration is zero; body j moves with V_j = V_bus + sum of S_i qd_i over
    the joints i on its path, and accelerates with A_j = sum of V_i x S_i qd_i (qdd = 0;
    Featherstone 2008, sec. 5.3). Its force is I_j A_j + V_j x* I_j V_j; joint j takes
    S_j . (forces of its subtree), the bus the total force, moved to the bus centroid.
    Path and subtree sums are one product each with the tree's descendant mask."""
    revolute = 1.0 - state.prismatic
    qd, base_com = nu[6:], _vec(jnp.asarray(robot.base_com))
    v, w = _vec(nu[:3]), _vec(nu[3:6])
    bus = (w, _sub(v, _cross(w, base_com)))  # the bus twist at the bus-frame origin
    motion = (
        _scale(revolute, state.axes),
        _add(_scale(revolute, _cross(state.origins, state.axes)), _scale(state.prismatic, state.axes)),
    )
    joint = tuple(_scale(qd, part) for part in motion)
    down = jnp.asarray(descendants(robot.parents), qd.dtype)  # down[i, j]: body j in joint i's subtree
    along_path = lambda x: tuple(tuple(jnp.tensordot(down, c, axes=(0, 0)) for c in part) for part in x)
    twist = tuple(_add(b, s) for b, s in zip(bus, along_path(joint), strict=True))
    accel = along_path(_motion_cross(twist, joint))
    mass = cst.link_mass.reshape((-1,) + (1,) * (qd.ndim - 1))
    linear = _scale(mass, _add(twist[1], _cross(twist[0], centroids)))
    momentum = (_add(_sym_matvec(inertias, twist[0]), _cross(centroids, linear)), linear)
    push = _scale(mass, _add(accel[1], _cross(accel[0], centroids)))
    rate = (_add(_sym_matvec(inertias, accel[0]), _cross(centroids, push)), push)
    body = tuple(_add(r, f) for r, f in zip(rate, _force_cross(twist, momentum), strict=True))
    subtree = tuple(tuple(jnp.tensordot(down, c, axes=(1, 0)) for c in part) for part in body)
    torque = _dot(motion[0], subtree[0]) + _dot(motion[1], subtree[1])
    # The bus and the roots fixed to it: first mass moment h and inertia K about the origin.
    fixed_mass = cst.total_mass - jnp.sum(cst.link_mass)
    moment, about = _vec(cst.fixed_moment), _mat(cst.fixed_inertia)
    fixed_linear = _add(_scale(fixed_mass, bus[1]), _cross(w, moment))
    fixed_momentum = (_add(_matvec(about, w), _cross(moment, bus[1])), fixed_linear)
    fixed = _force_cross(bus, fixed_momentum)
    total = tuple(_add(f, tuple(jnp.sum(c, axis=0) for c in part)) for f, part in zip(fixed, body, strict=True))
    wrench = _rows(total[1], _sub(total[0], _cross(base_com, total[1])))
    return jnp.concatenate([wrench, torque], axis=0)


def _bodies_pass(robot: TreeRobot, q):
    """`_tree_pass` keeping what Newton-Euler needs: (constants, the pass, the body centroids
    and the body inertias about them, bus axes)."""
    cst = tree_constants(robot)
    state, centroids, inertias = _forward_pass(robot, cst, q)
    _backward_pass(robot, cst, state, centroids, inertias)
    return cst, state, centroids, inertias


def _mass_and_bias_minor(robot: TreeRobot, x):
    """``(6 + n, 7 + n, *batch)``: [H | c] for ``x = [q; nu] (2 n + 6, *batch)``, from one pass."""
    n = robot.n_joints
    q, nu = x[:n], x[n:]
    cst, state, centroids, inertias = _bodies_pass(robot, q)
    H = _mass_from_pass(robot, state, q.shape[1:])
    bias = _bias_from(robot, cst, state, centroids, inertias, nu)
    return jnp.concatenate([H, bias[:, None]], axis=1)


def _free_minor(robot: TreeRobot, x, forward: bool):
    """The bus free (no wrench), for ``x = [q; qd; load; P; L; moving] (4 n + 6, *batch)`` with
    the momentum [P; L about the system centroid] in bus axes and ``moving`` 1 for the moving
    joints, 0 for the held ones (their rates are zero; the forward solve locks them): ``(6 + n, *batch)`` [v; w; qdd] (the
    bus twist and the joint accelerations) for torques ``load`` (``forward``), else ``(n, *batch)``
    tau for accelerations ``load``.

    About the system centroid G, H_b is blkdiag(M, I~) and the joints couple to the bus through
    the momenta p_j and I~_q (columns L_j - G x p_j), so every H_b^-1 is a 3x3 solve
    (`spacearm.models.tree.primitives`): the bus twist is w = I~^-1 (L - I~_q qd),
    v = (P - p qd) / M - w x (G - b) (b the bus centroid), and with the bus rows of c moved
    to G, [f; n_G], the free bus's H* = H_m - p^T p / M - I~_q^T I~^-1 I~_q and
    c* = c_m - p^T f / M - (I~^-1 I~_q)^T n_G."""
    n = robot.n_joints
    q, qd, load, momentum, moving = x[:n], x[n : 2 * n], x[2 * n : 3 * n], x[3 * n : 3 * n + 6], x[3 * n + 6 :]
    cst, state, centroids, inertias = _bodies_pass(robot, q)
    coupling, solved = _coupling(state)
    mass, p = state.mass, state.momentum
    rate = lambda columns: tuple(jnp.sum(c * qd, axis=0) for c in columns)
    w = _sub(_sym_solve(state.inertia_g, [_vec(momentum[3:])])[0], rate(solved))
    offset = _sub(state.centroid, _vec(jnp.asarray(robot.base_com)))
    v = _sub(_scale(1.0 / mass, _sub(_vec(momentum[:3]), rate(p))), _cross(w, offset))
    bias = _bias_from(robot, cst, state, centroids, inertias, jnp.concatenate([_rows(v, w), qd]))
    force = _vec(bias[:3])
    torque = _sub(_vec(bias[3:6]), _cross(offset, force))  # about G
    reduced_bias = bias[6:] - _dot(p, force) / mass - _dot(solved, torque)
    inertia = _mass_from(robot, state) - _outer(p, p) / mass - _outer(coupling, solved)
    if forward:  # held joints (moving 0) locked: qdd = 0 there, the rest solved with them still
        both = moving[:, None] * moving[None, :]
        held = jnp.eye(n, dtype=x.dtype).reshape((n, n) + (1,) * (x.ndim - 1)) * (1.0 - moving)[None]
        qdd = _cholesky_solve(inertia * both + held, moving * (load - reduced_bias))
        return jnp.concatenate([_rows(v, w), qdd])
    return sum(inertia[:, j] * load[j] for j in range(n)) + reduced_bias  # elementwise over the batch


def _tip_maps_minor(robot: TreeRobot, q):
    """``(k, 6, 6 + n, *batch)``: the twist [v; w] of every tip origin per nu, bus axes."""
    state = _tree_pass(robot, q, with_momentum=False)
    x, y, z = _sub(state.tips, _vec(jnp.asarray(robot.base_com)))  # (k, *batch) each
    zero = jnp.zeros_like(x)
    lever = jnp.stack([jnp.stack(row) for row in ((zero, z, -y), (-z, zero, x), (y, -x, zero))])  # -[r]x
    eye = jnp.broadcast_to(jnp.eye(3, dtype=x.dtype).reshape((3, 3) + (1,) * x.ndim), lever.shape)
    bus = jnp.concatenate(
        [jnp.concatenate([eye, lever], axis=1), jnp.concatenate([jnp.zeros_like(eye), eye], axis=1)], axis=0
    )
    return jnp.concatenate([jnp.moveaxis(bus, 2, 0), _tip_rows(*_fixed_columns(robot, state))], axis=2)


def _free_forward_minor(robot: TreeRobot, x):
    return _free_minor(robot, x, forward=True)


def _free_inverse_minor(robot: TreeRobot, x):
    return _free_minor(robot, x, forward=False)


system_mass_matrix = batched(_system_mass_minor, 2)
system_mass_matrix.__doc__ = """``(..., 6 + n, 6 + n)`` H in the coordinates [v; w; qdot] of the module docstring."""

_mass_and_bias = batched(_mass_and_bias_minor, 2)


def mass_and_bias(robot: TreeRobot, q: jax.Array, nu: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(H (..., 6 + n, 6 + n), c (..., 6 + n))`` at joints ``q (..., n)`` and velocity
    ``nu (..., 6 + n)`` (the module docstring's coordinates), from one pass (c by Newton-Euler)."""
    q, nu = jnp.asarray(q), jnp.asarray(nu)
    batch = jnp.broadcast_shapes(q.shape[:-1], nu.shape[:-1])
    q, nu = jnp.broadcast_to(q, batch + q.shape[-1:]), jnp.broadcast_to(nu, batch + nu.shape[-1:])
    stacked = _mass_and_bias(robot, jnp.concatenate([q, nu], axis=-1))
    return stacked[..., :-1], stacked[..., -1]


tip_maps = batched(_tip_maps_minor, 3)
tip_maps.__doc__ = """``(..., k, 6, 6 + n)`` J: the twist [v; w] of every tip origin per [v; w; qdot], bus axes.

The first six columns move the tip with the bus (v + w x (tip - bus centroid), w); the
others are the fixed-base Jacobian. G = J H^-1 J^T is Yoshida's extended inversed inertia."""


_free_forward = batched(_free_forward_minor, 1)
_free_inverse = batched(_free_inverse_minor, 1)


def free_dynamics(robot: TreeRobot, q, qd, load, momentum, moving=None, forward: bool = True) -> jax.Array:
    """The bus free (no wrench), at joints ``q``, rates ``qd`` (``(..., n)`` each) and the system
    momentum ``momentum (..., 6)`` [P; L about the system centroid], BUS axes: for torques
    ``load`` (``forward``) ``(..., 6 + n)`` [v; w; qdd], the bus twist (bus axes) and the joint
    accelerations; else ``(..., n)`` the torques for accelerations ``load``. ``moving`` ``(n,)``
    (default all ones) marks the joints that move; the held ones' rates must be zero, and the
    forward solve keeps them still (their torques are what holds them).

    One pass and closed forms per posture: H* qdd + c* = tau with H_b^-1 through the system
    centroid and H* by an unrolled Cholesky factorization (`_free_minor`)."""
    moving = jnp.ones(jnp.shape(q)[-1:], jnp.result_type(q)) if moving is None else moving
    arrays = [jnp.asarray(a) for a in (q, qd, load, momentum, moving)]
    batch = jnp.broadcast_shapes(*[a.shape[:-1] for a in arrays])
    stacked = jnp.concatenate([jnp.broadcast_to(a, batch + a.shape[-1:]) for a in arrays], axis=-1)
    return (_free_forward if forward else _free_inverse)(robot, stacked)


def tip_axes(robot: TreeRobot, q: jax.Array) -> jax.Array:
    """``(..., k, 3, 3)`` every tip frame's axes in bus axes at postures ``q`` ``(..., n)``."""
    return jnp.vectorize(lambda posture: tip_frames(robot, posture)[1], signature="(n)->(k,i,j)")(q)
