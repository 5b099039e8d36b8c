"""A URDF reader on the standard library's XML parser: the serial arm from a root link to a tip.

No mesh library: geometry (``<visual>``, ``<collision>``) is ignored. The reader keeps
the tree, joint types, origins, axes and limits, and each link's ``<inertial>``. Only
the direct ``<link>`` and ``<joint>`` children of ``<robot>`` count (``<joint>`` names
repeated inside ``<transmission>`` blocks are not joints).

The arm is the kinematic path from ``root_link`` to ``tip``. Its movable joints
(revolute, continuous, prismatic) become the arm joints, in path order. Everything
else below ``root_link`` is merged rigidly into the body it hangs from: fixed joints,
and movable joints named in ``lock_joints`` (held at the given value), on the path or
in side branches (a camera, fingers). Merging composes the transforms and sums the
spatial inertias. Links above ``root_link`` (a ``world`` link, a mobile base) are
dropped, unchecked. The ``tip`` is a link; its origin is the tip point and its axes the
tip frame. A lock value must lie within the joint's limits; ``lock_others`` holds every
movable joint off the path at 0 (or its nearest limit; a ``<mimic>`` follower of a locked
joint where its leader puts it), and without it one message names every movable joint
off the path that is not locked. A ``<mimic>`` joint on the path moves on its own.

The pieces (`parse_document`, `rigid_closure`, `checked_bodies`, `merge_links`,
`joint_and_body_fields`, `check_link`, `check_lock_joints`, `movable_off`) also serve the
tree reader, `spacearm.models.tree.urdf`.

Inertias as written (checked for the links kept, not the dropped ones): a link without
``<inertial>`` has zero mass and zero inertia. A link with mass 0 is taken as written,
inertia included, as Pinocchio does (vendor files often give the base link mass 0,
sometimes with a non-zero inertia). A link with a positive mass needs a
positive-definite inertia that satisfies the triangle inequality (each principal
moment at most the sum of the other two, what a physical body has);
``inertia_as_written=True`` skips the triangle inequality and accepts zero principal
moments, as Pinocchio does (MuJoCo refuses such files unless told to balance the
inertia). Negative masses and negative principal moments are always refused.

Every problem raises `ConfigError` with one message naming the
file and the link, joint or attribute.
"""

from __future__ import annotations

import collections
import dataclasses
import math
import os
import xml.etree.ElementTree as ET
from collections.abc import Mapping

import numpy as np

from ..._core.errors import ConfigError
from ..._core.groups import rpy_matrix
from ..._core.schema import MAX_MAGNITUDE, did_you_mean, quote, read_regular_file

__all__ = [
    "ArmChain",
    "UrdfDocument",
    "check_inertia",
    "check_kinds",
    "check_link",
    "check_lock_joints",
    "checked_bodies",
    "held_value",
    "hold_others",
    "joint_and_body_fields",
    "merge_links",
    "movable_off",
    "parse_document",
    "parse_urdf",
    "read_urdf",
    "read_urdf_text",
    "rigid_closure",
    "side_branches",
    "unlocked_message",
]

MOVABLE = ("revolute", "continuous", "prismatic")
_KNOWN_TYPES = MOVABLE + ("fixed", "floating", "planar")
# Relative tolerance for the symmetric-positive and triangle checks (URDF numbers are
# printed with a few digits; a body that is a thin rod sits on the triangle's edge).
_INERTIA_RTOL = 1e-9
# Bounds on what is read (so a hostile file cannot make the reader, or a run, blow up).
MAX_URDF_BYTES = 8 * 2**20
MAX_ARM_JOINTS = 64


