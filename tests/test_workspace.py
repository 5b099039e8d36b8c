"""Workspaces (sec. 3): closed forms, relations (eq. 9), dynamic singularities, straight paths."""

import numpy as np
import pytest

import spacearm as sa
from spacearm import analysis, paper

from . import reference
from .conftest import count_compiles, random_robot

GRID = dict(n_phi1=360, n_phi2=64)  # one compiled singular-set shape for every test


def _random_postures(rng, count, n):
    return rng.uniform(-np.pi, np.pi, (count, n + 1))


def _reference_tips(robot, phis):
    d = reference.design(robot)
    return np.array([reference.tip(d, p) for p in phis])


# Closed forms ------------------------------------------------------------------------


@pytest.mark.parametrize("n", [2, 3, 4])
def test_closed_form_radii_against_naive_model(n):
    rng = np.random.default_rng(n)
    robot = random_robot(rng, n)
    d = reference.design(robot)
    # Area 3: the stretched arm reaches K0+..+Kn, and no sampled posture goes farther.
    stretched = reference.tip(d, np.zeros(n + 1))
    assert np.linalg.norm(stretched) == pytest.approx(float(analysis.maximum_reachable_radius(robot)), rel=1e-12)
    phis = _random_postures(rng, 3000, n)
    radii = np.linalg.norm(_reference_tips(robot, phis), axis=-1)
    assert radii.max() <= float(analysis.maximum_reachable_radius(robot)) + 1e-12
    assert radii.min() >= float(analysis.maximum_reachable_inner_radius(robot)) - 1e-12
    # Area 2 (phi0 = 0): every tip within K1+..+Kn of (K0, 0), outside the hole.
    center, radius = paper.attitude_constraint(robot)
    phis[:, 0] = 0.0
    gaps = np.linalg.norm(_reference_tips(robot, phis) - np.asarray(center), axis=-1)
    assert gaps.max() <= float(radius) + 1e-12
    assert gaps.max() >= 0.9 * float(radius)
    assert gaps.min() >= float(paper.attitude_constraint_inner_radius(robot)) - 1e-12
    # Area 1 placement: joint 1 of the stretched posture phi = 0 is its centre.
    joint1 = stretched - np.array([float(robot.reach), 0.0])
    np.testing.assert_allclose(np.asarray(paper.fixed_vehicle_center(robot)), joint1, atol=1e-12)


def test_table1_radii_and_table2_areas():
    robot = sa.umetani1990()
    K = np.asarray(sa.tip_coefficients(robot))
    np.testing.assert_allclose(K, [1.4 * 1000 / 1200, 2100 / 1200, 2300 / 1200], rtol=1e-14)
    assert float(paper.guaranteed_radius(robot)) == pytest.approx(2.5, rel=1e-14)
    assert float(paper.kinematic_singularity_radius(robot)) == pytest.approx(1.0, rel=1e-14)
    assert float(paper.attitude_constraint_inner_radius(robot)) == pytest.approx(1 / 6, rel=1e-12)
    # Table 2 of the paper, S_M and S_G to its two printed decimals.
    printed = {0.0: (0.84, 0.84), 0.5: (1.13, 0.59), 1.0: (1.46, 0.39), 1.5: (1.83, 0.23), 2.0: (2.25, 0.11)}
    for ratio, (s_m, s_g) in printed.items():
        areas = paper.normalized_workspace_areas(robot.replace(base_attach=np.float64(1.4 * ratio)))
        assert float(areas["maximum_reachable_disk"]) == pytest.approx(s_m, abs=0.006)
        assert float(areas["guaranteed"]) == pytest.approx(s_g, abs=0.006)


def _contained(center_in, r_in, center_out, r_out, samples=720):
    """Disk containment by sampling the inner boundary (independent of the gap formula)."""
    angle = np.linspace(0, 2 * np.pi, samples, endpoint=False)
    ring = center_in[..., None, :] + r_in[..., None, None] * np.stack([np.cos(angle), np.sin(angle)], -1)
    return np.all(np.linalg.norm(ring - center_out[..., None, :], axis=-1) <= r_out[..., None] + 1e-9, axis=-1)


