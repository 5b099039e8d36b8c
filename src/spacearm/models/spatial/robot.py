"""The spatial robot design: a serial arm from a URDF on a free-floating bus.

The design is data. Every number (bus inertials, mount pose, joint placements and
axes, link inertials, tip offset, joint limits) is an array leaf of
`SpatialRobot`, so ``jit``, ``vmap`` and ``grad`` work over designs and a
batch of designs is the same pytree with leading axes on every leaf. The topology
(the number of joints and which are prismatic) is static and part of the tree
structure. Labels (the robot name, joint names, the URDF path) ride along in the tree
structure but take no part in its equality, so renaming a robot never recompiles.

Frames: the bus frame has its origin anywhere (the bus centroid is at ``base_com``);
the root body (the URDF ``root_link`` with everything rigidly attached) sits at the
mount pose in the bus frame; body i (1..n) is the child link frame of arm joint i.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax
import numpy as np

from ..._core.errors import ConfigError
from ..._core.groups import rpy_matrix
from .urdf import ArmChain, check_inertia

__all__ = ["Labels", "SpatialRobot", "robot_from_chain", "stack_spatial_robots"]

# Leaf fields in a fixed order: (name, trailing shape given n) for validation.
_LEAF_SHAPES = {
    "base_mass": lambda n: (),
    "base_com": lambda n: (3,),
    "base_inertia": lambda n: (3, 3),
    "mount_xyz": lambda n: (3,),
    "mount_rpy": lambda n: (3,),
    "root_mass": lambda n: (),
    "root_com": lambda n: (3,),
    "root_inertia": lambda n: (3, 3),
    "joint_rotation": lambda n: (n, 3, 3),
    "joint_translation": lambda n: (n, 3),
    "joint_axis": lambda n: (n, 3),
    "link_mass": lambda n: (n,),
    "link_com": lambda n: (n, 3),
    "link_inertia": lambda n: (n, 3, 3),
    "tip_rotation": lambda n: (3, 3),
    "tip_translation": lambda n: (3,),
    "joint_lower": lambda n: (n,),
    "joint_upper": lambda n: (n,),
}
_LEAF_FIELDS = tuple(_LEAF_SHAPES)


@dataclasses.dataclass(frozen=True)
class Labels:
    """Names carried with a design; never compared, never traced."""

    name: str = "robot"
    joint_names: tuple[str, ...] = ()
    urdf_types: tuple[str, ...] = ()
    body_links: tuple[tuple[str, ...], ...] = ()
    root_link: str = ""
    tip: str = ""
    source: str = ""


class _Structure:
    """The tree structure's auxiliary data: the topology compares, the labels do not."""

    __slots__ = ("joint_kinds", "labels")

    def __init__(self, joint_kinds: tuple[str, ...], labels: Labels):
        self.joint_kinds = joint_kinds
        self.labels = labels

    def __eq__(self, other):
        return isinstance(other, _Structure) and self.joint_kinds == other.joint_kinds

    def __hash__(self):
        return hash(("SpatialRobot", self.joint_kinds))

    def __repr__(self):
        return f"SpatialRobot{self.joint_kinds}"


