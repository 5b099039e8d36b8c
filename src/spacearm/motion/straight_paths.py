"""Straight tip paths and go-and-back motions of the free-floating arm, for every family.

With zero momentum the base turns as the joints move (Umetani & Yoshida 1990, eq. 5:
I_S dphi0 + I_M . dphi_M = 0 in the plane; omega_B = C_w(q) q' in 3-D), so a tip path
fixed in inertial axes couples the joints and the base attitude: the state
y = [family state (joints and attitude coordinates), s] is integrated together,

    q' = regularized rates of J*_v(q) (base axes) for the base-frame direction g^-1 d,
    g' = g [A(q) q'] (A the attitude-rate map; for SO(2) simply phi0' = A q'),
    s' = tip speed along d,

with respect to the joint-space arc length sigma (Fig. 3a). The rates are
`spacearm.kinematics.straight_path_rates`, written once: for a square J*_v the
adjugate form sgn0 adj(J*_v) d / |adj(J*_v) d| (finite and smooth through det J*_v = 0),
for a redundant arm the minimum-norm rates J*_v^T (J*_v J*_v^T)^-1 d regularized with
adj(J*_v J*_v^T). The path ends where ds/dsigma = 0 (the tip can no longer advance along
the line: the translational J* lost rank, a dynamic singularity; Papadopoulos & Dubowsky
1993), at a joint limit, or after ``max_length``.

Each family supplies its state (`spacearm.models.RobotFamily.split_state`), its
attitude group and the maps J*_v and A from one evaluation (``straight_maps``); a
family may register a closed-form field (the planar one) as a fast path. The
integrator is `spacearm.motion.lanes` (DOP853 with event location, lane refill,
power-of-two buckets), written once; docs/explanation/integrators.md compares it
with diffrax, SciPy and fixed-step RK4. SO(3) coordinates are
integrated as 9 numbers and projected back onto the group (polar factor) at the end, a
correction at the level of the tolerance.
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np

from .._core.batching import bucket_size, pad_leading, shapes_of
from .._core.errors import ConfigError
from .._core.linalg import gram_root_determinant
from ..kinematics import (
    fixed_base_jacobian,
    fixed_base_manipulability,
    square_determinant,
    straight_path_rates,
    tip_position,
)
from ..models.family import family_of, require_family
from .batching import check_arm_axis, flatten_batch, is_traced, unpad
from .dop853 import rk_step
from .lanes import PATH_BUCKET, lane_count, run_queue, start_lane, step_lane
from .path_ends import REASON_JOINT_LIMIT, REASON_MAX_LENGTH, REASON_SINGULAR, REASON_STEP_BUDGET

__all__ = [
    "PATH_BUCKET",
    "REASON_JOINT_LIMIT",
    "REASON_MAX_LENGTH",
    "REASON_SINGULAR",
    "REASON_STEP_BUDGET",
    "SpatialStraightPath",
    "StraightPath",
    "compile_straight_tip_path_history",
    "generic_straight_field",
    "go_and_back",
    "lane_count",
    "straight_tip_path",
    "straight_tip_path_history",
]


# The ends of straight tip paths -----------------------------------------------------------


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class StraightPath:
    """The end of a straight inertial tip path of a planar arm (Umetani & Yoshida 1990, section 3.1 (3-b)).

    Attributes:
        end_posture: ``(..., n+1)`` posture where the path ended, rad.
        end_tip: ``(..., 2)`` tip there, inertial frame (origin at the system centroid), m.
        length: ``(...)`` distance the tip travelled along the line, m.
        reason: ``(...)`` int32 why it ended: 0 = J* singular (the tip cannot advance along
            the line), 1 = max_length reached, 2 = joint limit, 3 = step budget exhausted
            (not converged; raise ``max_steps``).
        kinematic: ``(...)`` bool, True when the singular end is also a singularity of the
            fixed-base arm (for n = 2: phi2 at 0 or pi), False for a dynamic singularity.
        joint_arc: ``(...)`` joint-space arc length of the path, rad (the integration variable).
        steps: ``(...)`` int32 integration steps taken.
    """

    end_posture: jax.Array
    end_tip: jax.Array
    length: jax.Array
    reason: jax.Array
    kinematic: jax.Array
    joint_arc: jax.Array
    steps: jax.Array


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class SpatialStraightPath:
    """The end of a straight inertial tip path of a spatial arm.

    Attributes:
        end_joints: ``(..., n)`` joints where the path ended.
        end_rotation: ``(..., 3, 3)`` bus attitude there (bus axes -> inertial axes).
        end_tip: ``(..., 3)`` tip there, inertial axes, about the system centroid, m.
        length: ``(...)`` distance the tip travelled along the line, m.
        reason: ``(...)`` int32: 0 = J*_v lost rank (dynamic or kinematic singularity),
            1 = max_length reached, 2 = joint limit, 3 = step budget exhausted.
        fixed_manipulability: ``(...)`` the fixed-base w = sqrt det(J_v J_v^T) at the end
            (m^3): near 0 when the singular end is also a kinematic singularity.
        joint_arc: ``(...)`` joint-space arc length, rad (the integration variable).
        steps: ``(...)`` int32 accepted and rejected steps.
    """

    end_joints: jax.Array
    end_rotation: jax.Array
    end_tip: jax.Array
    length: jax.Array
    reason: jax.Array
    fixed_manipulability: jax.Array
    joint_arc: jax.Array
    steps: jax.Array


def _attitude_in_posture(robot, results):
    """Ends of a family whose posture carries the attitude (planar: phi = [phi0, joints])."""
    n = family_of(robot).joint_count(robot)
    posture = results["y"][:, : n + 1]
    reason = results["reason"]
    fixed_w = fixed_base_manipulability(robot, posture[:, 1:]) / robot.reach**2
    return StraightPath(
        end_posture=posture,
        end_tip=tip_position(robot, posture),
        length=results["y"][:, -1],
        reason=reason,
        kinematic=(reason == REASON_SINGULAR) & (fixed_w < 1e-6),
        joint_arc=results["arc"],
        steps=results["count"],
    )


def _attitude_beside_posture(robot, results, robot_batched):
    """Ends of a family whose attitude is a rotation beside the joints (spatial)."""
    family = family_of(robot)
    if "aux" in results:  # the fixed-base J_v and the tip from the field's last pass (``ends``)
        n = family.joint_count(robot)
        joints, coords = jax.vmap(lambda y: family.split_state(robot, y[:-1]))(results["y"])
        R = family.attitude.from_coords(coords)
        fixed_v = results["aux"][:, : 3 * n].reshape(-1, 3, n)
        return SpatialStraightPath(
            end_joints=joints,
            end_rotation=R,
            end_tip=jnp.einsum("pij,pj->pi", R, results["aux"][:, 3 * n :]),
            length=results["y"][:, -1],
            reason=results["reason"],
            fixed_manipulability=gram_root_determinant(fixed_v),
            joint_arc=results["arc"],
            steps=results["count"],
        )

    def one(robot, y):
        joints, coords = family.split_state(robot, y[:-1])
        R = family.attitude.from_coords(coords)
        both = family.fast_paths.tip_and_fixed_base_jacobian  # one chain pass for the two
        fixed, tip = both(robot, joints) if both else (fixed_base_jacobian(robot, joints), tip_position(robot, joints))
        return joints, R, R @ tip, gram_root_determinant(fixed[: family.translational_rows])

    joints, R, tip, fixed_w = jax.vmap(one, in_axes=(0 if robot_batched else None, 0))(robot, results["y"])
    return SpatialStraightPath(
        end_joints=joints,
        end_rotation=R,
        end_tip=tip,
        length=results["y"][:, -1],
        reason=results["reason"],
        fixed_manipulability=fixed_w,
        joint_arc=results["arc"],
        steps=results["count"],
    )


# The field ---------------------------------------------------------------------------------


def generic_straight_field(robot, direction: jax.Array, sign0, *, ends: bool = False):
    """The regularized straight-path field y' = f(y), y = [family state, s], of any family.

    Derivatives are with respect to the joint-space arc length sigma: the joint rates
    have unit norm, the attitude follows the family's attitude-rate map (eq. 5), the last
    entry is ds/dsigma. J*_v and the attitude-rate map come from one evaluation of the
    family's ``straight_maps`` (one pass over a spatial chain).

    ``ends`` (families with the fast path ``straight_maps_and_ends``): the field returns
    ``(slope, [fixed-base J_v (3 n), tip about the centroid (3)])``, bus axes, the end
    quantities of the path at y from the same chain pass, so the ends need no pass of
    their own.
    """
    family = family_of(robot)
    group = family.attitude
    rows = family.translational_rows

    def field(y):
        joints, coords = family.split_state(robot, y[:-1])
        if ends:
            maps, fixed_v, tip = family.fast_paths.straight_maps_and_ends(robot, joints)
            J, A = maps[:rows], maps[rows:]
        else:
            J, A = family.straight_maps(robot, joints)
        dq, ds = straight_path_rates(J, group.coords_matrix(coords).T @ direction, sign0)
        dg = group.rate(coords, A @ dq)
        slope = jnp.concatenate([family.join_state(robot, dq, dg), ds[None]])
        return (slope, jnp.concatenate([fixed_v.ravel(), tip])) if ends else slope

    return field


def _straight_field(robot, direction: jax.Array, sign0):
    """The family's closed-form field where it has one (chosen by type), else the generic one."""
    fast = family_of(robot).fast_paths.straight_path_field
    return (fast or generic_straight_field)(robot, direction, sign0)