@dataclasses.dataclass(frozen=True)
class ArmChain:
    """The arm read from a URDF, with fixed and locked parts merged (numpy, float64).

    Body 0 is the root body (``root_link`` and everything rigidly attached to it);
    body i (1..n) is the child link of arm joint i with its rigid attachments. Each
    body's frame is its URDF link frame (the child frame of its joint).

    Attributes:
        source: the URDF path (for messages).
        root_link, tip: link names.
        joint_names: ``n`` arm joint names in path order.
        joint_kinds: ``n`` of ``"revolute"`` or ``"prismatic"`` (continuous joints are
            revolute with free limits).
        urdf_types: ``n`` URDF joint types as written (``"continuous"`` kept).
        joint_rotation: ``(n, 3, 3)`` joint frame axes in the parent body frame.
        joint_translation: ``(n, 3)`` joint frame origin in the parent body frame, m.
        joint_axis: ``(n, 3)`` unit axis in the joint frame.
        joint_lower, joint_upper: ``(n,)`` limits, rad or m (``-inf``/``+inf`` when free).
        body_mass: ``(n+1,)`` kg.
        body_com: ``(n+1, 3)`` centroid in the body frame, m.
        body_inertia: ``(n+1, 3, 3)`` about the centroid, body axes, kg m^2.
        body_links: the URDF links merged into each body.
        tip_rotation: ``(3, 3)`` tip frame axes in the last body frame.
        tip_translation: ``(3,)`` tip origin in the last body frame, m.
    """

    source: str
    root_link: str
    tip: str
    joint_names: tuple[str, ...]
    joint_kinds: tuple[str, ...]
    urdf_types: tuple[str, ...]
    joint_rotation: np.ndarray
    joint_translation: np.ndarray
    joint_axis: np.ndarray
    joint_lower: np.ndarray
    joint_upper: np.ndarray
    body_mass: np.ndarray
    body_com: np.ndarray
    body_inertia: np.ndarray
    body_links: tuple[tuple[str, ...], ...]
    tip_rotation: np.ndarray
    tip_translation: np.ndarray

    @property
    def n_joints(self) -> int:
        return len(self.joint_names)


# Small rigid-body helpers (numpy) ------------------------------------------------------


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def _second_moment(vector: np.ndarray) -> np.ndarray:
    """S(c) = |c|^2 1 - c c^T: the inertia of a unit point mass at c about the origin."""
    return float(vector @ vector) * np.eye(3) - np.outer(vector, vector)


def check_inertia(where: str, inertia: np.ndarray, *, positive: bool, triangle: bool) -> None:
    """Refuse a 3x3 inertia that is not symmetric, not (semi)definite, or breaks the triangle inequality.

    Args:
        where: the message prefix naming the file and the field.
        positive: require positive definite (else positive semidefinite).
        triangle: require each principal moment <= the sum of the other two.
    """
    inertia = np.asarray(inertia, dtype=float)
    if inertia.shape != (3, 3):
        raise ConfigError(f"{where}: must be a 3x3 matrix, got shape {inertia.shape}")
    if not np.all(np.isfinite(inertia)):
        raise ConfigError(f"{where}: must be finite numbers, got {inertia.tolist()}")
    scale = max(float(np.max(np.abs(inertia))), 1e-300)
    if np.max(np.abs(inertia - inertia.T)) > _INERTIA_RTOL * scale:
        raise ConfigError(f"{where}: must be symmetric, got {inertia.tolist()}")
    moments = np.linalg.eigvalsh(0.5 * (inertia + inertia.T))
    shown = ", ".join(f"{m:.6g}" for m in moments)
    if positive and moments[0] <= _INERTIA_RTOL * scale:
        raise ConfigError(f"{where}: must be positive definite; principal moments {shown}")
    if moments[0] < -_INERTIA_RTOL * scale:
        raise ConfigError(f"{where}: must be positive semidefinite; principal moments {shown}")
    if triangle and moments[2] > moments[0] + moments[1] + _INERTIA_RTOL * scale:
        raise ConfigError(
            f"{where}: violates the triangle inequality (largest principal moment above the sum "
            f"of the other two); principal moments {shown}"
        )


# Parsing ---------------------------------------------------------------------------------


@dataclasses.dataclass
class _Link:
    name: str
    mass: float
    com: np.ndarray  # in the link frame
    inertia: np.ndarray  # about the com, link axes
    tensor: np.ndarray  # the <inertia> as written (inertial frame), for the checks


@dataclasses.dataclass
class _Joint:
    name: str
    kind: str
    parent: str
    child: str
    rotation: np.ndarray
    translation: np.ndarray
    axis: np.ndarray
    lower: float
    upper: float
    # URDF <mimic>: (leader joint, multiplier, offset), or None.
    mimic: tuple[str, float, float] | None = None


