"""The tree family on the robot-family seam: several arms (k tips) on one free-floating bus.

Posture ``q (n,)``: the joints of all arms in the robot's joint order; the bus attitude
is ``base_rotation`` in the public kernels, as for a spatial arm. Every per-tip result
carries a tip axis before its own axes: tips ``(k, 3)``, J* ``(k, 6, n)`` over all
joints, w* ``(k,)``; the bus quantities (C, H*, the attitude) have none.

Fast paths (each equals the generic path over the primitives; tests/test_tree_kernels.py):
the batch-last pass over the tree (`spacearm.models.tree.primitives`), J* by the 3x3
closed form for all tips at once, w* per tip by Cauchy-Binet inside the same batch-last pass.

A focused tree (`spacearm.models.tree.robot.TreeRobot.focus`) is a single-tip robot:
every kernel and hook gives the chosen tip's quantities without a tip axis, and every
joint-rate map has zero columns for the held joints, so the generic straight-path,
reach, reorientation and reaction-free planners serve it unchanged.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any, ClassVar

import jax
import jax.numpy as jnp
import numpy as np

import spacearm.models.tree.fields as tree_fields  # the module, not the package (no cycle)

from ..._core.errors import ConfigError
from ..._core.groups import SO3
from ..._core.linalg import gram_root_determinant
from ..._core.magnus import DEFAULT_ORDER, DEFAULT_STEPS, path_rotation
from ..family import Capabilities, FastPaths, RobotFamily
from ..payload import merged_link_fields
from .primitives import (
    base_twist_map,
    fixed_base_jacobian,
    fixed_base_jacobian_and_tips,
    generalized_jacobian,
    jacobians,
    manipulability,
    momentum_map,
    posture_quantities,
    straight_path_maps,
    tip,
    tip_frames,
)
from .robot import TreeRobot, tree_view
from .shell import tip_shell
from .view import tree_view_model

__all__ = ["TREE", "TreeFamily"]


def _columns(robot: TreeRobot, matrix):
    """Zero the columns (last axis) of the held joints of a focused tree."""
    if robot.focus_moving is None:
        return matrix
    return matrix * jnp.asarray(robot.focus_moving, matrix.dtype)


def _tip_index(robot: TreeRobot):
    """The focused tip's index, traced with the design (a leaf, not part of the compile key)."""
    return jnp.argmax(jnp.asarray(robot.focus_tip))


def _one_tip(robot: TreeRobot, per_tip, core: int):
    """The active tip's slice of a per-tip result ``(..., k, *core)`` (all tips without a focus on one)."""
    if robot.focus_tip is None:
        return per_tip
    return jnp.take(per_tip, _tip_index(robot), axis=-1 - core)


def _focused(robot: TreeRobot) -> bool:
    return robot.focused


def _tip(robot, posture):
    return _one_tip(robot, tip(robot, posture), 1)


def _generalized_jacobian(robot, posture):
    return _one_tip(robot, _columns(robot, generalized_jacobian(robot, posture)), 2)


def _base_rate_matrix(robot, posture):
    return _columns(robot, base_twist_map(robot, posture))


def _fixed_base_jacobian(robot, joints):
    return _one_tip(robot, _columns(robot, fixed_base_jacobian(robot, joints)), 2)


def _fixed_base_jacobian_and_tips(robot, joints):
    """Every tip's fixed-base twists ``(..., k, 6, n)`` (held joints' columns zero) and origins
    ``(..., k, 3)`` about the bus frame, bus axes, one pass (the relative Jacobian's inputs)."""
    J, tips = fixed_base_jacobian_and_tips(robot, joints)
    return _columns(robot, J), tips


def _manipulability(robot, posture):
    if not _focused(robot):
        return manipulability(robot, posture)  # Cauchy-Binet in the pass, every tip
    return gram_root_determinant(_generalized_jacobian(robot, posture)[..., :3, :])


def _locked(robot: TreeRobot, inertia):
    """H* (or H_m) of the held joints locked: the moving block, identity on the held joints
    (their rates are zero, so the moving joints see exactly that block)."""
    if robot.focus_moving is None:
        return inertia
    mask = jnp.asarray(robot.focus_moving, inertia.dtype)
    both = mask[:, None] * mask[None, :]
    return inertia * both + jnp.diag(1.0 - mask)