def _ends_size(robot) -> int:
    """The aux vector of the field with ``ends`` (3 n: the fixed-base J_v, 3: the tip), or 0 where the
    family has no one-pass kernel for it (its ends then take a pass of their own)."""
    family = family_of(robot)
    if family.fast_paths.straight_maps_and_ends is None or not family.straight_field_loops:
        return 0
    return 3 * family.joint_count(robot) + 3


def _square(robot) -> bool:
    family = family_of(robot)
    return family.joint_count(robot) == family.translational_rows


def _start_sign(robot, joints) -> jax.Array:
    """sign(det J*_v) at the start for a square J*_v (+1 when exactly singular, or redundant)."""
    dtype = joints.dtype
    if not _square(robot):
        return jnp.asarray(1.0, dtype)
    J, _ = family_of(robot).straight_maps(robot, joints)
    return jnp.where(square_determinant(J) < 0, -1.0, 1.0).astype(dtype)


def _initial_sign(robot, phi) -> jax.Array:
    """sign(det J*) at the start of a planar path from its posture ``phi`` (n = 2)."""
    return _start_sign(robot, family_of(robot).split_state(robot, phi)[0])


def _lane_start(robot, joints, coords, direction, max_step):
    """Integration state at the start of one straight path (a dict of arrays)."""
    family = family_of(robot)
    dtype = joints.dtype
    direction = direction / jnp.linalg.norm(direction)
    sign0 = _start_sign(robot, joints)
    aux = _ends_size(robot)
    field = (
        generic_straight_field(robot, direction, sign0, ends=True) if aux else _straight_field(robot, direction, sign0)
    )
    y0 = jnp.concatenate([family.join_state(robot, joints, coords), jnp.zeros((1,), dtype)])
    params = {"direction": direction, "sign0": sign0}
    return start_lane(field, y0, max_step, params, rolled=family.straight_field_loops, aux=aux)