def _floats(where: str, text: str | None, count: int, default=None) -> np.ndarray:
    if text is None:
        if default is None:
            raise ConfigError(f"{where}: missing")
        return np.array(default, dtype=float)
    parts = text.split()
    try:
        values = np.array([float(p) for p in parts])
    except ValueError:
        raise ConfigError(f"{where}: expected {count} numbers, got {quote(text)}") from None
    if values.shape != (count,):
        raise ConfigError(f"{where}: expected {count} numbers, got {quote(text)}")
    if not np.all(np.isfinite(values)):
        raise ConfigError(f"{where}: must be finite numbers, got {quote(text)}")
    if np.any(np.abs(values) > MAX_MAGNITUDE):
        raise ConfigError(f"{where}: numbers must be at most {MAX_MAGNITUDE:g} in magnitude, got {quote(text)}")
    return values


def _origin(where: str, element) -> tuple[np.ndarray, np.ndarray]:
    origin = element.find("origin")
    if origin is None:
        return np.eye(3), np.zeros(3)
    xyz = _floats(f"{where}origin xyz", origin.get("xyz"), 3, default=(0.0, 0.0, 0.0))
    rpy = _floats(f"{where}origin rpy", origin.get("rpy"), 3, default=(0.0, 0.0, 0.0))
    return rpy_matrix(rpy), xyz


def _read_link(source: str, element) -> _Link:
    """Read a link's ``<inertial>`` (numbers only; `check_link` checks the physics of kept links)."""
    name = element.get("name")
    where = f"{source}: link '{name}': "
    inertial = element.find("inertial")
    if inertial is None:
        return _Link(name, 0.0, np.zeros(3), np.zeros((3, 3)), np.zeros((3, 3)))
    rotation, com = _origin(f"{where}inertial ", inertial)
    mass_element = inertial.find("mass")
    mass = 0.0
    if mass_element is not None:
        mass = float(_floats(f"{where}inertial mass value", mass_element.get("value"), 1)[0])
    tensor = np.zeros((3, 3))
    inertia_element = inertial.find("inertia")
    if inertia_element is not None:
        values = {}
        for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
            text = inertia_element.get(key, "0")
            values[key] = float(_floats(f"{where}inertial inertia {key}", text, 1)[0])
        tensor = np.array(
            [
                [values["ixx"], values["ixy"], values["ixz"]],
                [values["ixy"], values["iyy"], values["iyz"]],
                [values["ixz"], values["iyz"], values["izz"]],
            ]
        )
    return _Link(name, mass, com, rotation @ tensor @ rotation.T, tensor)


def check_link(source: str, link: _Link, inertia_as_written: bool, switch: str = "arm.inertia_as_written") -> None:
    """Refuse a kept link's negative mass or unphysical inertia (see the module docstring).

    Only links that end up in the robot are checked: links above the root (a ``world``
    link, an antenna on a mobile base) are dropped unchecked.

    Args:
        switch: the robot-file key that takes inertias as written, named in the message.
    """
    where = f"{source}: link '{link.name}': "
    if link.mass < 0:
        raise ConfigError(f"{where}inertial mass: must not be negative, got {link.mass!r}")
    # Zero mass: taken as written (inertia included), as Pinocchio does.
    try:
        check_inertia(
            f"{where}inertial inertia",
            link.tensor,
            positive=link.mass > 0 and not inertia_as_written,
            triangle=not inertia_as_written,
        )
    except ConfigError as error:
        if inertia_as_written or "semidefinite" in str(error):
            raise
        # A vendor file's zero or unphysical inertia: name the switch that takes it as written.
        raise ConfigError(f"{error} ({switch}: true takes it as written)") from None


