"""The readings of Table 2's w-bar (spacearm.studies.table2_readings): every derivation variant
against a closed form or a limit where it must equal the faithful model, every
averaging rule against the ground robot's closed forms, and the report's bookkeeping."""

import dataclasses
import math

import jax
import numpy as np
import pytest

import spacearm as sa
from spacearm.models.planar import closed_forms as kin
from spacearm.paper import normalized_wbar
from spacearm.studies import table2_readings as tv

from .conftest import count_compiles, random_robot

B0 = 1.4
RATIOS = (0.0, 0.5, 1.0, 1.5, 2.0)
PRINTED = (5.59, 5.93, 6.70, 7.52, 8.08)


def variant(name):
    return tv.Derivation(**tv.DEPARTURES[name][0])


def postures(n=2, count=64, seed=0):
    return np.random.default_rng(seed).uniform(-math.pi, math.pi, (count, n + 1))


def with_b0(robot, ratio):
    return robot.replace(base_attach=np.float64(B0 * ratio))


def heavy(robot, mass=1e12):
    """The same design on a base so heavy that it does not translate."""
    return robot.replace(base_mass=np.float64(mass))


# The faithful derivation is the package's model -------------------------------------------


@pytest.mark.parametrize("n", [2, 3])
def test_faithful_derivation_is_the_kinematics_module(n):
    rng = np.random.default_rng(n)
    for _ in range(3):
        robot = random_robot(rng, n)
        phi = postures(n, seed=n)
        i_s, i_m = tv.momentum_inertias(tv.FAITHFUL, robot, phi)
        ref_s, ref_m = kin.momentum_inertias(robot, phi)
        np.testing.assert_allclose(i_s, ref_s, rtol=1e-13)
        np.testing.assert_allclose(i_m, ref_m, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(
            tv.generalized_jacobian(tv.FAITHFUL, robot, phi),
            kin.generalized_jacobian(robot, phi),
            rtol=1e-12,
            atol=1e-12,
        )
        np.testing.assert_allclose(
            tv.manipulability(tv.FAITHFUL, robot, phi), kin.manipulability(robot, phi), rtol=1e-11, atol=1e-13
        )
        coeffs, ref = tv.derivation_coefficients(tv.FAITHFUL, robot), kin.design_coefficients(robot)
        for field in ("tip", "centroids", "inertia_coupling", "inertia"):
            np.testing.assert_allclose(getattr(coeffs, field), getattr(ref, field), rtol=1e-13, atol=1e-12)


def test_faithful_grid_averages_match_the_adaptive_quadrature(table1):
    robots = sa.stack_robots([with_b0(table1, r) for r in RATIOS])
    stats = tv.grid_averages([tv.FAITHFUL], robots)
    np.testing.assert_allclose(stats["area"][0], normalized_wbar(robots), rtol=1e-5)
    np.testing.assert_allclose(stats["joint"][0], normalized_wbar(robots, measure="joint"), rtol=1e-5)


def test_faithful_closed_form_at_b0_zero(table1):
    # b0 = 0: K0 = 0 and the base row of W vanishes, so J_S = t1 and det J* = det(t1, t2) h0 / I_S:
    # w* = K1 K2 |sin phi2| I0 / I_S with K1 = 2100/1200, K2 = 2300/1200 (Table 1).
    robot, phi = with_b0(table1, 0.0), postures()
    i_s, _ = tv.momentum_inertias(tv.FAITHFUL, robot, phi)
    expected = 2100 / 1200 * 2300 / 1200 * np.abs(np.sin(phi[:, 2])) * 635.3 / i_s
    np.testing.assert_allclose(tv.manipulability(tv.FAITHFUL, robot, phi), expected, rtol=1e-12)


# Each departure: a closed form, an identity, or the limit where it is the faithful model ---


@pytest.mark.parametrize("name", ["momentum about base centroid", "no base orbital term", "tip from base centroid"])
def test_departures_that_vanish_for_a_base_that_does_not_translate(table1, name):
    # m0 -> infinity: the system centroid is the base centroid and the base's orbital term
    # m0 |r0|^2 ~ (arm mass)^2 / m0 -> 0, so these three are the faithful model in the limit.
    phi = postures()
    for ratio in (0.0, 1.0, 2.0):
        robot = heavy(with_b0(table1, ratio))
        np.testing.assert_allclose(
            tv.manipulability(variant(name), robot, phi), tv.manipulability(tv.FAITHFUL, robot, phi), rtol=1e-8
        )
    # ... and at Table 1's masses they do differ.
    robot = with_b0(table1, 1.0)
    assert (
        np.max(np.abs(tv.manipulability(variant(name), robot, phi) - tv.manipulability(tv.FAITHFUL, robot, phi))) > 1e-3
    )


def test_momentum_about_joint1_is_about_the_base_centroid_when_they_coincide(table1):
    robot, phi = with_b0(table1, 0.0), postures()
    np.testing.assert_allclose(
        tv.momentum_inertias(variant("momentum about joint 1"), robot, phi)[0],
        tv.momentum_inertias(variant("momentum about base centroid"), robot, phi)[0],
        rtol=1e-13,
    )
    # Pinned at joint 1 with b0 > 0 the base swings about the shoulder: I_S gains m0 b0^2 over
    # the momentum about the base centroid (its other terms are the arm's, about the same point shifted).
    robot = heavy(with_b0(table1, 1.0))
    about_joint = tv.momentum_inertias(variant("momentum about joint 1"), robot, phi)[0]
    assert np.all(about_joint > 1e12 * B0**2 * 0.999)


def test_base_orbital_term_is_the_m0_row_of_W(table1):
    robot = with_b0(table1, 1.5)
    full, dropped = (tv.derivation_coefficients(d, robot) for d in (tv.FAITHFUL, variant("no base orbital term")))
    r0 = full.centroids[0]
    np.testing.assert_allclose(full.inertia_coupling - dropped.inertia_coupling, 1000.0 * np.outer(r0, r0), atol=1e-12)


def test_I0_about_joint1_is_faithful_at_b0_zero_and_a_heavier_base_otherwise(table1):
    phi = postures()
    robot = with_b0(table1, 0.0)
    np.testing.assert_allclose(
        tv.manipulability(variant("I0 about joint 1"), robot, phi),
        tv.manipulability(tv.FAITHFUL, robot, phi),
        rtol=1e-13,
    )
    robot = with_b0(table1, 2.0)
    parallel_axis = robot.replace(base_inertia=np.float64(635.3 + 1000.0 * (2 * B0) ** 2))
    np.testing.assert_allclose(
        tv.manipulability(variant("I0 about joint 1"), robot, phi), kin.manipulability(parallel_axis, phi), rtol=1e-12
    )


def test_no_base_inertia_freezes_the_tip_at_b0_zero(table1):
    # b0 = 0: w* = K1 K2 |sin phi2| I0 / I_S (faithful closed form) = 0 with I0 = 0.
    phi = postures()
    np.testing.assert_allclose(
        tv.manipulability(variant("no base inertia"), with_b0(table1, 0.0), phi), 0.0, atol=1e-12
    )
    robot = with_b0(table1, 1.0)
    np.testing.assert_allclose(
        tv.manipulability(variant("no base inertia"), robot, phi),
        kin.manipulability(robot.replace(base_inertia=np.float64(1e-12)), phi),
        rtol=1e-10,
        atol=1e-14,  # 0 is not a valid design
    )


@pytest.mark.parametrize(
    ("name", "inertia"),
    [
        ("I_i about joint i", lambda r: r.link_inertia + r.link_mass * r.link_a**2),
        ("point-mass links", lambda r: np.full(2, 1e-12)),
    ],
)  # 0 is not a valid design
def test_link_inertia_departures_are_the_faithful_model_of_another_design(table1, name, inertia):
    phi = postures()
    for ratio in (0.0, 1.0):
        robot = with_b0(table1, ratio)
        other = robot.replace(link_inertia=np.asarray(inertia(robot), float))
        np.testing.assert_allclose(
            tv.manipulability(variant(name), robot, phi), kin.manipulability(other, phi), rtol=1e-10, atol=1e-14
        )


def test_no_cross_terms_is_the_posture_averaged_inertia(table1):
    # Without the cos(theta_k - theta_l) terms I_S and I_M are constant, equal to the mean of the
    # faithful ones over the joint torus (the cosines average to zero on a uniform periodic grid).
    robot = with_b0(table1, 1.0)
    grid = np.linspace(-math.pi, math.pi, 32, endpoint=False)
    p1, p2 = np.meshgrid(grid, grid, indexing="ij")
    phi = np.stack([np.zeros_like(p1), p1, p2], axis=-1).reshape(-1, 3)
    i_s, i_m = tv.momentum_inertias(variant("no cross terms"), robot, phi)
    ref_s, ref_m = kin.momentum_inertias(robot, phi)
    np.testing.assert_allclose(i_s, np.mean(ref_s), rtol=1e-12)
    np.testing.assert_allclose(i_m, np.broadcast_to(np.mean(ref_m, axis=0), i_m.shape), rtol=1e-12)


def test_no_base_arm_cross_terms_is_the_faithful_inertia_averaged_over_phi1(table1):
    # The base-arm terms are D01 cos phi1 and D02 cos(phi1 + phi2); the arm's own D12 cos phi2
    # does not depend on phi1. Averaging the faithful I_S, I_M over phi1 (uniform periodic grid)
    # removes exactly the base-arm terms and keeps D12's.
    robot = with_b0(table1, 1.5)
    grid = np.linspace(-math.pi, math.pi, 32, endpoint=False)
    phi2 = np.array([0.3, 1.1, 2.0, 2.9])
    p1, p2 = np.meshgrid(grid, phi2, indexing="ij")
    phi = np.stack([np.zeros_like(p1), p1, p2], axis=-1)
    i_s, i_m = tv.momentum_inertias(variant("no base-arm cross terms"), robot, phi)
    ref_s, ref_m = kin.momentum_inertias(robot, phi)
    np.testing.assert_allclose(i_s, np.broadcast_to(np.mean(ref_s, axis=0), i_s.shape), rtol=1e-12)
    np.testing.assert_allclose(i_m, np.broadcast_to(np.mean(ref_m, axis=0), i_m.shape), rtol=1e-12)
    # and it differs from dropping every cross term: D12 cos phi2 is still there
    all_dropped, _ = tv.momentum_inertias(variant("no cross terms"), robot, phi)
    assert np.ptp(np.asarray(i_s)[0]) > 1.0 and np.ptp(np.asarray(all_dropped)[0]) < 1e-9


def test_link_rate_slip_reads_h_for_H(table1):
    # H_j = sum_{l>=j} h_l (faithful); the slip takes h_j: I_S = H0 - H1, I_M = (H1 - H2, H2).
    robot, phi = with_b0(table1, 1.0), postures()
    i_s, i_m = tv.momentum_inertias(variant("link-rate slip"), robot, phi)
    ref_s, ref_m = kin.momentum_inertias(robot, phi)
    np.testing.assert_allclose(i_s, ref_s - ref_m[:, 0], rtol=1e-12)
    np.testing.assert_allclose(i_m, np.stack([ref_m[:, 0] - ref_m[:, 1], ref_m[:, 1]], axis=-1), rtol=1e-12)


def test_sign_slip_mirrors_J_star_about_J_M(table1):
    robot, phi = with_b0(table1, 1.0), postures()
    j_m = kin.arm_jacobian(robot, phi)
    np.testing.assert_allclose(
        tv.generalized_jacobian(variant("sign slip"), robot, phi) + kin.generalized_jacobian(robot, phi),
        2 * j_m,
        atol=1e-12,
    )


def test_tip_origins(table1):
    robot, phi = with_b0(table1, 1.0), postures()
    assert np.allclose(tv.derivation_coefficients(variant("tip from base centroid"), robot).tip, [B0, 2.0, 2.0])
    assert np.allclose(tv.derivation_coefficients(variant("tip from joint 1"), robot).tip, [0.0, 2.0, 2.0])
    # From joint 1 the base rotation moves the tip as joint 1 does: J_S = the first column of
    # J_M = the ground robot's, and w* has the faithful I_S, I_M:
    # det J* = det(t1, t2) (1 - I_M1 / I_S) = l1 l2 sin phi2 h0 / I_S.
    i_s, i_m = kin.momentum_inertias(robot, phi)
    expected = np.abs(4.0 * np.sin(phi[:, 2]) * (i_s - i_m[:, 0]) / i_s)
    np.testing.assert_allclose(tv.manipulability(variant("tip from joint 1"), robot, phi), expected, rtol=1e-12)


def test_every_variant_jits_and_batches(table1):
    robots = sa.stack_robots([with_b0(table1, r) for r in RATIOS])
    phi = postures(count=4)
    for name in tv.DEPARTURES:
        w = jax.jit(tv.manipulability, static_argnums=0)(variant(name), robots, phi[:, None, :])
        assert w.shape == (4, len(RATIOS))


# The averaging rules, on the ground robot (a base too heavy to move) ---------------------------


def test_averaging_rules_on_the_ground_robot(table1):
    # I0, m0 -> infinity: J* = J_M with K = (b0, l1, l2), w* = l1 l2 |sin phi2|, and each rule has a
    # closed form in x = l1 l2 / L^2 = 1/4: area x pi/4, joint x 2/pi, area / joint volume x/2,
    # square x pi/4 * pi x, area of w^2 x^2 <sin^3>/<sin> = x^2 2/3, inertial area x pi/4.
    robots = sa.stack_robots(
        [with_b0(table1, r).replace(base_mass=np.float64(1e12), base_inertia=np.float64(1e16)) for r in (0.0, 2.0)]
    )
    stats = tv.grid_averages([tv.FAITHFUL], robots)
    x = 0.25
    expected = {
        "area": x * math.pi / 4,
        "joint": x * 2 / math.pi,
        "area / joint volume": x / 2,
        "square": x * math.pi / 4 * math.pi * x,
        "area of w^2": x * x * 2 / 3,
        "inertial area": x * math.pi / 4,
    }
    assert set(expected) | {"(b0+L)^2"} == set(tv.AVERAGES)
    for rule, value in expected.items():
        np.testing.assert_allclose(stats[rule][0], value, rtol=1e-5, err_msg=rule)
    np.testing.assert_allclose(
        stats["(b0+L)^2"][0], x * math.pi / 4 * np.array([1.0, 16 / (2 * B0 + 4) ** 2]), rtol=1e-5
    )


def test_a_pole_of_w_star_is_reported_not_averaged(table1):
    # The link-rate slip without base inertia puts I_S = h0 = 0 on the strip at b0 = 0.
    robots = sa.stack_robots([with_b0(table1, 0.0)])
    combined = tv.Derivation(base_inertia="zero", link_rates=True)
    assert np.isnan(tv.grid_averages([combined], robots)["area"][0, 0])


# Bookkeeping of the readings ---------------------------------------------------------------


def test_model_variants_are_the_singles_and_the_pairs_of_different_fields():
    variants = tv.model_variants()
    names = [n for n, _ in variants]
    assert names[0] == () and variants[0][1] == tv.FAITHFUL
    singles = [n for n in names if len(n) == 1]
    assert len(singles) == len(tv.DEPARTURES)
    for combo, derivation in variants:
        assert len(derivation.departures()) == len(combo)  # each departure changes its own field
    assert ("momentum about base centroid", "no base orbital term") not in names  # degenerate
    assert len({d for _, d in variants}) == len(variants)


def test_readings_report_every_variant_by_every_rule(table1):
    """... and compile no program but the grid's: the set-up on concrete designs runs in
    NumPy (eager jax.numpy compiled ~50 tiny programs in every process, too small to cache)."""
    from spacearm.studies.table2 import wbar_readings

    with count_compiles() as programs:
        readings = wbar_readings(table1)
    assert set(programs) <= {"jit(_grid_statistics)"}, programs
    assert len(readings) == len(tv.model_variants()) * len(tv.AVERAGES) + 3
    faithful = next(r for r in readings if r["name"] == "faithful / area")
    batch = sa.stack_robots([with_b0(table1, r) for r in RATIOS])
    np.testing.assert_allclose(faithful["values"], 100 * np.asarray(normalized_wbar(batch)), rtol=1e-5)
    assert faithful["departures"] == 0


def test_relative_errors_and_chance_level():
    assert tv.relative_errors([2.0, 3.0], [2.0, 2.0]) == pytest.approx((0.5, math.sqrt(0.125)))
    values = np.array([PRINTED, np.linspace(5.59, 8.08, 5)])
    fraction, median = tv.chance_level(values, PRINTED, trials=200)
    assert fraction == 0.0 and median > 0.0  # an exact reading is matched by no random column
    assert dataclasses.replace(tv.FAITHFUL, sign=-1).departures() == ("sign",)
    with pytest.raises(ValueError, match="momentum_origin"):
        tv.Derivation(momentum_origin="moon")


def test_shape_error_is_blind_to_a_constant_factor():
    assert tv.shape_error(0.6 * np.asarray(PRINTED), PRINTED) == pytest.approx(0.0, abs=1e-15)
    assert tv.shape_error([1.0, 2.0], [1.0, 1.0]) == pytest.approx(1.0)
    assert math.isnan(tv.shape_error([0.0, 1.0], [1.0, 1.0]))
    values = np.array([2 * np.asarray(PRINTED), np.linspace(1.0, 2.0, 5)])
    fraction, _ = tv.chance_level(values, PRINTED, trials=200, statistic="shape")
    assert fraction == 0.0