def test_relations_of_section_3_2_on_random_designs():
    rng = np.random.default_rng(7)
    designs = sa.stack_robots([random_robot(rng, 2) for _ in range(1000)])
    rel = {k: np.asarray(v) for k, v in paper.workspace_relations(designs).items()}
    K = np.asarray(sa.tip_coefficients(designs))
    zero = np.zeros((1000, 2))
    c1, r1 = np.asarray(paper.fixed_vehicle_center(designs)), np.asarray(designs.reach)
    c2, r2 = (np.asarray(x) for x in paper.attitude_constraint(designs))
    r3, r5 = np.asarray(analysis.maximum_reachable_radius(designs)), np.asarray(paper.guaranteed_radius(designs))
    np.testing.assert_array_equal(rel["3>=2"], _contained(c2, r2, zero, r3))
    np.testing.assert_array_equal(rel["2>=5"], _contained(zero, r5, c2, r2))
    np.testing.assert_array_equal(rel["3>=1"], _contained(c1, r1, zero, r3))
    np.testing.assert_array_equal(rel["1>=2"], _contained(c2, r2, c1, r1))
    assert rel["3>=2"].all() and rel["1>=2"].all()
    # "Area 2 >= Area 5 always" fails exactly when K0 > K1 + K2 (Area 5 is then Area 3's hole).
    np.testing.assert_array_equal(rel["2>=5"], K[:, 0] <= K[:, 1] + K[:, 2] + 1e-12)
    assert 0 < np.sum(~rel["2>=5"]) < 1000
    # Eq. (9) is the condition for Area 3 >= Area 1, and both happen in the sample.
    np.testing.assert_array_equal(rel["3>=1"], rel["eq9"])
    assert 0 < np.sum(rel["eq9"]) < 1000


def test_maximum_reachable_radii_under_joint_limits():
    robot = sa.umetani1990()
    inner, outer, _, _ = paper.maximum_reachable_radii(robot)
    assert float(outer) == pytest.approx(float(analysis.maximum_reachable_radius(robot)), abs=1e-10)
    assert float(inner) == pytest.approx(float(analysis.maximum_reachable_inner_radius(robot)), abs=1e-7)
    limited = robot.replace(
        joint_lower=np.radians(np.array([-90.0, 30.0])), joint_upper=np.radians(np.array([90.0, 150.0]))
    )
    inner, outer, j_in, j_out = paper.maximum_reachable_radii(limited)
    # Brute force on the law of cosines: |p|^2 = sum K^2 + 2 sum K_i K_j cos(theta_i - theta_j).
    K0, K1, K2 = np.asarray(sa.tip_coefficients(robot))
    q1, q2 = np.meshgrid(np.radians(np.linspace(-90, 90, 1801)), np.radians(np.linspace(30, 150, 1201)))
    r = np.sqrt(
        K0**2 + K1**2 + K2**2 + 2 * K0 * K1 * np.cos(q1) + 2 * K0 * K2 * np.cos(q1 + q2) + 2 * K1 * K2 * np.cos(q2)
    )
    assert float(outer) == pytest.approx(r.max(), abs=1e-6) and float(outer) >= r.max() - 1e-12
    assert float(inner) == pytest.approx(r.min(), abs=1e-6) and float(inner) <= r.min() + 1e-12
    assert np.all(np.asarray(j_out) >= np.asarray(limited.joint_lower) - 1e-15)
    assert np.all(np.asarray(j_in) <= np.asarray(limited.joint_upper) + 1e-15)
    assert float(outer) < float(analysis.maximum_reachable_radius(robot)) - 0.05


# Dynamic singularities -----------------------------------------------------------------


