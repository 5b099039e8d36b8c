"""A grasped target as a payload of the tip, and the momentum of a robot at a given velocity.

After a rigid, perfectly plastic grasp (`spacearm.capture`; Yoshida & Nenchev, "Space robot
impact analysis and satellite-base impulse minimization using reaction null-space", ICRA 1995)
the target moves with the tip frame: robot and target are one system whose tip body carries
the target's mass, centroid and inertia (`spacearm.models.payload.with_payload`). A capture
target is given in INERTIAL axes at the grasp (its inertia about its centroid, and its centroid
minus the tip origin); the tip body holds it in TIP axes, so with R_tip the tip frame's axes
in inertial axes at the grasp state,

    offset_tip = R_tip^T offset,    inertia_tip = R_tip^T I R_tip.

The combined system's state right after the grasp is the robot's (``base_after``,
``qd_after``); `system_momentum` gives its momentum [P; L about the system centroid] from
that velocity (H nu's bus rows, Umetani & Yoshida 1990 eq. 4-5 read forwards), which is what
`spacearm.simulate` takes.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from .._core.groups import vee
from ..models.dynamics import system_mass_matrix
from ..models.payload import as_payload, with_payload
from .impacts import check_target
from .state import DynamicState, apply

__all__ = ["grasped_robot", "system_momentum", "target_from_tip_frame", "target_in_tip_frame"]


def _tip_axes(system: DynamicState, tip: int):
    """``(*batch, 3, 3)`` the grasping tip frame's axes in INERTIAL axes (a focused tree's tip 0
    is its focus, as in `spacearm.capture`)."""
    return system.pick_tip(system.tip_axes(), tip)


def target_in_tip_frame(robot, q, target, base_rotation=None, tip: int = 0) -> dict:
    """A capture target's mass properties in the tip frame at the grasp state.

    Args:
        robot: a design of any family.
        q: the posture at the grasp (planar ``[phi0, phi1..phin]``).
        target: ``mass`` (kg), ``inertia`` (3x3 about its centroid, inertial axes; planar also
            its moment about the plane's normal, a number) and ``offset`` (its centroid minus
            the tip origin, inertial axes; planar also (2,)), as `spacearm.capture` takes them.
        base_rotation: the bus attitude (spatial robots and trees).
        tip: which of the robot's tips grasps, numbered as `spacearm.capture` numbers them (a
            tree's index; a tree focused on one tip has that tip alone, tip 0).

    Returns:
        ``{"mass", "com" (..., 3), "inertia" (..., 3, 3)}``: the centroid and the inertia about
        it in TIP axes (R_tip^T offset, R_tip^T I R_tip), what `with_payload` takes.
    """
    check_target(robot, target, np.shape(q)[:-1], moving=False)
    system = DynamicState(robot, q, base_rotation)
    mass, offset, inertia = as_payload(target["mass"], target["offset"], target["inertia"], system.q.dtype)
    R_tip = _tip_axes(system, tip)
    Rt = jnp.swapaxes(R_tip, -1, -2)
    return {"mass": mass, "com": apply(Rt, offset), "inertia": Rt @ inertia @ R_tip}


def target_from_tip_frame(robot, q, target, base_rotation=None, tip: int = 0) -> dict:
    """A target held the same way by the hand at every posture, in inertial axes: its
    ``offset`` and ``inertia`` given in TIP axes become R_tip offset and R_tip I R_tip^T
    (what `spacearm.capture` takes); ``mass`` and ``velocity`` (inertial) pass through. The
    inverse of `target_in_tip_frame`."""
    check_target(robot, target, np.shape(q)[:-1])
    system = DynamicState(robot, q, base_rotation)
    mass, offset, inertia = as_payload(target["mass"], target["offset"], target["inertia"], system.q.dtype)
    R_tip = _tip_axes(system, tip)
    inertial = {"offset": apply(R_tip, offset), "inertia": R_tip @ inertia @ jnp.swapaxes(R_tip, -1, -2)}
    return {"mass": mass, **inertial, "velocity": target["velocity"]}


def grasped_robot(robot, q, target, base_rotation=None, tip: int = 0):
    """The robot with a grasped target welded to its tip: `with_payload` of `target_in_tip_frame`.

    One grasp state per call (map several with ``jax.vmap``). A planar target must be
    centred on the last link's line (ConfigError otherwise: a planar link has no other place
    for its centroid)."""
    payload = target_in_tip_frame(robot, q, target, base_rotation, tip)
    body_tip = DynamicState(robot, q, base_rotation).tree_tip(tip)  # with_payload counts the tree's own tips
    return with_payload(robot, payload["mass"], payload["com"], payload["inertia"], body_tip)


@jax.jit
def system_momentum(robot, q, qd, base_twist, base_rotation=None):
    """``(..., 6)`` the system momentum [P; L about the system centroid], INERTIAL axes, of the
    robot moving with the bus twist ``base_twist`` and joint rates ``qd`` (planar ``(..., 3)``).

    The inverse of `spacearm.base_velocity` (which gives the bus velocity of a momentum): H's
    bus rows give [R^T P; R^T L + (g - b) x R^T P] (g - b the system centroid about the bus
    centroid, bus axes).

    Args:
        base_twist: ``(..., 6)`` [v of the bus centroid; w of the bus], INERTIAL axes, as
            `spacearm.capture` returns it (planar ``(..., 3)`` [vx, vy, w]).
    """
    system = DynamicState(robot, q, base_rotation, joints={"qd": qd}, twists={"base": base_twist})
    H = system_mass_matrix(system.tree, system.q)
    nu = jnp.concatenate([system.unrotate(system.twists["base"]), system.rates("qd")], axis=-1)
    bus = apply(H[..., :6, :], nu)
    P, L = bus[..., :3], bus[..., 3:]
    offset = vee(H[..., 3:6, 0:3]) / H[..., 0, 0, None]  # the system centroid about the bus centroid
    return system.reduce(system.rotate(jnp.concatenate([P, L - jnp.cross(offset, P)], axis=-1)))