def _read_joint(source: str, element, links: Mapping[str, _Link]) -> _Joint:
    name = element.get("name")
    where = f"{source}: joint '{name}': "
    kind = element.get("type")
    if kind not in _KNOWN_TYPES:
        extra = did_you_mean(str(kind), _KNOWN_TYPES)
        raise ConfigError(f"{where}unknown type {kind!r}{extra}")
    ends = {}
    for end in ("parent", "child"):
        tag = element.find(end)
        link = tag.get("link") if tag is not None else None
        if link is None:
            raise ConfigError(f"{where}{end}: missing <{end} link=...>")
        if link not in links:
            extra = did_you_mean(link, list(links))
            raise ConfigError(f"{where}{end} link '{link}' is not defined{extra}")
        ends[end] = link
    rotation, translation = _origin(where, element)
    axis = np.array([1.0, 0.0, 0.0])
    if kind in MOVABLE:
        axis_element = element.find("axis")
        if axis_element is not None:
            axis = _floats(f"{where}axis xyz", axis_element.get("xyz"), 3, default=(1.0, 0.0, 0.0))
        norm = float(np.linalg.norm(axis))
        if norm == 0.0:
            raise ConfigError(f"{where}axis xyz: must not be zero")
        axis = axis / norm
    lower, upper = -math.inf, math.inf
    if kind in ("revolute", "prismatic"):
        limit = element.find("limit")
        if limit is not None:
            lower = float(_floats(f"{where}limit lower", limit.get("lower", "0"), 1)[0])
            upper = float(_floats(f"{where}limit upper", limit.get("upper", "0"), 1)[0])
            if lower > upper:
                raise ConfigError(f"{where}limit: lower {lower} is above upper {upper}")
            if lower == upper:  # URDF's default 0, 0: no usable range given; treat as free
                lower, upper = -math.inf, math.inf
    mimic = None
    mimic_element = element.find("mimic") if kind in MOVABLE else None
    if mimic_element is not None and mimic_element.get("joint"):
        multiplier = float(_floats(f"{where}mimic multiplier", mimic_element.get("multiplier", "1"), 1)[0])
        offset = float(_floats(f"{where}mimic offset", mimic_element.get("offset", "0"), 1)[0])
        mimic = (mimic_element.get("joint"), multiplier, offset)
    return _Joint(name, kind, ends["parent"], ends["child"], rotation, translation, axis, lower, upper, mimic)


def _joint_motion(joint: _Joint, value: float) -> tuple[np.ndarray, np.ndarray]:
    """The joint's own motion at a fixed value, in the joint frame."""
    if joint.kind == "prismatic":
        return np.eye(3), joint.axis * value
    if joint.kind == "fixed":
        return np.eye(3), np.zeros(3)
    return _axis_angle(joint.axis, value), np.zeros(3)


def _check_tree(
    source: str, links: Mapping[str, _Link], parent_joint: Mapping[str, _Joint], root_link: str | None
) -> dict[str, str]:
    """Refuse joints that form a cycle (naming them) and links in a second, unconnected tree
    (naming the orphan links); return each link's top link (the URDF's one root)."""
    top: dict[str, str] = {}
    for start in links:
        trail: list[str] = []
        on_trail: set[str] = set()
        link = start
        while link not in top and link in parent_joint:
            if link in on_trail:
                cycle = trail[trail.index(link) :]
                names = ", ".join(sorted(f"'{parent_joint[name].name}'" for name in cycle))
                raise ConfigError(f"{source}: joints {names} form a cycle (a URDF is a tree)")
            trail.append(link)
            on_trail.add(link)
            link = parent_joint[link].parent
        root = top.get(link, link)
        for name in trail + [link]:
            top[name] = root
    sizes = collections.Counter(top.values())
    if len(sizes) > 1:
        main = top.get(root_link) or sizes.most_common(1)[0][0]
        roots = [main] + sorted(r for r in sizes if r != main)
        orphans = sorted(name for name, root in top.items() if root != main)
        shown = ", ".join(f"'{name}'" for name in orphans[:8]) + (
            f" and {len(orphans) - 8} more" if len(orphans) > 8 else ""
        )
        raise ConfigError(
            f"{source}: links {shown} are not connected to the tree of '{roots[0]}' "
            f"(a URDF has one root link; {len(roots)} found: {', '.join(repr(r) for r in roots[:8])})"
        )
    return top


@dataclasses.dataclass(frozen=True)
class UrdfDocument:
    """A parsed URDF: links (numbers as written, unchecked), joints and the tree's index.

    Attributes:
        source: the URDF path (for messages).
        links: link name -> link, in file order.
        joints: joint name -> joint, in file order (only ``<robot>``'s direct children).
        children: link name -> the joints that hang from it, in file order.
        parent_joint: link name -> the joint it hangs from (the top link has none).
    """

    source: str
    links: dict[str, _Link]
    joints: dict[str, _Joint]
    children: dict[str, list[_Joint]]
    parent_joint: dict[str, _Joint]

    def path(self, top: str, link: str) -> list[_Joint] | None:
        """The joints from ``top`` down to ``link`` (top first), or None when ``link`` is not below ``top``."""
        path: list[_Joint] = []
        while link != top:
            if link not in self.parent_joint:
                return None
            joint = self.parent_joint[link]
            path.append(joint)
            link = joint.parent
        return path[::-1]

    def subtree_joints(self, top: str) -> list[_Joint]:
        """Every joint below link ``top``, in file order."""
        below: set[str] = set()
        stack = [top]
        while stack:
            for joint in self.children[stack.pop()]:
                below.add(joint.name)
                stack.append(joint.child)
        return [joint for name, joint in self.joints.items() if name in below]