def _lane_step(robot, lane, max_length, max_step, tol, rtol, sing_rate, tip_tol, max_steps, *, tableau):
    family = family_of(robot)
    n = family.joint_count(robot)
    dtype = lane["y"].dtype
    direction, sign0 = lane["direction"], lane["sign0"]
    ends = "aux" in lane
    field = (
        generic_straight_field(robot, direction, sign0, ends=True) if ends else _straight_field(robot, direction, sign0)
    )
    lower = jnp.broadcast_to(robot.joint_lower, (n,)).astype(dtype)
    upper = jnp.broadcast_to(robot.joint_upper, (n,)).astype(dtype)
    return step_lane(
        field,
        lane,
        (family.posture_offset, n),
        lower,
        upper,
        square=_square(robot),
        max_length=max_length,
        max_step=max_step,
        tol=tol,
        rtol=rtol,
        sing_rate=sing_rate,
        max_steps=max_steps,
        tip_tol=tip_tol,
        tableau=tableau,
        rolled=family.straight_field_loops,
    )


@functools.partial(jax.jit, static_argnames=("robot_batched", "lanes", "tableau"))
def _straight_flat(
    robot,
    joints,
    coords,
    direction,
    max_length,
    max_step,
    tol,
    rtol,
    sing_rate,
    tip_tol,
    max_steps,
    real,
    robot_batched,
    lanes,
    tableau,
):
    """Integrate a padded batch of straight paths (the first ``real`` rows) on ``lanes`` lanes."""
    count = joints.shape[0]
    robot_axis = 0 if robot_batched else None

    def robot_for(index):
        return jax.tree_util.tree_map(lambda x: x[index], robot) if robot_batched else robot

    start = jax.vmap(_lane_start, in_axes=(robot_axis, 0, 0, 0, None))
    step = jax.vmap(
        functools.partial(_lane_step, tableau=tableau), in_axes=(robot_axis, 0, 0, None, None, None, None, None, None)
    )
    results = run_queue(
        lambda index: start(robot_for(index), joints[index], coords[index], direction[index], max_step),
        lambda index, lane: step(
            robot_for(index), lane, max_length[index], max_step, tol, rtol, sing_rate, tip_tol, max_steps
        ),
        count,
        min(lanes, count),
        real,
    )
    if family_of(robot).posture_offset:
        return _attitude_in_posture(robot, results)
    return _attitude_beside_posture(robot, results, robot_batched)


