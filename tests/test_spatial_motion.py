"""Straight tip paths in 3-D, go-and-back, and reaction-free motion of a redundant arm."""

import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import spacearm as sa
from spacearm.analysis import reaction
from spacearm.models.spatial import primitives
from spacearm.motion import attitude, spatial_go_and_back, spatial_straight_tip_path
from spacearm.motion.straight_paths import generic_straight_field

from .conftest import count_compiles

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")


@pytest.fixture(scope="module")
def ur5():
    return sa.load_robot(os.path.join(CONFIGS, "ur5-smallsat.yaml"))


@pytest.mark.slow  # compiles a DOP853 loop or the planner: minutes on 2 shared cores
def test_straight_paths_follow_the_line_to_a_singularity(ur5):
    rng = np.random.default_rng(0)
    q0 = rng.uniform(-1.5, 1.5, (3, 6))
    d_bus = rng.normal(size=(3, 3))
    d_bus /= np.linalg.norm(d_bus, axis=1, keepdims=True)
    R0 = np.asarray(attitude.expm(jnp.asarray(rng.normal(size=(3, 3)))))
    d = np.einsum("pij,pj->pi", R0, d_bus)  # the same paths in bus axes as with R0 = 1 (left invariance)
    out = spatial_straight_tip_path(ur5, q0, d, base_rotation=R0, max_steps=1500)
    start = np.einsum("pij,pj->pi", R0, np.asarray(sa.tip_position(ur5, q0)))
    # the tip stays on the inertial line (R is integrated with q: an attitude error would bend it)
    np.testing.assert_allclose(np.asarray(out.end_tip) - start, np.asarray(out.length)[:, None] * d, atol=1e-8)
    # the ends, taken from the field's last chain pass, are those of the end joints
    tip_end = np.einsum("pij,pj->pi", np.asarray(out.end_rotation), np.asarray(sa.tip_position(ur5, out.end_joints)))
    np.testing.assert_allclose(out.end_tip, tip_end, rtol=0, atol=1e-14)
    w_fixed = np.asarray(sa.fixed_base_manipulability(ur5, out.end_joints))
    np.testing.assert_allclose(out.fixed_manipulability, w_fixed, rtol=1e-12, atol=1e-18)
    # all three end singular within 200 steps; paths 0 and 2 by the stall (a flat
    # ds/dsigma, the bus reaction to joint 6 alone moving the tip): J*_v lost rank there
    np.testing.assert_array_equal(out.reason, sa.motion.REASON_SINGULAR)
    assert np.all(np.asarray(out.steps) < 200)

    def rank_ratio(q):  # sigma_3 / sigma_1 of the translational J*
        sigma = np.linalg.svd(np.asarray(sa.generalized_jacobian(ur5, q))[:, :3], compute_uv=False)
        return sigma[:, 2] / sigma[:, 0]

    assert np.all(rank_ratio(q0) > 1e-2) and np.all(rank_ratio(out.end_joints) < 1e-4)
    # Path 0 integrated through the creep (no stall by travel) meets joint 6's limit after
    # ~3,150 steps, 0.9 mm further along the line: the stall end is short of it by at most
    # tip_tol (1e-3 m), with J*_v as singular there.
    exact = spatial_straight_tip_path(ur5, q0, d, base_rotation=R0, max_steps=3500, tip_tol=-np.inf)
    assert int(exact.reason[0]) == sa.motion.REASON_JOINT_LIMIT
    assert abs(float(exact.end_joints[0, 5]) + 2 * np.pi) < 1e-9
    assert 0.0 < float(exact.length[0] - out.length[0]) <= 1e-3
    assert rank_ratio(exact.end_joints[:1])[0] < 1e-4
    # the attitude is a rotation, and the bus did turn
    R = np.asarray(out.end_rotation)
    np.testing.assert_allclose(np.swapaxes(R, -1, -2) @ R, np.broadcast_to(np.eye(3), R.shape), atol=1e-13)
    assert np.all(np.asarray(attitude.geodesic_distance(R0, R)) > 1e-4)