def parse_document(text: str, *, source: str = "urdf", root_link: str | None = None) -> UrdfDocument:
    """Parse URDF text into links and joints, refusing malformed XML, unknown types, undefined
    links, cycles and unconnected trees. Link inertias are read, not checked (`check_link`).

    Args:
        root_link: the link the caller starts from (it names the main tree in a message
            about unconnected links).
    """
    if len(text) > MAX_URDF_BYTES:
        raise ConfigError(f"{source}: the URDF is {len(text):,} characters; at most {MAX_URDF_BYTES:,} are read")
    try:
        root = ET.fromstring(text)
    except ET.ParseError as error:
        line, column = error.position
        message = str(error).split(":")[0]
        raise ConfigError(f"{source}: malformed XML at line {line}, column {column + 1}: {message}") from None
    if root.tag != "robot":
        raise ConfigError(f"{source}: the root element must be <robot>, got <{root.tag}>")

    links: dict[str, _Link] = {}
    for element in root.findall("link"):
        name = element.get("name")
        if not name:
            raise ConfigError(f"{source}: a <link> has no name")
        if name in links:
            raise ConfigError(f"{source}: link '{name}' is defined twice")
        links[name] = _read_link(source, element)
    joints: dict[str, _Joint] = {}
    children: dict[str, list[_Joint]] = {name: [] for name in links}
    parent_joint: dict[str, _Joint] = {}
    for element in root.findall("joint"):
        name = element.get("name")
        if not name:
            raise ConfigError(f"{source}: a <joint> has no name")
        if name in joints:
            raise ConfigError(f"{source}: joint '{name}' is defined twice")
        joint = _read_joint(source, element, links)
        if joint.child in parent_joint:
            raise ConfigError(
                f"{source}: joint '{name}': link '{joint.child}' already has parent joint "
                f"'{parent_joint[joint.child].name}' (a URDF is a tree)"
            )
        joints[name] = joint
        parent_joint[joint.child] = joint
        children[joint.parent].append(joint)
    _check_tree(source, links, parent_joint, root_link)
    return UrdfDocument(source, links, joints, children, parent_joint)


def check_lock_joints(document: UrdfDocument, lock_joints: Mapping[str, float], where: str) -> None:
    """Refuse unknown, fixed or non-numeric entries of ``lock_joints``, and values outside a
    joint's limits (naming the joint, the value and the limits). ``where`` prefixes messages."""
    joints = document.joints
    for name, value in lock_joints.items():
        if name not in joints:
            extra = did_you_mean(str(name), list(joints))
            raise ConfigError(f"{where}unknown joint {quote(name)}{extra}")
        joint = joints[name]
        if joint.kind == "fixed":
            raise ConfigError(f"{where}joint '{name}' is fixed already; only movable joints are locked")
        if joint.kind not in MOVABLE:
            raise ConfigError(f"{where}joint '{name}' is {joint.kind}; only movable joints are locked")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ConfigError(f"{where}joint '{name}': the value must be a finite number, got {quote(value)}")
        if not joint.lower <= value <= joint.upper:
            unit = "m" if joint.kind == "prismatic" else "rad"
            raise ConfigError(
                f"{where}joint '{name}': the value {value:g} is outside its limits "
                f"[{joint.lower:g}, {joint.upper:g}] {unit}"
            )


def held_value(joint: _Joint, locked: Mapping[str, float] | None = None) -> float:
    """Where ``lock_others`` holds a joint: 0, or the nearest limit when 0 is outside them.

    A URDF ``<mimic>`` follower of a joint in ``locked`` (a gripper's second finger) is held
    where its leader puts it, ``multiplier * leader + offset``, clipped to its limits.
    """
    value = 0.0
    if joint.mimic is not None and locked is not None and joint.mimic[0] in locked:
        leader, multiplier, offset = joint.mimic
        value = multiplier * float(locked[leader]) + offset
    return float(min(max(value, joint.lower), joint.upper))


