"""The tree robot file: several arms on one bus, in two forms (``arms:`` or ``system:``).

Arms on a bus given here, each from its own URDF (two copies of one URDF may coexist:
their joint and tip names then carry the arm's name, ``left/shoulder_pan_joint``):

```yaml
name: dual-ur5
base: {mass: 400.0, com: [0, 0, 0], inertia: [[60, 0, 0], [0, 60, 0], [0, 0, 60]]}
arms:
  - name: left
    mount: {xyz: [0.3, 0.5526, 0.08], rpy: [-1.5708, 0, 0]}   # or rpy_deg
    urdf: {package: example-robot-data, path: robots/ur_description/urdf/ur5_robot.urdf}
    root_link: base_link
    tip: tool0
    lock_joints: {}            # joint: value, held fixed
    lock_others: false         # true: hold every movable joint off the path at 0
    inertia_as_written: false
  - name: right
    ...
```

One URDF whose ``base_link`` is the free-floating bus (see `spacearm.models.tree.urdf`):

```yaml
name: baxter
system:
  urdf: {package: example-robot-data, path: robots/baxter_description/urdf/baxter.urdf}
  base_link: base              # the bus: this link and its rigid attachments, as written
  tips: [left_gripper, right_gripper]
  lock_joints: {}
  lock_others: true            # hold the head and the fingers at 0 (or their nearest limit)
  inertia_as_written: true
```

Joint order: tip by tip in file order, each tip's path from the bus outward, a joint
already listed for an earlier tip not repeated (``robot.joint_names``, ``robot.tip_names``).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..._core.errors import ConfigError
from ..._core.schema import check_keys, check_name, quote, read_yaml, robot_file_name
from ..spatial.schema import read_base, read_flag, read_lock_joints, read_mount, urdf_path
from ..spatial.urdf import read_urdf
from .robot import TreeLabels, TreeRobot, tree_from_chains
from .urdf import MAX_TREE_JOINTS, read_urdf_tree

__all__ = ["is_tree_config", "load_tree_robot", "tree_robot_from_mapping"]

_ARMS_TOP_KEYS = {"name", "description", "base", "arms"}
_SYSTEM_TOP_KEYS = {"name", "description", "system", "base", "mount"}
_ARM_KEYS = {
    "name",
    "urdf",
    "root_link",
    "tip",
    "lock_joints",
    "lock_others",
    "drop_others",
    "mount",
    "inertia_as_written",
}
_SYSTEM_KEYS = {"urdf", "base_link", "tips", "lock_joints", "lock_others", "drop_others", "inertia_as_written"}
# At most this many arms in one file.
MAX_ARMS = 32


def is_tree_config(config: Any) -> bool:
    """True for a robot description of the tree family (a mapping with ``arms`` or ``system``)."""
    return isinstance(config, Mapping) and ("arms" in config or "system" in config)


def _section(where: str, value: Any, keys: set[str]) -> Mapping:
    if not isinstance(value, Mapping):
        raise ConfigError(f"{where}: must be a mapping with keys {', '.join(sorted(keys))}")
    check_keys(f"{where}: ", value, keys)
    return value


def _link_name(where: str, value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise ConfigError(f"{where}: missing or not a link name, got {quote(value)}")
    return value


def _inside_urdf(source: str, key: str, error: ConfigError) -> ConfigError:
    """A problem inside a URDF: name the robot file's field first."""
    if str(error).startswith(f"{source}: "):
        return error
    return ConfigError(f"{source}: {key}: {error}")