def _as_array(x, dtype):
    """``x`` as an array of ``dtype``: NumPy when concrete, ``jnp`` when traced."""
    return jnp.asarray(x, dtype) if is_traced(x) else np.asarray(x, dtype)


def _prepare_straight(robot, phi_start, direction, max_length):
    """Planar inputs as arrays, checked: ``(phi_start, direction, max_length)``."""
    family = family_of(robot)
    dtype = jnp.result_type(float)
    # Concrete inputs stay NumPy until the compiled kernel takes them: jnp.asarray of a
    # NumPy array compiles a small staging program per shape.
    phi_start, direction = (_as_array(x, dtype) for x in (phi_start, direction))
    n = family.joint_count(robot)
    name = "phi_start" if family.posture_offset else "q_start"
    check_arm_axis(robot, name, phi_start, n + family.posture_offset)
    space = family.attitude.space
    if direction.ndim < 1 or direction.shape[-1] != space:
        raise ConfigError(f"direction: expected shape (..., {space}), got {direction.shape}")
    if not is_traced(direction) and np.any(np.linalg.norm(np.asarray(direction), axis=-1) == 0):
        raise ConfigError("direction: must be a nonzero vector")
    max_length = _as_array(np.inf if max_length is None else max_length, dtype)
    if not is_traced(max_length) and np.any(np.asarray(max_length) < 0):
        raise ConfigError("max_length: must not be negative")
    return phi_start, direction, max_length


def _split_start(robot, posture, base_rotation):
    """``(joints (..., n), attitude coordinates (..., c))`` of the start, per family."""
    family = family_of(robot)
    group = family.attitude
    offset = family.posture_offset
    if offset:
        if base_rotation is not None:
            raise TypeError("base_rotation applies to spatial robots; a planar posture carries its base attitude")
        return posture[..., offset:], posture[..., :offset]
    dtype = posture.dtype
    if base_rotation is None:
        R0 = np.eye(group.space, dtype=dtype)
    else:
        R0 = _as_array(base_rotation, dtype)
        if R0.shape[-2:] != (group.space, group.space):
            raise ConfigError(f"base_rotation: expected shape (..., {group.space}, {group.space}), got {R0.shape}")
    return posture, R0.reshape(R0.shape[:-2] + (group.coords,))


