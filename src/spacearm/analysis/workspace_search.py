"""Workspaces of any robot family by search over the joint box.

The paper's workspaces in 3-D (Umetani & Yoshida 1990, sec. 3, and Papadopoulos &
Dubowsky 1993). All radii are tip distances from the system centroid, which zero
momentum keeps fixed in space; a bus rotation turns the tip about the centroid, and
cyclic joint motions inside the box turn the bus by any rotation, so every workspace
below is a spherical shell (planar: an annulus) described by radii.

- Maximum Reachable Space (Area 3): the shell between the smallest and the largest
  |tip| over the joint box. Found by batched multi-start projected gradient ascent
  (Adam steps in the unit-cube coordinates of the box, revolute joints that cover a
  turn wrapped, limited ones clipped; all starts in one ``vmap``-ed ``jit``).
  Differentiable in the design by the envelope theorem: the returned radius is |tip|
  at the optimizer's joints held fixed (``stop_gradient``), the box map included, so
  the derivative with respect to a limit that binds is kept.
- Dynamic singular set: postures where the translational Generalized Jacobian J*_v
  loses rank (det J*_v = 0 for a square J*_v, sigma_min(J*_v) = 0 otherwise).
  Sampled on Sobol points of the joint box, then the ``keep`` samples closest to it
  (smallest |s|, s the signed determinant or sigma_min) are moved onto it by Newton
  projection, q <- q - s grad s / |grad s|^2.
- Path-independent workspace (Papadopoulos & Dubowsky): the sphere about the centroid
  that no dynamic-singular tip position enters; its radius is min |tip| over the
  singular set, found by sampling, then descent of |tip|^2 along the singular set
  (tangent steps, each followed by Newton projection back onto it), optionally Newton
  steps on the KKT system at the best posture; differentiable in the design by the
  envelope theorem of the constrained minimum (the set's motion enters through its
  multipliers).
- Guaranteed Workspace (Area 5) in 3-D: the shell between the inner reachable radius
  and the path-independent radius (empty if the first exceeds the second). Beside it
  the analogue of eq. (8): the same search over the *kinematic* singular set (the
  fixed-base J_v losing rank), the paper's argument. For a planar two-link arm the
  kinematic value is min(|K0 - (K1 + K2)|, |K0 - |K1 - K2||) (eq. 8 and its folded
  branch, `kinematic_singularity_radius`), and
  the dynamic one `path_independent_radius`.

Every search here is single-design (``vmap`` it for batches). Sample counts are static
(they are shapes); step counts and seeds are traced, so new values reuse the program.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .._core.batching import bucket_size
from .._core.errors import ConfigError
from ..kinematics import fixed_base_jacobian, generalized_jacobian, square_determinant, tip_position
from ..models.family import family_of
from ..motion.spatial_paths import spatial_straight_tip_path
from .joint_box import (
    box_postures,
    check_joint_box,
    digital_shifts,
    joint_box,
    periodic_joints,
    sobol_direction_numbers,
    sobol_points,
)

__all__ = [
    "GuaranteedWorkspace",
    "ReachableRadii",
    "SingularPostures",
    "StraightPathWorkspace",
    "guaranteed_workspace",
    "icosphere_directions",
    "maximum_reachable_inner_radius",
    "maximum_reachable_radius",
    "path_independent_radius",
    "reachable_radii",
    "singular_postures",
    "singular_radius",
    "singularity_measure",
    "spatial_straight_path_workspace",
]


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class ReachableRadii:
    """The Maximum Reachable shell about the system centroid.

    Attributes:
        inner, outer: smallest and largest |tip| over the joint box, m.
        joints_inner, joints_outer: ``(n,)`` joint positions where they occur.
    """

    inner: jax.Array
    outer: jax.Array
    joints_inner: jax.Array
    joints_outer: jax.Array


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class SingularPostures:
    """Postures on a singular set, refined by Newton projection.

    Attributes:
        joints: ``(k, n)`` joint positions.
        residual: ``(k,)`` |s| after refinement (s: det J_v or sigma_min(J_v), m^t or m).
        on_set: ``(k,)`` bool: the refinement converged (|s| <= tol times the median
            |s| of the samples; tol 1e-9 for det J_v, 1e-6 for sigma_min, which comes
            from the square root of an eigenvalue and bottoms out near sqrt(eps)).
        radius: ``(k,)`` |tip| about the system centroid, m.
        tip: ``(k, d)`` tip about the centroid, bus (robot) axes, m.
        tolerance: the absolute bound on |s| that ``on_set`` used.
    """

    joints: jax.Array
    residual: jax.Array
    on_set: jax.Array
    radius: jax.Array
    tip: jax.Array
    tolerance: jax.Array


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class GuaranteedWorkspace:
    """The 3-D Guaranteed Workspace and its eq.-(8) analogue, radii about the centroid, m.

    Attributes:
        inner: the inner reachable radius (the shell's hole).
        path_independent: min |tip| over the dynamic singular set (Papadopoulos & Dubowsky).
        kinematic: min |tip| over the kinematic (fixed-base) singular set: eq. (8)'s argument.
        outer: the outer reachable radius.
        empty: bool, no point is both reachable and inside the singularity-free sphere
            (path_independent <= inner, to 1e-9 of the outer radius).

    Note: where |tip| has an interior extremum over the joint box, p^T J*_v = 0 there,
    so J*_v is singular: a hole whose nearest posture is not at a joint limit is
    bounded by singular tips, and the sphere is empty (the UR5 on its smallsat). Then
    the path-independent regions are the radial gaps between the shells that singular
    tips sweep (Papadopoulos & Dubowsky), visible in ``spatial_shells``; this record
    gives only the innermost sphere.
    """

    inner: jax.Array
    path_independent: jax.Array
    kinematic: jax.Array
    outer: jax.Array
    empty: jax.Array


# Maximum Reachable Space ---------------------------------------------------------------


def _wraps(robot):
    """``(n,)`` bool: the joint's box coordinate is periodic (a revolute joint covering one turn)."""
    lower, upper = joint_box(robot)
    return jnp.asarray(periodic_joints(robot)) & (upper - lower >= 2.0 * jnp.pi * (1.0 - 1e-12))


def _project(u, wraps):
    return jnp.where(wraps, jnp.mod(u, 1.0), jnp.clip(u, 0.0, 1.0))


def _start_points(robot, starts: int, seed: int):
    n = family_of(robot).joint_count(robot)
    shift = digital_shifts(seed, 1, n)
    return sobol_points(jnp.asarray(sobol_direction_numbers(n)), 0, starts, shift)[0]


def _adam_search(objective, u0, wraps, steps: int, rate: float, *rows):
    """Minimize ``objective(u, *row)`` from each row of ``u0`` (with the matching rows of
    ``rows``) by projected Adam with a cosine-decaying rate.

    Returns the end points and the objective there: one more pass of the loop evaluates
    them (no step), so the program holds one copy of the objective and its gradient."""
    value_and_grad = jax.vmap(jax.value_and_grad(objective))
    b1, b2, eps = 0.9, 0.999, 1e-12

    def step(k, state):
        u, m, v, _ = state
        f, g = value_and_grad(u, *rows)
        m = b1 * m + (1 - b1) * g
        v = b2 * v + (1 - b2) * g * g
        t = (k + 1).astype(u.dtype)
        lr = rate * (1e-4 + (1 - 1e-4) * 0.5 * (1 + jnp.cos(jnp.pi * k / steps)))
        moved = _project(u - lr * (m / (1 - b1**t)) / (jnp.sqrt(v / (1 - b2**t)) + eps), wraps)
        return jnp.where(k < steps, moved, u), m, v, f

    zeros = jnp.zeros_like(u0)
    u, _, _, f = jax.lax.fori_loop(0, steps + 1, step, (u0, zeros, zeros, jnp.zeros(u0.shape[:1], u0.dtype)))
    return u, f


@functools.partial(jax.jit, static_argnames=("start_room",))
def _reachable(robot, starts, steps, seed, rate, *, start_room: int):
    """Both radii from ``starts`` Sobol starts (traced: the search holds ``start_room`` rows,
    a power of two, whose rows past ``starts`` copy the first start and are never picked)."""
    wraps = _wraps(robot)
    real = jnp.arange(start_room) < starts
    u0 = _start_points(robot, start_room, seed)
    u0 = jnp.where(real[:, None], u0, u0[:1])
    # The search runs on the design with its gradient stopped (its step count is a traced
    # loop bound); the radius below is differentiable at the optimizer (envelope theorem).
    fixed = jax.tree_util.tree_map(jax.lax.stop_gradient, robot)

    def radius_sq(u):
        return jnp.sum(tip_position(fixed, box_postures(fixed, u)) ** 2)

    lower, upper = joint_box(robot)
    # Both searches in one loop (one copy of the chain pass and its gradient to compile):
    # the first ``starts`` rows minimize |tip|^2 (inner), the others maximize it (outer).
    signs = jnp.repeat(jnp.array([-1.0, 1.0], u0.dtype), start_room)
    u, f = _adam_search(lambda u, sign: -sign * radius_sq(u), jnp.concatenate([u0, u0]), wraps, steps, rate, signs)
    u, ends = jax.lax.stop_gradient(u), jax.lax.stop_gradient(-signs * f).reshape(2, start_room)  # |tip|^2 at the ends
    pick = jnp.argmax(jnp.where(real, signs.reshape(2, start_room) * ends, -jnp.inf), axis=1)
    best = u.reshape(2, start_room, -1)[jnp.arange(2), pick]
    # Envelope theorem: the radii at the optimizers' box coordinates, differentiable in the
    # design and the limits (through the box map); the program evaluates the tip again
    # only where the radii are differentiated (`_with_value`).
    squared = _with_value(lambda r, p, _: jnp.sum(tip_position(r, box_postures(r, p)) ** 2, axis=-1))(
        robot, best, (), ends[jnp.arange(2), pick]
    )
    positive = squared > 0
    radius = jnp.where(positive, jnp.sqrt(jnp.where(positive, squared, 1.0)), 0.0)
    joints = lower + (upper - lower) * best
    return ReachableRadii(radius[0], radius[1], joints[0], joints[1])


def reachable_radii(robot, *, starts: int = 128, steps: int = 400, seed: int = 0, rate: float = 0.05) -> ReachableRadii:
    """The Maximum Reachable shell of one design (either family), by multi-start search.

    Args:
        robot: one design (``vmap`` for batches).
        starts: Sobol starting points in the joint box. A traced size: every count
            between the same two consecutive powers of two runs one program, which
            searches from the larger (the extra starts copy the first and are never
            picked), so a count just past a power of two costs up to twice the work.
        steps: projected Adam steps per start (cosine-decaying rate from ``rate``, in
            unit-box coordinates).

    Returns:
        `ReachableRadii`. For planar arms without limits the radii equal the
        closed forms K0+..+Kn and max(0, 2 max K - sum K) (tests/test_spatial_workspaces.py).
    """
    check_joint_box(robot)
    starts = int(starts)
    if starts < 1:
        raise ConfigError(f"starts: at least 1, got {starts}")
    return _reachable(robot, np.int32(starts), steps, seed, rate, start_room=bucket_size(starts))


def maximum_reachable_radius(robot, **options) -> jax.Array:
    """Area 3's outer radius about the system centroid, m (the public ``sa.maximum_reachable_radius``).

    The family's closed form where it has one (planar: K0 + K1 + .. + Kn, sec. 3.1 (3-a));
    otherwise the largest |tip| over the joint box, by `reachable_radii`.
    """
    closed = family_of(robot).fast_paths.reachable_radii
    if closed is not None:
        return closed(robot)[0]
    return reachable_radii(robot, **options).outer


def maximum_reachable_inner_radius(robot, **options) -> jax.Array:
    """Area 3's hole (smallest |tip| over the joint box), m; the family's closed form where it has one."""
    closed = family_of(robot).fast_paths.reachable_radii
    if closed is not None:
        return closed(robot)[1]
    return reachable_radii(robot, **options).inner


# Singular sets ---------------------------------------------------------------------------


def _joints_to_posture(robot, joints):
    offset = family_of(robot).posture_offset
    if not offset:
        return joints
    return jnp.concatenate([jnp.zeros(joints.shape[:-1] + (offset,), joints.dtype), joints], axis=-1)


def singularity_measure(robot, joints: jax.Array, jacobian: str = "generalized") -> jax.Array:
    """s(q): zero exactly where the translational Jacobian loses rank.

    Args:
        robot: one design.
        joints: ``(..., n)`` joint positions (planar: without phi0).
        jacobian: "generalized" (J*_v, dynamic singularities) or "fixed_base" (J_v,
            kinematic singularities).

    Returns:
        ``(...)``: det J_v for a square J_v (t = n; signed, so it changes sign across
        the set), else sigma_min(J_v) >= 0 (m/rad).
    """
    if jacobian not in ("generalized", "fixed_base"):
        raise ValueError(f"jacobian: 'generalized' or 'fixed_base', got {jacobian!r}")
    return _measure_of(_translational(robot, joints, jacobian))


def _measure_of(J):
    """s of `singularity_measure` from ``(..., t, n)`` J_v: det J_v (t = n <= 3), else sigma_min."""
    if J.shape[-1] == J.shape[-2] and J.shape[-1] <= 3:
        return square_determinant(J)
    smallest = jnp.linalg.eigvalsh(J @ jnp.swapaxes(J, -1, -2))[..., 0]
    positive = smallest > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, smallest, 1.0)), 0.0)


