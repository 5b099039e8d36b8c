"""A rigid payload welded to a tip: its mass properties merged into the body that carries the tip.

A grasped object that moves with the tip frame (a rigid, perfectly plastic grasp; Yoshida &
Nenchev, "Space robot impact analysis and satellite-base impulse minimization using reaction
null-space", ICRA 1995) is, for the dynamics, part of the tip's body: the combined body's mass
is the sum, its centroid the mass-weighted mean, and its inertia about that centroid the sum of
both inertias carried there by the parallel-axis theorem,

    I = I_b + m_b ([c_b - c]x^T [c_b - c]x) + I_p + m_p ([c_p - c]x^T [c_p - c]x),

all in the body's own frame. The payload is given in the TIP frame (its centroid and its
inertia about the centroid, tip axes); `payload_in_body` turns it into the body frame
through the tip's placement in that body.

Each family says where its tip lives (`spacearm.models.family.RobotFamily.with_payload`): a
spatial arm's tip is on body n, a tree's tip t on body ``tip_bodies[t]``, and a planar arm's
on link n, whose centroid must stay on the link line (`planar_payload`). The spatial and
tree merges are pure ``jnp`` on the leaves (``jit``, ``vmap`` and ``grad`` pass through).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .._core.errors import ConfigError
from .._core.groups import second_moment
from .family import family_of

__all__ = [
    "as_payload",
    "merge_rigid_bodies",
    "merged_link_fields",
    "payload_in_body",
    "planar_payload",
    "with_payload",
]


def merge_rigid_bodies(mass, com, inertia, payload_mass, payload_com, payload_inertia):
    """Two rigid bodies in one frame as one: ``(mass, centroid (..., 3), inertia about it (..., 3, 3))``.

    Args:
        mass, com, inertia: the first body (kg; its centroid, m; its inertia about its centroid).
        payload_mass, payload_com, payload_inertia: the second, in the same frame.

    Two massless bodies keep the first centroid (the combined inertia is then the sum).
    """
    mass, payload_mass = jnp.asarray(mass), jnp.asarray(payload_mass)
    com, payload_com = jnp.asarray(com), jnp.asarray(payload_com)
    total = mass + payload_mass
    positive = total > 0
    weighted = mass[..., None] * com + payload_mass[..., None] * payload_com
    centroid = jnp.where(positive[..., None], weighted / jnp.where(positive, total, 1.0)[..., None], com)
    combined = (
        jnp.asarray(inertia)
        + mass[..., None, None] * second_moment(com - centroid)
        + jnp.asarray(payload_inertia)
        + payload_mass[..., None, None] * second_moment(payload_com - centroid)
    )
    return total, centroid, 0.5 * (combined + jnp.swapaxes(combined, -1, -2))


def payload_in_body(tip_rotation, tip_translation, com, inertia):
    """A payload's centroid and inertia from tip axes to the frame of the tip's body:
    ``(t + R c, R I R^T)`` with (R, t) the tip frame's placement in that body."""
    R = jnp.asarray(tip_rotation)
    com = jnp.einsum("...ij,...j->...i", R, jnp.asarray(com))
    return jnp.asarray(tip_translation) + com, R @ jnp.asarray(inertia) @ jnp.swapaxes(R, -1, -2)


def merged_link_fields(robot, body: int, tip_rotation, tip_translation, mass, com, inertia) -> dict:
    """``link_mass``, ``link_com`` and ``link_inertia`` of a spatial arm or a tree with the payload
    (tip axes) merged into link ``body`` (static index), whose frame holds the tip at
    (``tip_rotation``, ``tip_translation``): the fields to replace."""
    dtype = jnp.result_type(jnp.asarray(robot.link_mass).dtype, float)
    mass, com, inertia = as_payload(mass, com, inertia, dtype)
    com, inertia = payload_in_body(tip_rotation, tip_translation, com, inertia)
    link_mass, link_com, link_inertia = (
        jnp.asarray(robot.link_mass),
        jnp.asarray(robot.link_com),
        jnp.asarray(robot.link_inertia),
    )
    merged = merge_rigid_bodies(
        link_mass[..., body], link_com[..., body, :], link_inertia[..., body, :, :], mass, com, inertia
    )
    return {
        "link_mass": link_mass.at[..., body].set(merged[0]),
        "link_com": link_com.at[..., body, :].set(merged[1]),
        "link_inertia": link_inertia.at[..., body, :, :].set(merged[2]),
    }


# How far across the last link (relative to the tip's distance from the joint) a planar
# payload's centroid may lie and still count as on the link line: an offset typed to a few
# digits and turned to tip axes lands micrometres off it, and dropping so small a distance
# changes the link's moment by m_p y^2, below 1e-12 of it for any real payload.
PLANAR_LINE_TOLERANCE = 1e-6