@dataclasses.dataclass(frozen=True)
class SpatialRobot:
    """A free-floating spatial manipulator: bus, mount, and an n-joint serial arm.

    SI units (kg, m, kg m^2, rad; prismatic joints in m). Leading batch axes, when
    present, are the same on every leaf.

    Attributes:
        base_mass: ``(...)`` bus mass, kg (positive).
        base_com: ``(..., 3)`` bus centroid, bus frame, m.
        base_inertia: ``(..., 3, 3)`` bus inertia about its centroid, bus axes, kg m^2.
        mount_xyz: ``(..., 3)`` root-link origin in the bus frame, m.
        mount_rpy: ``(..., 3)`` root-link attitude in the bus frame, URDF roll-pitch-yaw
            (R = Rz(yaw) Ry(pitch) Rx(roll)), rad.
        root_mass, root_com, root_inertia: ``(...)``, ``(..., 3)``, ``(..., 3, 3)``: the
            root body (root link and its rigid attachments) in the root-link frame.
        joint_rotation: ``(..., n, 3, 3)`` joint frame axes in the parent body frame.
        joint_translation: ``(..., n, 3)`` joint frame origin in the parent body frame, m.
        joint_axis: ``(..., n, 3)`` joint axis in the joint frame (non-zero; normalized
            by the kernels).
        link_mass, link_com, link_inertia: ``(..., n)``, ``(..., n, 3)``,
            ``(..., n, 3, 3)``: body i (child of joint i, merged) in its own frame; the
            inertia is about the centroid, kg m^2.
        tip_rotation: ``(..., 3, 3)`` tip frame axes in body n's frame.
        tip_translation: ``(..., 3)`` tip origin in body n's frame, m.
        joint_lower, joint_upper: ``(..., n)`` joint limits (``-inf``/``+inf`` when free).
        joint_kinds: static, ``n`` of ``"revolute"`` / ``"prismatic"``.
        labels: names (not compared; renaming does not recompile).
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
    labels: Labels = Labels()

    def __post_init__(self):
        kinds = tuple(self.joint_kinds)
        object.__setattr__(self, "joint_kinds", kinds)
        for kind in kinds:
            if kind not in ("revolute", "prismatic"):
                raise ConfigError(f"joint_kinds: unknown kind {kind!r}; use 'revolute' or 'prismatic'")
        if all(_is_concrete(getattr(self, f)) for f in _LEAF_FIELDS):
            _validate(self)

    # Derived, static ---------------------------------------------------------------
    @property
    def name(self) -> str:
        return self.labels.name

    @property
    def n_joints(self) -> int:
        """Number of arm joints n (static)."""
        return len(self.joint_kinds)

    @property
    def n_links(self) -> int:
        """Number of moving bodies, n (one per arm joint; the same as `n_joints`)."""
        return len(self.joint_kinds)

    @property
    def reach(self):
        """``(...)`` L: joint 1 to the tip along the chain (sum of joint-to-joint offsets and the
        tip offset), m; prismatic joints at zero extension. An upper bound on the distance."""
        offsets = np.linalg.norm(np.asarray(self.joint_translation)[..., 1:, :], axis=-1).sum(-1)
        return offsets + np.linalg.norm(np.asarray(self.tip_translation), axis=-1)

    @property
    def batch_shape(self) -> tuple[int, ...]:
        """Leading design-batch shape (``()`` for a single design)."""
        return tuple(np.shape(self.base_mass))

    @property
    def joint_names(self) -> tuple[str, ...]:
        return self.labels.joint_names

    def replace(self, **changes) -> SpatialRobot:
        """A copy with some fields changed (validated again when concrete)."""
        return dataclasses.replace(self, **changes)

    def rename(self, name: str) -> SpatialRobot:
        """The same design under another name (same tree structure: no recompilation)."""
        return dataclasses.replace(self, labels=dataclasses.replace(self.labels, name=name))


def _flatten(robot: SpatialRobot):
    children = [(jax.tree_util.GetAttrKey(k), getattr(robot, k)) for k in _LEAF_FIELDS]
    return children, _Structure(robot.joint_kinds, robot.labels)


def _unflatten(structure: _Structure, children) -> SpatialRobot:
    # Bypass __init__: gradients, optimizer updates and batching placeholders have the
    # robot's shape too and must not be validated as physical designs.
    robot = object.__new__(SpatialRobot)
    for key, value in zip(_LEAF_FIELDS, children, strict=False):
        object.__setattr__(robot, key, value)
    object.__setattr__(robot, "joint_kinds", structure.joint_kinds)
    object.__setattr__(robot, "labels", structure.labels)
    return robot


jax.tree_util.register_pytree_with_keys(SpatialRobot, _flatten, _unflatten)


def _is_concrete(x) -> bool:
    if isinstance(x, jax.core.Tracer):
        return False
    return isinstance(x, (np.ndarray, np.generic, float, int, jax.Array))


# Validation --------------------------------------------------------------------------


def _joint_label(robot: SpatialRobot, i: int) -> str:
    names = robot.labels.joint_names
    return f"joints[{i}] '{names[i]}'" if i < len(names) else f"joints[{i}]"


def _looks_valid(robot: SpatialRobot, values: dict) -> bool:
    """Every check of `_check_fields`, vectorized over designs and bodies (NaN fails each);
    only a batch that fails pays for the per-design pass that names the culprit."""
    n = robot.n_joints
    batch = values["base_mass"].shape
    if any(values[f].shape != batch + shape(n) for f, shape in _LEAF_SHAPES.items()):
        return False
    finite = all(np.isfinite(v).all() for f, v in values.items() if f not in ("joint_lower", "joint_upper"))
    if not finite or np.isnan(values["joint_lower"]).any() or np.isnan(values["joint_upper"]).any():
        return False
    if (values["base_mass"] <= 0).any() or (values["root_mass"] < 0).any() or (values["link_mass"] < 0).any():
        return False
    if (values["joint_lower"] > values["joint_upper"]).any():
        return False
    if (np.linalg.norm(values["joint_axis"], axis=-1) == 0).any():
        return False
    tol = 1e-9
    for field in ("base_inertia", "root_inertia", "link_inertia"):
        tensor = values[field]
        scale = np.maximum(np.abs(tensor).max(axis=(-2, -1)), 1e-300)
        if (np.abs(tensor - np.swapaxes(tensor, -1, -2)).max(axis=(-2, -1)) > tol * scale).any():
            return False
        moments = np.linalg.eigvalsh(tensor)
        low = moments[..., 0] <= tol * scale if field == "base_inertia" else moments[..., 0] < -tol * scale
        if low.any():
            return False
        if field == "base_inertia" and (moments[..., 2] > moments[..., 0] + moments[..., 1] + tol * scale).any():
            return False
    rotations = np.concatenate(
        [values["joint_rotation"].reshape(-1, 3, 3), values["tip_rotation"].reshape(-1, 3, 3)], axis=0
    )
    if (np.abs(rotations @ np.swapaxes(rotations, -1, -2) - np.eye(3)).max(axis=(-2, -1)) > tol).any():
        return False
    if (np.linalg.det(rotations) < 0).any():
        return False
    total = values["base_mass"] + values["root_mass"] + values["link_mass"].sum(-1)
    return bool((total > 0).all())


def _validate(robot: SpatialRobot) -> None:
    """Raise ConfigError naming the body or joint and the field for an invalid design."""
    if robot.n_joints < 1:
        raise ConfigError("joint_kinds: the arm needs at least one movable joint")
    values = {f: np.asarray(getattr(robot, f), dtype=float) for f in _LEAF_FIELDS}
    if not _looks_valid(robot, values):
        _check_fields(robot)


def _check_fields(robot: SpatialRobot) -> None:
    """The per-design, per-field checks behind `_validate` (they name the culprit)."""
    n = robot.n_joints
    if n < 1:
        raise ConfigError("joint_kinds: the arm needs at least one movable joint")
    values = {f: np.asarray(getattr(robot, f), dtype=float) for f in _LEAF_FIELDS}
    batch = values["base_mass"].shape
    for field, shape in _LEAF_SHAPES.items():
        expected = batch + shape(n)
        if values[field].shape != expected:
            raise ConfigError(f"{field}: expected shape {expected}, got {values[field].shape}")
    for field, value in values.items():
        if field in ("joint_lower", "joint_upper"):
            if np.any(np.isnan(value)):
                raise ConfigError(f"{field}: joint limits must not be NaN")
        elif not np.all(np.isfinite(value)):
            raise ConfigError(f"{field}: must be finite numbers")
    if np.any(values["base_mass"] <= 0):
        raise ConfigError(f"base.mass: must be positive, got {_show(values['base_mass'])}")
    if np.any(values["root_mass"] < 0):
        raise ConfigError(f"root_mass: must not be negative, got {_show(values['root_mass'])}")
    for index in np.ndindex(*batch):
        try:
            check_inertia("base.inertia", values["base_inertia"][index], positive=True, triangle=True)
            check_inertia("root_inertia", values["root_inertia"][index], positive=False, triangle=False)
            _check_rotation("mount", rpy_matrix(values["mount_rpy"][index]))
            _check_rotation("tip_rotation", values["tip_rotation"][index])
            for i in range(n):
                label = _joint_label(robot, i)
                if values["link_mass"][index][i] < 0:
                    raise ConfigError(f"{label}: link_mass must not be negative, got {values['link_mass'][index][i]}")
                check_inertia(
                    f"{label}: link_inertia", values["link_inertia"][index][i], positive=False, triangle=False
                )
                if np.linalg.norm(values["joint_axis"][index][i]) == 0:
                    raise ConfigError(f"{label}: joint_axis must not be zero")
                _check_rotation(f"{label}: joint_rotation", values["joint_rotation"][index][i])
                if values["joint_lower"][index][i] > values["joint_upper"][index][i]:
                    raise ConfigError(f"{label}: joint_lower is above joint_upper")
        except ConfigError as error:
            if not batch:
                raise
            raise ConfigError(f"design {index}: {error}") from None
    total = values["base_mass"] + values["root_mass"] + values["link_mass"].sum(-1)
    if np.any(total <= 0):
        raise ConfigError("the total mass must be positive")


def _check_rotation(where: str, rotation: np.ndarray) -> None:
    if np.max(np.abs(rotation @ rotation.T - np.eye(3))) > 1e-9 or np.linalg.det(rotation) < 0:
        raise ConfigError(f"{where}: must be a rotation matrix (orthonormal, determinant +1)")


def _show(value: np.ndarray) -> str:
    return str(value.item()) if value.size == 1 else np.array2string(value, threshold=6)


# Construction ------------------------------------------------------------------------


def robot_from_chain(
    chain: ArmChain,
    *,
    base_mass: float,
    base_com,
    base_inertia,
    mount_xyz,
    mount_rpy,
    name: str = "robot",
) -> SpatialRobot:
    """Build a validated `SpatialRobot` from a URDF arm and the bus and mount.

    Raises:
        ConfigError: naming the field.
    """
    f = lambda x: np.asarray(x, dtype=np.float64)
    return SpatialRobot(
        base_mass=f(base_mass),
        base_com=f(base_com),
        base_inertia=f(base_inertia),
        mount_xyz=f(mount_xyz),
        mount_rpy=f(mount_rpy),
        root_mass=f(chain.body_mass[0]),
        root_com=f(chain.body_com[0]),
        root_inertia=f(chain.body_inertia[0]),
        joint_rotation=f(chain.joint_rotation),
        joint_translation=f(chain.joint_translation),
        joint_axis=f(chain.joint_axis),
        link_mass=f(chain.body_mass[1:]),
        link_com=f(chain.body_com[1:]),
        link_inertia=f(chain.body_inertia[1:]),
        tip_rotation=f(chain.tip_rotation),
        tip_translation=f(chain.tip_translation),
        joint_lower=f(chain.joint_lower),
        joint_upper=f(chain.joint_upper),
        joint_kinds=chain.joint_kinds,
        labels=Labels(
            name=name,
            joint_names=chain.joint_names,
            urdf_types=chain.urdf_types,
            body_links=chain.body_links,
            root_link=chain.root_link,
            tip=chain.tip,
            source=chain.source,
        ),
    )


def stack_spatial_robots(robots: list[SpatialRobot]) -> SpatialRobot:
    """Stack single designs (same topology) into one batched design with a leading axis."""
    if not robots:
        raise ValueError("stack_spatial_robots needs at least one robot")
    return jax.tree_util.tree_map(lambda *xs: np.stack([np.asarray(x) for x in xs]), *robots)