def _tip_radius_sq(robot, joints):
    return jnp.sum(tip_position(robot, _joints_to_posture(robot, joints)) ** 2, axis=-1)


def _translational(robot, joints, jacobian):
    t = family_of(robot).translational_rows
    if jacobian == "generalized":
        return generalized_jacobian(robot, _joints_to_posture(robot, joints))[..., :t, :]
    return fixed_base_jacobian(robot, joints)[..., :t, :]


def _jacobian_and_tip(robot, joints, jacobian):
    """``(..., t, n)`` J_v and ``(..., d)`` tip about the centroid; one chain pass where the family has one for both."""
    family = family_of(robot)
    both = family.fast_paths.tip_and_generalized_jacobian if jacobian == "generalized" else None
    if both is not None:
        J, tip = both(robot, joints)
        return J[..., : family.translational_rows, :], tip
    return _translational(robot, joints, jacobian), tip_position(robot, _joints_to_posture(robot, joints))


def _jet(robot, x, jacobian):
    """J_v, tip and their derivatives at the rows of ``x (k, n)``, by forward mode.

    Returns ``(J (k, t, n), tip (k, d), dJ (k, t, n, n), dtip (k, d, n))``, the last
    axis of a derivative the joint it is taken along. The n tangents ride along ONE
    evaluation (one chain pass for the spatial family) as n copies of the rows, each
    copy moved along one joint: every array of the pass then has one shape, primal and
    tangent alike, which compiles to fewer, larger fused loops than a ``vmap`` over
    the tangents (and runs as fast).
    """
    k, n = x.shape
    copies = jnp.tile(x, (n, 1))  # (n k, n): block j is moved along joint j
    along = jnp.repeat(jnp.eye(n, dtype=x.dtype), k, axis=0)
    (J, tip), (dJ, dtip) = jax.jvp(lambda y: _jacobian_and_tip(robot, y, jacobian), (copies,), (along,))

    def per_joint(d):  # (n k, ...) -> (k, ..., n)
        return jnp.moveaxis(d.reshape((n, k) + d.shape[1:]), 0, -1)

    return J[:k], tip[:k], per_joint(dJ), per_joint(dtip)


