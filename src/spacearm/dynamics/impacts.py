"""Impulses at the tip: Yoshida's extended inversed inertia tensor and the response to an impulse.

G = J H^-1 J^T (J = [J_S, J_M] the tip map, H the system mass matrix) is the tip's twist jump
per tip impulse [linear; angular about the tip origin] (Yoshida 1994); with the joints locked
the robot is one rigid body and G = J_S H_b^-1 J_S^T.

Two design quantities read G along a unit direction u of a linear tip impulse [u; 0]:
the virtual mass 1 / (u^T G_v u) (G_v the linear block of G), the mass a target hitting the
hand along u meets (Yoshida & Nenchev 1995: the impulse of a plastic impact is
m_t m_v / (m_t + m_v) times the approach speed for a point target), and the bus angular-rate
jump per unit impulse ||dw_bus|| (rad/s per N s), the disturbance the same impact leaves on
the bus's attitude.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

from .._core.groups import hat, safe_norm
from ..models.dynamics import system_mass_matrix
from ..models.family import family_of
from ..models.payload import as_payload
from .state import DynamicState, apply, full_velocity, solve, solve_columns

__all__ = [
    "JOINT_MODES",
    "bus_rate_jump",
    "capture",
    "check_joints",
    "check_target",
    "impulse_response",
    "tip_inverse_inertia",
    "virtual_mass",
]

JOINT_MODES = ("free", "locked")


def check_joints(joints: str) -> None:
    if joints not in JOINT_MODES:
        raise ValueError(f"joints: one of {', '.join(JOINT_MODES)}, got {joints!r}")


def _response_map(system: DynamicState, joints: str):
    """``(J (*batch, [k,] 6, 6 + n), X (*batch, [k,] 6 + n, 6))``: X = H^-1 J^T (``"locked"``:
    only the bus columns, H_b^-1 J_S^T, joint rows zero), bus axes."""
    H = system.locked(system_mass_matrix(system.tree, system.q))
    J = system.tip_maps()
    per_tip = J.ndim == system.R.ndim + 1
    Jt = jnp.swapaxes(J, -1, -2)
    if per_tip:
        H = jnp.broadcast_to(H[..., None, :, :], Jt.shape[:-2] + H.shape[-2:])
    if joints == "free":
        return J, solve_columns(H, Jt)
    bus = solve_columns(H[..., :6, :6], Jt[..., :6, :])
    return J, jnp.concatenate([bus, jnp.zeros(bus.shape[:-2] + (system.n, 6), bus.dtype)], axis=-2)


@functools.partial(jax.jit, static_argnames=("joints",))
def tip_inverse_inertia(robot, q: jax.Array, base_rotation=None, joints: str = "free") -> jax.Array:
    """``(..., 6, 6)`` (trees ``(..., k, 6, 6)``; planar ``(..., 3, 3)`` over [vx, vy, w]) G =
    J H^-1 J^T of the tip frame's origin, rows [v; w], inertial axes: Yoshida's extended
    inversed inertia tensor, the tip twist jump per tip impulse [linear; angular].
    ``joints="locked"``: the whole robot as one rigid body."""
    check_joints(joints)
    system = DynamicState(robot, q, base_rotation)
    J, X = _response_map(system, joints)
    G = J @ X
    rotated = system.rotate(jnp.swapaxes(system.rotate(G), -1, -2))  # blkdiag(R, R) G blkdiag(R, R)^T
    rows = system.keep
    return rotated[..., rows[:, None], rows[None, :]]


def impulse_response(robot, q, impulse, base_rotation=None, tip=0, joints: str = "free"):
    """``(dqd (..., n), dbase (..., 6))``: the jump of the joint rates and of [v of the bus
    centroid; w of the bus] (INERTIAL axes) under an impulse [linear; angular] at the tip
    frame's origin, inertial axes (planar [px, py, angular], dbase [vx, vy, w]).

    ``tip`` indexes a tree's tips (checked here when it is a number; a robot without a tip
    axis takes 0); ``joints="locked"`` holds the joint rates (dqd = 0).
    """
    check_joints(joints)
    if not isinstance(tip, jax.core.Tracer):
        DynamicState(robot, q, base_rotation).pick_tip(None, tip)
    return _impulse_response(robot, q, impulse, base_rotation, tip, joints)


@functools.partial(jax.jit, static_argnames=("joints",))
def _impulse_response(robot, q, impulse, base_rotation, tip, joints: str):
    system = DynamicState(robot, q, base_rotation, twists={"impulse": impulse})
    _, X = _response_map(system, joints)
    X = system.pick_tip(X, tip)
    jump = apply(X, system.unrotate(system.twists["impulse"]))
    return jump[..., 6:], system.reduce(system.rotate(jump[..., :6]))


# Virtual mass and bus-rate jump ------------------------------------------------------


def _impulse_along(robot, direction) -> jax.Array:
    """The unit linear impulse [u; 0] along ``direction`` in the family's kept components
    (planar [ux, uy, 0] from a 2-vector; spatial [u; 0, 0, 0] from a 3-vector)."""
    keep = np.asarray(family_of(robot).twist_axes)
    linear = int(np.sum(keep < 3))
    u = jnp.asarray(direction)
    if u.shape[-1:] != (linear,):
        raise ValueError(f"direction: needs {linear} components (the tip's linear axes), got shape {u.shape}")
    if not jnp.issubdtype(u.dtype, jnp.floating):
        u = u.astype(float)
    if not isinstance(u, jax.core.Tracer) and np.any(np.linalg.norm(np.asarray(u), axis=-1) == 0):
        raise ValueError("direction: must not be zero")
    u = u / jnp.linalg.norm(u, axis=-1, keepdims=True)
    return jnp.concatenate([u, jnp.zeros(u.shape[:-1] + (len(keep) - linear,), u.dtype)], axis=-1)


@functools.partial(jax.jit, static_argnames=("joints",))
def _unit_response(robot, q, impulse, base_rotation, tip, joints: str):
    """``(u . tip jump, bus angular-rate jump)`` for the unit impulse ``impulse`` at the tip."""
    system = DynamicState(robot, q, base_rotation, twists={"impulse": impulse})
    J, X = _response_map(system, joints)
    X, J = system.pick_tip(X, tip), system.pick_tip(J, tip)
    jump = apply(X, system.unrotate(system.twists["impulse"]))
    along = jnp.sum(system.rotate(apply(J, jump)) * system.twists["impulse"], axis=-1)
    angular = system.reduce(system.rotate(jump[..., :6]))[..., int(np.sum(system.keep < 3)) :]
    return along, safe_norm(angular)[0]


def _checked_response(robot, q, direction, base_rotation, tip, joints):
    check_joints(joints)
    impulse = _impulse_along(robot, direction)
    if not isinstance(tip, jax.core.Tracer):
        DynamicState(robot, q, base_rotation).pick_tip(None, tip)
    return _unit_response(robot, q, impulse, base_rotation, tip, joints)


def virtual_mass(robot, q, direction, base_rotation=None, tip=0, joints: str = "free") -> jax.Array:
    """``(...)`` kg: the virtual mass 1 / (u^T G_v u) of the tip along the unit ``direction`` u
    (inertial axes, normalized here; planar robots a 2-vector in the plane), G_v the linear
    block of `tip_inverse_inertia`: the mass a point target striking the hand along u meets.
    ``joints="locked"``: the whole robot as one rigid body."""
    along, _ = _checked_response(robot, q, direction, base_rotation, tip, joints)
    return 1.0 / along


def bus_rate_jump(robot, q, direction, base_rotation=None, tip=0, joints: str = "free") -> jax.Array:
    """``(...)`` rad/s per N s: the norm of the bus angular-velocity jump under a unit linear
    impulse at the tip along ``direction`` (inertial axes, normalized; planar a 2-vector,
    the jump |dw_z|): how much one newton-second of impact at the hand turns the bus."""
    _, jump = _checked_response(robot, q, direction, base_rotation, tip, joints)
    return jump


# Capture ---------------------------------------------------------------------------------


def _target_in_bus_axes(system: DynamicState, target, dtype):
    """The target's spatial inertia at the tip origin ``(*batch, 6, 6)`` and its twist there
    ``(*batch, 6)`` [v of its point at the tip origin; w], bus axes.

    A planar target gives the in-plane parts: velocity [vx, vy, w], offset (2,) or (3,), and
    its moment about z (a scalar) or a 3x3 inertia; it moves in the plane, so only its offset's
    x, y and its moment Izz enter (the plane's motions and the others decouple)."""
    mass, offset, inertia = as_payload(target["mass"], target["offset"], target["inertia"], dtype)
    if len(system.keep) < 6:
        offset = offset.at[..., 2].set(0.0)
        inertia = inertia[..., 2, 2, None, None] * jnp.eye(3, dtype=dtype)
    Rt = jnp.swapaxes(system.R, -1, -2)
    d = apply(Rt, offset)
    inertia = Rt @ inertia @ system.R
    velocity = system.unrotate(system.embed(jnp.asarray(target["velocity"], dtype)))
    v_origin = velocity[..., :3] - jnp.cross(velocity[..., 3:], d)  # the target's point at the tip origin
    skew = hat(d)
    m = mass[..., None, None]
    eye = jnp.broadcast_to(jnp.eye(3, dtype=dtype), skew.shape)  # the batch of the postures
    top = jnp.concatenate([m * eye, -m * skew], axis=-1)
    bottom = jnp.concatenate([m * skew, inertia - m * skew @ skew], axis=-1)
    return jnp.concatenate([top, bottom], axis=-2), jnp.concatenate([v_origin, velocity[..., 3:]], axis=-1)


_TARGET_KEYS = ("mass", "inertia", "offset", "velocity")


def check_target(robot, target, batch: tuple[int, ...], *, moving: bool = True) -> None:
    """Refuse a target whose keys or trailing shapes do not fit the robot's family, naming the
    key: ``mass`` ``(...)``, ``inertia`` ``(..., 3, 3)`` (planar also Izz, one or one per state),
    ``offset`` ``(..., 3)`` (planar also 2), ``velocity`` ``(..., 6)`` (planar 3; required
    only when ``moving``: a grasp needs it, a payload does not)."""
    if not hasattr(target, "keys"):
        raise ValueError(f"target: a mapping with {', '.join(_TARGET_KEYS)}, got {type(target).__name__}")
    missing = [key for key in _TARGET_KEYS[: 4 if moving else 3] if key not in target]
    unknown = [str(key) for key in target if key not in _TARGET_KEYS]
    if missing or unknown:
        what = "; ".join(
            part
            for part in (
                f"missing {', '.join(missing)}" if missing else "",
                f"unknown {', '.join(unknown)}" if unknown else "",
            )
            if part
        )
        raise ValueError(f"target: {what} (the keys: {', '.join(_TARGET_KEYS)})")
    twist = len(family_of(robot).twist_axes)
    planar = twist == 3
    shapes = {
        "inertia": [(3, 3)],
        "offset": [(2,), (3,)] if planar else [(3,)],
        "velocity": [(twist,)],
    }
    for key, allowed in shapes.items():
        if key not in target:
            continue
        shape = np.shape(target[key])
        if planar and key == "inertia" and _broadcasts(shape, batch):
            continue  # Izz alone, or one per state
        if not any(len(shape) >= len(tail) and shape[len(shape) - len(tail) :] == tail for tail in allowed):
            wanted = " or ".join(str(tail) for tail in allowed)
            raise ValueError(f"target.{key}: expected trailing axes {wanted}, got shape {shape}")
    mass = target["mass"]
    if not isinstance(mass, jax.core.Tracer) and not np.all(np.asarray(mass) > 0):
        raise ValueError(f"target.mass: must be positive (kg), got {np.asarray(mass).tolist()}")
    if planar:
        _check_in_plane(target)


def _broadcasts(shape: tuple[int, ...], batch: tuple[int, ...]) -> bool:
    try:
        return np.broadcast_shapes(shape, batch) == batch
    except ValueError:
        return False


def _check_in_plane(target) -> None:
    """A planar robot's target moves in the plane: no offset along z, no inertia products
    with z (Ixz, Iyz), where they are concrete."""
    offset, inertia = target["offset"], target["inertia"]
    concrete = not isinstance(offset, jax.core.Tracer) and not isinstance(inertia, jax.core.Tracer)
    if concrete and np.shape(offset)[-1:] == (3,) and np.any(np.asarray(offset)[..., 2] != 0):
        raise ValueError("target.offset: a planar robot's target lies in the plane (z = 0)")
    matrix = concrete and np.shape(inertia)[-2:] == (3, 3)
    products = np.abs(np.asarray(inertia)[..., [0, 1], 2]) if matrix else 0.0
    if matrix and np.any(products > 1e-12 * np.max(np.abs(inertia))):
        raise ValueError("target.inertia: a planar robot's target turns about z alone (Ixz = Iyz = 0)")


def capture(robot, q, qd, target, base_rotation=None, momentum=None, tip=0, joints: str = "free"):
    """``(qd_after (..., n), base_after (..., 6), impulse (..., 6))``: a rigid, perfectly plastic
    grasp of a target by the tip frame (afterwards the target moves with it).

    With M_t the target's spatial inertia at the tip origin, t_t its twist there and J the tip
    map, momentum balance of the robot (H dnu = J^T F) and of the target (M_t (J nu+ - t_t) = -F)
    give (H + J^T M_t J) nu+ = H nu- + J^T M_t t_t; with the joints locked only the bus rows
    (qd unchanged, impulsive joint torques unknown). Yoshida's G enters as
    F = -(1 + M_t G)^-1 M_t (J nu- - t_t) in the free case.

    Args:
        target: a mapping (or small pytree) with ``mass`` (kg), ``inertia`` (3x3 about its
            centroid, inertial axes), ``offset`` (3,) (its centroid minus the tip frame's
            origin, inertial axes) and ``velocity`` (6,) [v of its centroid; w], inertial
            axes. Planar robots: velocity [vx, vy, w], offset (2,) or (3,), inertia Izz.
        momentum: the robot's own system momentum before the grasp, [P; L about its centroid].
        tip: which tip of a tree grasps.
        joints: ``"free"`` (no impulsive joint torque) or ``"locked"`` (joint rates unchanged).

    Returns:
        the joint rates after; [v of the bus centroid; w of the bus] after, INERTIAL axes; the
        impulse the target applies to the tip frame [linear; angular about the tip origin],
        inertial axes (planar robots: the in-plane parts).
    """
    check_joints(joints)
    check_target(robot, target, np.shape(q)[:-1])
    if not isinstance(tip, jax.core.Tracer):
        DynamicState(robot, q, base_rotation).pick_tip(None, tip)
    return _capture(robot, q, qd, dict(target), base_rotation, momentum, tip, joints)


@functools.partial(jax.jit, static_argnames=("joints",))
def _capture(robot, q, qd, target, base_rotation, momentum, tip, joints: str):
    system = DynamicState(robot, q, base_rotation, joints={"qd": qd}, momentum=momentum)
    qd = system.rates("qd")
    H = system.locked(system_mass_matrix(system.tree, system.q))
    nu = full_velocity(system, qd)
    J = system.pick_tip(system.tip_maps(), tip)
    M_t, t_t = _target_in_bus_axes(system, target, qd.dtype)
    coupled = jnp.swapaxes(J, -1, -2) @ M_t
    if joints == "free":
        after = solve(H + coupled @ J, apply(H, nu) + apply(coupled, t_t))
    else:
        J_S = J[..., :6]
        bus = solve(
            H[..., :6, :6] + coupled[..., :6, :] @ J_S,
            apply(H[..., :6, :6], nu[..., :6]) + apply(coupled[..., :6, :], t_t - apply(J[..., 6:], qd)),
        )
        after = jnp.concatenate([bus, qd], axis=-1)
    impulse = -apply(M_t, apply(J, after) - t_t)
    return after[..., 6:], system.reduce(system.rotate(after[..., :6])), system.reduce(system.rotate(impulse))
