"""The tree robot design: several arms (or one branched URDF) on a free-floating bus.

A tree has n movable joints over all arms and k tips. The design is data: every
number is an array leaf of `TreeRobot`, so ``jit``, ``vmap`` and ``grad`` work over
designs and a batch of designs is the same pytree with leading axes on every leaf.
The topology is static and part of the tree structure: the joint kinds, each joint's
parent body (`parents`) and the body that carries each tip (`tip_bodies`). Labels
(names) ride along in the structure but take no part in its equality, so renaming
never recompiles.

Bodies and frames:

- the bus frame: origin anywhere, the bus centroid at ``base_com``;
- r root bodies (``root_*``, one per arm: the arm's URDF ``root_link`` with everything
  rigidly attached), each at its mount pose ``mount_xyz[r], mount_rpy[r]`` in the bus
  frame. A whole-system URDF has one root at the identity with no mass (the bus is
  the URDF's base link and its rigid attachments, folded into ``base_*``);
- body j (0..n-1), the child link frame of joint j with its rigid attachments.

``parents[j]`` is the index of the body joint j hangs from: ``i >= 0`` for body i
(always ``i < j``) or ``-1 - r`` for root r. Joint order: tip by tip in file order,
each tip's path from the bus outward, a joint already listed for an earlier tip not
repeated; so a joint's parent always comes before it.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax
import numpy as np

from ..._core.errors import ConfigError
from ..._core.groups import rpy_matrix
from ..._core.schema import did_you_mean
from ..spatial.urdf import ArmChain, check_inertia

__all__ = ["TreeLabels", "TreeRobot", "stack_tree_robots", "support_mask", "tree_from_chains", "tree_view"]

# Leaf fields in a fixed order: (name, trailing shape given n joints, r roots, k tips).
_LEAF_SHAPES = {
    "base_mass": lambda n, r, k: (),
    "base_com": lambda n, r, k: (3,),
    "base_inertia": lambda n, r, k: (3, 3),
    "mount_xyz": lambda n, r, k: (r, 3),
    "mount_rpy": lambda n, r, k: (r, 3),
    "root_mass": lambda n, r, k: (r,),
    "root_com": lambda n, r, k: (r, 3),
    "root_inertia": lambda n, r, k: (r, 3, 3),
    "joint_rotation": lambda n, r, k: (n, 3, 3),
    "joint_translation": lambda n, r, k: (n, 3),
    "joint_axis": lambda n, r, k: (n, 3),
    "link_mass": lambda n, r, k: (n,),
    "link_com": lambda n, r, k: (n, 3),
    "link_inertia": lambda n, r, k: (n, 3, 3),
    "tip_rotation": lambda n, r, k: (k, 3, 3),
    "tip_translation": lambda n, r, k: (k, 3),
    "joint_lower": lambda n, r, k: (n,),
    "joint_upper": lambda n, r, k: (n,),
}
_LEAF_FIELDS = tuple(_LEAF_SHAPES)


@dataclasses.dataclass(frozen=True)
class TreeLabels:
    """Names carried with a design; never compared, never traced.

    Attributes:
        name: the robot's name.
        joint_names: ``n`` joint names (an arm's prefix added where two arms share a URDF).
        tip_names: ``k`` tip names (the tip link, or ``arm/link`` where arms share a URDF).
        root_names: ``r`` names of the root bodies (the arm names of an ``arms:`` file).
        root_links: ``r`` tuples of the URDF links merged into each root body.
        joint_roots: ``n`` index of the root (arm) each joint belongs to.
        urdf_types: ``n`` URDF joint types as written (``"continuous"`` kept).
        body_links: ``n`` tuples of the URDF links merged into each body.
        source: where the design came from (the robot file).
    """

    name: str = "robot"
    joint_names: tuple[str, ...] = ()
    tip_names: tuple[str, ...] = ()
    root_names: tuple[str, ...] = ()
    root_links: tuple[tuple[str, ...], ...] = ()
    joint_roots: tuple[int, ...] = ()
    urdf_types: tuple[str, ...] = ()
    body_links: tuple[tuple[str, ...], ...] = ()
    source: str = ""


class _Structure:
    """The tree structure's auxiliary data: the topology and the kind of focus compare, the labels
    do not. Which tip and which joints a focus chooses are leaves (data), never part of the key."""

    __slots__ = ("focus", "joint_kinds", "labels", "parents", "tip_bodies")

    def __init__(self, joint_kinds, parents, tip_bodies, labels, focus=None):
        self.joint_kinds = joint_kinds
        self.parents = parents
        self.tip_bodies = tip_bodies
        self.labels = labels
        self.focus = focus

    def _key(self):
        return (self.joint_kinds, self.parents, self.tip_bodies, self.focus)

    def __eq__(self, other):
        return isinstance(other, _Structure) and self._key() == other._key()

    def __hash__(self):
        return hash(("TreeRobot", *self._key()))

    def __repr__(self):
        focus = "" if self.focus is None else f", focus={self.focus}"
        return f"TreeRobot(kinds={self.joint_kinds}, parents={self.parents}, tips={self.tip_bodies}{focus})"


@dataclasses.dataclass(frozen=True)
class TreeRobot:
    """Several arms (or one branched URDF) on a free-floating bus: n joints, r roots, k tips.

    SI units (kg, m, kg m^2, rad; prismatic joints in m). Leading batch axes, when
    present, are the same on every leaf.

    Attributes:
        base_mass: ``(...)`` bus mass, kg (positive).
        base_com: ``(..., 3)`` bus centroid, bus frame, m.
        base_inertia: ``(..., 3, 3)`` bus inertia about its centroid, bus axes, kg m^2.
        mount_xyz: ``(..., r, 3)`` root-body origins in the bus frame, m.
        mount_rpy: ``(..., r, 3)`` root-body attitudes in the bus frame, URDF roll-pitch-yaw.
        root_mass, root_com, root_inertia: ``(..., r)``, ``(..., r, 3)``, ``(..., r, 3, 3)``:
            root bodies in their own frames (inertia about the centroid).
        joint_rotation: ``(..., n, 3, 3)`` joint frame axes in the parent body's frame.
        joint_translation: ``(..., n, 3)`` joint frame origin in the parent body's frame, m.
        joint_axis: ``(..., n, 3)`` joint axis in the joint frame (non-zero).
        link_mass, link_com, link_inertia: ``(..., n)``, ``(..., n, 3)``, ``(..., n, 3, 3)``:
            body j (child of joint j, merged) in its own frame, inertia about the centroid.
        tip_rotation: ``(..., k, 3, 3)`` tip frame axes in the frame of body ``tip_bodies[t]``.
        tip_translation: ``(..., k, 3)`` tip origin in that body's frame, m.
        joint_lower, joint_upper: ``(..., n)`` joint limits (``-inf``/``+inf`` when free).
        joint_kinds: static, ``n`` of ``"revolute"`` / ``"prismatic"``.
        parents: static, ``n`` parent body of each joint: ``i >= 0`` body i (``i < j``),
            ``-1 - r`` root r.
        tip_bodies: static, ``k`` body index (``>= 0``) carrying each tip.
        labels: names (not compared; renaming does not recompile).
        focus_tip: ``(..., k)`` one-hot weights of the focused tip (`focus`), or ``None``: with
            one, the tree acts as a single-tip robot (tip ``(..., 3)``, J* ``(..., 6, n)``).
        focus_moving: ``(..., n)`` 1 for the joints that move and 0 for the held ones
            (`focus`), or ``None`` without a focus: every joint-rate map has zero columns
            for the held joints.
    """

    base_mass: Any
    base_com: Any
    base_inertia: Any
    mount_xyz: Any
    mount_rpy: Any
    root_mass: Any
    root_com: Any
    root_inertia: Any
    joint_rotation: Any
    joint_translation: Any
    joint_axis: Any
    link_mass: Any
    link_com: Any
    link_inertia: Any
    tip_rotation: Any
    tip_translation: Any
    joint_lower: Any
    joint_upper: Any
    joint_kinds: tuple[str, ...] = ()
    parents: tuple[int, ...] = ()
    tip_bodies: tuple[int, ...] = ()
    labels: TreeLabels = TreeLabels()
    focus_tip: Any = None
    focus_moving: Any = None

    def __post_init__(self):
        object.__setattr__(self, "joint_kinds", tuple(self.joint_kinds))
        if self.focus_tip is not None and self.focus_moving is None:
            object.__setattr__(self, "focus_moving", np.ones(np.shape(self.focus_tip)[:-1] + (len(self.joint_kinds),)))
        object.__setattr__(self, "parents", tuple(int(p) for p in self.parents))
        object.__setattr__(self, "tip_bodies", tuple(int(b) for b in self.tip_bodies))
        _check_topology(self)
        if all(_is_concrete(getattr(self, f)) for f in _LEAF_FIELDS):
            _check_fields(self)

    # Derived, static ---------------------------------------------------------------
    @property
    def name(self) -> str:
        return self.labels.name

    @property
    def n_joints(self) -> int:
        """Number of movable joints n over all arms (static)."""
        return len(self.joint_kinds)

    @property
    def n_tips(self) -> int:
        """Number of tips k (static)."""
        return len(self.tip_bodies)

    @property
    def n_roots(self) -> int:
        """Number of root bodies r (static): the arms of an ``arms:`` file, 1 for a system URDF."""
        return int(np.shape(self.root_mass)[-1])

    @property
    def joint_names(self) -> tuple[str, ...]:
        return self.labels.joint_names

    @property
    def tip_names(self) -> tuple[str, ...]:
        return self.labels.tip_names

    @property
    def support(self) -> np.ndarray:
        """``(k, n)`` static booleans: joint j moves tip t (j is on t's path from the bus)."""
        return support_mask(self.parents, self.tip_bodies)

    @property
    def batch_shape(self) -> tuple[int, ...]:
        """Leading design-batch shape (``()`` for a single design)."""
        return tuple(np.shape(self.base_mass))

    @property
    def focused(self) -> bool:
        """Whether the design is a focus of the tree (`focus`): a tip, held joints, or both (static)."""
        return self.focus_moving is not None

    @property
    def moving_mask(self) -> np.ndarray:
        """``(n,)`` host booleans: the joints that move (all unless `focus` held some); concrete designs only."""
        if self.focus_moving is None:
            return np.ones(self.n_joints, dtype=bool)
        return np.reshape(_host(self.focus_moving, "moving_mask"), (-1, self.n_joints))[0] > 0

    @property
    def active_tip(self) -> int | None:
        """The focused tip's index on the host, or ``None`` without a focus on one tip; concrete designs only."""
        if self.focus_tip is None:
            return None
        return int(np.argmax(np.reshape(_host(self.focus_tip, "active_tip"), (-1, self.n_tips))[0]))

    @property
    def active_tip_name(self) -> str | None:
        """The focused tip's name, or ``None`` without a focus on one tip."""
        index = self.active_tip
        if index is None:
            return None
        names = self.labels.tip_names
        return names[index] if index < len(names) else f"tips[{index}]"

    def focus(self, tip=None, moving=None) -> TreeRobot:
        """The same design acting on one tip with some joints held: the single-tip view of the tree.

        The generic motion and planning stack (straight tip paths, reach, reorientation,
        reaction-free paths) serves robots with one tip; a focused tree is one. Its tip,
        J*, w*, fixed-base Jacobian and straight-path maps are those of the chosen tip
        (no tip axis), and every joint-rate map (J*, C, C_w, J_M, I_M) has zero columns
        for the held joints, which is exact physics for joints locked where they stand
        (a locked joint has zero rate): the rates the planners compute for held joints
        are exactly zero, and the reorientation loops leave them where they are.

        The design's leaves are shared (no copy, no validation). The chosen tip and the
        held joints are leaves too (`focus_tip`, `focus_moving`), so another tip or another
        set of held joints runs the programs already compiled; only whether a tip is
        chosen is part of the structure.

        Args:
            tip: a tip name (``"left/tool0"``) or index; ``None`` keeps every tip (a
                focus on the moving joints only, e.g. for reorientation).
            moving: the joints that move, ``None`` for all: names of arms (the roots of
                an ``arms:`` file, ``"left"``), of tips (the joints on that tip's path
                from the bus) or of joints, or ``n`` booleans.

        Raises:
            ConfigError: an unknown tip, arm or joint (with a did-you-mean hint), or no
                moving joint.
        """
        mask = np.ones(self.n_joints, dtype=bool) if moving is None else np.asarray(_moving_mask(self, moving))
        if not mask.any():
            raise ConfigError("moving: no joint moves; name at least one arm, tip or joint")
        children, structure = _flatten(self)
        leaves = [value for _, value in children][: len(_LEAF_FIELDS)]
        if tip is None and moving is None:
            return _unflatten(_Structure(*_topology(structure)), leaves)
        batch = self.batch_shape
        if tip is not None:
            weights = np.zeros(self.n_tips)
            weights[_tip_index(self, tip)] = 1.0
            leaves.append(np.broadcast_to(weights, batch + weights.shape))
        leaves.append(np.broadcast_to(mask.astype(float), batch + mask.shape))
        return _unflatten(_Structure(*_topology(structure), focus="tip" if tip is not None else "joints"), leaves)

    def replace(self, **changes) -> TreeRobot:
        """A copy with some fields changed (validated again when concrete)."""
        return dataclasses.replace(self, **changes)

    def rename(self, name: str) -> TreeRobot:
        """The same design under another name (same tree structure: no recompilation)."""
        return dataclasses.replace(self, labels=dataclasses.replace(self.labels, name=name))


def support_mask(parents: tuple[int, ...], tip_bodies: tuple[int, ...]) -> np.ndarray:
    """``(k, n)`` booleans: joint j is an ancestor of (or is) the body carrying tip t."""
    mask = np.zeros((len(tip_bodies), len(parents)), dtype=bool)
    for t, body in enumerate(tip_bodies):
        while body >= 0:
            mask[t, body] = True
            body = parents[body]
    return mask


def _tip_index(robot: TreeRobot, tip) -> int:
    names = tuple(robot.labels.tip_names)
    if isinstance(tip, str):
        if tip not in names:
            raise ConfigError(f"tip: unknown tip {tip!r}{did_you_mean(tip, names)}; the tips are {', '.join(names)}")
        return names.index(tip)
    index = int(tip)
    if not -robot.n_tips <= index < robot.n_tips:
        raise ConfigError(f"tip: index {index} is out of range for {robot.n_tips} tips")
    return index % robot.n_tips


def _moving_mask(robot: TreeRobot, moving) -> tuple[bool, ...]:
    """``n`` booleans from arm, tip or joint names (or booleans)."""
    n = robot.n_joints
    if isinstance(moving, str):
        moving = (moving,)
    entries = list(moving)
    if entries and all(isinstance(m, (bool, np.bool_)) for m in entries):
        if len(entries) != n:
            raise ConfigError(f"moving: expected {n} booleans (one per joint), got {len(entries)}")
        return tuple(bool(m) for m in entries)
    labels = robot.labels
    arms = tuple(labels.root_names)
    tips = tuple(labels.tip_names)
    joints = tuple(labels.joint_names)
    support = robot.support
    mask = np.zeros(n, dtype=bool)
    for entry in entries:
        name = str(entry)
        if name in arms and len(labels.joint_roots) == n:
            mask |= np.asarray(labels.joint_roots) == arms.index(name)
        elif name in tips:
            mask |= support[tips.index(name)]
        elif name in joints:
            mask[joints.index(name)] = True
        else:
            known = arms + tips + joints
            # A system: file has one root, the bus: its name is no arm, so name tips and joints.
            choices = f"the arms are {', '.join(arms)}; " if len(arms) > 1 else ""
            raise ConfigError(
                f"moving: unknown arm, tip or joint {name!r}{did_you_mean(name, known)}; "
                f"{choices}the tips are {', '.join(tips)}; the joints are "
                + (", ".join(joints) if len(joints) <= 16 else f"{len(joints)}: {', '.join(joints[:3])}, ...")
            )
    return tuple(bool(m) for m in mask)


def _focus_fields(focus: str | None) -> tuple[str, ...]:
    """The focus leaves a structure carries after the design's own."""
    return {None: (), "joints": ("focus_moving",), "tip": ("focus_tip", "focus_moving")}[focus]


def _topology(structure: _Structure) -> tuple:
    return structure.joint_kinds, structure.parents, structure.tip_bodies, structure.labels


def _host(value, what: str) -> np.ndarray:
    if isinstance(value, jax.core.Tracer):
        raise TypeError(f"TreeRobot.{what}: the focus is traced here; read it from a concrete design")
    return np.asarray(value)


def _flatten(robot: TreeRobot):
    focus = None if robot.focus_moving is None else ("joints" if robot.focus_tip is None else "tip")
    fields = _LEAF_FIELDS + _focus_fields(focus)
    children = [(jax.tree_util.GetAttrKey(k), getattr(robot, k)) for k in fields]
    return children, _Structure(robot.joint_kinds, robot.parents, robot.tip_bodies, robot.labels, focus)


def _unflatten(structure: _Structure, children) -> TreeRobot:
    # Bypass __init__: gradients, optimizer updates and batching placeholders have the
    # robot's shape too and must not be validated as physical designs.
    robot = object.__new__(TreeRobot)
    object.__setattr__(robot, "focus_tip", None)
    object.__setattr__(robot, "focus_moving", None)
    for key, value in zip(_LEAF_FIELDS + _focus_fields(structure.focus), children, strict=True):
        object.__setattr__(robot, key, value)
    object.__setattr__(robot, "joint_kinds", structure.joint_kinds)
    object.__setattr__(robot, "parents", structure.parents)
    object.__setattr__(robot, "tip_bodies", structure.tip_bodies)
    object.__setattr__(robot, "labels", structure.labels)
    return robot


jax.tree_util.register_pytree_with_keys(TreeRobot, _flatten, _unflatten)


def _is_concrete(x) -> bool:
    if isinstance(x, jax.core.Tracer):
        return False
    return isinstance(x, (np.ndarray, np.generic, float, int, jax.Array))


# Validation --------------------------------------------------------------------------


def _check_topology(robot: TreeRobot) -> None:
    n = robot.n_joints
    if n < 1:
        raise ConfigError("joint_kinds: the robot needs at least one movable joint")
    for kind in robot.joint_kinds:
        if kind not in ("revolute", "prismatic"):
            raise ConfigError(f"joint_kinds: unknown kind {kind!r}; use 'revolute' or 'prismatic'")
    if len(robot.parents) != n:
        raise ConfigError(f"parents: expected {n} entries (one per joint), got {len(robot.parents)}")
    roots = int(np.shape(robot.root_mass)[-1]) if np.ndim(robot.root_mass) else 0
    for j, parent in enumerate(robot.parents):
        if parent >= j or parent < -roots:
            raise ConfigError(f"parents[{j}]: {parent} must be an earlier body (0..{j - 1}) or a root (-1..-{roots})")
    if not robot.tip_bodies:
        raise ConfigError("tip_bodies: the robot needs at least one tip")
    for t, body in enumerate(robot.tip_bodies):
        if not 0 <= body < n:
            raise ConfigError(f"tip_bodies[{t}]: {body} is not a body (0..{n - 1}); a tip needs a movable joint")


def _joint_label(robot: TreeRobot, j: int) -> str:
    names = robot.labels.joint_names
    return f"joints[{j}] '{names[j]}'" if j < len(names) else f"joints[{j}]"


def _check_fields(robot: TreeRobot) -> None:
    """Raise ConfigError naming the body or joint and the field for an invalid design."""
    n, k = robot.n_joints, robot.n_tips
    values = {f: np.asarray(getattr(robot, f), dtype=float) for f in _LEAF_FIELDS}
    batch = values["base_mass"].shape
    r = values["root_mass"].shape[-1] if values["root_mass"].ndim > len(batch) else 0
    for field, shape in _LEAF_SHAPES.items():
        expected = batch + shape(n, r, k)
        if values[field].shape != expected:
            raise ConfigError(f"{field}: expected shape {expected}, got {values[field].shape}")
    for field, value in values.items():
        if field in ("joint_lower", "joint_upper"):
            if np.any(np.isnan(value)):
                raise ConfigError(f"{field}: joint limits must not be NaN")
        elif not np.all(np.isfinite(value)):
            raise ConfigError(f"{field}: must be finite numbers")
    if np.any(values["base_mass"] <= 0):
        raise ConfigError(f"base.mass: must be positive, got {values['base_mass']}")
    roots = robot.labels.root_names
    for index in np.ndindex(*batch):
        try:
            check_inertia("base.inertia", values["base_inertia"][index], positive=True, triangle=True)
            for i in range(r):
                where = f"roots[{i}] '{roots[i]}'" if i < len(roots) else f"roots[{i}]"
                if values["root_mass"][index][i] < 0:
                    raise ConfigError(f"{where}: root_mass must not be negative")
                check_inertia(
                    f"{where}: root_inertia", values["root_inertia"][index][i], positive=False, triangle=False
                )
                _check_rotation(f"{where}: mount", rpy_matrix(values["mount_rpy"][index][i]))
            for t in range(k):
                _check_rotation(f"tips[{t}]: tip_rotation", values["tip_rotation"][index][t])
            for j in range(n):
                label = _joint_label(robot, j)
                if values["link_mass"][index][j] < 0:
                    raise ConfigError(f"{label}: link_mass must not be negative, got {values['link_mass'][index][j]}")
                check_inertia(
                    f"{label}: link_inertia", values["link_inertia"][index][j], positive=False, triangle=False
                )
                if np.linalg.norm(values["joint_axis"][index][j]) == 0:
                    raise ConfigError(f"{label}: joint_axis must not be zero")
                _check_rotation(f"{label}: joint_rotation", values["joint_rotation"][index][j])
                if values["joint_lower"][index][j] > values["joint_upper"][index][j]:
                    raise ConfigError(f"{label}: joint_lower is above joint_upper")
        except ConfigError as error:
            if not batch:
                raise
            raise ConfigError(f"design {index}: {error}") from None


def _check_rotation(where: str, rotation: np.ndarray) -> None:
    if np.max(np.abs(rotation @ rotation.T - np.eye(3))) > 1e-9 or np.linalg.det(rotation) < 0:
        raise ConfigError(f"{where}: must be a rotation matrix (orthonormal, determinant +1)")


def tree_view(design, joint_kinds, parents, tip_bodies, labels: TreeLabels | None = None, **leaves) -> TreeRobot:
    """A `TreeRobot` over another design's leaves (its attributes of the same names, replaced by
    ``leaves`` where given), without validation: that design seen as a tree (its leaves already
    checked, or traced)."""
    structure = _Structure(tuple(joint_kinds), tuple(parents), tuple(tip_bodies), labels or TreeLabels())
    return _unflatten(structure, [leaves[f] if f in leaves else getattr(design, f) for f in _LEAF_FIELDS])


def stack_tree_robots(robots: list[TreeRobot]) -> TreeRobot:
    """Stack single designs (same topology) into one batched design with a leading axis."""
    if not robots:
        raise ValueError("stack_tree_robots needs at least one robot")
    return jax.tree_util.tree_map(lambda *xs: np.stack([np.asarray(x) for x in xs]), *robots)


def tree_from_chains(
    chains: list[ArmChain],
    *,
    arm_names: list[str],
    mount_xyz,
    mount_rpy,
    base_mass: float,
    base_com,
    base_inertia,
    name: str = "robot",
    source: str = "",
) -> TreeRobot:
    """Serial arms, each on its own mount, as one validated `TreeRobot` (one root and one tip per arm).

    Joints are numbered arm by arm, each from its root outward; where arms share a URDF
    (two copies of one arm), joint and tip names get the arm's name as a prefix
    (``left/shoulder_pan_joint``).

    Args:
        chains: the arms read from their URDFs (`spacearm.models.spatial.urdf.parse_urdf`).
        arm_names: one name per arm.
        mount_xyz, mount_rpy: ``(r, 3)`` root-link poses in the bus frame (URDF rpy).
        base_mass, base_com, base_inertia: the bus.
    """
    f = lambda x: np.asarray(x, dtype=np.float64)
    shared = len({c.source for c in chains}) < len(chains) or len({c.tip for c in chains}) < len(chains)
    label = lambda arm, text: f"{arm}/{text}" if shared else text
    parents: list[int] = []
    tips: list[int] = []
    joint_names: list[str] = []
    joint_roots: list[int] = []
    for r, (arm, chain) in enumerate(zip(arm_names, chains, strict=True)):
        start = len(parents)
        parents += [-1 - r] + [start + i for i in range(chain.n_joints - 1)]
        tips.append(start + chain.n_joints - 1)
        joint_names += [label(arm, j) for j in chain.joint_names]
        joint_roots += [r] * chain.n_joints
    cat = lambda pick: np.concatenate([f(pick(c)) for c in chains])
    return TreeRobot(
        base_mass=f(base_mass),
        base_com=f(base_com),
        base_inertia=f(base_inertia),
        mount_xyz=f(mount_xyz),
        mount_rpy=f(mount_rpy),
        root_mass=f([c.body_mass[0] for c in chains]),
        root_com=f([c.body_com[0] for c in chains]),
        root_inertia=f([c.body_inertia[0] for c in chains]),
        joint_rotation=cat(lambda c: c.joint_rotation),
        joint_translation=cat(lambda c: c.joint_translation),
        joint_axis=cat(lambda c: c.joint_axis),
        link_mass=cat(lambda c: c.body_mass[1:]),
        link_com=cat(lambda c: c.body_com[1:]),
        link_inertia=cat(lambda c: c.body_inertia[1:]),
        tip_rotation=f([c.tip_rotation for c in chains]),
        tip_translation=f([c.tip_translation for c in chains]),
        joint_lower=cat(lambda c: c.joint_lower),
        joint_upper=cat(lambda c: c.joint_upper),
        joint_kinds=tuple(k for c in chains for k in c.joint_kinds),
        parents=tuple(parents),
        tip_bodies=tuple(tips),
        labels=TreeLabels(
            name=name,
            joint_names=tuple(joint_names),
            tip_names=tuple(label(arm, c.tip) for arm, c in zip(arm_names, chains, strict=True)),
            root_names=tuple(arm_names),
            root_links=tuple(c.body_links[0] for c in chains),
            joint_roots=tuple(joint_roots),
            urdf_types=tuple(t for c in chains for t in c.urdf_types),
            body_links=tuple(b for c in chains for b in c.body_links[1:]),
            source=source,
        ),
    )