def _refine(robot, x, jacobian, first, steps, length, lower, upper, wraps):
    """Tangent step (optional) then Newton projection of the rows of ``x`` onto the singular set.

    One loop whose body evaluates `_jet` once: iteration 0 (run when ``first`` is 0)
    moves each row a distance ``length`` along the descent direction of |tip|^2 within
    the set's tangent plane; iterations 1..``steps`` are projection steps (see
    `_newton_project`); iteration ``steps + 1`` only evaluates. Returns the rows, and
    s and |tip|^2 at them.

    Square J_v (t = n): Newton steps on the scalar s = det J_v along its gradient.
    Redundant J_v (t < n): rank loss is codimension n - t + 1 > 1 and sigma_min is not
    smooth enough for scalar Newton to converge fast; instead Gauss-Newton
    (minimum-norm steps) on the system J_v(q)^T u = 0, |u|^2 = 1 in the unknowns (q, u),
    u the left null direction (started at the smallest left singular vector of J_v at
    iteration 1): quadratic convergence onto the set.
    """
    k, n = x.shape
    t = family_of(robot).translational_rows
    square = n == t

    def evaluate(x):
        """s and its gradient from the jet; sigma_min's by the eigenvalue derivative
        d lambda = v^T d(J J^T) v, with the eigenvector v that also starts u."""
        J, tip, dJ, dtip = _jet(robot, x, jacobian)
        if square:
            s, ds = jax.vmap(lambda d: jax.jvp(_measure_of, (J,), (d,)), in_axes=-1, out_axes=(None, -1))(dJ)
            return tip, dJ, dtip, J, s, ds, None
        values, vectors = jnp.linalg.eigh(J @ jnp.swapaxes(J, -1, -2))
        smallest, v = values[..., 0], vectors[..., 0]
        positive = smallest > 0
        s = jnp.where(positive, jnp.sqrt(jnp.where(positive, smallest, 1.0)), 0.0)
        d_smallest = 2.0 * jnp.einsum("kjm,kj->km", jnp.einsum("ki,kijm->kjm", v, dJ), jnp.einsum("kij,ki->kj", J, v))
        ds = jnp.where(positive[:, None], d_smallest / (2.0 * jnp.where(positive, s, 1.0))[:, None], 0.0)
        return tip, dJ, dtip, J, s, ds, v

    def tangent_step(x, tip, dtip, ds):
        g = 2.0 * jnp.einsum("kd,kdn->kn", tip, dtip)  # grad |tip|^2
        nn = jnp.sum(ds * ds, axis=-1, keepdims=True)
        tangent = g - jnp.sum(g * ds, axis=-1, keepdims=True) * ds / jnp.where(nn > 0, nn, 1.0)
        size = jnp.linalg.norm(tangent, axis=-1, keepdims=True)
        return x - length * tangent / jnp.where(size > 0, size, 1.0)

    def newton_step(x, s, ds):
        norm_sq = jnp.sum(ds * ds, axis=-1, keepdims=True)
        ok = norm_sq > 0
        return x - jnp.where(ok, s[:, None] * ds / jnp.where(ok, norm_sq, 1.0), 0.0)

    def gauss_newton(q, u, J, dJ):
        G = jnp.concatenate([J.T @ u, 0.5 * (jnp.sum(u * u) - 1.0)[None]])
        A = jnp.block([[jnp.einsum("i,ijk->jk", u, dJ), J.T], [jnp.zeros((1, n), q.dtype), u[None]]])  # (n+1, n+t)
        gram = A @ A.T
        damping = 1e-14 * jnp.trace(gram) / gram.shape[0]
        dz = A.T @ jnp.linalg.solve(gram + damping * jnp.eye(gram.shape[0], dtype=gram.dtype), G)
        return q - dz[:n], u - dz[n:]

    def body(state):
        i, x, u, _, _ = state
        tip, dJ, dtip, J, s, ds, v = evaluate(x)
        if square:
            projected, u_next = newton_step(x, s, ds), u
        else:
            u = jnp.where(i == 1, v, u)
            projected, u_next = jax.vmap(gauss_newton)(x, u, J, dJ)
        projected = jnp.where(wraps, projected, jnp.clip(projected, lower, upper))
        x_next = jnp.where(i == 0, tangent_step(x, tip, dtip, ds), jnp.where(i <= steps, projected, x))
        return i + 1, x_next, u_next, s, jnp.sum(tip * tip, axis=-1)

    zeros = jnp.zeros((k,), x.dtype)
    state = (jnp.asarray(first), x, jnp.zeros((k, t), x.dtype), zeros, zeros)
    _, x, _, s, radius_sq = jax.lax.while_loop(lambda state: state[0] <= steps + 1, body, state)
    return x, s, radius_sq


def _newton_project(robot, joints, jacobian, steps, lower, upper, wraps):
    """Move each row of ``joints`` onto the singular set (clipped to the box), by `_refine`'s projection."""
    return _refine(robot, joints, jacobian, 1, steps, 0.0, lower, upper, wraps)[0]