@pytest.mark.slow  # compiles a DOP853 loop or the planner: minutes on 2 shared cores
def test_go_and_back_retraces_the_way_out(ur5):
    q0 = np.array([0.3, -1.2, 1.6, -0.9, 1.2, 0.2])
    out, back = spatial_go_and_back(ur5, q0, np.array([0.3, -0.5, 0.8]), 0.2)
    assert int(out.reason) == sa.motion.REASON_MAX_LENGTH and int(back.reason) == sa.motion.REASON_MAX_LENGTH
    assert float(attitude.geodesic_distance(np.eye(3), out.end_rotation)) > 1e-4  # the way out turns the bus
    # the field is odd in the direction: the way back retraces it (joints and bus return)
    np.testing.assert_allclose(back.end_tip, np.asarray(sa.tip_position(ur5, q0)), atol=1e-9)
    np.testing.assert_allclose(back.end_joints, q0, atol=1e-8)
    assert float(attitude.geodesic_distance(np.eye(3), back.end_rotation)) < 1e-9


def test_straight_field_takes_one_chain_pass_and_equals_the_two_pass_field(ur5):
    """The field's J*_v and C_w come from one pass over the chain; the same numbers as J* and
    the base twist map computed apart, and the field is the formula of the module docstring."""
    rng = np.random.default_rng(5)
    q = rng.uniform(-2, 2, (6, 6))
    # The internal kernels on concrete arrays: one program each, not one per operation.
    maps_of, jstar, twist_map, maps_and_ends, fixed_base, tip_of = map(
        jax.jit,
        (
            primitives.straight_path_maps,
            primitives.generalized_jacobian,
            primitives.base_twist_map,
            primitives.straight_maps_and_ends,
            primitives.fixed_base_jacobian,
            primitives.tip,
        ),
    )
    field = jax.jit(lambda d, y: generic_straight_field(ur5, d, jnp.asarray(1.0))(y))
    maps = np.asarray(maps_of(ur5, q))
    np.testing.assert_allclose(maps[:, :3], np.asarray(jstar(ur5, q))[:, :3], rtol=0, atol=1e-15)
    np.testing.assert_allclose(maps[:, 3:], np.asarray(twist_map(ur5, q))[:, 3:], rtol=0, atol=1e-15)
    # the same pass also gives a path's end quantities: fixed-base J_v and the tip
    both, fixed_v, tip = (np.asarray(x) for x in maps_and_ends(ur5, q))
    np.testing.assert_allclose(both, maps, rtol=0, atol=1e-15)
    np.testing.assert_allclose(fixed_v, np.asarray(fixed_base(ur5, q))[:, :3], rtol=0, atol=1e-15)
    np.testing.assert_allclose(tip, np.asarray(tip_of(ur5, q)), rtol=0, atol=1e-15)
    for qk in q:
        R = np.asarray(attitude.expm(rng.normal(size=3)))
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        y = np.concatenate([qk, R.reshape(9), [0.2]])
        f = np.asarray(field(d, y))
        J = np.asarray(sa.generalized_jacobian(ur5, qk))[:3]
        rates = J.T @ np.linalg.solve(J @ J.T, R.T @ d)  # minimum-norm rates, unit tip speed
        scale = np.linalg.norm(rates)
        np.testing.assert_allclose(f[:6], rates / scale, atol=1e-12)
        np.testing.assert_allclose(f[-1], 1.0 / scale, rtol=1e-11)
        w = np.asarray(attitude.bus_rate_map(ur5, qk)) @ f[:6]
        np.testing.assert_allclose(f[6:15], (R @ np.asarray(attitude.hat(w))).reshape(9), atol=1e-13)