def test_dynamic_singular_set_table1():
    robot = sa.umetani1990()
    s = paper.dynamic_singularities(robot, **GRID)
    phi1, phi2 = np.asarray(s.phi1), np.asarray(s.phi2)
    found = np.isfinite(phi2)
    assert np.all(found.sum(axis=1) == 2)  # one stretched and one folded root for each phi1
    # det J* vanishes there, by the naive model's complex-step Jacobian.
    d = reference.design(robot)
    rows = np.argwhere(found)[::37]
    for i, j in rows:
        J = reference.generalized_jacobian(d, np.array([0.0, phi1[i, j], phi2[i, j]]))
        scale = np.linalg.norm(J[:, 0]) * np.linalg.norm(J[:, 1])
        assert abs(np.linalg.det(J)) <= 1e-11 * scale
    folded = np.asarray(s.folded)
    stretched_phi2 = np.abs(phi2[found & ~folded])
    # Not phi2 = 0: the stretched branch bulges ~17.8 deg away for Table 1 ...
    assert 15.0 < np.degrees(stretched_phi2.max()) < 20.0
    # ... but passes through the collinear postures, where eq. (8) is attained.
    radius = np.asarray(s.radius)
    assert np.nanmin(np.where(folded, np.nan, radius)) == pytest.approx(2.5, abs=1e-9)
    assert np.nanmax(radius) == pytest.approx(float(analysis.maximum_reachable_radius(robot)), abs=1e-9)
    # The folded branch, which eq. (8) ignores, comes to 1.0 m of the centroid.
    assert float(analysis.path_independent_radius(robot, **GRID)) == pytest.approx(1.0, abs=1e-9)
    with count_compiles() as compiled:  # the bisection's step count is traced: no program of its own
        coarse = paper.dynamic_singularities(robot, **GRID, bisection_steps=20)
    assert sum(compiled.values()) == 0, compiled
    # 20 halvings of a 2 pi / 64 cell: within 1e-7 rad of the 55-step roots
    np.testing.assert_allclose(np.asarray(coarse.phi2)[found], phi2[found], rtol=0, atol=1e-7)
    assert np.max(np.abs(np.asarray(coarse.phi2)[found] - phi2[found])) > 0
    # Robot-frame tips are the fixed-base tips of those postures.
    np.testing.assert_allclose(
        np.linalg.norm(np.asarray(s.tip_robot)[found], axis=-1),
        np.sqrt(8 + 8 * np.cos(phi2[found])),
        atol=1e-12,
    )


def test_singular_set_with_base_at_centroid_is_kinematic():
    # b0 = 0: det J* = (1 - I_M1/I_S) K1 K2 sin(phi2) (J_S equals J_M's first column).
    robot = random_robot(np.random.default_rng(3), 2).replace(base_attach=np.float64(0.0))
    s = paper.dynamic_singularities(robot, **GRID)
    phi2 = np.asarray(s.phi2)[np.isfinite(np.asarray(s.phi2))]
    assert np.allclose(np.minimum(np.abs(phi2), np.pi - np.abs(phi2)), 0.0, atol=1e-12)
    K = np.asarray(sa.tip_coefficients(robot))
    assert float(analysis.path_independent_radius(robot, **GRID)) == pytest.approx(abs(K[1] - K[2]), abs=1e-12)


def test_path_independent_radius_never_exceeds_collinear_bound():
    rng = np.random.default_rng(11)
    designs = sa.stack_robots([random_robot(rng, 2) for _ in range(4)])
    piw = np.asarray(analysis.path_independent_radius(designs, **GRID))
    kin = np.asarray(paper.kinematic_singularity_radius(designs))
    assert np.all(piw <= kin + 1e-9)
    assert np.all(kin <= np.asarray(paper.guaranteed_radius(designs)) + 1e-12)


def test_dynamic_singularities_rejects_n3():
    with pytest.raises(sa.ConfigError, match="links"):
        paper.dynamic_singularities(random_robot(np.random.default_rng(0), 3))