def _checked_sizes(samples, keep) -> tuple[int, int]:
    """``samples`` and ``keep`` of a singular-set search as ints, ``1 <= keep <= samples``."""
    samples, keep = int(samples), int(keep)
    if not 1 <= keep <= samples:
        raise ConfigError(f"keep: from 1 to samples ({samples}) postures, got {keep}")
    return samples, keep


@functools.partial(jax.jit, static_argnames=("jacobian", "keep", "sample_room"))
def _singular_postures(robot, jacobian, samples, keep, newton_steps, seed, tol, *, sample_room):
    """``samples`` is traced (``sample_room`` rows, a power of two; the rows past it are never kept);
    ``keep`` is the result's row count (static)."""
    n = family_of(robot).joint_count(robot)
    lower, upper = joint_box(robot)
    wraps = _wraps(robot)
    unit = sobol_points(jnp.asarray(sobol_direction_numbers(n)), 0, sample_room, digital_shifts(seed, 1, n))[0]
    real = jnp.arange(sample_room) < samples
    joints = lower + (upper - lower) * unit
    joints = jnp.where(real[:, None], joints, joints[:1])  # rows past the samples: copies of the first
    # Rows past the samples are NaN: top_k ranks them last (after any real NaN), the median skips them.
    absolute = jnp.where(real, jnp.abs(singularity_measure(robot, joints, jacobian)), jnp.nan)
    scale = _median_of_first(absolute, jnp.asarray(samples))
    _, nearest = jax.lax.top_k(-absolute, keep)
    q = _newton_project(robot, joints[nearest], jacobian, newton_steps, lower, upper, wraps)
    residual = jnp.abs(singularity_measure(robot, q, jacobian))
    tip = tip_position(robot, _joints_to_posture(robot, q))
    tolerance = tol * scale
    return SingularPostures(q, residual, residual <= tolerance, jnp.linalg.norm(tip, axis=-1), tip, tolerance)


def singular_postures(
    robot,
    jacobian: str = "generalized",
    *,
    samples: int = 2**14,
    keep: int = 2048,
    newton_steps: int = 16,
    seed: int = 0,
    tol: float | None = None,
) -> SingularPostures:
    """The dynamic (``"generalized"``) or kinematic (``"fixed_base"``) singular set, sampled then refined.

    ``samples`` Sobol points of the joint box; the ``keep`` with the smallest |s| are
    moved onto s = 0 by ``newton_steps`` Newton projections (see
    `singularity_measure`). Rows with ``on_set`` False did not converge (for
    example where the set meets a joint limit); discard them. ``samples`` is a traced
    size: every count between the same two consecutive powers of two runs one program,
    which evaluates s at the larger count of points (the extra ones are never kept);
    ``keep`` fixes the result's shape.
    """
    check_joint_box(robot)
    samples, keep = _checked_sizes(samples, keep)
    if tol is None:
        tol = 1e-9 if family_of(robot).joint_count(robot) == family_of(robot).translational_rows else 1e-6
    return _singular_postures(
        robot, jacobian, np.int32(samples), keep, newton_steps, seed, tol, sample_room=bucket_size(samples)
    )


def _kkt_polish(robot, best, free, jacobian, lower, upper, wraps, steps: int = 3):
    """Newton steps on the KKT system of min |tip| over the singular set, from ``best``.

    The set in the form `_refine` projects with, g(q, u) = (J_v(q)^T u, (|u|^2 - 1) / 2) = 0,
    u the left null direction of J_v (square and redundant J_v alike). Stationarity of the
    Lagrangian |tip| - mu . J_v^T u - nu (|u|^2 - 1) / 2 in (q, u), with g = 0, is solved
    for (q, u, mu, nu) by Newton's method: its Hessian in q by central differences of the
    jet (`_jet` at the 2n + 1 rows q, q +- h e_k in one pass), everything else exact.
    Joints on a limit (``free`` False) stay where they are. The descent before leaves the
    posture ~1e-5 rad from the minimum, which the multipliers (hence the gradient) feel to
    first order; two or three Newton steps take it to rounding.

    Returns:
        ``(q (n,), u (t,), multipliers (n + 1,), accepted)``: the polished posture and the
        least-squares multipliers there, or the posture as given and its multipliers where
        Newton did not reduce the KKT residual or left the box (``accepted`` False).
    """
    fixed = jax.tree_util.tree_map(jax.lax.stop_gradient, robot)
    n, t = best.shape[-1], family_of(robot).translational_rows
    dtype = best.dtype
    h = float(jnp.finfo(dtype).eps) ** (1.0 / 3.0)
    eye = jnp.eye(n, dtype=dtype)
    offsets = jnp.concatenate([jnp.zeros((1, n), dtype), h * eye, -h * eye]) * free

    def evaluate(q, u, first):
        J, tip, dJ, dtip = _jet(fixed, q[None] + offsets, jacobian)
        u = jnp.where(first, jnp.linalg.eigh(J[0] @ J[0].T)[1][:, 0], u)
        grad_r = jnp.einsum("kd,kdn->kn", tip, dtip) / jnp.sqrt(jnp.sum(tip * tip, axis=-1))[:, None] * free
        A_q = jnp.einsum("i,kijm->kjm", u, dJ) * free  # d(J_v^T u)_j / dq_m at each row
        A = jnp.block([[A_q[0], J[0].T], [jnp.zeros((1, n), dtype), u[None]]])  # (n + 1, n + t)
        gram = A @ A.T
        damping = 1e-14 * jnp.trace(gram) / (n + 1)
        rhs = A @ jnp.concatenate([grad_r[0], jnp.zeros((t,), dtype)])
        multipliers = jnp.linalg.solve(gram + damping * jnp.eye(n + 1, dtype=dtype), rhs)
        return J[0], dJ[0], u, grad_r, A_q, multipliers

    def residual(J, u, grad_r0, A_q0, mu, nu):
        return jnp.concatenate([grad_r0 - A_q0.T @ mu, -J @ mu - nu * u, J.T @ u, (0.5 * (u @ u - 1.0))[None]])

    def body(i, state):
        q, u, lam, _, lam0, norm0, _ = state
        J, dJ, u, grad_r, A_q, lam_ls = evaluate(q, u, i == 0)
        lam = jnp.where(i == 0, lam_ls, lam)
        mu, nu = lam[:n], lam[n]
        F = residual(J, u, grad_r[0], A_q[0], mu, nu)
        gradient_l = grad_r - jnp.einsum("kjm,j->km", A_q, mu)  # d Lagrangian / dq at each row
        H = (gradient_l[1 : n + 1] - gradient_l[n + 1 :]) / (2.0 * h)
        H = 0.5 * (H + H.T)
        H = jnp.where(free[:, None] & free[None, :], H, eye)
        M = -jnp.einsum("ijk,j->ki", dJ, mu) * free[:, None]  # d(-J mu)/dq, transposed
        K = jnp.block(
            [
                [H, M, -A_q[0].T, jnp.zeros((n, 1), dtype)],
                [M.T, -nu * jnp.eye(t, dtype=dtype), -J, -u[:, None]],
                [A_q[0], J.T, jnp.zeros((n, n + 1), dtype)],
                [jnp.zeros((1, n), dtype), u[None], jnp.zeros((1, n + 1), dtype)],
            ]
        )
        # Minimum-norm steps: a joint that does not move the tip (the UR5's last) leaves K
        # singular, and a plain solve would swing it along the null direction.
        delta = jnp.linalg.lstsq(K, -F, rcond=float(jnp.finfo(dtype).eps) ** 0.6)[0]
        step = i < steps  # the last iteration only evaluates
        norm_now = jnp.linalg.norm(F)
        return (
            jnp.where(step, q + delta[:n] * free, q),
            jnp.where(step, u + delta[n : n + t], u),
            jnp.where(step, lam + delta[n + t :], lam_ls),
            lam_ls,
            jnp.where(i == 0, lam_ls, lam0),
            jnp.where(i == 0, norm_now, norm0),
            norm_now,
        )

    zero = jnp.zeros((), dtype)
    state = (best, jnp.zeros((t,), dtype), jnp.zeros((n + 1,), dtype), jnp.zeros((n + 1,), dtype))
    state = jax.lax.fori_loop(0, steps + 1, body, (*state, jnp.zeros((n + 1,), dtype), zero, zero))
    q, u, _, lam, lam0, norm0, norm = state
    inside = jnp.all(wraps | ((q >= lower) & (q <= upper)))
    accepted = jnp.isfinite(norm) & (norm <= norm0) & inside & jnp.all(jnp.abs(q - best) <= 0.05)
    J0 = _translational(fixed, best, jacobian)
    u0 = jnp.linalg.eigh(J0 @ J0.T)[1][:, 0]
    return jnp.where(accepted, q, best), jnp.where(accepted, u, u0), jnp.where(accepted, lam, lam0), accepted


