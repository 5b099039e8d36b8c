"""Dynamic singularities of the planar arm and the path-independent workspace (n = 2).

The Generalized Jacobian J* loses rank on curves that pass through the collinear
postures and bulge away from the kinematic singularity phi_2 = 0 when b0 > 0
(Papadopoulos & Dubowsky's dynamic singularities). `dynamic_singularities`
traces the zero set of det J*; `path_independent_radius` gives the largest
singularity-free disk about the system centroid.
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np

from ..._core.errors import ConfigError
from ..._core.linalg import square_determinant
from ..family import require_family
from .closed_forms import generalized_jacobian, robot_frame_tip_position, tip_position
from .robot import PlanarRobot

__all__ = ["SingularSet", "dynamic_singularities", "path_independent_radius", "two_link_path_independent_radius"]


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class SingularSet:
    """Postures where det J* = 0 (n = 2), traced on a grid of phi_1 values.

    Each row is one phi_1; each column one cell of the phi_2 grid that holds a root
    (NaN where it does not). phi0 = 0: det J* does not depend on phi0, and a change of
    phi0 rotates the tip about the system centroid, so the inertial singular set is the
    union of the circles of radius ``radius``.

    Attributes:
        phi1: ``(M, N)`` joint 1 angle, rad (N = max_roots slots per phi_1).
        phi2: ``(M, N)`` joint 2 angle where det J* = 0, rad in [-pi, pi), NaN if none.
        radius: ``(M, N)`` |tip| in the inertial frame (distance to the system centroid), m.
        tip_inertial: ``(M, N, 2)`` tip at phi0 = 0, inertial frame, m.
        tip_robot: ``(M, N, 2)`` tip in the robot frame Sigma_R (origin at joint 1), m.
        folded: ``(M, N)`` bool, the branch near the folded arm (|phi2| > pi/2).
    """

    phi1: jax.Array
    phi2: jax.Array
    radius: jax.Array
    tip_inertial: jax.Array
    tip_robot: jax.Array
    folded: jax.Array


def _det_generalized_jacobian(robot, phi1, phi2):
    phi = jnp.stack(jnp.broadcast_arrays(jnp.zeros_like(phi1), phi1, phi2), axis=-1)
    return square_determinant(generalized_jacobian(robot, phi))


@functools.partial(jax.jit, static_argnames=("n_phi1", "n_phi2", "max_roots"))
def _singular_roots(robot, n_phi1, n_phi2, bisection_steps, max_roots):
    dtype = jnp.asarray(robot.link_a).dtype
    phi1 = -jnp.pi + 2.0 * jnp.pi * jnp.arange(n_phi1, dtype=dtype) / n_phi1
    # Offset by half a cell so the collinear roots phi2 = 0 and pi fall inside cells.
    step = 2.0 * jnp.pi / n_phi2
    left = -jnp.pi + step * (jnp.arange(n_phi2, dtype=dtype) + 0.5)
    d_left = _det_generalized_jacobian(robot, phi1[:, None], left[None, :])
    d_right = jnp.roll(d_left, -1, axis=1)  # the last cell wraps through pi
    crossing = d_left * d_right < 0
    # Keep the first max_roots bracketing cells of each row (static shape).
    cells = jnp.argsort(~crossing, axis=1, stable=True)[:, :max_roots]
    has_root = jnp.take_along_axis(crossing, cells, axis=1)
    P1 = jnp.broadcast_to(phi1[:, None], cells.shape)
    lo0 = left[cells]

    def bisect(_, bracket):
        lo, hi, f_lo = bracket
        mid = 0.5 * (lo + hi)
        f_mid = _det_generalized_jacobian(robot, P1, mid)
        go_left = f_lo * f_mid <= 0
        return jnp.where(go_left, lo, mid), jnp.where(go_left, mid, hi), jnp.where(go_left, f_lo, f_mid)

    f0 = jnp.take_along_axis(d_left, cells, axis=1)
    lo, hi, _ = jax.lax.fori_loop(0, bisection_steps, bisect, (lo0, lo0 + step, f0))
    root = jnp.mod(0.5 * (lo + hi) + jnp.pi, 2.0 * jnp.pi) - jnp.pi
    safe = jnp.where(has_root, root, 0.0)
    phi = jnp.stack([jnp.zeros_like(P1), P1, safe], axis=-1)
    tip = tip_position(robot, phi)
    tip_r = robot_frame_tip_position(robot, phi[..., 1:])
    nan2 = jnp.where(has_root[..., None], 1.0, jnp.nan)
    return SingularSet(
        phi1=P1,
        phi2=jnp.where(has_root, root, jnp.nan),
        radius=jnp.where(has_root, jnp.linalg.norm(tip, axis=-1), jnp.nan),
        tip_inertial=tip * nan2,
        tip_robot=tip_r * nan2,
        folded=has_root & (jnp.abs(safe) > 0.5 * jnp.pi),
    )


def dynamic_singularities(
    robot: PlanarRobot, n_phi1: int = 1440, n_phi2: int = 256, bisection_steps: int = 55, max_roots: int = 4
) -> SingularSet:
    """The zero set of det J* (eq. 6) for a two-link arm: the free base's real singularities.

    Planar arms only (another family raises TypeError).

    For every phi_1 on an even grid of ``n_phi1`` values in [-pi, pi), the roots in phi_2
    are bracketed by sign changes on ``n_phi2`` cells (the first ``max_roots`` per row
    are kept; rows of the shape ``(M, max_roots)``) and refined by bisection to
    2 pi / n_phi2 / 2**bisection_steps rad. The grid sizes and ``max_roots`` fix the
    program's shapes; ``bisection_steps`` is traced (a new count compiles nothing). A
    root of even multiplicity (a tangency without sign change) would be missed; for the
    designs we tried det J* changes sign across both branches everywhere but at the
    collinear crossings.

    Raises:
        ConfigError: for n != 2 (for n > 2, J* loses rank on a set of codimension 2 in
            joint space, which a one-dimensional scan cannot trace).
    """
    require_family(robot, "planar", "dynamic_singularities")
    if robot.n_links != 2:
        raise ConfigError(f"links: dynamic_singularities traces det J* for n = 2 links, got n = {robot.n_links}")
    steps = np.int32(bisection_steps)  # traced: a new count runs the same program
    if robot.batch_shape:
        return jax.vmap(lambda r: _singular_roots(r, n_phi1, n_phi2, steps, max_roots))(robot)
    return _singular_roots(robot, n_phi1, n_phi2, steps, max_roots)


def path_independent_radius(robot: PlanarRobot, **grid) -> jax.Array:
    """``(...)`` radius of the largest disk about the system centroid that no singular posture reaches, m.

    The min of |tip| over the zero set of det J* (n = 2): inside this disk a tip path
    meets no dynamic singularity whatever the base attitude (Papadopoulos & Dubowsky
    1991's path-independent workspace; it contains points only where Area 3 has no hole).
    Compare `guaranteed_radius` (eq. 8), which considers phi_2 = 0 only.
    """
    return jnp.nanmin(dynamic_singularities(robot, **grid).radius, axis=(-2, -1))


def two_link_path_independent_radius(robot: PlanarRobot, **grid) -> jax.Array | None:
    """`path_independent_radius` where the root tracing holds (two links), ``None`` otherwise."""
    return path_independent_radius(robot, **grid) if robot.n_links == 2 else None
