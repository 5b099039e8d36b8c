"""Straight tip paths in 3-D, go-and-back, and reaction-free motion of a redundant arm."""

import os

import jax.numpy as jnp
import numpy as np
import pytest

import spacearm as sa
from spacearm.analysis import reaction
from spacearm.motion import attitude, spatial_go_and_back, spatial_straight_tip_path

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")


@pytest.fixture(scope="module")
def ur5():
    return sa.load_robot(os.path.join(CONFIGS, "ur5-smallsat.yaml"))


def test_straight_paths_follow_the_line_to_a_singularity(ur5):
    rng = np.random.default_rng(0)
    q0 = rng.uniform(-1.5, 1.5, (3, 6))
    d = rng.normal(size=(3, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    R0 = np.asarray(attitude.expm(jnp.asarray(rng.normal(size=(3, 3)))))
    out = spatial_straight_tip_path(ur5, q0, d, base_rotation=R0, max_steps=1500)
    start = np.einsum("pij,pj->pi", R0, np.asarray(sa.tip_position(ur5, q0)))
    # the tip stays on the inertial line (R is integrated with q: an attitude error would bend it)
    np.testing.assert_allclose(np.asarray(out.end_tip) - start, np.asarray(out.length)[:, None] * d, atol=1e-8)
    singular = np.asarray(out.reason) == sa.motion.REASON_SINGULAR
    assert singular.any()
    w_end = np.asarray(sa.manipulability(ur5, out.end_joints))
    assert np.all(w_end[singular] < 1e-3 * np.asarray(sa.manipulability(ur5, q0))[singular])
    # the attitude is a rotation, and the bus did turn
    R = np.asarray(out.end_rotation)
    np.testing.assert_allclose(np.swapaxes(R, -1, -2) @ R, np.broadcast_to(np.eye(3), R.shape), atol=1e-13)
    assert np.all(np.asarray(attitude.geodesic_distance(R0, R)) > 1e-4)


def test_go_and_back_returns_the_tip_but_not_the_bus(ur5):
    q0 = np.array([0.3, -1.2, 1.6, -0.9, 1.2, 0.2])
    out, back = spatial_go_and_back(ur5, q0, np.array([0.3, -0.5, 0.8]), 0.2)
    assert int(out.reason) == sa.motion.REASON_MAX_LENGTH and int(back.reason) == sa.motion.REASON_MAX_LENGTH
    np.testing.assert_allclose(back.end_tip, np.asarray(sa.tip_position(ur5, q0)), atol=1e-9)
    assert float(attitude.geodesic_distance(np.eye(3), back.end_rotation)) > 1e-5  # nonholonomic


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


def test_reaction_free_tip_motion_keeps_the_bus_still(ur5):
    q0 = np.array([[0.3, -1.2, 1.6, -0.9, 1.2, 0.2], [-0.4, -0.8, 1.1, 0.5, -1.0, 0.7]])
    d = np.array([[0.0, 0.6, 0.8], [1.0, 0.0, 0.0]])
    path = reaction.reaction_free_tip_path(ur5, q0, d, 0.01, steps=400)
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