def _with_value(expression):
    """``expression(robot, posture, constants)`` as a function of ``(robot, posture,
    constants, value)`` whose value is ``value`` (the same number, computed already) and
    whose derivatives in the robot and the posture are the expression's: the program
    evaluates the expression (its passes over the chain) only where it is differentiated."""

    @jax.custom_jvp
    def function(robot, posture, constants, value):
        return value

    @function.defjvp
    def function_jvp(primals, tangents):
        robot, posture, constants, value = primals
        d_robot, d_posture = tangents[:2]
        _, tangent = jax.jvp(lambda r, p: expression(r, p, constants), (robot, posture), (d_robot, d_posture))
        return value, tangent

    return function


def _closest_value(robot, q, radius_sq, jacobian, lower, upper, wraps, polish: bool, posture_radius_sq):
    """The smallest radius over the rows of ``q`` (``radius_sq`` their |tip|^2, inf off the set),
    differentiable in the design, and its posture (``polish``: `_polished_value`, static).

    ``posture_radius_sq``: |tip|^2 at the chosen posture (the best row with its joints
    near a limit moved onto it) as the search evaluated it (unused with ``polish``): the
    value is its square root, and only the design derivatives evaluate the chain again."""
    q = jax.lax.stop_gradient(q)
    k = jnp.argmin(radius_sq)
    best = q[k]
    # Joints resting on a limit follow the limit (a design leaf); the others stay put.
    at_lower, at_upper = _at_limits(best, lower, upper, wraps)
    free = ~(at_lower | at_upper)
    if polish:
        value, best = _polished_value(robot, best, free, at_lower, at_upper, jacobian, lower, upper, wraps)
        return jnp.where(jnp.isfinite(radius_sq[k]), value, jnp.inf), best
    posture = jnp.where(at_upper, upper, jnp.where(at_lower, lower, best))

    def expression(robot, posture, constants):
        best, free = constants
        value = jnp.sqrt(_tip_radius_sq(robot, posture))
        if best.shape[-1] != family_of(robot).translational_rows:
            return value
        # A minimum of |tip| on the hypersurface s = 0 moves with the design: by the
        # envelope theorem for the constrained minimum, d radius / d design =
        # d r / d design - lambda d s / d design at the fixed posture, with the Lagrange
        # multiplier lambda = (grad_F r . grad_F s) / |grad_F s|^2 over the free joints F
        # (stationarity grad_F r = lambda grad_F s; the joints on a limit carry their own
        # multipliers, accounted for by moving them with the limit above). The value is
        # unchanged (s = 0 at the posture to rounding).
        fixed = jax.tree_util.tree_map(jax.lax.stop_gradient, robot)
        J, tip, dJ, dtip = _jet(fixed, best[None], jacobian)
        grad_r = jnp.einsum("d,dn->n", tip[0], dtip[0]) / jnp.sqrt(jnp.sum(tip[0] * tip[0]))
        grad_s = jax.vmap(lambda d: jax.jvp(_measure_of, (J[0],), (d,))[1], in_axes=-1)(dJ[0])
        grad_r, grad_s = jnp.where(free, grad_r, 0.0), jnp.where(free, grad_s, 0.0)
        multiplier = jax.lax.stop_gradient(jnp.dot(grad_r, grad_s) / jnp.maximum(jnp.dot(grad_s, grad_s), 1e-300))
        constraint = singularity_measure(robot, posture, jacobian)
        return value - multiplier * (constraint - jax.lax.stop_gradient(constraint))

    value = _with_value(expression)(robot, posture, (best, free), jnp.sqrt(jax.lax.stop_gradient(posture_radius_sq)))
    return jnp.where(jnp.isfinite(radius_sq[k]), value, jnp.inf), best


def _at_limits(best, lower, upper, wraps):
    """Joints of ``best`` within 1e-6 of their range from the lower and the upper limit."""
    span = upper - lower
    return ~wraps & (best <= lower + 1e-6 * span), ~wraps & (best >= upper - 1e-6 * span)


def _polished_value(robot, best, free, at_lower, at_upper, jacobian, lower, upper, wraps):
    """The radius at ``best`` after `_kkt_polish`, with the envelope-theorem gradient of the
    constrained minimum for square and redundant J_v alike, and the polished posture."""
    # A minimum of |tip| on the singular set moves with the design: by the envelope theorem
    # for the constrained minimum, d radius / d design = d r / d design - mu . d(J_v^T u) /
    # d design at the fixed (q, u), with the Lagrange multipliers mu of the polished KKT
    # point (`_kkt_polish`; the joints on a limit carry their own multipliers, accounted for
    # by moving them with the limit). mu = 0 where |tip| is stationary in the box. The
    # value is unchanged (J_v^T u = 0 at the posture to rounding).
    bounds = (jax.lax.stop_gradient(lower), jax.lax.stop_gradient(upper))
    best, u, multipliers, _ = _kkt_polish(robot, best, free, jacobian, *bounds, wraps)
    best = jax.lax.stop_gradient(best)
    posture = jnp.where(at_upper, upper, jnp.where(at_lower, lower, best))
    value = jnp.sqrt(_tip_radius_sq(robot, posture))
    n = best.shape[-1]
    constraint = _translational(robot, posture, jacobian).T @ jax.lax.stop_gradient(u)
    mu = jax.lax.stop_gradient(jnp.where(jnp.all(jnp.isfinite(multipliers)), multipliers[:n], 0.0))  # no set found
    value = value - jnp.dot(mu, constraint - jax.lax.stop_gradient(constraint))
    return value, best