def _arms_robot(config: Mapping, source: str, base_dir: str) -> TreeRobot:
    name = robot_file_name(source, config, _ARMS_TOP_KEYS)
    base_mass, base_com, base_inertia = read_base(source, config)
    arms = config["arms"]
    if not isinstance(arms, list) or not arms:
        raise ConfigError(f"{source}: arms: must be a list of one or more arms, got {quote(arms)}")
    if len(arms) > MAX_ARMS:
        raise ConfigError(f"{source}: arms: at most {MAX_ARMS} arms, got {len(arms)}")
    names, chains, mount_xyz, mount_rpy = [], [], [], []
    for i, value in enumerate(arms):
        section = f"arms[{i}]"
        arm = _section(f"{source}: {section}", value, _ARM_KEYS)
        arm_name = arm.get("name")
        if not isinstance(arm_name, str) or not arm_name or "/" in arm_name:
            raise ConfigError(f"{source}: {section}.name: missing, or not a name without '/', got {quote(arm_name)}")
        if arm_name in names:
            raise ConfigError(f"{source}: {section}.name: '{arm_name}' is already arms[{names.index(arm_name)}]")
        root_link = _link_name(f"{source}: {section}.root_link", arm.get("root_link"))
        tip = _link_name(f"{source}: {section}.tip", arm.get("tip"))
        xyz, rpy = read_mount(f"{source}: {section}.mount", arm.get("mount", {}))
        lock = read_lock_joints(f"{source}: {section}.lock_joints", arm.get("lock_joints"))
        as_written = read_flag(f"{source}: {section}.inertia_as_written", arm.get("inertia_as_written", False))
        lock_others = read_flag(f"{source}: {section}.lock_others", arm.get("lock_others", False))
        drop_others = read_flag(f"{source}: {section}.drop_others", arm.get("drop_others", False))
        urdf = urdf_path(source, arm, base_dir, section)
        try:
            chain = read_urdf(
                urdf,
                root_link=root_link,
                tip=tip,
                lock_joints=lock,
                inertia_as_written=as_written,
                fields=f"{source}: {section}.",
                lock_others=lock_others,
                drop_others=drop_others,
                keys=f"{section}.",
            )
        except ConfigError as error:
            raise _inside_urdf(source, f"{section}.urdf", error) from None
        names.append(arm_name)
        chains.append(chain)
        mount_xyz.append(xyz)
        mount_rpy.append(rpy)
    joints = sum(len(chain.joint_lower) for chain in chains)
    if joints > MAX_TREE_JOINTS:
        raise ConfigError(
            f"{source}: arms: {joints} movable joints in all; at most {MAX_TREE_JOINTS} are supported "
            "(lock some in an arm's lock_joints)"
        )
    try:
        robot = tree_from_chains(
            chains,
            arm_names=names,
            mount_xyz=np.array(mount_xyz),
            mount_rpy=np.array(mount_rpy),
            base_mass=base_mass,
            base_com=base_com,
            base_inertia=base_inertia,
            name=name,
            source=source,
        )
    except ConfigError as error:
        raise ConfigError(f"{source}: {error}") from None
    labels = robot.labels
    if len(set(labels.joint_names)) < len(labels.joint_names) or len(set(labels.tip_names)) < len(labels.tip_names):
        # Arms from different URDFs that name joints alike: every name carries its arm's.
        labels = dataclasses.replace(
            labels,
            joint_names=tuple(f"{names[r]}/{j}" for r, c in enumerate(chains) for j in c.joint_names),
            tip_names=tuple(f"{arm}/{c.tip}" for arm, c in zip(names, chains, strict=True)),
        )
        robot = dataclasses.replace(robot, labels=labels)
    return robot


def _system_bus(config: Mapping, source: str, base_link: str, urdf: str, tree) -> tuple[dict, dict]:
    """The bus and the root body of a ``system:`` file, as `TreeRobot` fields.

    Without ``base:`` the bus is ``base_link`` with its rigid attachments, as written. With
    ``base:`` (a real bus) that body becomes the root, fixed to the bus at ``mount:``.
    """
    f = lambda x: np.asarray(x, dtype=np.float64)
    if "base" not in config:
        if "mount" in config:
            raise ConfigError(f"{source}: mount: places system.base_link on a bus, which needs a base: section")
        if tree.body_mass[0] <= 0:
            raise ConfigError(
                f"{source}: system.base_link: the bus '{base_link}' and the links rigidly attached to it "
                f"({', '.join(tree.body_links[0][:6])}) have no mass in {urdf}"
            )
        bus = {
            "base_mass": f(tree.body_mass[0]),
            "base_com": f(tree.body_com[0]),
            "base_inertia": f(tree.body_inertia[0]),
        }
        root = {"root_mass": np.zeros(1), "root_com": np.zeros((1, 3)), "root_inertia": np.zeros((1, 3, 3))}
        return bus, {**root, "mount_xyz": np.zeros((1, 3)), "mount_rpy": np.zeros((1, 3))}
    base_mass, base_com, base_inertia = read_base(source, config)
    xyz, rpy = read_mount(f"{source}: mount", config.get("mount", {}))
    bus = {"base_mass": f(base_mass), "base_com": f(base_com), "base_inertia": f(base_inertia)}
    root = {
        "root_mass": f(tree.body_mass[:1]),
        "root_com": f(tree.body_com[:1]),
        "root_inertia": f(tree.body_inertia[:1]),
    }
    return bus, {**root, "mount_xyz": f(xyz)[None], "mount_rpy": f(rpy)[None]}


