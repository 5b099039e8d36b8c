"""w-bar (eq. 12), S_M and S_G (Table 2), manipulability maps: against closed forms,
finite differences, brute-force quadrature and the paper's printed areas."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import spacearm as sa
from spacearm import ConfigError
from spacearm.kinematics import manipulability
from spacearm.paper import (
    fixed_base_average_manipulability,
    grid_average,
    inverse_kinematics,
    manipulability_map,
    normalized_areas,
    normalized_wbar,
    workspace_map,
)

from .conftest import random_robot

B0 = 1.4
RATIOS = (0.0, 0.5, 1.0, 1.5, 2.0)
PRINTED_S_M = (0.84, 1.13, 1.46, 1.83, 2.25)
PRINTED_S_G = (0.84, 0.59, 0.39, 0.23, 0.11)


def _with_b0(robot, ratio):
    return robot.replace(base_attach=np.float64(B0 * ratio))


def test_normalized_areas_match_closed_form_and_table2(table1):
    for ratio, s_m_printed, s_g_printed in zip(RATIOS, PRINTED_S_M, PRINTED_S_G, strict=False):
        robot = _with_b0(table1, ratio)
        s_m, s_g = normalized_areas(robot)
        # Closed form from Table 1: w = 1200 kg, K0 = 1000 b0 / 1200, K1 = (1000*2 + 100*1) / 1200,
        # K2 = (1100*2 + 100*1) / 1200, L = 4 m.
        k0, k1, k2 = 1000 * B0 * ratio / 1200, 2100 / 1200, 2300 / 1200
        assert float(s_m) == pytest.approx((k0 + k1 + k2) ** 2 / 16, rel=1e-14)
        assert float(s_g) == pytest.approx((k0 - k1 - k2) ** 2 / 16, rel=1e-14)
        assert round(float(s_m), 2) == s_m_printed
        assert round(float(s_g), 2) == s_g_printed


def _brute_force_wbar(robot, n1=720, n2=360):
    """Midpoint rule on the elbow-down strip with w* from the public kernel (no shared code)."""
    phi1 = -math.pi + 2 * math.pi * (np.arange(n1) + 0.5) / n1
    phi2 = math.pi * (np.arange(n2) + 0.5) / n2
    p1, p2 = np.meshgrid(phi1, phi2, indexing="ij")
    phi = np.stack([np.zeros_like(p1), p1, p2], axis=-1)
    w = np.asarray(manipulability(robot, phi)) / float(robot.reach) ** 2
    l1, l2 = np.asarray(robot.link_length)
    ds = l1 * l2 * np.abs(np.sin(p2))
    return float(np.sum(w * ds) / np.sum(ds))


def test_wbar_agrees_with_brute_force_midpoint_rule(table1):
    for ratio in (0.0, 1.0, 2.0):
        robot = _with_b0(table1, ratio)
        # The midpoint rule is second order at the kinks: 720 x 360 points leave ~1e-6.
        assert float(normalized_wbar(robot)) == pytest.approx(_brute_force_wbar(robot), rel=2e-5)


def test_wbar_reproduces_faithful_values(table1):
    # Regression on the faithful reading (eq. 12): converged to ~1e-14 (see the convergence test).
    expected = (0.0876862727874975, 0.0907243239426461, 0.0970120167785581, 0.1014599860992248, 0.1023088639013738)
    batch = sa.stack_robots([_with_b0(table1, r) for r in RATIOS])
    values = np.asarray(jax.jit(normalized_wbar)(batch))
    np.testing.assert_allclose(values, expected, rtol=1e-12)


def test_quadrature_converges_spectrally_and_product_rule_at_second_order(table1):
    robot = _with_b0(table1, 2.0)
    reference = float(normalized_wbar(robot, order=16))
    errors = [abs(float(normalized_wbar(robot, order=q)) - reference) for q in (4, 8)]
    # Gauss-Legendre split at det J* = 0: 7e-6 (2 points), 4e-10 (4), 1e-13 (6), 1e-15 (8) in
    # the study of the README; here the two ends of that range.
    assert 1e-11 < errors[0] < 1e-8 and errors[1] < 1e-13, errors
    plain = [
        abs(float(normalized_wbar(robot, phi1_panels=p, phi2_panels=p // 2, order=8, rule="product")) - reference)
        for p in (8, 16, 32)
    ]
    orders = [math.log2(plain[i] / plain[i + 1]) for i in range(2)]
    # The plain product rule sees the kinks of |det J*|: observed order ~2.
    assert all(1.5 < k < 3.0 for k in orders), orders


def test_written_out_determinant_matches_generic_kernel():
    from spacearm.kinematics import generalized_jacobian
    from spacearm.models.planar.closed_forms import design_coefficients
    from spacearm.paper.manipulability_average import _signed_determinant

    rng = np.random.default_rng(5)
    for robot in (sa.umetani1990(), random_robot(rng, 2)):
        phi = rng.uniform(-4, 4, (50, 2))
        det = _signed_determinant(design_coefficients(robot), np.cos(phi[:, 0]), np.sin(phi[:, 0]), phi[:, 1])
        full = np.concatenate([np.zeros((50, 1)), phi], axis=1)
        np.testing.assert_allclose(
            np.asarray(det), np.linalg.det(np.asarray(generalized_jacobian(robot, full))), atol=1e-13
        )


def test_elbow_sheets_agree_by_mirror_symmetry(table1):
    robot = _with_b0(table1, 1.0)
    down = float(normalized_wbar(robot))
    assert float(normalized_wbar(robot, elbow="up")) == pytest.approx(down, rel=1e-12)


def test_ground_robot_limit_matches_closed_form(table1):
    # An (almost) immovable base turns J* into the fixed-base Jacobian, w = l1 l2 |sin phi2|;
    # its area average is (l1 l2 / L^2) pi / 4 (the formula, verified:
    # int (l1 l2 sin)^2 dphi / (4 pi l1 l2 L^2) = 2 pi (pi/2) l1^2 l2^2 / (4 pi l1 l2 L^2)).
    heavy = table1.replace(base_mass=np.float64(1e15), base_inertia=np.float64(1e17))
    closed = float(fixed_base_average_manipulability(heavy))
    assert closed == pytest.approx(4.0 / 16.0 * math.pi / 4.0, rel=1e-15)
    assert float(normalized_wbar(heavy)) == pytest.approx(closed, rel=1e-9)
    joint = float(fixed_base_average_manipulability(heavy, measure="joint"))
    assert joint == pytest.approx(4.0 / 16.0 * 2.0 / math.pi, rel=1e-15)
    assert float(normalized_wbar(heavy, measure="joint")) == pytest.approx(joint, rel=1e-9)


def test_ground_robot_closed_form_for_unequal_links():
    robot = random_robot(np.random.default_rng(3), 2).replace(base_mass=np.float64(1e15), base_inertia=np.float64(1e17))
    l1, l2 = np.asarray(robot.link_length)
    expected = l1 * l2 / (l1 + l2) ** 2 * math.pi / 4
    assert float(normalized_wbar(robot)) == pytest.approx(expected, rel=1e-9)


def test_gradient_wrt_design_matches_finite_differences(table1):
    grad_fn = jax.grad(normalized_wbar)
    for b0 in (1.4, 2.8):
        robot = table1.replace(base_attach=np.float64(b0))
        grads = grad_fn(robot)
        for leaf in jax.tree_util.tree_leaves(grads):
            assert np.all(np.isfinite(np.asarray(leaf)))
        h = 1e-4
        # Fourth-order central difference in b0; the quadrature error (~1e-15) is far below h^4.
        f = [float(normalized_wbar(table1.replace(base_attach=np.float64(b0 + k * h)))) for k in (-2, -1, 1, 2)]
        fd = (f[0] - 8 * f[1] + 8 * f[2] - f[3]) / (12 * h)
        assert float(grads.base_attach) == pytest.approx(fd, rel=1e-7)
        h = 1e-3
        bumped = [robot.replace(link_inertia=robot.link_inertia + np.array([s * h, 0.0])) for s in (1, -1)]
        fd = (float(normalized_wbar(bumped[0])) - float(normalized_wbar(bumped[1]))) / (2 * h)
        assert float(grads.link_inertia[0]) == pytest.approx(fd, rel=1e-6)
    # w-bar is even in b0 (mirror symmetry), so its slope vanishes at b0 = 0.
    assert abs(float(grad_fn(table1.replace(base_attach=np.float64(0.0))).base_attach)) < 1e-12


def test_vmap_over_designs_equals_loop(table1):
    rng = np.random.default_rng(0)
    robots = [random_robot(rng, 2) for _ in range(2)]
    vmapped = jax.vmap(lambda r: normalized_wbar(r))(sa.stack_robots(robots))
    singles = np.array([float(normalized_wbar(r)) for r in robots])
    np.testing.assert_allclose(np.asarray(vmapped), singles, rtol=1e-13)


def test_random_designs_against_brute_force():
    rng = np.random.default_rng(7)
    for _ in range(2):
        robot = random_robot(rng, 2)
        assert float(normalized_wbar(robot)) == pytest.approx(_brute_force_wbar(robot), rel=5e-5)


def test_joint_measure_for_three_links_matches_dense_grid():
    robot = random_robot(np.random.default_rng(11), 3)
    coarse = float(normalized_wbar(robot, measure="joint", n_points_joint=24))
    # Same numbers from the unchunked public kernel.
    axis = np.linspace(-math.pi, math.pi, 24, endpoint=False)
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1)
    phi = np.concatenate([np.zeros(grid.shape[:-1] + (1,)), grid], axis=-1)
    direct = float(np.mean(np.asarray(manipulability(robot, phi)))) / float(robot.reach) ** 2
    assert coarse == pytest.approx(direct, rel=1e-12)
    assert float(grid_average(robot, 24, rows_per_chunk=5)) == pytest.approx(direct, rel=1e-12)


def test_bad_options_raise_config_error(table1):
    with pytest.raises(ConfigError, match="measure"):
        normalized_wbar(table1, measure="volume")
    with pytest.raises(ConfigError, match="elbow"):
        normalized_wbar(table1, elbow="sideways")
    with pytest.raises(ConfigError, match="phi1_panels"):
        normalized_wbar(table1, phi1_panels=3)
    three = random_robot(np.random.default_rng(1), 3)
    with pytest.raises(ConfigError, match="n = 3"):
        normalized_wbar(three)


def test_manipulability_map_chunks_equal_direct(table1):
    axes = [np.linspace(-math.pi, math.pi, 12), np.linspace(0, math.pi, 7)]
    chunked = manipulability_map(table1, axes, rows_per_chunk=5)  # 12 rows: chunks of 5, 5, 2
    p1, p2 = np.meshgrid(*axes, indexing="ij")
    direct = np.asarray(manipulability(table1, np.stack([0 * p1, p1, p2], -1))) / 16.0
    np.testing.assert_allclose(np.asarray(chunked), direct, rtol=1e-12, atol=1e-15)


def test_workspace_map_inverse_kinematics_round_trip(table1):
    points = np.array([[1.0, 2.0], [-3.0, 0.5], [0.2, -3.9]])
    for elbow in ("down", "up"):
        phi_arm, ok = inverse_kinematics(table1, points, elbow=elbow)
        assert np.all(np.asarray(ok))
        np.testing.assert_allclose(np.asarray(sa.robot_frame_tip_position(table1, phi_arm)), points, atol=1e-12)
        assert np.all(np.asarray(phi_arm[:, 1]) * (1 if elbow == "down" else -1) >= 0)
    _x, _y, w = workspace_map(table1, 41)
    assert np.isnan(np.asarray(w)[0, 0])  # the corner (-L, -L) is out of reach
    _, _, ground = workspace_map(table1, 41, ground=True)
    # Ground robot: w/L^2 = l1 l2 |sin phi2| / L^2 is at most 1/4 (at r^2 = l1^2 + l2^2).
    assert float(np.nanmax(np.asarray(ground))) <= 0.25 + 1e-12


def test_panel_forms_of_the_determinant_match_the_written_out_one():
    # The adaptive rule's det J* = N / H: trigonometric forms in phi2, rotated to panel
    # centers, and N as a quartic in t = tan((phi2 - c) / 2), against _signed_determinant.
    from spacearm.models.planar.closed_forms import design_coefficients
    from spacearm.paper.manipulability_average import (
        _TO_QUARTIC,
        _fourier_forms,
        _panel_rotations,
        _polynomial,
        _signed_determinant,
    )

    rng = np.random.default_rng(8)
    centers = np.array([0.3, 2.0, -2.9])
    rotate_n, rotate_h = _panel_rotations(centers)
    for robot in (sa.umetani1990(), random_robot(rng, 2)):
        coeffs = design_coefficients(robot)
        phi1, offset = rng.uniform(-4, 4, 50), rng.uniform(-0.6, 0.6, 50)
        numerator, total = (np.asarray(x) for x in _fourier_forms(coeffs, np.cos(phi1), np.sin(phi1)))
        for k, c in enumerate(centers):
            det = np.asarray(_signed_determinant(coeffs, np.cos(phi1), np.sin(phi1), c + offset))
            n_local, h_local = numerator @ rotate_n[:, 5 * k : 5 * k + 5], total @ rotate_h[:, 3 * k : 3 * k + 3]
            basis = np.stack(
                [np.ones_like(offset), np.cos(offset), np.sin(offset), np.cos(2 * offset), np.sin(2 * offset)], -1
            )
            h = np.sum(h_local * basis[:, :3], -1)
            assert np.all(h > 0)
            np.testing.assert_allclose(np.sum(n_local * basis, -1) / h, det, rtol=1e-12, atol=1e-13)
            t = np.tan(offset / 2)
            quartic = np.asarray(_polynomial(jnp.asarray(n_local @ _TO_QUARTIC), t)) / (1 + t * t) ** 2
            np.testing.assert_allclose(quartic / h, det, rtol=1e-12, atol=1e-13)


def test_closed_form_edge_crossings_are_the_sign_changes_on_the_strip_edges():
    # phi1 splits of the adaptive rule: besides phi1 = 0, pi, det J* changes sign on
    # phi2 = 0 (pi) exactly at +-arccos of _edge_crossings; compare with a dense scan.
    from spacearm.models.planar.closed_forms import design_coefficients
    from spacearm.paper.manipulability_average import _edge_crossings, _signed_determinant

    rng = np.random.default_rng(9)
    robots = [random_robot(rng, 2).replace(base_attach=np.float64(rng.uniform(0.2, 4.0))) for _ in range(12)]
    robots += [
        r.replace(base_mass=np.float64(rng.uniform(20, 60)), base_inertia=np.float64(rng.uniform(2, 20)))
        for r in robots[:8]
    ]
    grid = np.linspace(1e-9, math.pi - 1e-9, 200_001)
    found = 0
    for robot in robots:
        coeffs = design_coefficients(robot)
        cosines, valid = (np.asarray(x) for x in _edge_crossings(coeffs))
        for edge, phi2 in enumerate((0.0, math.pi)):
            det = np.asarray(_signed_determinant(coeffs, np.cos(grid), np.sin(grid), phi2))
            changes = grid[np.nonzero(np.sign(det[1:]) != np.sign(det[:-1]))[0]]
            if valid[edge]:
                found += 1
                assert changes.shape == (1,) and abs(changes[0] - math.acos(cosines[edge])) < 1e-4, (changes, cosines)
            else:
                assert changes.size == 0, changes
    assert found >= 3  # the scan does test crossings away from phi1 = 0, pi


def test_polynomial_roots_and_taylor_cos_sin():
    from spacearm.paper.manipulability_average import _cos_sin, _polynomial_roots

    # (t - 0.1)(t + 2)(t^2 + 1): one root in [-0.5, 0.5]; none in [0.2, 0.5] (midpoint returned).
    quartic = np.polynomial.polynomial.polyfromroots([0.1, -2.0, 1j, -1j]).real
    roots = _polynomial_roots(jnp.asarray(quartic), jnp.array([-0.5, 0.2]), jnp.array([0.5, 0.5]), newton_steps=4)
    np.testing.assert_allclose(np.asarray(roots), [0.1, 0.35], rtol=0, atol=1e-15)
    for bound in (math.pi / 16, math.pi / 8, math.pi / 2):
        theta = np.linspace(-bound, bound, 1001)
        cos, sin = _cos_sin(jnp.asarray(theta), bound)
        np.testing.assert_allclose(np.asarray(cos), np.cos(theta), rtol=0, atol=3e-16)
        np.testing.assert_allclose(np.asarray(sin), np.sin(theta), rtol=0, atol=3e-16)


def test_elbow_sheets_and_measures_agree_with_a_converged_reference():
    # elbow "both" and measure="joint" through the same adaptive rule, against a finer one.
    robot = random_robot(np.random.default_rng(12), 2).replace(base_attach=np.float64(3.0))
    fine = {"phi1_panels": 16, "phi2_panels": 8, "order": 16, "newton_steps": 8}
    for options in ({"elbow": "both"}, {"measure": "joint"}, {"measure": "joint", "elbow": "up"}):
        value = float(normalized_wbar(robot, **options))
        assert value == pytest.approx(float(normalized_wbar(robot, **options, **fine)), rel=1e-11), options