def _median_of_first(values, count):
    """``jnp.median(values[:count])`` for a traced ``count``, the rest of ``values`` NaN:
    the same sort, middle indices and midpoint, so the same number to the bit (NaN where
    one of the first ``count`` is NaN, as ``jnp.median``)."""
    ordered = jnp.sort(values)  # NaN last: the first count are the real values, sorted
    q = 0.5 * (count.astype(values.dtype) - 1.0)
    low, high = jnp.floor(q).astype(int), jnp.ceil(q).astype(int)
    middle = (ordered[low] + ordered[high]) * 0.5
    real = jnp.arange(values.shape[0]) < count
    return jnp.where(jnp.any(jnp.isnan(values) & real), jnp.nan, middle)


class _Search(NamedTuple):
    """The layout of one singular-radius search (`_singular_radius`): its rows, sizes and phases."""

    robot: Any  # the design, its gradient stopped
    jacobian: str  # static
    lower: jax.Array  # (n,) the joint box
    upper: jax.Array
    wraps: jax.Array  # (n,) the joints that cover a turn
    padded: jax.Array  # (whole blocks, n) the Sobol samples; rows past ``samples`` copy the first
    real: jax.Array  # (whole blocks,) which rows of ``padded`` are samples
    samples: jax.Array  # traced sizes
    keep: jax.Array
    candidates: int  # rows per iteration (static)
    keep_room: int  # static
    chunk_room: int  # keep_room in whole chunks of candidates (static)
    factor: float  # the on-set bound relative to the samples' median |s|
    blocks: jax.Array  # iterations 0..blocks-1 evaluate the samples
    chunks: jax.Array  # then ``chunks`` project the kept ones onto the set
    descend: jax.Array  # the first descent iteration
    last: jax.Array  # the iteration that evaluates the chosen posture (without polish)
    span: jax.Array  # the widest joint range
    descent_steps: jax.Array
    projection_steps: Any
    newton_steps: Any