# Straight-Path workspaces (on motion.straight_tip_path) ---------------------------------

N_DIRECTIONS = 144


def _starts_inside_piw(robot, count, seed=5):
    """Fig. 3's posture first, then random postures whose tips lie inside the 1.0 m
    singularity-free disk of Table 1."""
    phis = paper.random_joint_postures(robot, 4000, seed)
    radii = np.linalg.norm(np.asarray(sa.tip_position(robot, phis)), axis=-1)
    chosen = phis[radii < 0.98][: count - 1]
    return np.concatenate([np.radians([[0.0, -60.0, 120.0]]), chosen])


@pytest.fixture(scope="module")
def table1_paths():
    robot = sa.umetani1990()
    phis = _starts_inside_piw(robot, 8)
    return robot, phis, paper.straight_path_ends(robot, phis, N_DIRECTIONS)


def test_straight_path_ends_compiles_no_program_of_its_own(table1_paths):
    """straight_path_ends is a plain function over straight_tip_path's compiled program:
    other postures and another number of directions (same bucket) compile nothing."""
    robot, phis, _ = table1_paths
    with count_compiles() as compiles:
        paper.straight_path_ends(robot, phis + 0.01, N_DIRECTIONS + 5)  # 1192 paths, bucket 2048 as 1152
    assert not compiles, dict(compiles)


def test_end_points_lie_on_their_lines_at_singularities(table1_paths):
    robot, phis, ends = table1_paths
    start = np.asarray(sa.tip_position(robot, phis))[:, None, :]
    end = np.asarray(ends.end_tip)
    d = np.asarray(paper.evenly_spaced_directions(N_DIRECTIONS))
    offset = end - start
    off_line = np.abs(offset[..., 0] * d[:, 1] - offset[..., 1] * d[:, 0])
    assert off_line.max() < 1e-9
    # The integrated length agrees with the geometric distance.
    length_error = np.abs(np.sum(offset * d, -1) - np.asarray(ends.length))
    assert length_error.max() < 1e-8
    assert np.all(np.asarray(ends.reason) == 0)
    w_end = np.asarray(sa.manipulability(robot, ends.end_posture)) / float(robot.reach) ** 2
    assert w_end.max() < 1e-8
    # The first direction is the inertial x axis (Fig. 3a): the tip keeps its y.
    np.testing.assert_allclose(end[:, 0, 1], start[:, 0, 1], atol=1e-10)
    assert np.all(end[:, 0, 0] > start[:, 0, 0])
    np.testing.assert_allclose(
        np.asarray(paper.straight_path_workspace(robot, phis[0], N_DIRECTIONS)), end[0], atol=1e-12
    )


def test_fig3_workspace_reaches_area3_and_guaranteed_disk_is_not_safe(table1_paths):
    robot, _phis, ends = table1_paths
    radius = np.linalg.norm(np.asarray(ends.end_tip), axis=-1)
    r3, r_g = float(analysis.maximum_reachable_radius(robot)), float(paper.guaranteed_radius(robot))
    assert radius[0].max() <= r3 + 1e-9 and radius[0].max() > r3 - 1e-3
    # Paths that start inside the eq. (8) disk (rows 1..) can end inside it: at the
    # folded-arm singularity, whose tips lie 1.0-1.54 m from the centroid.
    inside = radius[1:] < r_g
    assert inside.mean() > 0.05
    folded = np.abs(np.asarray(ends.end_posture)[1:, :, 2]) > np.pi / 2
    np.testing.assert_array_equal(inside, folded)
    assert radius[1:][inside].min() >= 1.0 - 1e-9 and radius[1:][inside].max() <= 1.55