def straight_tip_path(
    robot,
    phi_start: jax.Array,
    direction: jax.Array,
    *,
    max_length=None,
    max_step: float | None = None,
    tol: float | None = None,
    rtol: float | None = None,
    max_steps: int | None = None,
    tableau: str = "dop853",
    lanes: int | None = None,
    base_rotation: jax.Array | None = None,
    sing_rate: float | None = None,
    tip_tol: float | None = None,
):
    """Move the tip along a straight inertial line until J* loses rank (Fig. 3a), any family.

    Joint rates invert the Generalized Jacobian (eq. 6), minimum-norm for a redundant arm,
    and the base attitude follows eq. (5). Integration runs in joint-space arc length with
    the adjugate regularization (module docstring) and DOP853 steps of at most
    ``max_step`` rad sized by the embedded error estimate, shortened near an event; the
    end is located by Newton steps on the event functions to ``tol`` rad of joint arc.
    Batched over directions, initial postures and designs (all broadcast).

    Args:
        robot: the design (or a batch of designs).
        phi_start: planar: ``(..., n+1)`` initial posture, rad; spatial: ``(..., n)`` joints.
        direction: ``(..., 2)`` or ``(..., 3)`` direction of travel, inertial axes (normalized here).
        max_length: scalar or ``(...)`` length limit, m (None: none).
        max_step: largest integration step, rad of joint arc (None: 0.25 planar, 0.1 spatial).
        tol: event location tolerance, rad of joint arc (None: planar 1e-12 in float64,
            1e-5 in float32, where 1e-12 is below rounding and no step would pass; spatial 1e-11).
        rtol: local error tolerance of the DOP853 step controller (relative to 1 + |y|);
            ignored by "rk4", which takes fixed steps of ``max_step`` (None: planar as
            ``tol``, spatial 1e-12).
        max_steps: step budget per path (None: 4096 planar, 4000 spatial); paths that
            exhaust it get reason 3.
        tableau: "dop853" (8th order with its embedded error control, default) or "rk4"
            (fixed steps, a baseline; static).
        lanes: paths integrated side by side (static; None: `lane_count` of the
            padded batch, 64 to 512); a lane whose path ends takes the next one, so short
            paths do not wait for long ones (``lanes`` = the batch size is a plain vmap).
            The batch is padded to 512 paths or the next power of two (one compiled
            program per bucket, not per batch size); the padding is never integrated.
        base_rotation: spatial robots: ``(..., 3, 3)`` bus attitude at the start (bus axes ->
            inertial axes; default identity). A planar posture carries its base angle.
        sing_rate: spatial redundant arms: the path also ends (singular) once the tip
            advances less than this per radian of joint motion, m/rad (None: 1e-6; the
            minimum-norm flow of a redundant arm may approach rank loss only
            asymptotically). Planar paths have no such stall event.
        tip_tol: spatial redundant arms: the path also ends (singular) once ds/dsigma is
            flat and the tip travel it predicts up to the next joint limit is below this,
            m (None: 1e-3; `spacearm.motion.lanes.step_lane`): the UR5 can creep there
            for thousands of steps, moved only by the bus reaction to its last joint.

    Returns:
        `StraightPath` (planar) or `SpatialStraightPath` (spatial) with batch shape ``(...)``.
    """
    family = family_of(robot)
    phi_start, direction, max_length = _prepare_straight(robot, phi_start, direction, max_length)
    joints, coords = _split_start(robot, phi_start, base_rotation)
    batch, flat_robot, batched, (joints_flat, coords_flat, dir_flat, len_flat) = flatten_batch(
        robot, [(joints, 1), (coords, 1), (direction, 1), (max_length, 0)]
    )
    dtype = joints_flat.dtype
    settings = _integration_settings(
        family, dtype, max_step=max_step, tol=tol, rtol=rtol, sing_rate=sing_rate, tip_tol=tip_tol, max_steps=max_steps
    )
    if tableau not in ("dop853", "rk4"):
        raise ConfigError(f"tableau: unknown scheme {tableau!r}; use 'dop853' or 'rk4'")
    # One program for every batch of up to 512 paths, and one per power of two beyond:
    # the batch is padded (the padding is never integrated, see lanes.run_queue).
    count = joints_flat.shape[0]
    padded = bucket_size(count, minimum=PATH_BUCKET)
    if batched:
        flat_robot = pad_leading(flat_robot, padded)
    joints_flat, coords_flat, dir_flat, len_flat = pad_leading((joints_flat, coords_flat, dir_flat, len_flat), padded)
    out = _straight_flat(
        flat_robot,
        joints_flat,
        coords_flat,
        dir_flat,
        len_flat,
        *settings,
        np.int32(count),
        batched,
        lane_count(padded, lanes),
        tableau,
    )
    return unpad(out, count, batch)