@pytest.mark.slow  # compiles the spatial DOP853 loop once (~5 s CPU)
def test_spatial_straight_paths_one_program_per_bucket(ur5):
    """64 and 65 paths, and a new step budget, run in the program compiled for 8 (batches are
    padded to a power-of-two bucket, the budget is traced); the padding is never integrated."""
    rng = np.random.default_rng(6)
    q0 = np.array([0.3, -1.2, 1.6, -0.9, 1.2, 0.2])
    d = rng.normal(size=(65, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    few = spatial_straight_tip_path(ur5, q0, d[:8], 0.03, max_steps=300)
    with count_compiles() as compiles:
        many = spatial_straight_tip_path(ur5, q0, d[:64], 0.03, max_steps=300)
        more = spatial_straight_tip_path(ur5, q0, d, 0.03, max_steps=400)
    assert not [name for name in compiles if "_straight_flat" in name]
    assert more.length.shape == (65,) and np.all(np.asarray(more.reason) == sa.motion.REASON_MAX_LENGTH)
    np.testing.assert_allclose(many.end_joints[:8], few.end_joints, atol=1e-14)
    np.testing.assert_allclose(more.end_joints[:64], many.end_joints, atol=1e-14)
    start = np.asarray(sa.tip_position(ur5, q0))
    np.testing.assert_allclose(np.asarray(more.end_tip) - start, 0.03 * d, atol=1e-9)  # on the line


def test_reaction_null_space_and_disturbance_map(ur5):
    rng = np.random.default_rng(1)
    q = rng.uniform(-2, 2, (4, 5, 6))  # a small grid of postures
    N = reaction.reaction_null_space(ur5, q)
    C = np.asarray(attitude.bus_rate_map(ur5, q))
    assert N.shape == (4, 5, 6, 3)
    np.testing.assert_allclose(np.einsum("...ij,...jk->...ik", C, N), 0.0, atol=1e-15)
    np.testing.assert_allclose(np.swapaxes(N, -1, -2) @ N, np.broadcast_to(np.eye(3), (4, 5, 3, 3)), atol=1e-13)
    m = reaction.disturbance_map(ur5, q)
    assert np.all(np.asarray(reaction.disturbance(ur5, q, m.least_disturbing)) < 1e-15)
    np.testing.assert_allclose(reaction.disturbance(ur5, q, m.most_disturbing), m.largest, rtol=1e-12)
    u = rng.normal(size=(4, 5, 6))
    assert np.all(np.asarray(reaction.disturbance(ur5, q, u)) <= np.asarray(m.largest) * (1 + 1e-12))


@pytest.mark.slow  # compiles a DOP853 loop or the planner: minutes on 2 shared cores
def test_reaction_free_tip_motion_keeps_the_bus_still(ur5):
    rng = np.random.default_rng(0)
    q0, d = rng.uniform(-1.5, 1.5, (3, 6))[:2], rng.normal(size=(3, 3))[:2]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    path = reaction.reaction_free_tip_path(ur5, q0, d, 0.01, steps=400)
    assert np.all(np.asarray(path.smallest_singular_value) > 1e-5)  # [C_w; J*_v] keeps full rank
    np.testing.assert_allclose(np.asarray(path.tip[:, -1] - path.tip[:, 0]), 0.01 * d, atol=1e-12)
    assert np.all(np.asarray(path.tip_residual) < 1e-10) and np.all(np.asarray(path.bus_rate) < 1e-10)
    # independently: the sampled joint path through the SO(3) integrator turns the bus by
    # O(chord^2) only (400 and 200 chords), below 1e-9 rad
    joints = np.asarray(path.joints)
    fine, _ = sa.integrate_joint_path(ur5, joints[:, 0], joints)
    coarse, _ = sa.integrate_joint_path(ur5, joints[:, 0], joints[:, ::2])
    fine_angle = np.asarray(attitude.geodesic_distance(np.eye(3), fine))
    assert np.all(fine_angle < 1e-9)
    assert np.all(np.asarray(attitude.geodesic_distance(np.eye(3), coarse)) > 3.0 * fine_angle)
    # the same tip motion by minimum-norm rates (no null-space constraint) does turn the bus
    plain = spatial_straight_tip_path(ur5, q0, d, 0.01)
    assert np.all(np.asarray(attitude.geodesic_distance(np.eye(3), plain.end_rotation)) > 1e-5)
