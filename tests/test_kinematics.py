"""The kinematic kernels against the paper's closed forms, a naive reference and physics."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.integrate import solve_ivp

import spacearm as sa

from . import reference as ref
from .conftest import random_robot

B0 = 1.4
L = 4.0
# Table 2 of Umetani & Yoshida 1990, printed to two decimals.
TABLE2 = {0.0: (0.84, 0.84), 0.5: (1.13, 0.59), 1.0: (1.46, 0.39), 1.5: (1.83, 0.23), 2.0: (2.25, 0.11)}


@pytest.mark.parametrize("ratio", sorted(TABLE2))
def test_K_and_normalized_areas_match_table2(table1, ratio):
    robot = table1.replace(base_attach=np.float64(ratio * B0))
    K0, K1, K2 = np.asarray(sa.tip_coefficients(robot))
    # eq. (1) closed forms
    w = 1200.0
    np.testing.assert_allclose(K0, 1000.0 * ratio * B0 / w, rtol=1e-15)
    np.testing.assert_allclose(K1, (1000.0 * 2.0 + 100.0 * 1.0) / w, rtol=1e-15)
    np.testing.assert_allclose(K2, ((1000.0 + 100.0) * 2.0 + 100.0 * 1.0) / w, rtol=1e-15)
    s_m, s_g = (K0 + K1 + K2) ** 2 / L**2, (K0 - K1 - K2) ** 2 / L**2
    assert round(s_m, 2) == TABLE2[ratio][0]
    assert round(s_g, 2) == TABLE2[ratio][1]


@pytest.mark.parametrize("n", [2, 3, 4])
def test_kernels_match_naive_reference(n):
    rng = np.random.default_rng(n)
    for _ in range(5):
        robot = random_robot(rng, n)
        d = ref.design(robot)
        phi = rng.uniform(-np.pi, np.pi, n + 1)
        np.testing.assert_allclose(sa.tip_position(robot, phi), ref.tip(d, phi), atol=1e-13)
        centroids, _ = ref.bodies_and_tip(d, phi)
        np.testing.assert_allclose(sa.centroid_positions(robot, phi), centroids, atol=1e-13)
        J = np.asarray(sa.generalized_jacobian(robot, phi))
        np.testing.assert_allclose(J, ref.generalized_jacobian(d, phi), atol=1e-12)
        rates = rng.normal(size=n)
        np.testing.assert_allclose(sa.base_rate(robot, phi, rates), ref.base_rate(d, phi, rates), atol=1e-12)
        w = float(sa.manipulability(robot, phi))
        np.testing.assert_allclose(w, np.sqrt(np.linalg.det(J @ J.T)), rtol=1e-10)


def test_jacobian_pieces_compose(table1):
    phi = jnp.array([0.4, -0.7, 1.9])
    J_S, J_M = sa.base_jacobian(table1, phi), sa.arm_jacobian(table1, phi)
    i_s, i_m = sa.momentum_inertias(table1, phi)
    expected = J_M - J_S[:, None] * i_m[None, :] / i_s  # eq. (6)
    np.testing.assert_allclose(sa.generalized_jacobian(table1, phi), expected, atol=1e-15)
    # J_S, J_M are the partial derivatives of eq. (1)
    jac = jax.jacfwd(lambda p: sa.tip_position(table1, p))(phi)
    np.testing.assert_allclose(jac[:, 0], J_S, atol=1e-14)
    np.testing.assert_allclose(jac[:, 1:], J_M, atol=1e-14)


def _naive_motion(d, phi_start, joint_rate_fn, t_end):
    """Integrate the base with the naive momentum balance (scipy, tight tolerances)."""

    def rhs(t, phi):
        rates = joint_rate_fn(t)
        return np.r_[ref.base_rate(d, phi, rates), rates]

    return solve_ivp(rhs, (0.0, t_end), phi_start, rtol=1e-12, atol=1e-12, dense_output=True)


def test_generalized_jacobian_along_momentum_conserving_motion(table1):
    d = ref.design(table1)
    rates = lambda t: np.array([0.3 * np.cos(t), -0.5 + 0.2 * np.sin(2 * t)])
    sol = _naive_motion(d, np.radians([0.0, -60.0, 120.0]), rates, 3.0)
    h = 1e-5
    for t in np.linspace(0.2, 2.8, 7):
        phi = sol.sol(t)
        tip_rate = (ref.tip(d, sol.sol(t + h)) - ref.tip(d, sol.sol(t - h))) / (2 * h)
        predicted = np.asarray(sa.generalized_jacobian(table1, phi)) @ rates(t)
        np.testing.assert_allclose(predicted, tip_rate, atol=1e-7)
        phi_rates = np.r_[ref.base_rate(d, phi, rates(t)), rates(t)]
        linear, angular = ref.momentum(d, phi, phi_rates)
        assert np.all(np.abs(linear) < 1e-10) and abs(angular) < 1e-10
        assert abs(float(sa.angular_momentum(table1, phi, phi_rates))) < 1e-10


def test_manipulability_independent_of_base_attitude(table1):
    rng = np.random.default_rng(0)
    phi = rng.uniform(-np.pi, np.pi, (100, 3))
    w = sa.manipulability(table1, phi)
    for phi0 in (0.7, -2.0, 3.0):
        moved = phi.at[:, 0].set(phi0) if isinstance(phi, jax.Array) else np.c_[np.full(100, phi0), phi[:, 1:]]
        np.testing.assert_allclose(sa.manipulability(table1, moved), w, rtol=1e-13)
        J = sa.generalized_jacobian(table1, moved)
        np.testing.assert_allclose(jnp.abs(jnp.linalg.det(J)), w, rtol=1e-10, atol=1e-14)


def test_infinitely_heavy_base_gives_fixed_base_jacobian(table1):
    phi = np.array([0.3, 0.8, 1.1])
    heavy = table1.replace(base_mass=np.float64(1e15), base_inertia=np.float64(1e15))
    J = sa.generalized_jacobian(heavy, np.r_[0.0, phi[1:]])
    np.testing.assert_allclose(J, sa.fixed_base_jacobian(table1, phi[1:]), atol=1e-11)
    l1, l2 = 2.0, 2.0
    np.testing.assert_allclose(sa.fixed_base_manipulability(table1, phi[1:]), l1 * l2 * abs(np.sin(phi[2])), rtol=1e-14)


def test_singular_postures_zero_and_finite_gradients(table1):
    # The base at b0 = 0 with phi2 = 0 and the arm stretched: J* loses rank.
    robot = table1.replace(base_attach=np.float64(0.0))
    phi = jnp.array([0.0, 0.3, 0.0])
    assert float(sa.manipulability(robot, phi)) < 1e-15
    g = jax.grad(lambda p: sa.manipulability(robot, p))(phi)
    assert np.all(np.isfinite(g))
    # General n: a stretched 3-link arm on a centred base is singular (all minors vanish).
    rng = np.random.default_rng(1)
    r3 = random_robot(rng, 3).replace(base_attach=np.float64(0.0))
    phi3 = jnp.array([0.2, 0.5, 0.0, 0.0])
    assert float(sa.manipulability(r3, phi3)) < 1e-12
    g3 = jax.grad(lambda p: sa.manipulability(r3, p))(phi3)
    assert np.all(np.isfinite(g3))
    gd = jax.grad(lambda r: sa.manipulability(r, phi3))(r3)
    assert all(np.all(np.isfinite(x)) for x in jax.tree_util.tree_leaves(gd))


def test_dynamic_singularity_differs_from_phi2_zero(table1):
    """With b0 > 0 the free-floating arm is not singular at phi2 = 0 (issue 3, note)."""
    w = sa.manipulability(table1, jnp.array([0.0, 1.0, 0.0]))
    assert float(w) > 0.1


def test_ellipse_axes_are_singular_values():
    rng = np.random.default_rng(3)
    for n in (2, 3):
        robot = random_robot(rng, n)
        phi = rng.uniform(-np.pi, np.pi, (20, n + 1))
        major, minor, angle = sa.manipulability_ellipse(robot, phi)
        J = np.asarray(sa.generalized_jacobian(robot, phi))
        U, S, _ = np.linalg.svd(J)
        np.testing.assert_allclose(major, S[:, 0], rtol=1e-12)
        np.testing.assert_allclose(minor, S[:, 1], rtol=1e-10, atol=1e-14)
        direction = np.stack([np.cos(angle), np.sin(angle)], -1)
        np.testing.assert_allclose(np.abs(np.sum(direction * U[:, :, 0], -1)), 1.0, atol=1e-10)
        np.testing.assert_allclose(major * minor, sa.manipulability(robot, phi), rtol=1e-12)


def test_grid_equals_pointwise(table1):
    a1 = jnp.linspace(-np.pi, np.pi, 37)
    a2 = jnp.linspace(0.0, np.pi, 19)
    grid = sa.manipulability_on_grid(table1, [a1, a2])
    P1, P2 = jnp.meshgrid(a1, a2, indexing="ij")
    pointwise = sa.manipulability(table1, jnp.stack([jnp.zeros_like(P1), P1, P2], -1))
    np.testing.assert_allclose(grid, pointwise, atol=1e-14)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n=st.sampled_from([2, 3, 4]))
def test_random_designs_reference_and_invariants(seed, n):
    rng = np.random.default_rng(seed)
    robot = random_robot(rng, n)
    d = ref.design(robot)
    phi = rng.uniform(-np.pi, np.pi, n + 1)
    J = np.asarray(sa.generalized_jacobian(robot, phi))
    np.testing.assert_allclose(J, ref.generalized_jacobian(d, phi), atol=1e-11)
    # zero momentum for any joint rates with the base rate of eq. (5)
    rates = rng.normal(size=n)
    full = np.r_[float(sa.base_rate(robot, phi, rates)), rates]
    _, angular = ref.momentum(d, phi, full)
    assert abs(angular) < 1e-10 * (1 + np.sum(d["m"]))
    # w* never exceeds the product of the row norms (Hadamard on J* J*^T)
    w = float(sa.manipulability(robot, phi))
    assert w <= np.prod(np.linalg.norm(J, axis=1)) * (1 + 1e-12)


def test_no_recompilation_for_new_values(table1):
    traces = []

    @jax.jit
    def f(robot, phi):
        traces.append(1)
        return sa.manipulability(robot, phi)

    rng = np.random.default_rng(0)
    f(table1, rng.uniform(size=(64, 3))).block_until_ready()
    other = table1.replace(base_attach=np.float64(2.8), link_mass=np.array([50.0, 70.0]))
    f(other, rng.uniform(size=(64, 3))).block_until_ready()
    f(table1, rng.uniform(size=(64, 3))).block_until_ready()
    assert len(traces) == 1


def test_vmap_over_designs_matches_loop(table1):
    ratios = np.linspace(0, 2, 5)
    batch = sa.stack_robots([table1.replace(base_attach=np.float64(r * B0)) for r in ratios])
    phi = jnp.array([0.1, -1.0, 2.0])
    batched = jax.jit(jax.vmap(sa.manipulability, in_axes=(0, None)))(batch, phi)
    for i, r in enumerate(ratios):
        single = sa.manipulability(table1.replace(base_attach=np.float64(r * B0)), phi)
        np.testing.assert_allclose(batched[i], single, rtol=1e-14)
    # Broadcasting: one posture per design without vmap.
    phis = jnp.tile(phi, (5, 1))
    np.testing.assert_allclose(sa.manipulability(batch, phis), batched, rtol=1e-14)