def test_paths_starting_in_the_singularity_free_disk_leave_it(table1_paths):
    robot, phis, ends = table1_paths
    r_piw = float(analysis.path_independent_radius(robot, **GRID))
    starts = np.asarray(sa.tip_position(robot, phis))
    end_radius = np.linalg.norm(np.asarray(ends.end_tip), axis=-1)
    assert end_radius[1:].min() >= r_piw - 1e-9
    clearance = np.asarray(paper.clearance_radius(starts, np.asarray(ends.end_tip)))
    assert clearance[1:].min() >= r_piw - 1e-9
    assert float(paper.straight_path_intersection_radius(starts[1:], np.asarray(ends.end_tip)[1:])) >= r_piw - 1e-9


def test_boundary_converges_with_step_and_directions(table1_paths):
    robot, phis, ends = table1_paths
    finer = paper.straight_path_ends(robot, phis, N_DIRECTIONS, max_step=0.025, tol=1e-13)
    change = np.linalg.norm(np.asarray(finer.end_tip) - np.asarray(ends.end_tip), axis=-1)
    assert change.max() < 1e-8
    # Polygon area and clearance as the directions double (subsets of the 144 evenly
    # spaced directions are the 36- and 72-direction sets).
    start = np.asarray(sa.tip_position(robot, phis))
    end = np.asarray(ends.end_tip)

    def area(points):
        x, y = points[..., 0], points[..., 1]
        return 0.5 * np.abs(np.sum(x * np.roll(y, -1, -1) - np.roll(x, -1, -1) * y, axis=-1))

    areas = [area(end[:, ::step]) for step in (4, 2, 1)]
    gaps = [np.abs(areas[1] - areas[0]).max(), np.abs(areas[2] - areas[1]).max()]
    # First order only: the radial function jumps where neighbouring paths end on
    # different singular branches (the slits of Fig. 3b).
    assert gaps[1] < 0.7 * gaps[0]
    clear = [np.asarray(paper.clearance_radius(start, end[:, ::step])) for step in (4, 2, 1)]
    assert np.all(clear[2] <= clear[1] + 1e-12) and np.all(clear[1] <= clear[0] + 1e-12)


def test_straight_paths_respect_joint_limits(table1_paths):
    robot = table1_paths[0]
    limited = robot.replace(
        joint_lower=np.radians(np.array([-200.0, 0.0])), joint_upper=np.radians(np.array([200.0, 135.0]))
    )
    rng = np.random.default_rng(2)
    phis = np.stack([np.zeros(8), rng.uniform(-np.pi, np.pi, 8), np.radians(rng.uniform(20, 120, 8))], -1)
    ends = paper.straight_path_ends(limited, phis, N_DIRECTIONS)
    reason = np.asarray(ends.reason)
    assert np.any(reason == 2) and np.any(reason == 0)
    q2 = np.asarray(ends.end_posture)[..., 2]
    assert q2.min() >= -1e-9 and q2.max() <= np.radians(135.0) + 1e-9
    # Every path stopped by a limit ends on one of the four limit values.
    joints = np.asarray(ends.end_posture)[..., 1:][reason == 2]
    gap = np.minimum(np.abs(joints - np.asarray(limited.joint_lower)), np.abs(joints - np.asarray(limited.joint_upper)))
    assert np.all(gap.min(axis=-1) < 1e-9)


def test_clearance_of_synthetic_star_sets():
    d = np.asarray(paper.evenly_spaced_directions(360))
    for center, radius in (((0.0, 0.0), 2.0), ((0.5, -0.3), 2.0), ((3.0, 0.0), 1.0)):
        c = np.array(center)
        ends = c + radius * d
        expected = max(radius - np.linalg.norm(c), 0.0)
        assert float(paper.clearance_radius(c, ends)) == pytest.approx(expected, abs=5e-4)
        inside = np.asarray(
            paper.inside_straight_path_workspace(c, ends, c + np.array([[0.99 * radius, 0.0], [0.0, -1.01 * radius]]))
        )
        np.testing.assert_array_equal(inside, [True, False])
