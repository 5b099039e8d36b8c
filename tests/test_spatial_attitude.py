"""The bus attitude on SO(3): helpers, synthetic maps with known answers, the UR5 against
a converged reference and SciPy, time reversal, batching and the public dispatch."""

import functools
import itertools
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import spacearm as sa
from spacearm.models.spatial import stack_spatial_robots
from spacearm.motion import attitude

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")

# One program per map and shape instead of one per operation (the tests call it on concrete arrays).
path_rotation = jax.jit(attitude.path_rotation, static_argnums=(0, 2, 3))


@pytest.fixture(scope="module")
def ur5():
    return sa.load_robot(os.path.join(CONFIGS, "ur5-smallsat.yaml"))


def _loops(rng, count, n, segments=12, size=1.0):
    q0 = rng.uniform(-2.0, 2.0, (count, n))
    basis = np.linalg.qr(rng.normal(size=(count, n, 2)))[0]
    theta = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    plane = size * np.stack([np.cos(theta) - 1.0, np.sin(theta)], -1)
    loops = q0[:, None, :] + np.einsum("cnk,sk->csn", basis, plane)
    loops[:, -1] = q0
    return loops


def _skew(w):
    """[w]x in NumPy, for the SciPy references."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def _random_rotations(rng, count):
    return Rotation.random(count, random_state=rng.integers(1 << 30)).as_matrix()


# SO(3) helpers ------------------------------------------------------------------------------


def test_expm_log_geodesic():
    rng = np.random.default_rng(0)
    axes = rng.normal(size=(500, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = rng.uniform(0.0, np.pi, 500)
    angles[:4] = [0.0, 1e-9, np.pi, np.pi - 1e-6]
    v = axes * angles[:, None]
    R = attitude.expm(v)
    np.testing.assert_allclose(R, Rotation.from_rotvec(v).as_matrix(), atol=1e-15)
    np.testing.assert_allclose(attitude.log(R), v, atol=1e-12)  # near pi the axis costs ~1e-13
    np.testing.assert_allclose(attitude.geodesic_distance(np.eye(3), R), angles, atol=1e-15)
    np.testing.assert_allclose(attitude.vee(attitude.hat(v)), v)
    # finite gradients at the identity
    assert np.all(np.isfinite(jax.grad(lambda x: attitude.log(attitude.expm(x)).sum())(jnp.zeros(3))))
    assert np.all(np.isfinite(jax.jacobian(attitude.expm)(jnp.zeros(3))))


# Synthetic maps with known answers -----------------------------------------------------------


def test_constant_map_is_exact():
    """C_w constant: each segment turns the bus by expm([C dq]x), whatever the step."""
    rng = np.random.default_rng(1)
    C = rng.normal(size=(3, 4))
    omega_map = lambda q: jnp.broadcast_to(jnp.asarray(C), q.shape[:-1] + C.shape)
    waypoints = rng.normal(size=(5, 4))
    expected = np.eye(3)
    for a, b in itertools.pairwise(waypoints):
        expected = expected @ Rotation.from_rotvec(C @ (b - a)).as_matrix()
    for order in (4, 6, "rkmk4"):
        np.testing.assert_allclose(path_rotation(omega_map, jnp.asarray(waypoints), 1, order), expected, atol=1e-14)


def test_commuting_loop_turns_by_the_enclosed_area():
    """C_w(q) = e_z (-q2, q1) / 2: a closed polygon turns the bus about z by its signed area."""

    def omega_map(q):
        row = 0.5 * jnp.stack([-q[..., 1], q[..., 0]], -1)
        zeros = jnp.zeros_like(row)
        return jnp.stack([zeros, zeros, row], -2)

    rng = np.random.default_rng(2)
    polygon = rng.normal(size=(7, 2))
    polygon = np.concatenate([polygon, polygon[:1]])
    area = 0.5 * np.sum(polygon[:-1, 0] * polygon[1:, 1] - polygon[1:, 0] * polygon[:-1, 1])
    R = path_rotation(omega_map, jnp.asarray(polygon), 1, 6)
    np.testing.assert_allclose(R, Rotation.from_rotvec([0.0, 0.0, area]).as_matrix(), atol=1e-14)


def test_orders_on_a_smooth_map():
    """Halving the step divides the error by 2^order against an adaptive DOP853 reference."""
    rng = np.random.default_rng(3)
    C, B = rng.normal(size=(3, 4)), 0.3 * rng.normal(size=(3, 4, 4))
    omega_map = lambda q: jnp.asarray(C) + jnp.einsum("ijk,...k->...ij", jnp.asarray(B), jnp.sin(q))
    waypoints = 0.5 * rng.normal(size=(4, 4))
    R = np.eye(3)
    for a, b in itertools.pairwise(waypoints):

        def rhs(t, y, a=a, d=b - a):  # the same map in NumPy (the reference runs no JAX)
            w = (C + np.einsum("ijk,k->ij", B, np.sin(a + t * d))) @ d
            return (y.reshape(3, 3) @ _skew(w)).ravel()

        R = solve_ivp(rhs, (0.0, 1.0), R.ravel(), method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1].reshape(3, 3)
    for order, expected in ((4, 16.0), (6, 64.0), ("rkmk4", 16.0)):
        errors = [
            float(attitude.geodesic_distance(path_rotation(omega_map, jnp.asarray(waypoints), s, order), R))
            for s in (8, 16)
        ]
        assert 0.6 * expected < errors[0] / errors[1] < 1.5 * expected, (order, errors)


# The UR5 on its smallsat ---------------------------------------------------------------------


def test_ur5_against_converged_reference_and_scipy(ur5):
    rng = np.random.default_rng(4)
    loops = _loops(rng, 6, 6, size=1.2)
    R0 = _random_rotations(rng, 6)
    R_end, q_end = sa.integrate_joint_path(ur5, loops[:, 0], loops, base_rotation=R0)
    reference = R0 @ np.asarray(
        path_rotation(functools.partial(attitude.bus_rate_map, ur5), jnp.asarray(loops), 128, 6)
    )
    assert np.max(attitude.geodesic_distance(R_end, reference)) < 1e-10
    np.testing.assert_array_equal(q_end, loops[:, -1])
    assert np.min(attitude.geodesic_distance(R0, R_end)) > 1e-3  # the loops do turn the bus

    # SciPy's DOP853 on the 9 entries of R (independent of the Magnus code), one loop
    omega = jax.jit(functools.partial(attitude.bus_rate_map, ur5))
    R = R0[0]
    for a, b in zip(loops[0, :-1], loops[0, 1:], strict=False):

        def rhs(t, y, a=a, d=b - a):
            w = np.asarray(omega(a + t * d)) @ d
            return (y.reshape(3, 3) @ _skew(w)).ravel()

        R = solve_ivp(rhs, (0.0, 1.0), R.ravel(), method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1].reshape(3, 3)
    assert float(attitude.geodesic_distance(R_end[0], R)) < 1e-11


def test_loop_backwards_undoes_its_rotation(ur5):
    rng = np.random.default_rng(5)
    loops = _loops(rng, 4, 6, size=1.5)
    R0 = _random_rotations(rng, 4)
    R_end, _ = sa.integrate_joint_path(ur5, loops[:, 0], loops, base_rotation=R0)
    back, _ = sa.integrate_joint_path(ur5, loops[:, -1], loops[:, ::-1], base_rotation=R_end)
    assert np.min(attitude.geodesic_distance(R0, R_end)) > 1e-3
    assert np.max(attitude.geodesic_distance(R0, back)) < 1e-14  # symmetric nodes: reversible to rounding
    # the attitude at the start does not change the relative rotation (left invariance)
    relative = np.swapaxes(R0, -1, -2) @ np.asarray(R_end)
    R_id, _ = sa.integrate_joint_path(ur5, loops[:, 0], loops)
    assert np.max(attitude.geodesic_distance(relative, R_id)) < 1e-14


def test_batches_of_paths_attitudes_and_designs(ur5):
    rng = np.random.default_rng(6)
    designs = stack_spatial_robots([ur5, ur5.replace(base_mass=np.float64(150.0))])
    loops = _loops(rng, 3, 6).reshape(3, 1, 13, 6)  # (3, 1) paths x (2,) designs -> (3, 2)
    R0 = _random_rotations(rng, 2)
    R_end, q_end = sa.integrate_joint_path(designs, loops[:, :, 0], loops, base_rotation=R0)
    assert R_end.shape == (3, 2, 3, 3) and q_end.shape == (3, 2, 6)
    for i in range(3):
        for j, design in enumerate((ur5, ur5.replace(base_mass=np.float64(150.0)))):
            one, _ = sa.integrate_joint_path(design, loops[i, 0, 0], loops[i, 0], base_rotation=R0[j])
            assert float(attitude.geodesic_distance(one, R_end[i, j])) < 1e-14
    # the two designs do differ
    angles = np.asarray(attitude.geodesic_distance(R0, R_end))
    assert np.all(np.abs(angles[:, 1] - angles[:, 0]) > 1e-6)


def test_dispatch_and_errors(ur5, table1):
    phi = jnp.array([0.1, 0.3, -0.4])
    waypoints = jnp.array([[0.3, -0.4], [1.0, 0.2], [0.3, -0.4]])
    phi0_end, joints_end = sa.integrate_joint_path(table1, phi, waypoints)  # planar: (phi0, joints)
    assert phi0_end.shape == () and joints_end.shape == (2,)
    with pytest.raises(TypeError):
        sa.integrate_joint_path(table1, phi, waypoints, base_rotation=np.eye(3))
    with pytest.raises(sa.ConfigError, match="first row"):
        sa.integrate_joint_path(ur5, np.zeros(6), np.ones((3, 6)))
    with pytest.raises(sa.ConfigError, match="q_start"):
        sa.integrate_joint_path(ur5, np.zeros(5), np.zeros((3, 6)))
    with pytest.raises(sa.ConfigError, match="order"):
        sa.integrate_joint_path(ur5, np.zeros(6), np.zeros((3, 6)), order=5)
    # options of the other family's integrator are refused, never silently ignored
    for option in ({"nodes": 10}, {"pieces": 2}):
        with pytest.raises(TypeError, match="Magnus"):
            sa.integrate_joint_path(ur5, np.zeros(6), np.zeros((3, 6)), **option)
    for option in ({"steps": 4}, {"order": 6}):
        with pytest.raises(TypeError, match="line integral"):
            sa.integrate_joint_path(table1, phi, waypoints, **option)


def test_no_retrace_and_gradients(ur5):
    rng = np.random.default_rng(7)
    loops = _loops(rng, 2, 6)
    sa.integrate_joint_path(ur5, loops[:, 0], loops)
    size = attitude._integrate_flat._cache_size()
    sa.integrate_joint_path(ur5, loops[:, 0] + 0.1, loops + 0.1)
    assert attitude._integrate_flat._cache_size() == size

    arm3 = sa.load_robot(os.path.join(CONFIGS, "arm3dof-100kg.yaml"))  # a small graph to differentiate
    omega_map = functools.partial(attitude.bus_rate_map, arm3)
    loop = _loops(rng, 1, 3, segments=6)[0]

    @jax.jit
    def angle(scale):
        wp = loop[0] + scale * (jnp.asarray(loop) - loop[0])
        return attitude.log(attitude.path_rotation(omega_map, wp, 1, 6))[2]

    grad = jax.jit(jax.grad(angle))(1.0)
    step = 1e-5
    fd = (angle(1.0 + step) - angle(1.0 - step)) / (2 * step)
    np.testing.assert_allclose(grad, fd, rtol=1e-6)


def test_history_ends_where_the_integrator_does(ur5):
    rng = np.random.default_rng(8)
    loop = _loops(rng, 1, 6)[0]
    R, q, tips = sa.joint_path_history(ur5, loop[0], loop, 8)  # one Magnus step per sample
    assert R.shape == (12 * 8 + 1, 3, 3) and q.shape == (12 * 8 + 1, 6) and tips.shape == (12 * 8 + 1, 3)
    R_end, _ = sa.integrate_joint_path(ur5, loop[0], loop)
    assert float(attitude.geodesic_distance(R[-1], R_end)) < 1e-10
    np.testing.assert_allclose(q[::8], loop, atol=1e-15)
    # the tips are the inertial tips of the sampled attitudes and joints
    np.testing.assert_allclose(tips, np.einsum("sij,sj->si", R, np.asarray(sa.tip_position(ur5, q))), atol=1e-14)