def hold_others(joints: list[_Joint], locked: Mapping[str, float]) -> dict[str, float]:
    """Where ``lock_others`` holds ``joints`` (see `held_value`): mimic followers after their leaders."""
    held = {j.name: held_value(j) for j in joints if j.mimic is None}
    every = {**locked, **held}
    for joint in joints:
        if joint.mimic is not None:
            held[joint.name] = every[joint.name] = held_value(joint, every)
    return held


def check_kinds(document: UrdfDocument, joints: list[_Joint]) -> None:
    """Refuse a floating or planar joint among the kept ones (below the root): the bus is the
    only free body. Above the root they are dropped with their links (a ``world`` link's
    floating joint)."""
    for joint in joints:
        if joint.kind in ("floating", "planar"):
            raise ConfigError(
                f"{document.source}: joint '{joint.name}': type '{joint.kind}' is not supported (the bus is "
                "the only free body; arm joints are revolute, continuous, prismatic or fixed)"
            )


def unlocked_message(source: str, joints: list[_Joint], where: str, keys: str) -> str:
    """One message naming every movable joint that is not locked off the kept paths.

    Args:
        where: the paths, ``"off the path from 'a' to 'b'"``.
        keys: the robot-file section whose ``lock_joints`` and ``lock_others`` the advice names.
    """
    shown = ", ".join(f"'{j.name}' ({j.kind})" for j in joints)
    example = ", ".join(f"{j.name}: {held_value(j):g}" for j in joints[:2])
    others = (
        f", or set {keys}lock_others: true to hold each at 0 (or its nearest limit), or {keys}drop_others: "
        "true to leave out each with everything below it"
    )
    if len(joints) == 1:
        return (
            f"{source}: joint {shown} is {where} and not locked; add it to "
            f"{keys}lock_joints (e.g. {{{example}}}) to hold it fixed{others}"
        )
    return (
        f"{source}: {len(joints)} joints are {where} and not locked: {shown}; add them to "
        f"{keys}lock_joints (e.g. {{{example}{', ...' if len(joints) > 2 else ''}}}) to hold them fixed{others}"
    )


def side_branches(
    source: str, others: list[_Joint], locks: Mapping[str, float], *, hold: bool, drop: bool, where: str, keys: str
) -> tuple[dict[str, float], set[str]]:
    """What becomes of the movable joints ``others`` off the kept paths: held (``hold``,
    `hold_others`: their links merge into the bodies), dropped with everything below them
    (``drop``: their mass leaves the model), or refused naming them.

    Returns:
        The joints to hold with their values, and the joints that cut the bodies off.
    """
    if hold and drop:
        raise ConfigError(f"{source}: give {keys}lock_others or {keys}drop_others, not both")
    if others and not (hold or drop):
        raise ConfigError(unlocked_message(source, others, where, keys))
    if drop:
        return {}, {joint.name for joint in others}
    return hold_others(others, locks), set()


Pose = tuple[str, np.ndarray, np.ndarray]


def rigid_closure(document: UrdfDocument, start: str, cut: set[str], locks: Mapping[str, float]) -> list[Pose]:
    """The links rigidly attached to ``start``, with their poses in start's frame.

    Fixed joints are crossed, locked joints at their lock value; joints in ``cut`` (the
    kept joints) end the body. Every other movable joint must be locked by the caller.
    """
    out = [(start, np.eye(3), np.zeros(3))]
    stack = [(start, np.eye(3), np.zeros(3))]
    while stack:
        name, rotation, translation = stack.pop()
        for joint in document.children[name]:
            if joint.name in cut:
                continue
            if joint.kind in MOVABLE and joint.name not in locks:  # the callers lock them all first
                raise ConfigError(f"{document.source}: joint '{joint.name}' is neither kept nor locked")
            motion_r, motion_t = _joint_motion(joint, float(locks.get(joint.name, 0.0)))
            r = rotation @ joint.rotation
            t = translation + rotation @ joint.translation
            r, t = r @ motion_r, t + r @ motion_t
            out.append((joint.child, r, t))
            stack.append((joint.child, r, t))
    return out