def _integration_settings(family, dtype, **given) -> tuple:
    """`straight_tip_path`'s ``(max_step, tol, rtol, sing_rate, tip_tol, max_steps)`` as
    `_straight_flat` takes them: each as given, else the family's default
    (``family.straight_defaults``), else the dtype's tolerance (``tol``, ``rtol``) or no
    travel stall (``tip_tol``)."""
    defaults = family.straight_defaults
    default_tol = 1e-12 if jnp.finfo(dtype).bits >= 64 else 1e-5
    fallbacks = {"tol": default_tol, "rtol": default_tol, "tip_tol": -np.inf}

    def option(name):
        if given[name] is not None:
            return given[name]
        return fallbacks.get(name) if defaults.get(name) is None else defaults[name]

    floats = (_as_array(option(name), dtype) for name in ("max_step", "tol", "rtol", "sing_rate", "tip_tol"))
    return (*floats, np.int32(option("max_steps")))


def _history_one(robot, phi_start, direction, joint_arc, *, intervals, substeps, tableau):
    n = robot.n_links
    dtype = phi_start.dtype
    direction = direction / jnp.linalg.norm(direction)
    sign0 = _initial_sign(robot, phi_start) if n == 2 else jnp.asarray(1.0, dtype)
    field = _straight_field(robot, direction, sign0)
    h = joint_arc / (intervals * substeps)

    def advance(y, _):
        # A loop over the substeps rather than an unrolled body: the DOP853 stages are
        # already unrolled inside one step, so unrolling the substeps would only lengthen
        # compiles.
        y = jax.lax.fori_loop(0, substeps, lambda _, y: rk_step(field, y, h, tableau), y)
        return y, y

    y0 = jnp.concatenate([phi_start, jnp.zeros((1,), dtype)])
    _, ys = jax.lax.scan(advance, y0, None, length=intervals)
    ys = jnp.concatenate([y0[None], ys], axis=0)
    postures = ys[:, : n + 1]
    return postures, tip_position(robot, postures)


@functools.partial(jax.jit, static_argnames=("robot_batched", "intervals", "substeps", "tableau"))
def _history_flat(robot, phi_start, direction, joint_arc, robot_batched, intervals, substeps, tableau):
    one = functools.partial(_history_one, intervals=intervals, substeps=substeps, tableau=tableau)
    return jax.vmap(one, in_axes=(0 if robot_batched else None, 0, 0, 0))(robot, phi_start, direction, joint_arc)


def compile_straight_tip_path_history(
    robot, count: int = 1, n_samples: int = 101, *, substeps: int = 4, tableau: str = "dop853"
) -> None:
    """Compile, without running, the sampler `straight_tip_path_history` uses for
    ``count`` paths of one design; a later call with those sizes finds the program.

    XLA compiles outside Python's GIL, so a caller can compile this on a second core (in
    a thread) while it integrates the paths it will sample (``planning.plan_reach`` does).
    """
    dtype = jnp.result_type(float)
    padded = bucket_size(count)
    n = robot.n_links
    shapes = [jax.ShapeDtypeStruct(shape, dtype) for shape in ((padded, n + 1), (padded, 2), (padded,))]
    _history_flat.lower(shapes_of(robot), *shapes, False, int(n_samples) - 1, int(substeps), tableau).compile()