def _system_robot(config: Mapping, source: str, base_dir: str) -> TreeRobot:
    if not isinstance(config, Mapping):
        raise ConfigError(f"{source}: the robot description must be a mapping, got {type(config).__name__}")
    check_keys(f"{source}: ", config, _SYSTEM_TOP_KEYS)
    name = check_name(f"{source}: name", config.get("name", "robot"))
    system = _section(f"{source}: system", config["system"], _SYSTEM_KEYS)
    base_link = _link_name(f"{source}: system.base_link", system.get("base_link"))
    tips = system.get("tips")
    if isinstance(tips, str):
        raise ConfigError(f"{source}: system.tips: must be a list of link names, e.g. [{tips}]")
    if not isinstance(tips, list) or not tips:
        raise ConfigError(f"{source}: system.tips: must be a list of one or more link names, got {quote(tips)}")
    if len(tips) > MAX_ARMS:
        raise ConfigError(f"{source}: system.tips: at most {MAX_ARMS} tips, got {len(tips)}")
    tips = [_link_name(f"{source}: system.tips[{t}]", tip) for t, tip in enumerate(tips)]
    lock = read_lock_joints(f"{source}: system.lock_joints", system.get("lock_joints"))
    as_written = read_flag(f"{source}: system.inertia_as_written", system.get("inertia_as_written", False))
    lock_others = read_flag(f"{source}: system.lock_others", system.get("lock_others", False))
    drop_others = read_flag(f"{source}: system.drop_others", system.get("drop_others", False))
    urdf = urdf_path(source, system, base_dir, "system")
    try:
        tree = read_urdf_tree(
            urdf,
            base_link=base_link,
            tips=tips,
            lock_joints=lock,
            lock_others=lock_others,
            drop_others=drop_others,
            inertia_as_written=as_written,
            fields=f"{source}: system.",
            keys="system.",
        )
    except ConfigError as error:
        raise _inside_urdf(source, "system.urdf", error) from None
    f = lambda x: np.asarray(x, dtype=np.float64)
    bus, root = _system_bus(config, source, base_link, urdf, tree)
    try:
        return TreeRobot(
            **bus,
            **root,
            joint_rotation=f(tree.joint_rotation),
            joint_translation=f(tree.joint_translation),
            joint_axis=f(tree.joint_axis),
            link_mass=f(tree.body_mass[1:]),
            link_com=f(tree.body_com[1:]),
            link_inertia=f(tree.body_inertia[1:]),
            tip_rotation=f(tree.tip_rotation),
            tip_translation=f(tree.tip_translation),
            joint_lower=f(tree.joint_lower),
            joint_upper=f(tree.joint_upper),
            joint_kinds=tree.joint_kinds,
            parents=tree.parents,
            tip_bodies=tree.tip_bodies,
            labels=TreeLabels(
                name=name,
                joint_names=tree.joint_names,
                tip_names=tree.tips,
                root_names=(base_link,),
                root_links=tree.body_links[:1],
                joint_roots=(0,) * tree.n_joints,
                urdf_types=tree.urdf_types,
                body_links=tree.body_links[1:],
                source=source,
            ),
        )
    except ConfigError as error:
        raise ConfigError(f"{source}: system.base_link: (the bus '{base_link}' in {urdf}) {error}") from None


def tree_robot_from_mapping(
    config: Mapping[str, Any], *, source: str = "robot", base_dir: str | os.PathLike = "."
) -> TreeRobot:
    """Build a validated `TreeRobot` from a parsed robot file (``arms:`` or ``system:``).

    Args:
        config: the mapping.
        source: a label for messages (the file name).
        base_dir: the folder relative URDF paths start from (the robot file's folder).

    Raises:
        ConfigError: naming the file and the field (``arms[1].tip``).
    """
    base_dir = os.fspath(base_dir)
    if isinstance(config, Mapping) and "arms" in config and "system" in config:
        raise ConfigError(f"{source}: give either 'arms' (arms on a bus) or 'system' (one URDF), not both")
    if isinstance(config, Mapping) and "system" in config:
        return _system_robot(config, source, base_dir)
    return _arms_robot(config, source, base_dir)


def load_tree_robot(source: str | os.PathLike | Mapping[str, Any], *, base_dir=None) -> TreeRobot:
    """Load and validate a tree robot from a YAML file path or an already parsed mapping.

    Raises:
        ConfigError: for a missing or malformed file and for any invalid field.
    """
    if isinstance(source, Mapping):
        return tree_robot_from_mapping(source, base_dir=base_dir or ".")
    path = os.fspath(source)
    config = read_yaml(path, what="robot file")
    return tree_robot_from_mapping(config, source=path, base_dir=base_dir or os.path.dirname(path) or ".")