def merge_links(document: UrdfDocument, body: list[Pose]) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, centroid (body frame) and inertia about the centroid (body axes) of rigidly joined links."""
    mass, moment, about_origin = 0.0, np.zeros(3), np.zeros((3, 3))
    for name, r, t in body:
        link = document.links[name]
        com = t + r @ link.com
        mass += link.mass
        moment += link.mass * com
        about_origin += r @ link.inertia @ r.T + link.mass * _second_moment(com)
    com = moment / mass if mass > 0 else np.zeros(3)
    inertia = about_origin - mass * _second_moment(com)
    return mass, com, 0.5 * (inertia + inertia.T)


def movable_off(joints: list[_Joint], kept: set[str], locks: Mapping[str, float]) -> list[_Joint]:
    """The movable joints of ``joints`` neither kept nor locked: the side branches to settle."""
    return [joint for joint in joints if joint.kind in MOVABLE and joint.name not in kept and joint.name not in locks]


def checked_bodies(
    document: UrdfDocument,
    starts: list[str],
    cut: set[str],
    locks: Mapping[str, float],
    inertia_as_written: bool,
    keys: str,
) -> list[list[Pose]]:
    """The rigid body of each start link (`rigid_closure`), every link in it checked (`check_link`)."""
    bodies = [rigid_closure(document, start, cut, locks) for start in starts]
    for body in bodies:
        for name, _, _ in body:
            check_link(document.source, document.links[name], inertia_as_written, f"{keys}inertia_as_written")
    return bodies


def joint_and_body_fields(document: UrdfDocument, joints: list[_Joint], bodies: list[list[Pose]]) -> dict:
    """The fields an `ArmChain` and a tree share: the joints' names, kinds, axes and limits, and
    each body's links merged (`merge_links`)."""
    merged = [merge_links(document, body) for body in bodies]
    return dict(
        joint_names=tuple(j.name for j in joints),
        joint_kinds=tuple("prismatic" if j.kind == "prismatic" else "revolute" for j in joints),
        urdf_types=tuple(j.kind for j in joints),
        joint_axis=np.array([j.axis for j in joints]),
        joint_lower=np.array([j.lower for j in joints]),
        joint_upper=np.array([j.upper for j in joints]),
        body_mass=np.array([m for m, _, _ in merged]),
        body_com=np.array([c for _, c, _ in merged]),
        body_inertia=np.array([i for _, _, i in merged]),
        body_links=tuple(tuple(name for name, _, _ in body) for body in bodies),
    )


def parse_urdf(
    text: str,
    *,
    source: str = "urdf",
    root_link: str,
    tip: str,
    lock_joints: Mapping[str, float] | None = None,
    inertia_as_written: bool = False,
    fields: str | None = None,
    lock_others: bool = False,
    keys: str = "arm.",
    drop_others: bool = False,
) -> ArmChain:
    """Read the arm from URDF text. See the module docstring for the rules.

    Args:
        text: the URDF XML.
        source: a label for messages (the file path).
        root_link: the link the arm starts from (fixed to the bus at the mount).
        tip: the link whose origin is the tip point.
        lock_joints: movable joints held fixed, name -> value (rad or m), within the joint's limits.
        inertia_as_written: skip the triangle inequality and accept zero principal moments.
        fields: where ``root_link``, ``tip`` and ``lock_joints`` were given (``"robot.yaml: arm."``):
            problems with them name that file and field, and the URDF after it.
        lock_others: hold every movable joint off the root-to-tip path (and not in
            ``lock_joints``) at 0, or at its nearest limit when 0 is outside them.
        keys: the robot-file section named in advice (``"arm."``, ``"arms[1]."``).
        drop_others: leave out every movable joint off the path (and not in
            ``lock_joints``) with everything below it: "just the arm" of a larger robot.

    Raises:
        ConfigError: naming the file and the link, joint or attribute.
    """
    lock_joints = dict(lock_joints or {})

    def field(name: str) -> str:
        """The prefix of a message about the root_link, tip or lock_joints field."""
        return f"{fields}{name}: (in {source}) " if fields else f"{source}: {name}: "

    document = parse_document(text, source=source, root_link=root_link)
    check_lock_joints(document, lock_joints, field("lock_joints"))
    path = _arm_path(document, root_link, tip, field)
    below = document.subtree_joints(root_link)
    check_kinds(document, below)
    arm = _arm_joints(source, path, lock_joints, root_link=root_link, tip=tip, keys=keys)
    arm_names = {j.name for j in arm}
    where = f"off the path from '{root_link}' to '{tip}'"
    held, dropped = side_branches(
        source,
        movable_off(below, arm_names, lock_joints),
        lock_joints,
        hold=lock_others,
        drop=drop_others,
        where=where,
        keys=keys,
    )
    lock_joints.update(held)

    starts = [root_link] + [j.child for j in arm]
    bodies = checked_bodies(document, starts, arm_names | dropped, lock_joints, inertia_as_written, keys)
    joint_rotation, joint_translation, tip_rotation, tip_translation = _arm_frames(source, arm, bodies, tip)
    return ArmChain(
        source=source,
        root_link=root_link,
        tip=tip,
        joint_rotation=joint_rotation,
        joint_translation=joint_translation,
        tip_rotation=tip_rotation,
        tip_translation=tip_translation,
        **joint_and_body_fields(document, arm, bodies),
    )


