"""The base-attitude groups SO(2) and SO(3): exp/log, compose, act, coordinates, candidates."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from spacearm._core.groups import SO2, SO3, fibonacci_sphere, polar_rotation


def test_so3_exp_matches_scipy_and_log_inverts_it():
    rng = np.random.default_rng(0)
    axes = rng.normal(size=(50, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = np.concatenate([[0.0, 1e-9, 1e-4, 0.5, 2.0, np.pi - 1e-6, np.pi - 1e-2], rng.uniform(0, np.pi, 43)])
    v = axes * angles[:, None]
    R = np.asarray(SO3.exp(jnp.asarray(v)))
    np.testing.assert_allclose(R, Rotation.from_rotvec(v).as_matrix(), atol=1e-15)
    np.testing.assert_allclose(SO3.log(R), v, atol=1e-9)  # near pi the axis costs ~1e-10
    np.testing.assert_allclose(SO3.log(R)[angles < 3.0], v[angles < 3.0], atol=1e-14)
    np.testing.assert_allclose(SO3.distance(np.eye(3), R), angles, atol=1e-15)


def test_so3_compose_inverse_and_act():
    rng = np.random.default_rng(1)
    a, b = (Rotation.random(8, random_state=rng) for _ in range(2))
    A, B = a.as_matrix(), b.as_matrix()
    np.testing.assert_allclose(SO3.compose(A, B), (a * b).as_matrix(), atol=1e-15)
    np.testing.assert_allclose(SO3.compose(SO3.inverse(A), A), np.broadcast_to(np.eye(3), A.shape), atol=1e-15)
    x = rng.normal(size=(8, 3))
    np.testing.assert_allclose(SO3.act(A, x), a.apply(x), atol=1e-15)
    np.testing.assert_allclose(SO3.act_inverse(A, x), a.inv().apply(x), atol=1e-15)
    # the flat coordinates the integrators carry, and their projection back onto the group
    c = np.asarray(SO3.to_coords(A))
    np.testing.assert_allclose(SO3.from_coords(c + 1e-9 * rng.normal(size=c.shape)), A, atol=1e-8)
    np.testing.assert_allclose(polar_rotation(A), A, atol=1e-15)


def test_so3_rate_is_the_body_velocity_derivative():
    """d/dt (R expm(t w)) at t = 0 equals R [w]x, the coordinate rate (finite difference)."""
    rng = np.random.default_rng(2)
    R = Rotation.random(random_state=rng).as_matrix()
    w = rng.normal(size=3)
    h = 1e-6
    numeric = (R @ np.asarray(SO3.exp(jnp.asarray(h * w))) - R @ np.asarray(SO3.exp(jnp.asarray(-h * w)))) / (2 * h)
    np.testing.assert_allclose(SO3.rate(SO3.to_coords(R), w), numeric.reshape(9), atol=1e-9)
    np.testing.assert_allclose(np.asarray(SO3.coords_matrix(SO3.to_coords(R))), R)


def test_so2_is_the_angle_group():
    rng = np.random.default_rng(3)
    a, b = rng.uniform(-3, 3, 10), rng.uniform(-3, 3, 10)
    Ra, Rb = np.asarray(SO2.matrix(a)), np.asarray(SO2.matrix(b))
    np.testing.assert_allclose(SO2.matrix(SO2.compose(a, b)), Ra @ Rb, atol=1e-15)
    np.testing.assert_allclose(SO2.exp(SO2.log(a + 2 * np.pi)), a, atol=1e-14)  # log wraps to [-pi, pi)
    x = rng.normal(size=(10, 2))
    np.testing.assert_allclose(SO2.act(a, x), np.einsum("pij,pj->pi", Ra, x), atol=1e-15)
    np.testing.assert_allclose(SO2.act_inverse(a, SO2.act(a, x)), x, atol=1e-15)
    np.testing.assert_allclose(SO2.distance(a, b), np.abs((b - a + np.pi) % (2 * np.pi) - np.pi), atol=1e-14)
    np.testing.assert_allclose(SO2.coords_matrix(SO2.to_coords(a[0])), Ra[0])


@pytest.mark.parametrize("group", [SO2, SO3], ids=["SO2", "SO3"])
def test_exp_log_round_trip_and_gradients(group):
    rng = np.random.default_rng(4)
    v = rng.uniform(-1.0, 1.0, (20, group.dim))
    np.testing.assert_allclose(group.log(group.exp(jnp.asarray(v))), v, atol=1e-14)
    grad = jax.grad(lambda x: group.log(group.exp(x)).sum())(jnp.zeros(group.dim))
    np.testing.assert_allclose(grad, np.ones(group.dim), atol=1e-12)  # log . exp = id near 0


def test_candidate_rotations_smallest_first():
    so3 = SO3.candidates(64, (0.02, 0.1))
    assert so3.shape == (128, 3)
    np.testing.assert_allclose(np.linalg.norm(so3, axis=1), np.repeat([0.02, 0.1], 64))
    units = fibonacci_sphere(64)
    assert abs(np.mean(units, axis=0)).max() < 0.02  # spread over the sphere
    so2 = SO2.candidates(8)[:, 0]
    np.testing.assert_allclose(np.sort(so2), np.pi / 4 * np.arange(-4, 4), atol=1e-15)
    assert np.all(np.diff(np.abs(so2)) >= 0)
