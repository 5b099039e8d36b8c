"""A whole system from one URDF: the bus is a chosen link, the arms are the paths to the tips.

The free-floating bus is ``base_link`` with every link rigidly attached to it (fixed or
locked joints), its inertials as written. Links above ``base_link`` (a ``world`` link,
a mobile base, its antennas) are dropped and not checked. Each tip is a link below
``base_link``; the movable joints on the paths from ``base_link`` to the tips are the
tree's joints, in this order: tip by tip in the order given, each path from the bus
outward, a joint already listed for an earlier tip not repeated. Each joint's child
link, with everything rigidly attached to it, is one body; parents come before
children. Every other movable joint below ``base_link`` must be locked, in
``lock_joints`` or all at once with ``lock_others`` (held at 0, or at the nearest
limit when 0 is outside them); without it, one message names them all.

The link, joint and inertia rules are those of the single-arm reader,
`spacearm.models.spatial.urdf`, whose pieces this module uses.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..._core.errors import ConfigError
from ..._core.schema import did_you_mean, quote
from ..spatial.urdf import (
    MOVABLE,
    Pose,
    UrdfDocument,
    check_kinds,
    check_lock_joints,
    checked_bodies,
    joint_and_body_fields,
    movable_off,
    parse_document,
    read_urdf_text,
    side_branches,
)

if TYPE_CHECKING:
    from ..spatial.urdf import _Joint

__all__ = ["MAX_TREE_JOINTS", "UrdfTree", "parse_urdf_tree", "read_urdf_tree"]

# The most movable joints a tree may keep (the arms of one system together).
MAX_TREE_JOINTS = 64  # movable joints of a tree: the reach planner's memory grows steeply with them


@dataclasses.dataclass(frozen=True)
class UrdfTree:
    """A branched system read from one URDF, fixed and locked parts merged (numpy, float64).

    Body 0 is the bus (``base_link`` and its rigid attachments), in the ``base_link``
    frame; body j + 1 is the child link of joint j with its rigid attachments, in that
    link's frame.

    Attributes:
        source: the URDF path (for messages).
        base_link: the bus link.
        tips: ``k`` tip link names.
        joint_names, joint_kinds, urdf_types: ``n`` names, ``"revolute"``/``"prismatic"``,
            the URDF types as written.
        parents: ``n`` the body joint j hangs from, as `spacearm.models.tree.TreeRobot`
            numbers it: ``-1`` for the bus, ``i >= 0`` for the child body of joint i.
        joint_rotation, joint_translation: ``(n, 3, 3)``, ``(n, 3)`` joint frames in the
            parent body's frame.
        joint_axis: ``(n, 3)`` unit axes in the joint frames.
        joint_lower, joint_upper: ``(n,)`` limits (``-inf``/``+inf`` when free).
        body_mass, body_com, body_inertia: ``(n+1,)``, ``(n+1, 3)``, ``(n+1, 3, 3)``, the bus first.
        body_links: ``n + 1`` tuples of the URDF links merged into each body.
        tip_bodies: ``k`` joint index whose child body carries each tip.
        tip_rotation, tip_translation: ``(k, 3, 3)``, ``(k, 3)`` tip frames in those bodies.
        locked: every locked joint and the value it is held at (``lock_others`` included).
    """

    source: str
    base_link: str
    tips: tuple[str, ...]
    joint_names: tuple[str, ...]
    joint_kinds: tuple[str, ...]
    urdf_types: tuple[str, ...]
    parents: tuple[int, ...]
    joint_rotation: np.ndarray
    joint_translation: np.ndarray
    joint_axis: np.ndarray
    joint_lower: np.ndarray
    joint_upper: np.ndarray
    body_mass: np.ndarray
    body_com: np.ndarray
    body_inertia: np.ndarray
    body_links: tuple[tuple[str, ...], ...]
    tip_bodies: tuple[int, ...]
    tip_rotation: np.ndarray
    tip_translation: np.ndarray
    locked: dict[str, float]

    @property
    def n_joints(self) -> int:
        return len(self.joint_names)


def parse_urdf_tree(
    text: str,
    *,
    source: str = "urdf",
    base_link: str,
    tips: Sequence[str],
    lock_joints: Mapping[str, float] | None = None,
    lock_others: bool = False,
    inertia_as_written: bool = False,
    fields: str | None = None,
    keys: str = "system.",
    drop_others: bool = False,
) -> UrdfTree:
    """Read a branched system from URDF text (see the module docstring for the rules).

    Args:
        text: the URDF XML.
        source: a label for messages (the file path).
        base_link: the bus link.
        tips: one or more tip links below ``base_link``.
        lock_joints: movable joints held fixed, name -> value within the joint's limits.
        lock_others: hold every other movable joint off the tip paths at 0 (or its nearest limit).
        inertia_as_written: skip the triangle inequality and accept zero principal moments.
        fields: where the fields were given (``"robot.yaml: system."``): messages about them
            name that file and field, and the URDF after it.
        keys: the robot-file section named in advice (``"system."``).
        drop_others: leave out every other movable joint off the tip paths with
            everything below it (their mass leaves the model).

    Raises:
        ConfigError: naming the file and the field, link or joint.
    """
    lock_joints = dict(lock_joints or {})

    def field(name: str) -> str:
        return f"{fields}{name}: (in {source}) " if fields else f"{source}: {name}: "

    document = parse_document(text, source=source, root_link=base_link)
    check_lock_joints(document, lock_joints, field("lock_joints"))
    paths = _tip_paths(document, base_link, tips, field)
    below = document.subtree_joints(base_link)
    check_kinds(document, below)
    order, kept = _joint_order(paths, lock_joints)
    _check_joint_order(source, order, kept, paths, base_link, tips, field, keys)
    where = f"off the paths from base_link '{base_link}' to the tips {', '.join(repr(t) for t in tips)}"
    held, dropped = side_branches(
        source,
        movable_off(below, kept, lock_joints),
        lock_joints,
        hold=lock_others,
        drop=drop_others,
        where=where,
        keys=keys,
    )
    lock_joints.update(held)

    starts = [base_link] + [joint.child for joint in order]
    bodies = checked_bodies(document, starts, kept | dropped, lock_joints, inertia_as_written, keys)
    frames = _tree_frames(order, tips, bodies)
    return UrdfTree(
        source=source,
        base_link=base_link,
        tips=tuple(tips),
        **frames,
        **joint_and_body_fields(document, order, bodies),
        locked=lock_joints,
    )


def _tip_paths(document: UrdfDocument, base_link: str, tips: Sequence[str], field) -> list[list[_Joint]]:
    """The joints from ``base_link`` down to each tip; `ConfigError` (``field(name)`` first) for a
    missing base or tip, no tips, a tip given twice, or a tip not below the base."""
    if base_link not in document.links:
        extra = did_you_mean(str(base_link), list(document.links))
        raise ConfigError(f"{field('base_link')}link {quote(base_link)} is not in the URDF{extra}")
    if not tips:
        raise ConfigError(f"{field('tips')}give one or more tip links")
    paths = []
    for t, tip in enumerate(tips):
        where = field(f"tips[{t}]")
        if tip not in document.links:
            extra = did_you_mean(str(tip), list(document.links))
            raise ConfigError(f"{where}link {quote(tip)} is not in the URDF{extra}")
        if tip in tips[:t]:
            raise ConfigError(f"{where}link '{tip}' is already tips[{list(tips).index(tip)}]")
        path = document.path(base_link, tip)
        if path is None:
            raise ConfigError(f"{where}link '{tip}' is not below base_link '{base_link}'")
        paths.append(path)
    return paths


def _joint_order(paths: list[list[_Joint]], locks: Mapping[str, float]) -> tuple[list[_Joint], set[str]]:
    """The tree's joints: tip by tip, each path from the bus outward, no joint twice, none
    locked; and the set of their names."""
    order = []
    kept: set[str] = set()
    for path in paths:
        for joint in path:
            if joint.kind in MOVABLE and joint.name not in locks and joint.name not in kept:
                order.append(joint)
                kept.add(joint.name)
    return order, kept


def _check_joint_order(
    source: str,
    order: list[_Joint],
    kept: set[str],
    paths: list[list[_Joint]],
    base_link: str,
    tips: Sequence[str],
    field,
    keys: str,
) -> None:
    """`ConfigError` for a tip with no movable joint on its path, or more than `MAX_TREE_JOINTS` joints."""
    for t, path in enumerate(paths):
        if not any(joint.name in kept for joint in path):
            raise ConfigError(
                f"{field(f'tips[{t}]')}no movable joint between base_link '{base_link}' and '{tips[t]}' "
                "(all fixed or locked)"
            )
    if len(order) > MAX_TREE_JOINTS:
        raise ConfigError(
            f"{source}: the paths from '{base_link}' to the tips have {len(order)} movable joints; "
            f"at most {MAX_TREE_JOINTS} are supported (lock some in {keys}lock_joints)"
        )


def _tree_frames(order: list[_Joint], tips: Sequence[str], bodies: list[list[Pose]]) -> dict:
    """The `UrdfTree` fields that place joints and tips in their bodies: ``parents``, the joint
    frames and, per tip, its body and frame."""
    # Where each kept link sits: (body index, pose in that body's frame); body 0 is the bus.
    home = {name: (b, r, t) for b, body in enumerate(bodies) for name, r, t in body}
    n = len(order)
    parents = []
    joint_rotation = np.zeros((n, 3, 3))
    joint_translation = np.zeros((n, 3))
    for j, joint in enumerate(order):
        b, r, t = home[joint.parent]
        parents.append(b - 1)
        joint_rotation[j] = r @ joint.rotation
        joint_translation[j] = t + r @ joint.translation
    tip_bodies, tip_rotation, tip_translation = [], [], []
    for tip in tips:
        b, r, t = home[tip]
        tip_bodies.append(b - 1)
        tip_rotation.append(r)
        tip_translation.append(t)
    return dict(
        parents=tuple(parents),
        joint_rotation=joint_rotation,
        joint_translation=joint_translation,
        tip_bodies=tuple(tip_bodies),
        tip_rotation=np.array(tip_rotation),
        tip_translation=np.array(tip_translation),
    )


def read_urdf_tree(path: str | os.PathLike, **options) -> UrdfTree:
    """Read a branched system from a URDF file (see `parse_urdf_tree` for the options).

    Raises:
        ConfigError: for a missing or unreadable file, and as `parse_urdf_tree`.
    """
    path = os.fspath(path)
    return parse_urdf_tree(read_urdf_text(path), source=path, **options)