def straight_tip_path_history(
    robot,
    phi_start: jax.Array,
    direction: jax.Array,
    n_samples: int = 101,
    *,
    max_length=None,
    substeps: int = 4,
    **options,
) -> tuple[jax.Array, jax.Array]:
    """Postures and inertial tips along a straight tip path, for plots (Fig. 3a, 9).

    Finds the end with `straight_tip_path` (``options`` are passed on), then
    samples the path at ``n_samples`` points equally spaced in joint-space arc length.
    Planar arms only (another family raises TypeError; a spatial arm's samples come from
    `spacearm.motion.spatial_go_and_back`).

    Returns:
        ``postures (..., n_samples, n+1)`` rad and ``tips (..., n_samples, 2)`` m, inertial.
    """
    require_family(robot, "planar", "straight_tip_path_history")
    if n_samples < 2:
        raise ConfigError("n_samples: must be at least 2")
    path = straight_tip_path(robot, phi_start, direction, max_length=max_length, **options)
    phi_start, direction, _ = _prepare_straight(robot, phi_start, direction, max_length)
    batch, flat_robot, batched, (phi_flat, dir_flat, arc_flat) = flatten_batch(
        robot, [(phi_start, 1), (direction, 1), (path.joint_arc, 0)]
    )
    count = phi_flat.shape[0]
    padded = bucket_size(count)  # one program per power of two of paths
    if batched:
        flat_robot = pad_leading(flat_robot, padded)
    phi_flat, dir_flat, arc_flat = pad_leading((phi_flat, dir_flat, arc_flat), padded)
    postures, tips = _history_flat(
        flat_robot,
        phi_flat,
        dir_flat,
        arc_flat,
        batched,
        int(n_samples) - 1,
        int(substeps),
        options.get("tableau", "dop853"),
    )
    return unpad((postures, tips), count, batch)


def go_and_back(
    robot,
    phi_start: jax.Array,
    direction: jax.Array,
    distance,
    n_samples: int = 51,
    **options,
) -> tuple[jax.Array, jax.Array, jax.Array]:
    """A small go-and-back tip motion: out along ``direction`` by ``distance``, then back (Fig. 9).

    Planar arms only (another family raises TypeError; a spatial arm's is
    `spacearm.motion.spatial_go_and_back`).

    Args:
        phi_start: ``(..., n+1)`` initial posture, rad.
        direction: ``(..., 2)`` inertial direction of the outward leg.
        distance: scalar or ``(...)`` leg length, m.

    Returns:
        ``postures (..., 2 n_samples - 1, n+1)``, ``tips (..., 2 n_samples - 1, 2)`` (out then
        back, the turning point shared) and ``travelled (..., 2 n_samples - 1)``, the tip's
        cumulative path length, m. Each leg stops early at a singularity of J*.
    """
    require_family(robot, "planar", "go_and_back")
    direction = jnp.asarray(direction, jnp.result_type(float))
    out_postures, out_tips = straight_tip_path_history(
        robot, phi_start, direction, n_samples, max_length=distance, **options
    )
    back_postures, back_tips = straight_tip_path_history(
        robot, out_postures[..., -1, :], -direction, n_samples, max_length=distance, **options
    )
    postures = jnp.concatenate([out_postures, back_postures[..., 1:, :]], axis=-2)
    tips = jnp.concatenate([out_tips, back_tips[..., 1:, :]], axis=-2)
    steps = jnp.linalg.norm(jnp.diff(tips, axis=-2), axis=-1)
    travelled = jnp.concatenate([jnp.zeros_like(steps[..., :1]), jnp.cumsum(steps, axis=-1)], axis=-1)
    return postures, tips, travelled