def _search_layout(
    robot,
    jacobian,
    samples,
    keep,
    candidates,
    descent_steps,
    projection_steps,
    newton_steps,
    seed,
    sample_room,
    keep_room,
) -> _Search:
    """The Sobol samples of the box, padded to whole blocks of ``candidates`` rows, and the
    iterations of each phase."""
    n = family_of(robot).joint_count(robot)
    lower, upper = joint_box(robot)
    wraps = _wraps(robot)
    samples, keep = jnp.asarray(samples), jnp.asarray(keep)
    unit = sobol_points(jnp.asarray(sobol_direction_numbers(n)), 0, sample_room, digital_shifts(seed, 1, n))[0]
    joints = lower + (upper - lower) * unit
    block_room, chunk_room = -(-sample_room // candidates), -(-keep_room // candidates)
    real = jnp.arange(block_room * candidates) < samples
    padded = jnp.concatenate([joints, jnp.broadcast_to(joints[:1], (block_room * candidates - sample_room, n))])
    padded = jnp.where(real[:, None], padded, joints[:1])  # rows past the samples: copies of the first
    blocks = (samples + candidates - 1) // candidates
    factor = 1e-9 if n == family_of(robot).translational_rows else 1e-6
    chunks = (keep + candidates - 1) // candidates
    descend = blocks + chunks  # the first descent iteration
    span = jnp.max(upper - lower)
    descent_steps = jnp.asarray(descent_steps)
    last = descend + jnp.maximum(descent_steps, 1)  # without polish: evaluates the chosen posture
    return _Search(
        robot=robot,
        jacobian=jacobian,
        lower=lower,
        upper=upper,
        wraps=wraps,
        padded=padded,
        real=real,
        samples=samples,
        keep=keep,
        candidates=candidates,
        keep_room=keep_room,
        chunk_room=chunk_room,
        factor=factor,
        blocks=blocks,
        chunks=chunks,
        descend=descend,
        last=last,
        span=span,
        descent_steps=descent_steps,
        projection_steps=projection_steps,
        newton_steps=newton_steps,
    )


def _nearest_samples(search: _Search, measures):
    """The ``keep`` samples of smallest |s| (padded to whole chunks), and the on-set bound."""
    # Rows past the samples are NaN: top_k ranks them last (after any real NaN), the median skips them.
    n = search.padded.shape[1]
    absolute = jnp.where(search.real, jnp.abs(measures), jnp.nan)
    _, nearest = jax.lax.top_k(-absolute, search.keep_room)
    buffer = search.padded[nearest]
    rows = search.chunk_room * search.candidates
    buffer = jnp.concatenate([buffer, jnp.broadcast_to(buffer[:1], (rows - search.keep_room, n))])
    buffer = jnp.where(jnp.arange(rows)[:, None] < search.keep, buffer, buffer[:1])
    return buffer, search.factor * _median_of_first(absolute, search.samples)


def _candidates_of(search: _Search, buffer, buffer_radius_sq):
    """The ``candidates`` refined rows closest to the centroid, and their |tip|^2 (inf off
    the set; padding never chosen)."""
    radius_sq = jnp.where(jnp.arange(buffer_radius_sq.shape[0]) < search.keep, buffer_radius_sq, jnp.inf)
    _, best = jax.lax.top_k(-radius_sq, search.candidates)
    return buffer[best], radius_sq[best]


def _chosen_posture(search: _Search, q, q_radius_sq):
    """As `_closest_value` picks it: the best row, its joints near a limit moved onto it (every row)."""
    best = q[jnp.argmin(q_radius_sq)]
    at_lower, at_upper = _at_limits(best, search.lower, search.upper, search.wraps)
    return jnp.broadcast_to(jnp.where(at_upper, search.upper, jnp.where(at_lower, search.lower, best)), q.shape)


def _search_start(search: _Search) -> tuple:
    """The loop state before the first iteration: (measures, buffer, buffer_radius_sq,
    tolerance, q, q_radius_sq, posture_radius_sq)."""
    dtype = search.padded.dtype
    n = search.padded.shape[1]
    rows = search.chunk_room * search.candidates
    return (
        jnp.zeros((search.padded.shape[0],), dtype),
        jnp.zeros((rows, n), dtype),
        jnp.full((rows,), jnp.inf, dtype),
        jnp.zeros((), dtype),
        jnp.zeros((search.candidates, n), dtype),
        jnp.full((search.candidates,), jnp.inf, dtype),
        jnp.zeros((), dtype),
    )


def _refine_inputs(search: _Search, t, phases, buffer, q, q_radius_sq):
    """What `_refine` takes at iteration ``t``: the rows (a block of samples, a chunk of the
    kept ones, the candidates, or the chosen posture), whether to evaluate first, the
    Newton steps and the descent length; and where the chunk sits in the buffer."""
    sampling, projecting, final = phases
    candidates = search.candidates
    block = jax.lax.dynamic_slice_in_dim(search.padded, jnp.minimum(t, search.blocks - 1) * candidates, candidates)
    chunk_at = jnp.clip(t - search.blocks, 0, search.chunks - 1) * candidates
    chunk = jax.lax.dynamic_slice_in_dim(buffer, chunk_at, candidates)
    # geometric: 2 % of the box to ~5e-6
    length = search.span * 0.02 * 0.5 ** (12.0 * (t - search.descend) / search.descent_steps)
    steps = jnp.where(sampling, 0, jnp.where(projecting, search.projection_steps, search.newton_steps))
    rows = jnp.where(final, _chosen_posture(search, q, q_radius_sq), q)
    x = jnp.where(sampling, block, jnp.where(projecting, chunk, rows))
    # sampling and the chosen posture: evaluate only; descent: tangent step first
    first = jnp.where(sampling | projecting | final, 1, 0)
    return (x, first, jnp.where(final, 0, steps), length), chunk_at


def _search_step(search: _Search, t, state):
    """Iteration ``t`` of the search: one `_refine` of ``candidates`` rows, its results
    written where the phase keeps them."""
    measures, buffer, buffer_radius_sq, tolerance, q, q_radius_sq, posture_radius_sq = state
    blocks, descend = search.blocks, search.descend
    phases = sampling, projecting, final = t < blocks, (t >= blocks) & (t < descend), t == search.last
    buffer, tolerance = jax.lax.cond(
        t == blocks, lambda: _nearest_samples(search, measures), lambda: (buffer, tolerance)
    )
    q, q_radius_sq = jax.lax.cond(
        t == descend, lambda: _candidates_of(search, buffer, buffer_radius_sq), lambda: (q, q_radius_sq)
    )
    (x, first, steps, length), chunk_at = _refine_inputs(search, t, phases, buffer, q, q_radius_sq)
    moved, moved_s, moved_radius_sq = _refine(
        search.robot, x, search.jacobian, first, steps, length, search.lower, search.upper, search.wraps
    )
    measures = jnp.where(
        sampling, jax.lax.dynamic_update_slice_in_dim(measures, moved_s, t * search.candidates, 0), measures
    )
    on_set = jnp.abs(moved_s) <= tolerance
    refined = jnp.where(on_set, moved_radius_sq, jnp.inf)
    buffer = jnp.where(projecting, jax.lax.dynamic_update_slice_in_dim(buffer, moved, chunk_at, 0), buffer)
    buffer_radius_sq = jnp.where(
        projecting, jax.lax.dynamic_update_slice_in_dim(buffer_radius_sq, refined, chunk_at, 0), buffer_radius_sq
    )
    # The step at t == descend exists only to pick the candidates when no descent is asked for.
    accept = (t >= descend) & ~final & (search.descent_steps > 0) & (moved_radius_sq < q_radius_sq) & on_set
    q = jnp.where(accept[:, None], moved, q)
    posture_radius_sq = jnp.where(final, moved_radius_sq[0], posture_radius_sq)
    q_radius_sq = jnp.where(accept, moved_radius_sq, q_radius_sq)
    return measures, buffer, buffer_radius_sq, tolerance, q, q_radius_sq, posture_radius_sq


@functools.partial(jax.jit, static_argnames=("jacobian", "sample_room", "keep_room", "candidates", "polish"))
def _singular_radius(
    robot,
    jacobian,
    samples,
    keep,
    candidates,
    descent_steps,
    projection_steps,
    newton_steps,
    seed,
    polish,
    *,
    sample_room,
    keep_room,
):
    """Sampling, projection and descent in ONE loop whose body holds the only evaluation (`_refine`).

    ``candidates`` rows at a time: iterations 0..S-1 evaluate s on the Sobol samples;
    S..S+P-1 project the ``keep`` samples nearest the set onto it; S+P..S+P+D-1 descend
    on the ``candidates`` closest to the centroid; without ``polish``, one more evaluates
    the chosen posture. So the program holds one forward-mode pass over the chain. Step
    counts, seed, ``samples`` and ``keep`` are traced: the arrays hold ``sample_room`` and
    ``keep_room`` rows (static powers of two), and rows past a size copy the first and are
    never chosen. The search runs with the design's gradient stopped; the radius is
    differentiable through `_closest_value` (envelope theorem).
    """
    design = robot
    robot = jax.tree_util.tree_map(jax.lax.stop_gradient, robot)
    search = _search_layout(
        robot,
        jacobian,
        samples,
        keep,
        candidates,
        descent_steps,
        projection_steps,
        newton_steps,
        seed,
        sample_room,
        keep_room,
    )
    # The polished value evaluates its own posture: no iteration for the chosen one.
    count = search.last + (0 if polish else 1)
    state = jax.lax.fori_loop(0, count, functools.partial(_search_step, search), _search_start(search))
    q, q_radius_sq = state[4], state[5]
    lower, upper = joint_box(design)  # limits are design leaves: a joint on a limit moves with it
    return _closest_value(design, q, q_radius_sq, jacobian, lower, upper, search.wraps, polish, state[6])


def singular_radius(
    robot,
    jacobian: str = "generalized",
    *,
    samples: int = 2**14,
    keep: int = 2048,
    candidates: int = 32,
    descent_steps: int = 150,
    newton_steps: int = 4,
    seed: int = 0,
    polish: bool = False,
) -> tuple[jax.Array, jax.Array]:
    """The closest approach to the system centroid of the tip over a singular set.

    With ``jacobian="generalized"``: the path-independent workspace radius
    (Papadopoulos & Dubowsky 1993), the largest sphere about the centroid with no
    dynamic-singular tip position inside. With ``"fixed_base"``: the analogue of the
    paper's eq. (8), which takes the straight-path boundary to be the kinematic
    singularity.

    The ``candidates`` refined singular postures of smallest radius are moved along
    the set (tangent descent of |tip|^2, Newton projection after each step, steps
    shrinking geometrically). ``samples`` and ``keep`` are traced sizes, like the step
    counts and the seed: counts between the same two consecutive powers of two run one
    program (its loop visits only the real samples), with the result an exact-size
    program gives. ``candidates`` (the rows moved together; at most ``keep``) and
    ``polish`` are compiled in.

    Returns:
        ``(radius, joints)``: m, and the ``(n,)`` singular posture where it occurs;
        ``inf`` when no sampled posture converged onto the set (none in the box).
        The radius is differentiable in the design by the envelope theorem of the
        constrained minimum: for a square J_v (n = 3 spatial, n = 2 planar) through the
        Lagrange multiplier of s = 0 (tested against the planar closed form); for
        redundant arms, without ``polish``, with the singular posture held fixed (the
        motion of the set is left out: 4e-4 to 3e-3 relative off on the UR5). Joints at
        a limit at the minimum move with the limit.

    ``polish=True`` (static; the design objective ``reach_radius`` sets it) adds Newton
    steps on the KKT system of the constrained minimum at the best posture
    (`_kkt_polish`), which moves the radius by ~1e-10 m and makes the gradient exact for
    redundant arms too (the multipliers of J_v^T u = 0; central differences on the UR5
    to ~1e-8 relative, tests/test_reach_radius.py). It costs a second Jacobian jet and
    a least-squares solve, so a longer compile.
    """
    check_joint_box(robot)
    samples, keep = _checked_sizes(samples, keep)
    candidates = int(candidates)
    if candidates < 1:
        raise ConfigError(f"candidates: at least 1, got {candidates}")
    return _singular_radius(
        robot,
        jacobian,
        np.int32(samples),
        np.int32(keep),
        min(candidates, keep),
        descent_steps,
        16,
        newton_steps,
        seed,
        bool(polish),
        sample_room=bucket_size(samples),
        keep_room=bucket_size(keep),
    )


def path_independent_radius(robot, **options) -> jax.Array:
    """The path-independent workspace radius (Papadopoulos & Dubowsky), m, for any family.

    The closest approach to the system centroid of a dynamic-singular tip position.
    Where the family has a closed form (planar two-link arms: the root tracing of det J*,
    options ``n_phi1``, ``n_phi2``, ... of
    `spacearm.models.planar.singularities.dynamic_singularities`; batches of designs
    accepted), that; otherwise `singular_radius` with ``jacobian="generalized"`` (one
    design; its options), the radius alone.
    """
    closed = family_of(robot).fast_paths.path_independent_radius
    radius = None if closed is None else closed(robot, **options)
    return singular_radius(robot, "generalized", **options)[0] if radius is None else radius


def guaranteed_workspace(robot, **options) -> GuaranteedWorkspace:
    """The Guaranteed Workspace in 3-D (any family), with the eq.-(8) analogue beside it.

    The shell between the inner reachable radius and the path-independent radius
    (Papadopoulos & Dubowsky): from any initial posture, along any tip path inside it,
    J*_v keeps full rank. ``kinematic`` is the same construction with the fixed-base
    Jacobian, the paper's eq. (8) argument; the difference between the two is the
    free base's share (eq. 8 overestimates the safe radius where the dynamic singular
    set bulges inwards: Table 1, 2.5 m against 1.0 m).

    Args:
        options: passed to `singular_radius` (sampling and refinement).
    """
    reach = reachable_radii(robot)
    dynamic, _ = singular_radius(robot, "generalized", **options)
    kinematic, _ = singular_radius(robot, "fixed_base", **options)
    empty = dynamic <= reach.inner + 1e-9 * reach.outer
    return GuaranteedWorkspace(reach.inner, dynamic, kinematic, reach.outer, empty)


# Directions --------------------------------------------------------------------------


def icosphere_directions(subdivisions: int = 4) -> np.ndarray:
    """Unit vectors of an icosphere: 10 4^k + 2 nearly uniform directions (k = 4: 2,562).

    Each subdivision splits every triangle of the icosahedron into four and projects the
    new vertices onto the sphere.
    """
    phi = (1.0 + math.sqrt(5.0)) / 2.0
    vertices = [(-1, phi, 0), (1, phi, 0), (-1, -phi, 0), (1, -phi, 0), (0, -1, phi), (0, 1, phi),
                (0, -1, -phi), (0, 1, -phi), (phi, 0, -1), (phi, 0, 1), (-phi, 0, -1), (-phi, 0, 1)]  # fmt: skip
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5),
             (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]  # fmt: skip
    points = [np.asarray(v, float) / np.linalg.norm(v) for v in vertices]
    for _ in range(subdivisions):
        midpoint: dict[tuple[int, int], int] = {}

        def middle(a: int, b: int, midpoint: dict = midpoint) -> int:
            key = (min(a, b), max(a, b))
            if key not in midpoint:
                m = points[a] + points[b]
                points.append(m / np.linalg.norm(m))
                midpoint[key] = len(points) - 1
            return midpoint[key]

        new_faces = []
        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            new_faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new_faces
    return np.stack(points)