def _arm_path(document: UrdfDocument, root_link: str, tip: str, field) -> list[_Joint]:
    """The joints from ``root_link`` down to ``tip``; `ConfigError` (``field(role)`` first) when
    either link is missing or the tip is not below the root."""
    for role, name in (("root_link", root_link), ("tip", tip)):
        if name not in document.links:
            extra = did_you_mean(str(name), list(document.links))
            raise ConfigError(f"{field(role)}link {quote(name)} is not in the URDF{extra}")
    path = document.path(root_link, tip)
    if path is None:
        raise ConfigError(f"{field('tip')}link '{tip}' is not below root_link '{root_link}'")
    return path


def _arm_joints(
    source: str, path: list[_Joint], locks: Mapping[str, float], *, root_link: str, tip: str, keys: str
) -> list[_Joint]:
    """The arm: the movable joints of ``path`` not in ``locks``, at least one and at most `MAX_ARM_JOINTS`."""
    arm = [j for j in path if j.kind in MOVABLE and j.name not in locks]
    if not arm:
        raise ConfigError(
            f"{source}: no movable joint between root_link '{root_link}' and tip '{tip}' (all fixed or locked)"
        )
    if len(arm) > MAX_ARM_JOINTS:
        raise ConfigError(
            f"{source}: the arm from '{root_link}' to '{tip}' has {len(arm)} movable joints; "
            f"at most {MAX_ARM_JOINTS} are supported (lock the others in {keys}lock_joints)"
        )
    return arm


def _arm_frames(
    source: str, arm: list[_Joint], bodies: list[list[Pose]], tip: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Joint frames ``(n, 3, 3)``, ``(n, 3)`` in their parent bodies, and the tip frame
    ``(3, 3)``, ``(3,)`` in the last body."""
    pose_in_body = [{name: (r, t) for name, r, t in body} for body in bodies]
    n = len(arm)
    joint_rotation = np.zeros((n, 3, 3))
    joint_translation = np.zeros((n, 3))
    for i, joint in enumerate(arm):
        r, t = pose_in_body[i][joint.parent]
        joint_rotation[i] = r @ joint.rotation
        joint_translation[i] = t + r @ joint.translation
    if tip not in pose_in_body[n]:  # cannot happen: the tip is on the path below the last arm joint
        raise ConfigError(f"{source}: tip: link '{tip}' is not rigidly attached to the last arm joint")
    tip_rotation, tip_translation = pose_in_body[n][tip]
    return joint_rotation, joint_translation, tip_rotation, tip_translation


def read_urdf_text(path: str) -> str:
    """A URDF file's text (a regular file of at most `MAX_URDF_BYTES`); `ConfigError` when unreadable."""
    data = read_regular_file(path, what="URDF file", limit=MAX_URDF_BYTES)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: cannot read the URDF file (not UTF-8 text)") from None


def read_urdf(
    path: str | os.PathLike,
    *,
    root_link: str,
    tip: str,
    lock_joints: Mapping[str, float] | None = None,
    inertia_as_written: bool = False,
    fields: str | None = None,
    lock_others: bool = False,
    keys: str = "arm.",
    drop_others: bool = False,
) -> ArmChain:
    """Read the arm from a URDF file (see `parse_urdf`).

    Raises:
        ConfigError: for a missing or unreadable file, and as `parse_urdf`.
    """
    path = os.fspath(path)
    text = read_urdf_text(path)
    return parse_urdf(
        text,
        source=path,
        root_link=root_link,
        tip=tip,
        lock_joints=lock_joints,
        inertia_as_written=inertia_as_written,
        fields=fields,
        lock_others=lock_others,
        keys=keys,
        drop_others=drop_others,
    )
