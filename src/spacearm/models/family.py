"""The robot-family seam: the few per-posture primitives every family implements.

Both families describe a serial arm on a free-floating base with zero momentum. A
family gives, for ONE posture (no batch axes):

- the tip position about the system centroid;
- the Jacobians J_S (tip twist per base velocity) and J_M (tip twist per joint rate);
- the momentum map (I_S, I_M), with I_S x_base_dot + I_M q_dot = 0;
- the fixed-base Jacobian of the same arm;
- the base attitude as a group (`spacearm._core.groups`: SO(2) or SO(3)), the
  split/join of an integrator state into joints and attitude coordinates, the
  attitude-rate map (base angular velocity per joint rate at zero momentum), and the
  maps a straight tip path needs at one posture, in one evaluation;
- for pose targets, the whole J* with the attitude-rate map (``pose_maps``) and the
  tip frame's axes (``tip_frame``).

Everything else (J* = J_M - J_S I_S^-1 I_M, w*, ellipses and ellipsoids, base rates,
straight-path fields, averages) is written once over these in
`spacearm.kinematics` and above. A family may give closed forms in
its `FastPaths` record (``fast_paths``, one typed field per kernel); the
generic layer picks them by type at trace time, so a closed form is an optimization,
never a second definition (the tests check each one against the generic path).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import jax
import jax.numpy as jnp
import numpy as np

from .._core.groups import Group

__all__ = ["Capabilities", "FastPaths", "RobotFamily", "family_of", "known_families", "require_family"]


@dataclasses.dataclass(frozen=True)
class Capabilities:
    """The optional analyses a family offers beyond its primitives: what the sweep metrics and
    design objectives above `spacearm.models` may ask of its robots (each declares which it needs).

    Attributes:
        virtual_manipulator: the paper's virtual-manipulator closed forms (K_i of eq. 1, the
            workspace radii and areas S_M, S_G, the w-bar of eq. 12; `spacearm.paper`).
        joint_box_averages: the averages over the joint box of w*, 1/kappa, ||C_w||_F and the
            dynamic manipulability (the arm inertia H*), and the metrics at one posture.
        tip_radius_search: one tip whose reach and path-independent radius a search over the
            joint box finds (several tips: not built).
    """

    virtual_manipulator: bool = False
    joint_box_averages: bool = False
    tip_radius_search: bool = False


_FAMILIES: list[RobotFamily] = []


def known_families() -> tuple[RobotFamily, ...]:
    """Every family record made so far (each family's module makes one), by name: what a
    message listing the families that offer something names."""
    return tuple(sorted(_FAMILIES, key=lambda family: family.name))


@dataclasses.dataclass(frozen=True)
class FastPaths:
    """A family's closed forms and one-pass kernels: each equals what the generic layer computes
    from the primitives (the tests compare them), and ``None`` means the generic path runs.

    The public kernels (same signature as the kernel of the same name in `spacearm.kinematics`):
        tip_position, generalized_jacobian, manipulability, base_rate, base_rate_matrix,
        fixed_base_jacobian, fixed_base_manipulability.

    One pass for several results:
        posture_quantities: ``(robot, posture, needs) -> dict`` what the joint-box averages need.
        tip_and_generalized_jacobian, tip_and_fixed_base_jacobian: ``(robot, joints) -> (J, tip)``.
        fixed_base_jacobian_and_tips: ``(robot, joints) -> (J (k, 6, n), tips (k, 3))``, bus frame.
        straight_maps_and_ends: ``(robot, joints) -> (maps, fixed J_v, tip)`` a straight path's
            field and end checks.
        straight_path_field: ``(robot, direction, sign0) -> field`` the whole straight-path field.

    Workspace radii in closed form (free joints):
        reachable_radii: ``robot -> (outer, inner)`` Area 3's radii about the system centroid.
        path_independent_radius: ``(robot, **options) -> radius`` the largest disk about the
            system centroid that no dynamic-singular tip reaches.
    """

    tip_position: Callable[..., Any] | None = None
    generalized_jacobian: Callable[..., Any] | None = None
    manipulability: Callable[..., Any] | None = None
    base_rate: Callable[..., Any] | None = None
    base_rate_matrix: Callable[..., Any] | None = None
    fixed_base_jacobian: Callable[..., Any] | None = None
    fixed_base_manipulability: Callable[..., Any] | None = None
    posture_quantities: Callable[..., Any] | None = None
    tip_and_generalized_jacobian: Callable[..., Any] | None = None
    tip_and_fixed_base_jacobian: Callable[..., Any] | None = None
    fixed_base_jacobian_and_tips: Callable[..., Any] | None = None
    straight_maps_and_ends: Callable[..., Any] | None = None
    straight_path_field: Callable[..., Any] | None = None
    reachable_radii: Callable[..., Any] | None = None
    path_independent_radius: Callable[..., Any] | None = None


class RobotFamily:
    """Per-posture primitives of one robot family (shapes for one posture, no batch axes).

    Attributes:
        name: the family's name (``"planar"``, ``"spatial"``).
        task_rows: rows m of J* (2 planar: [x, y]; 6 spatial: [v; w]).
        translational_rows: how many leading rows of J* are the tip's linear velocity.
        posture_offset: entries of the posture vector before the joints (1 for the
            planar base angle phi0, 0 for spatial arms whose attitude is a rotation matrix).
        rotates_with_base: whether kernels take ``base_rotation`` (spatial: the
            primitives work in bus axes; the generic layer rotates the results).
        fast_paths: the family's closed forms (`FastPaths`).
        attitude: the base-attitude group.
        straight_field_loops: whether the straight-path field holds a loop (a scan
            over the chain): the integrator then rolls its Runge-Kutta stages into a
            loop instead of writing them out (a shorter compile for the same speed).
        straight_defaults: the family's defaults of the straight-path options
            (``max_step``, ``tol``, ``rtol``, ``sing_rate``, ``tip_tol``, ``max_steps``).
        twist_axes: the components of a 6-vector [x, y, z, rx, ry, rz] (a twist, momentum,
            wrench or impulse) the family's dynamics keep: all six, or the plane's
            [x, y, rz] for a planar family (its robots move in the bus's x-y plane).
        fields: the family's named design numbers (a module with ``FIELD_HELP``,
            ``canonical_name``, ``check_field``, ``set_field``, ``field_stage``,
            ``conflicting_number``, ``field_unit``, ``field_columns``): what sweep axes
            and design variables set.
    """

    name: ClassVar[str] = "abstract"
    task_rows: ClassVar[int] = 0
    translational_rows: ClassVar[int] = 0
    posture_offset: ClassVar[int] = 0
    rotates_with_base: ClassVar[bool] = False
    fast_paths: ClassVar[FastPaths] = FastPaths()
    attitude: ClassVar[Group]
    straight_field_loops: ClassVar[bool] = True
    straight_defaults: ClassVar[Mapping[str, Any]] = {}
    twist_axes: ClassVar[tuple[int, ...]] = (0, 1, 2, 3, 4, 5)
    fields: ClassVar[Any] = None
    capabilities: ClassVar[Capabilities] = Capabilities()

    def __init__(self) -> None:
        _FAMILIES.append(self)

    def joint_count(self, robot) -> int:
        """The number of joints n (static)."""
        raise NotImplementedError

    def tip_count(self, robot) -> int | None:
        """The number of tips k of a family with a tip axis (static); ``None``: one tip, no tip axis.

        With a tip axis, ``tip`` gives ``(k, d)``, ``jacobians`` stack the tips' rows
        (``(k m, b)``, ``(k m, n)``) and the public kernels give ``(..., k, ...)``.
        """
        return None

    def tip(self, robot, posture: jax.Array) -> jax.Array:
        """``(d,)`` tip position about the system centroid, m (spatial: bus axes)."""
        raise NotImplementedError

    def jacobians(self, robot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        """``(J_S (m, b), J_M (m, n))``: tip twist per base velocity and per joint rate (eq. 2)."""
        raise NotImplementedError

    def momentum_map(self, robot, posture: jax.Array) -> tuple[jax.Array, jax.Array]:
        """``(I_S (b, b), I_M (b, n))`` with I_S x_base_dot + I_M q_dot = 0 (eq. 4, 5)."""
        raise NotImplementedError

    def fixed_base_jacobian(self, robot, joints: jax.Array) -> jax.Array:
        """``(m, n)`` Jacobian of the same arm with its base held fixed."""
        raise NotImplementedError

    def joint_kinds(self, robot) -> tuple[str, ...]:
        """Static ``n`` joint kinds, ``"revolute"`` or ``"prismatic"`` (every joint revolute by default)."""
        return ("revolute",) * self.joint_count(robot)

    def joint_names(self, robot) -> tuple[str, ...]:
        """Static ``n`` joint names, or ``()`` where the family's joints have none (they are numbered)."""
        return ()

    def tip_names(self, robot) -> tuple[str, ...]:
        """Static names of the tips a per-tip result indexes (``tip_count``), ``()`` without a tip axis."""
        return ()

    def dynamic_tree(self, robot):
        """The whole robot (one design, or a batch) as the `spacearm.models.tree.TreeRobot` whose
        pass gives its dynamics (`spacearm.models.dynamics`): every joint free, every tip kept.

        A planar robot is the tree in the bus's x-y plane whose joints turn about z; its
        dynamics are that tree's rows and columns in `twist_axes` and the joints.
        """
        raise NotImplementedError(f"the {self.name} family gives no tree for its dynamics")

    def dynamic_tips(self, robot):
        """``(k,)`` weights choosing one tip of `dynamic_tree` (a per-tip result then has no tip
        axis), or ``None``: every tip, on a tip axis (a tree's k tips)."""
        return np.ones(1) if self.tip_count(robot) is None else None

    def moving_joints(self, robot):
        """``(n,)`` 1 for the joints a planner may move and 0 for held ones (all move, unless the
        robot holds some: a focused tree, whose mask is data and traced with the design). Held
        joints have zero columns in every joint-rate map."""
        return np.ones(self.joint_count(robot))

    def tip_joints(self, robot) -> np.ndarray:
        """``(n,)`` host booleans: the moving joints on the tip's own path from the base (all
        moving joints of a serial arm; a focused tree's other arms move its tip only through the bus)."""
        return np.asarray(self.moving_joints(robot)) > 0

    def normal_form(self, robot) -> dict | None:
        """The robot as the mapping of a robot file written from its numbers alone, where the
        family writes one (planar); ``None``: the file's own mapping stands for it."""
        return None

    def view_model(self, robot) -> dict:
        """The robot (one design) as the family-free tree of bodies a view draws
        (`spacearm.models.view_model`: mounts, joints, tips, bus box, posture layout)."""
        raise NotImplementedError(f"the {self.name} family writes no view model")

    # Planning hooks (spacearm.planning) ---------------------------------------------------

    def tip_shell(self, robot) -> tuple[float, float]:
        """Host-side ``(inner, outer)`` radii about the system centroid between which every
        tip position lies, whatever the joints and the base attitude, m (one design).

        The virtual manipulator's bound (Vafa & Dubowsky 1990): the outer radius is the
        sum of the virtual link lengths (the planar K_0 + .. + K_n of eq. 1, exact there).
        A target outside it is unreachable; computed without compiling a program.
        """
        raise NotImplementedError

    # The base attitude and the integrator state -----------------------------------------

    def split_state(self, robot, state: jax.Array) -> tuple[jax.Array, jax.Array]:
        """``(joints (n,), attitude coordinates (attitude.coords,))`` of a flat integrator state."""
        n = self.joint_count(robot)
        offset = self.posture_offset
        if offset:
            return state[offset : offset + n], state[:offset]
        return state[:n], state[n:]

    def join_state(self, robot, joints: jax.Array, coords: jax.Array) -> jax.Array:
        """The flat integrator state of joints and attitude coordinates (inverse of `split_state`)."""
        if self.posture_offset:
            return jnp.concatenate([coords, joints])
        return jnp.concatenate([joints, coords])

    def attitude_rate_map(self, robot, joints: jax.Array) -> jax.Array:
        """``(attitude.dim, n)`` base angular velocity (base axes) per joint rate, zero momentum."""
        raise NotImplementedError

    def loop_holonomy(self, robot, waypoints: jax.Array, **options) -> jax.Array:
        """The base attitude change (a group element, base axes) along a joint polyline ``(k, n)``.

        The fast path of each group (`spacearm._core.magnus`): for SO(2) the line integral
        by Gauss-Legendre quadrature (exact, SO(2) being abelian; options ``nodes``,
        ``pieces``), for SO(3) the 6th-order Magnus integrator (options ``steps``, ``order``).
        """
        raise NotImplementedError

    def straight_maps(self, robot, joints: jax.Array) -> tuple[jax.Array, jax.Array]:
        """``(J*_v (translational_rows, n) in base axes, attitude_rate_map (attitude.dim, n))`` at one
        posture, in one evaluation (a straight tip path's field needs both)."""
        raise NotImplementedError

    # Pose targets (spacearm.motion.pose_paths) ---------------------------------------------

    def pose_maps(self, robot, joints: jax.Array) -> tuple[jax.Array, jax.Array]:
        """``(J* (task_rows, n), attitude_rate_map (attitude.dim, n))`` at one posture, base axes.

        What a straight pose path's field needs per evaluation: the whole J* (tip
        velocity and angular velocity per joint rate at zero momentum) and the base
        angular velocity per joint rate. The default goes through the primitives; a
        family may compute both in one pass.
        """
        J_S, J_M = self.jacobians(robot, joints)
        I_S, I_M = self.momentum_map(robot, joints)
        return J_M - J_S @ jnp.linalg.solve(I_S, I_M), self.attitude_rate_map(robot, joints)

    def with_payload(self, robot, mass, com, inertia, tip=0):
        """The same robot with a rigid payload welded to tip ``tip`` (`spacearm.models.payload`).

        The payload (mass kg, centroid m and inertia about it kg m^2, both in the TIP frame) is
        merged into the body that carries the tip by the parallel-axis theorem: one body of the
        combined mass, centroid and inertia, in that body's own frame. What a rigid grasp makes
        of a grasped object. Families implement it on their own fields.
        """
        raise NotImplementedError(f"the {self.name} family takes no payload")

    def tip_frame(self, robot, joints: jax.Array) -> tuple[jax.Array, jax.Array]:
        """``(position (space,), axes (space, space))``: the tip frame at one posture, base axes.

        The position is about the system centroid (as `tip`); the axes are the tip
        frame's, expressed in base axes. Families whose tip has an orientation to aim
        (6-row J*) implement it; pose targets need it.
        """
        raise NotImplementedError(f"the {self.name} family gives no tip orientation")


def family_of(robot) -> RobotFamily:
    """The family of a robot pytree (its class attribute ``family``)."""
    family = getattr(type(robot), "family", None)
    if not isinstance(family, RobotFamily):
        raise TypeError(
            f"expected a spacearm robot (PlanarRobot, SpatialRobot or TreeRobot), got {type(robot).__name__}"
        )
    return family


def require_family(robot, family: str, what: str) -> None:
    """Refuse a robot of another family in a function that serves one family only.

    Raises:
        TypeError: naming the function, the family it serves and the robot it got
            (at trace time under ``jit``: no run-time cost).
    """
    got = family_of(robot).name
    if got != family:
        raise TypeError(
            f"{what}: {family} arms only, got a {type(robot).__name__} ({got} family); "
            "spacearm.tip_position, generalized_jacobian, manipulability and base_rate serve every family"
        )