def _posture_quantities(robot, posture, needs):
    out = posture_quantities(robot, posture, needs)
    if "jacobian" in out:
        out["jacobian"] = _one_tip(robot, _columns(robot, out["jacobian"]), 2)
    if "base_rate" in out:
        out["base_rate"] = _columns(robot, out["base_rate"])
    if "arm_inertia" in out:
        out["arm_inertia"] = _locked(robot, out["arm_inertia"])
    return out


def _base_rate(robot, posture, joint_rates):
    return jnp.einsum("...ij,...j->...i", _base_rate_matrix(robot, posture), joint_rates)


def _fixed_base_manipulability(robot, joints):
    return gram_root_determinant(_fixed_base_jacobian(robot, joints)[..., :3, :])


def _require_tip(robot: TreeRobot, what: str) -> None:
    if robot.focus_tip is None:
        raise TypeError(
            f"{what}: a tree robot with {robot.n_tips} tips; choose one with robot.focus(tip=...) "
            f"(the tips are {', '.join(robot.tip_names)})"
        )


def _tip_rows(robot: TreeRobot, maps, rows: int):
    """The active tip's first ``rows`` rows of stacked per-tip maps ``(..., 6 k + extra, n)``."""
    k = robot.n_tips
    per_tip = maps[..., : 6 * k, :].reshape(maps.shape[:-2] + (k, 6, maps.shape[-1]))
    return _one_tip(robot, per_tip, 2)[..., :rows, :]