def planar_payload(robot, mass, com, inertia, tip=0):
    """A planar arm with the payload merged into link n (Umetani & Yoshida 1990's link: mass
    m, moment I about its centroid, the centroid a from the joint, the tip b beyond it).

    The tip frame's x axis runs along link n. With the payload's centroid x beyond the tip
    along it, the combined link has mass m + m_p, its centroid at
    a' = (m a + m_p (a + b + x)) / (m + m_p) from the joint, b' = a + b - a' (the tip stays
    where it was) and the moment I + m (a - a')^2 + I_p + m_p (a + b + x - a')^2. A signed
    a' or b' (the combined centroid beyond the tip, or behind the joint) is what the
    formulas of every planar kernel take; the robot file's check that refuses it is not run.

    Exact only when the payload's centroid is on the link line (its y in tip axes zero, to
    `PLANAR_LINE_TOLERANCE` of the tip's distance): a planar link has no field for a centroid
    off its line. Host numbers off it raise ConfigError; traced ones give NaN numbers.
    """
    if tip != 0:
        raise ConfigError(f"tip {tip!r}: a planar arm has one tip, 0")
    dtype = jnp.result_type(jnp.asarray(robot.link_a).dtype, float)
    mass, com, inertia = as_payload(mass, com, inertia, dtype)
    a, b = jnp.asarray(robot.link_a)[..., -1], jnp.asarray(robot.link_b)[..., -1]
    m, moment = jnp.asarray(robot.link_mass)[..., -1], jnp.asarray(robot.link_inertia)[..., -1]
    along = a + b + com[..., 0]
    off = jnp.abs(com[..., 1]) > PLANAR_LINE_TOLERANCE * (a + b + jnp.abs(com[..., 0]))
    if concrete(off) and bool(jnp.any(off)):
        raise ConfigError(
            f"payload: its centroid lies {float(jnp.max(jnp.abs(com[..., 1]))):.6g} m across the last link (tip axes); "
            "a planar link's centroid lies on its line, so only a payload centred on that line can be welded to its tip"
        )
    total = m + mass
    centroid = jnp.where(total > 0, (m * a + mass * along) / jnp.where(total > 0, total, 1.0), a)
    combined = moment + m * (a - centroid) ** 2 + inertia[..., 2, 2] + mass * (along - centroid) ** 2
    nan = jnp.asarray(jnp.nan, dtype)
    total, centroid, combined = (jnp.where(off, nan, x) for x in (total, centroid, combined))
    leaves = {
        "link_mass": jnp.asarray(robot.link_mass, dtype).at[..., -1].set(total),
        "link_inertia": jnp.asarray(robot.link_inertia, dtype).at[..., -1].set(combined),
        "link_a": jnp.asarray(robot.link_a, dtype).at[..., -1].set(centroid),
        "link_b": jnp.asarray(robot.link_b, dtype).at[..., -1].set(a + b - centroid),
    }
    values, structure = jax.tree_util.tree_flatten_with_path(robot)
    return jax.tree_util.tree_unflatten(structure, [leaves.get(path[-1].name, leaf) for path, leaf in values])


def with_payload(robot, mass, com, inertia, tip=0):
    """The same robot with a rigid payload welded to a tip (the family's `RobotFamily.with_payload`).

    Args:
        robot: a design of any family (or a batch: the payload broadcasts against its design
            axes; map other payload batches with ``jax.vmap``).
        mass: the payload's mass, kg.
        com: ``(3,)`` its centroid in the tip frame, m (planar arms also ``(2,)``: along the
            last link, and across it, which must be zero).
        inertia: ``(3, 3)`` its inertia about its centroid, tip axes, kg m^2 (planar arms also
            the moment about the plane's normal, a number).
        tip: which tip (a tree's index or name; the one tip of other robots is 0).

    Returns:
        a robot of the same type whose tip body carries the payload.

    Raises:
        ConfigError: a planar payload whose centroid is off the last link's line, or a tip
            the robot does not have.
    """
    return family_of(robot).with_payload(robot, mass, com, inertia, tip)


def as_payload(mass, com, inertia, dtype=None):
    """The payload's numbers as arrays: ``(mass, com (..., 3), inertia (..., 3, 3))`` (a 2-D
    centroid gains z = 0, a number becomes that moment about z on the diagonal, as
    `spacearm.capture` reads a planar target's)."""
    dtype = dtype or jnp.result_type(float)
    com = jnp.asarray(com, dtype)
    if com.shape[-1:] == (2,):
        com = jnp.concatenate([com, jnp.zeros(com.shape[:-1] + (1,), dtype)], axis=-1)
    inertia = jnp.asarray(inertia, dtype)
    if inertia.shape[-2:] != (3, 3):
        inertia = inertia[..., None, None] * jnp.eye(3, dtype=dtype)
    return jnp.asarray(mass, dtype), com, inertia


def concrete(*values) -> bool:
    """Whether every value is a host number (not traced): checks that raise may run."""
    return not any(isinstance(value, jax.core.Tracer) for value in jax.tree_util.tree_leaves(values))