# Straight-Path Workspace in 3-D ------------------------------------------------------------


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class StraightPathWorkspace:
    """Area 4 in 3-D from one initial posture: where straight tip paths end, per direction.

    Attributes:
        directions: ``(k, 3)`` unit directions of the paths, inertial axes.
        start: ``(3,)`` tip at the initial posture, about the system centroid, m.
        ends: ``(k, 3)`` tip where each path ended (the boundary of Area 4), m.
        lengths: ``(k,)`` distance travelled along each direction, m.
        reasons: ``(k,)`` int32 why each path ended (0 singular, 1 max_length, 2 joint
            limit, 3 step budget; `SpatialStraightPath`).
    """

    directions: jax.Array
    start: jax.Array
    ends: jax.Array
    lengths: jax.Array
    reasons: jax.Array


def spatial_straight_path_workspace(
    robot, q_start: jax.Array, *, subdivisions: int = 4, base_rotation: jax.Array | None = None, **path_options
) -> StraightPathWorkspace:
    """The 3-D Straight-Path Workspace from one posture (sec. 3.1 (3-b) in 3-D).

    From ``q_start`` the tip moves along each of the 10 4^k + 2 icosphere directions
    (k = ``subdivisions``; 2,562 for k = 4) until J*_v loses rank, a joint limit or
    ``max_length`` (`spatial_straight_tip_path`,
    the bus attitude integrated with the joints); the end points bound the
    star-shaped set reachable by straight lines from the start.

    Args:
        robot: one spatial design.
        q_start: ``(n,)`` initial joints.
        base_rotation: ``(3, 3)`` bus attitude at the start (default identity).
        path_options: passed to the path integrator (``max_length``, ``max_step``, ``tol`` ...).
    """
    directions = jnp.asarray(icosphere_directions(subdivisions), jnp.result_type(float))
    q_start = jnp.asarray(q_start, directions.dtype)
    k = directions.shape[0]
    rotation = (
        None if base_rotation is None else jnp.broadcast_to(jnp.asarray(base_rotation, directions.dtype), (k, 3, 3))
    )
    paths = spatial_straight_tip_path(
        robot, jnp.broadcast_to(q_start, (k, q_start.shape[-1])), directions, base_rotation=rotation, **path_options
    )
    start = tip_position(robot, q_start, base_rotation=None if base_rotation is None else jnp.asarray(base_rotation))
    return StraightPathWorkspace(directions, start, paths.end_tip, paths.length, paths.reason)