class TreeFamily(RobotFamily):
    """Arms from URDF on one free-floating bus, k tips (J* is k x 6 x n, rows [v; w]).

    Base twist coordinates b = [v of the bus centroid; w], bus axes. The generic
    ``jacobians`` stack the tips' rows (6k rows); the public kernels split them per tip.
    """

    name = "tree"
    task_rows = 6
    translational_rows = 3
    posture_offset = 0
    rotates_with_base = True
    fast_paths = FastPaths(
        tip_position=_tip,
        generalized_jacobian=_generalized_jacobian,
        manipulability=_manipulability,
        base_rate=_base_rate,
        base_rate_matrix=_base_rate_matrix,
        fixed_base_jacobian=_fixed_base_jacobian,
        fixed_base_manipulability=_fixed_base_manipulability,
        posture_quantities=_posture_quantities,
        fixed_base_jacobian_and_tips=_fixed_base_jacobian_and_tips,
    )
    fields = tree_fields
    capabilities = Capabilities(joint_box_averages=True, tip_radius_search=False)
    attitude = SO3
    straight_field_loops = True
    straight_defaults: ClassVar[Mapping[str, Any]] = {
        "max_step": 0.1,
        "tol": 1e-11,
        "rtol": 1e-12,
        "sing_rate": 1e-6,
        "tip_tol": 1e-3,
        "max_steps": 4000,
    }

    def joint_count(self, robot: TreeRobot) -> int:
        return robot.n_joints

    def tip_count(self, robot: TreeRobot) -> int | None:
        """k, or ``None`` for a tree focused on one tip (a single-tip robot)."""
        return robot.n_tips if robot.focus_tip is None else None

    def moving_joints(self, robot: TreeRobot):
        """``(n,)`` 1 for the moving joints, 0 for the held ones (traced with a traced design)."""
        if robot.focus_moving is None:
            return np.ones(robot.n_joints)
        return robot.focus_moving

    def tip_joints(self, robot: TreeRobot) -> np.ndarray:
        """Host booleans: the moving joints on the active tip's path from the bus (all moving ones
        without a tip focus); concrete designs only."""
        if robot.focus_tip is None:
            return robot.moving_mask
        return robot.support[robot.active_tip] & robot.moving_mask

    def attitude_rate_map(self, robot: TreeRobot, joints: jax.Array) -> jax.Array:
        """``(..., 3, n)`` bus angular velocity per joint rate (all arms; zero columns for held joints), bus axes."""
        return _base_rate_matrix(robot, joints)[..., 3:, :]

    def straight_maps(self, robot: TreeRobot, joints: jax.Array) -> tuple[jax.Array, jax.Array]:
        """J*_v of the active tip and C_w (held joints' columns zero), one pass over the tree."""
        _require_tip(robot, "straight tip paths")
        maps = _columns(robot, straight_path_maps(robot, joints))
        return _tip_rows(robot, maps, 3), maps[..., -3:, :]

    def pose_maps(self, robot: TreeRobot, joints: jax.Array) -> tuple[jax.Array, jax.Array]:
        """J* ``(6, n)`` of the active tip and C_w ``(3, n)`` (held joints' columns zero), one pass."""
        _require_tip(robot, "pose targets")
        maps = _columns(robot, straight_path_maps(robot, joints))
        return _tip_rows(robot, maps, 6), maps[..., -3:, :]

    def tip_frame(self, robot: TreeRobot, joints: jax.Array) -> tuple[jax.Array, jax.Array]:
        """The active tip's origin about the system centroid ``(3,)`` and axes ``(3, 3)``, bus axes."""
        _require_tip(robot, "pose targets")
        origins, axes = tip_frames(robot, joints)  # one pass over the tree
        return _one_tip(robot, origins, 1), _one_tip(robot, axes, 2)

    def tip_shell(self, robot: TreeRobot) -> tuple[float, float]:
        """The tree's virtual-manipulator shell of the active tip (`spacearm.models.tree.shell`)."""
        _require_tip(robot, "the tip shell")
        return tip_shell(robot, robot.active_tip)

    def view_model(self, robot: TreeRobot) -> dict:
        """The tree as the view tree (`spacearm.models.tree.view`)."""
        return tree_view_model(robot)

    def loop_holonomy(
        self, robot: TreeRobot, waypoints: jax.Array, *, steps: int = DEFAULT_STEPS, order=DEFAULT_ORDER
    ) -> jax.Array:
        """``(..., 3, 3)`` bus rotation along joint polylines ``(..., k, n)``, bus axes (6th-order Magnus)."""
        return path_rotation(functools.partial(self.attitude_rate_map, robot), waypoints, steps, order)

    def tip(self, robot: TreeRobot, posture: jax.Array) -> jax.Array:
        """``(k, 3)`` tips about the system centroid, bus axes (``(3,)`` for a focused tree)."""
        return _tip(robot, posture)

    def jacobians(self, robot: TreeRobot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        J_S, J_M = jacobians(robot, posture)
        J_M = _columns(robot, J_M)
        if robot.focus_tip is None:
            return J_S, J_M
        return _tip_rows(robot, J_S, 6), _tip_rows(robot, J_M, 6)

    def momentum_map(self, robot: TreeRobot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        I_S, I_M = momentum_map(robot, posture)
        return I_S, _columns(robot, I_M)

    def fixed_base_jacobian(self, robot: TreeRobot, joints: jax.Array) -> jax.Array:
        """``(k, 6, n)`` fixed-base Jacobians of the tips, bus axes (``(6, n)`` for a focused tree)."""
        return _fixed_base_jacobian(robot, joints)

    def with_payload(self, robot: TreeRobot, mass, com, inertia, tip=0) -> TreeRobot:
        """The payload (tip frame) merged into body ``tip_bodies[tip]`` (`spacearm.models.payload`);
        ``tip`` indexes the tree's tips (a focus does not renumber them), or names one."""
        names = tuple(robot.tip_names)
        index = names.index(tip) if isinstance(tip, str) and tip in names else tip
        if isinstance(index, str) or not 0 <= int(index) < robot.n_tips:
            raise ConfigError(f"tip {tip!r}: the tree's tips are 0..{robot.n_tips - 1} ({', '.join(names)})")
        t = int(index)
        fields = merged_link_fields(
            robot,
            robot.tip_bodies[t],
            jnp.asarray(robot.tip_rotation)[..., t, :, :],
            jnp.asarray(robot.tip_translation)[..., t, :],
            mass,
            com,
            inertia,
        )
        return robot.replace(**fields)

    def dynamic_tree(self, robot: TreeRobot) -> TreeRobot:
        """The tree itself with every joint free and every tip (a focus dropped)."""
        if robot.focus_tip is None and robot.focus_moving is None:
            return robot
        return tree_view(robot, robot.joint_kinds, robot.parents, robot.tip_bodies, robot.labels)

    def dynamic_tips(self, robot: TreeRobot):
        """Every tip on a tip axis, or the focused tip's one-hot weights."""
        return robot.focus_tip

    def joint_kinds(self, robot: TreeRobot) -> tuple[str, ...]:
        return tuple(robot.joint_kinds)

    def joint_names(self, robot: TreeRobot) -> tuple[str, ...]:
        return tuple(robot.labels.joint_names)

    def tip_names(self, robot: TreeRobot) -> tuple[str, ...]:
        return tuple(robot.tip_names)


TREE = TreeFamily()
TreeRobot.family = TREE
