"""Motion integrators against independent references: SciPy quadrature and ODE solves
over the naive model of tests/reference.py, momentum conservation, loop reversal,
convergence, and the singular ends of straight tip paths."""

import itertools

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

import spacearm as sa
from spacearm import motion
from spacearm.motion import straight_paths

from . import reference as ref
from .conftest import count_compiles, random_robot

DEG = np.pi / 180.0
# Fig. 2 of Umetani & Yoshida 1990 starts from (phi1, phi2) = (-60, 120) deg; the corners
# of the loop are our choice (the paper does not print them).
LOOP = np.array([[-60.0, 120.0], [30.0, 120.0], [30.0, 30.0], [-60.0, 30.0], [-60.0, 120.0]]) * DEG
PHI_FIG3 = np.array([0.0, -60.0, 120.0]) * DEG


def _posture(end):
    """[phi0, joints] from `integrate_joint_path`'s (attitude, joints) of a planar robot."""
    phi0, joints = end
    return np.concatenate([np.asarray(phi0)[..., None], np.asarray(joints)], axis=-1)


def reference_base_rotation(d, waypoints):
    """Line integral of eq. (5) by scipy.integrate.quad over the naive model, segment by segment."""
    total = 0.0
    for start, end in itertools.pairwise(waypoints):
        step = end - start

        def integrand(t, start=start, step=step):
            phi = np.r_[0.0, start + t * step]
            return ref.base_rate(d, phi, step)

        value, _ = quad(integrand, 0.0, 1.0, epsabs=1e-15, epsrel=1e-13, limit=200)
        total += value
    return total


def central_derivative(values, h):
    """6th-order central difference along axis 0 (interior points 3..-3)."""
    c = np.array([-1.0, 9.0, -45.0, 0.0, 45.0, -9.0, 1.0]) / 60.0
    out = sum(c[k] * values[k : len(values) - 6 + k] for k in range(7))
    return out / h


# Joint-space paths ------------------------------------------------------------------------


def test_fig2_loop_matches_scipy_quadrature_and_reverses(table1):
    phi_start = np.r_[0.0, LOOP[0]]
    phi_end = _posture(sa.integrate_joint_path(table1, phi_start, LOOP))
    expected = reference_base_rotation(ref.design(table1), LOOP)
    assert abs(phi_end[0] - expected) < 1e-12
    np.testing.assert_allclose(phi_end[1:], LOOP[-1], atol=0)
    assert abs(expected) > 0.05  # a closed joint loop turns the base (Fig. 2)
    increments = np.asarray(motion.joint_path_base_increments(table1, LOOP))
    assert increments.shape == (4,) and abs(increments.sum() - phi_end[0]) < 1e-15
    # the same loop run backwards, from where the first one ended, undoes the rotation
    back = _posture(sa.integrate_joint_path(table1, phi_end, LOOP[::-1]))
    assert abs(back[0] - phi_start[0]) < 1e-13
    # and run backwards from the start, it turns the base the other way by the same angle
    reverse = _posture(sa.integrate_joint_path(table1, phi_start, LOOP[::-1]))
    assert abs(reverse[0] + phi_end[0]) < 1e-13
    # the tip does not come back to where it was (no one-to-one joint/inertial map)
    moved = np.linalg.norm(sa.tip_position(table1, phi_end) - sa.tip_position(table1, phi_start))
    assert moved > 0.05


@pytest.mark.parametrize("n", [2, 3])
def test_random_paths_batched_over_designs_match_scipy(n):
    rng = np.random.default_rng(10 + n)
    robots = [random_robot(rng, n) for _ in range(3)]
    batch = sa.stack_robots(robots)
    # long segments: every joint turns up to a full revolution per segment
    waypoints = rng.uniform(-np.pi, np.pi, (3, 4, n))
    phi_start = np.concatenate([rng.uniform(-1, 1, (3, 1)), waypoints[:, 0]], axis=-1)
    phi_end = _posture(sa.integrate_joint_path(batch, phi_start, waypoints))
    for i, robot in enumerate(robots):
        expected = phi_start[i, 0] + reference_base_rotation(ref.design(robot), waypoints[i])
        assert abs(phi_end[i, 0] - expected) < 1e-10


def test_quadrature_converges_to_rounding(table1):
    rng = np.random.default_rng(3)
    waypoints = rng.uniform(-2 * np.pi, 2 * np.pi, (16, 3, 2))
    phi_start = np.concatenate([np.zeros((16, 1)), waypoints[:, 0]], axis=-1)
    fine = _posture(sa.integrate_joint_path(table1, phi_start, waypoints, nodes=40, pieces=32))[:, 0]
    errors = []
    for nodes, pieces in [(8, 1), (8, 2), (8, 4), (24, 8)]:
        coarse = _posture(sa.integrate_joint_path(table1, phi_start, waypoints, nodes=nodes, pieces=pieces))
        errors.append(np.max(np.abs(coarse[:, 0] - fine)))
    assert errors[-1] < 1e-12  # the default rule
    assert errors[0] > errors[1] > errors[2] > errors[3]


def test_history_conserves_angular_momentum_and_ends_where_the_integral_does(table1):
    d = ref.design(table1)
    samples = 400
    phi_start = np.r_[0.3, LOOP[0]]
    phi0, joints, tips = sa.joint_path_history(table1, phi_start, LOOP, samples)
    postures, tips = _posture((phi0, joints)), np.asarray(tips)
    assert postures.shape == (4 * samples + 1, 3) and tips.shape == (4 * samples + 1, 2)
    np.testing.assert_allclose(postures[-1], _posture(sa.integrate_joint_path(table1, phi_start, LOOP)), atol=1e-13)
    for i in range(0, len(postures), 97):
        np.testing.assert_allclose(tips[i], ref.tip(d, postures[i]), atol=1e-13)
    # segment 1 only: posture derivative in the segment parameter t by finite differences
    seg = postures[: samples + 1]
    rates = central_derivative(seg, 1.0 / samples)
    worst_angular = worst_linear = 0.0
    for phi, rate in zip(seg[3:-3], rates, strict=False):
        linear, angular = ref.momentum(d, phi, rate)
        worst_angular = max(worst_angular, abs(angular))
        worst_linear = max(worst_linear, np.max(np.abs(linear)))
    # |I_S dphi0| alone is ~ 1e3 kg m^2/s here, so this is conservation to ~1e-13 relative
    assert worst_angular < 1e-9
    assert worst_linear < 1e-9


def test_joint_path_errors(table1):
    with pytest.raises(sa.ConfigError, match="first row"):
        sa.integrate_joint_path(table1, np.zeros(3), LOOP)
    with pytest.raises(sa.ConfigError, match="joint_waypoints"):
        sa.integrate_joint_path(table1, np.zeros(3), np.zeros((4, 3)))
    with pytest.raises(sa.ConfigError, match="phi_start"):
        sa.integrate_joint_path(table1, np.zeros(2), np.zeros((4, 2)))


# Straight tip paths -----------------------------------------------------------------------

DIRECTIONS = np.stack([np.cos(np.arange(8) * np.pi / 4), np.sin(np.arange(8) * np.pi / 4)], axis=-1)


@pytest.fixture(scope="module")
def fig3_paths():
    robot = sa.umetani1990()
    return robot, motion.straight_tip_path(robot, PHI_FIG3, DIRECTIONS)


def test_straight_paths_stay_on_the_line_and_end_where_J_star_is_singular(fig3_paths):
    robot, paths = fig3_paths
    d = ref.design(robot)
    start = ref.tip(d, PHI_FIG3)
    for i, direction in enumerate(DIRECTIONS):
        end = np.asarray(paths.end_posture[i])
        offset = ref.tip(d, end) - start
        assert abs(offset[0] * direction[1] - offset[1] * direction[0]) < 1e-10  # on the line
        assert abs(offset @ direction - float(paths.length[i])) < 1e-10
        np.testing.assert_allclose(paths.end_tip[i], ref.tip(d, end), atol=1e-13)
        assert int(paths.reason[i]) == motion.REASON_SINGULAR
        J = ref.generalized_jacobian(d, end)
        scale = np.linalg.norm(J, 2)
        assert abs(np.linalg.det(J)) / scale**2 < 1e-10  # J* lost rank
        # b0 > 0: a dynamic singularity, not the fixed-base one at phi2 = 0
        assert not bool(paths.kinematic[i])
        assert abs(np.sin(end[2])) > 1e-3  # (near phi2 = 0 only where phi1 is near 0 or pi)


def test_straight_path_matches_scipy_solve_ivp_of_the_naive_model(fig3_paths):
    """Integrate dphi/ds = [base rate; J*^-1 d] with the naive model up to 90 % of the length."""
    robot, paths = fig3_paths
    d = ref.design(robot)
    i = 0  # along X_A, Fig. 3a
    direction = DIRECTIONS[i]
    target = 0.9 * float(paths.length[i])

    def rhs(_, phi):
        dq = np.linalg.solve(ref.generalized_jacobian(d, phi), direction)
        return np.r_[ref.base_rate(d, phi, dq), dq]

    sol = solve_ivp(rhs, (0.0, target), PHI_FIG3, method="DOP853", rtol=1e-13, atol=1e-13)
    ours = motion.straight_tip_path(robot, PHI_FIG3, DIRECTIONS, max_length=target)
    assert int(ours.reason[i]) == motion.REASON_MAX_LENGTH
    assert abs(float(ours.length[i]) - target) < 1e-12
    np.testing.assert_allclose(ours.end_posture[i], sol.y[:, -1], atol=1e-9)


def test_straight_path_converges_with_tolerance_and_step(fig3_paths):
    robot, default = fig3_paths
    converged = motion.straight_tip_path(robot, PHI_FIG3, DIRECTIONS, max_step=0.02, rtol=1e-14)
    errors = []
    for rtol in (1e-6, 1e-9, 1e-12):
        path = motion.straight_tip_path(robot, PHI_FIG3, DIRECTIONS, rtol=rtol)
        errors.append(float(np.max(np.abs(path.end_posture - converged.end_posture))))
    assert errors[0] >= errors[1] >= errors[2]
    assert errors[2] < 2e-12
    np.testing.assert_allclose(default.end_posture, converged.end_posture, atol=2e-12)
    # DOP853 with the error control off (fixed steps): halving the step divides the
    # error by ~2^8 until rounding (fixed-step RK4 is measured in benchmarks/bench_motion.py)
    fixed = [
        float(
            np.max(
                np.abs(
                    motion.straight_tip_path(robot, PHI_FIG3, DIRECTIONS, max_step=step, rtol=1e30).end_posture
                    - converged.end_posture
                )
            )
        )
        for step in (0.4, 0.2, 0.1)
    ]
    assert fixed[0] > 30 * fixed[1] > 30 * 30 * fixed[2]
    assert fixed[2] < 1e-9


def test_straight_path_history_conserves_momentum(fig3_paths):
    robot, paths = fig3_paths
    d = ref.design(robot)
    samples = 401
    postures, tips = motion.straight_tip_path_history(robot, PHI_FIG3, DIRECTIONS, samples)
    postures, tips = np.asarray(postures[0]), np.asarray(tips[0])
    np.testing.assert_allclose(postures[-1], paths.end_posture[0], atol=1e-10)
    np.testing.assert_allclose(tips[:, 1], tips[0, 1], atol=1e-10)  # along X_A: y stays
    h = float(paths.joint_arc[0]) / (samples - 1)
    rates = central_derivative(postures, h)
    worst = 0.0
    for phi, rate in zip(postures[3:-3], rates, strict=False):
        _, angular = ref.momentum(d, phi, rate)
        worst = max(worst, abs(angular))
    assert worst < 1e-8  # |I_M dphi_M| ~ 1e2..1e3 kg m^2 per unit arc


def test_b0_zero_ends_at_the_kinematic_singularity(table1):
    robot = table1.replace(base_attach=np.float64(0.0))
    paths = motion.straight_tip_path(robot, PHI_FIG3, DIRECTIONS)
    assert np.all(np.asarray(paths.reason) == motion.REASON_SINGULAR)
    assert np.all(np.asarray(paths.kinematic))
    np.testing.assert_allclose(np.sin(paths.end_posture[:, 2]), 0.0, atol=1e-10)


def test_length_and_joint_limits_end_paths(table1):
    limited = table1.replace(joint_lower=np.array([-np.pi, 100.0 * DEG]), joint_upper=np.array([np.pi, 140.0 * DEG]))
    lengths = np.full(8, 0.05)
    lengths[:4] = np.inf
    paths = motion.straight_tip_path(limited, PHI_FIG3, DIRECTIONS, max_length=lengths)
    reason = np.asarray(paths.reason)
    assert np.all(np.isin(reason[:4], [motion.REASON_JOINT_LIMIT, motion.REASON_SINGULAR]))
    assert np.any(reason[:4] == motion.REASON_JOINT_LIMIT)
    for i in np.flatnonzero(reason == motion.REASON_JOINT_LIMIT):
        phi2 = float(paths.end_posture[i, 2])
        assert min(abs(phi2 - 100.0 * DEG), abs(phi2 - 140.0 * DEG)) < 1e-12
    np.testing.assert_array_equal(reason[4:], motion.REASON_MAX_LENGTH)
    np.testing.assert_allclose(paths.length[4:], 0.05, atol=1e-13)


def test_redundant_arm_batched_over_designs_uses_minimum_norm_rates():
    rng = np.random.default_rng(7)
    robots = [random_robot(rng, 3) for _ in range(2)]
    batch = sa.stack_robots(robots)
    phi = np.array([0.0, -0.8, 1.3, 0.9])
    directions = DIRECTIONS[None, ::2]  # (1, 4, 2) against designs (2, 1)
    batch_axes = jax.tree_util.tree_map(lambda x: np.asarray(x)[:, None], batch)
    paths = motion.straight_tip_path(batch_axes, phi, directions)
    assert paths.end_posture.shape == (2, 4, 4)
    for i, robot in enumerate(robots):
        d = ref.design(robot)
        for j, direction in enumerate(directions[0]):
            end = np.asarray(paths.end_posture[i, j])
            offset = ref.tip(d, end) - ref.tip(d, phi)
            assert abs(offset[0] * direction[1] - offset[1] * direction[0]) < 1e-10
            assert int(paths.reason[i, j]) == motion.REASON_SINGULAR
            singular_values = np.linalg.svd(ref.generalized_jacobian(d, end), compute_uv=False)
            assert singular_values[1] / singular_values[0] < 1e-10  # J* J*^T singular
    # The rates at the start, by a central difference of two short paths (+d and -d,
    # the same compiled shapes): minimum-norm (no component in the null space of J*),
    # J* dq = d (eq. 6), and zero angular momentum with the base rate (eq. 5).
    step = 1e-4
    ahead = motion.straight_tip_path(batch_axes, phi, directions, max_length=step)
    behind = motion.straight_tip_path(batch_axes, phi, -directions, max_length=step)
    rates = (np.asarray(ahead.end_posture) - np.asarray(behind.end_posture)) / (2 * step)  # per metre
    for i, robot in enumerate(robots):
        d = ref.design(robot)
        J = ref.generalized_jacobian(d, phi)
        null = np.cross(J[0], J[1])
        for j, direction in enumerate(directions[0]):
            rate = rates[i, j]
            assert abs(null @ rate[1:]) / (np.linalg.norm(null) * np.linalg.norm(rate[1:])) < 1e-7
            np.testing.assert_allclose(J @ rate[1:], direction, atol=1e-7)
            _, arm_share = ref.momentum(d, phi, np.r_[0.0, rate[1:]])
            _, angular = ref.momentum(d, phi, rate)
            assert abs(angular) < 1e-7 * abs(arm_share)


def test_no_retrace_for_new_values(fig3_paths):
    robot, _ = fig3_paths
    motion.straight_tip_path(robot, PHI_FIG3, DIRECTIONS)
    before = straight_paths._straight_flat._cache_size()
    motion.straight_tip_path(robot, PHI_FIG3 + 0.1, -DIRECTIONS, max_step=0.1, max_length=3.0)
    assert straight_paths._straight_flat._cache_size() == before


def test_one_program_for_every_batch_up_to_the_bucket(fig3_paths):
    """1 and 320 paths run in the program that integrated 8 (batches are padded to 512),
    with the same numbers: the padding is never integrated."""
    robot, paths = fig3_paths
    before = straight_paths._straight_flat._cache_size()
    with count_compiles() as compiles:
        one = motion.straight_tip_path(robot, PHI_FIG3, DIRECTIONS[3])
        many = motion.straight_tip_path(robot, PHI_FIG3, np.tile(DIRECTIONS, (40, 1)))
    assert straight_paths._straight_flat._cache_size() == before
    assert not [name for name in compiles if "_straight_flat" in name]
    assert one.length.shape == () and many.length.shape == (320,)
    np.testing.assert_allclose(one.length, paths.length[3], rtol=1e-13)
    np.testing.assert_allclose(
        np.asarray(many.end_posture).reshape(40, 8, 3),
        np.broadcast_to(paths.end_posture, (40, 8, 3)),
        rtol=1e-13,
        atol=1e-13,
    )


def test_straight_path_errors(table1):
    with pytest.raises(sa.ConfigError, match="direction"):
        motion.straight_tip_path(table1, PHI_FIG3, np.zeros(2))
    with pytest.raises(sa.ConfigError, match="direction"):
        motion.straight_tip_path(table1, PHI_FIG3, np.ones(3))
    with pytest.raises(sa.ConfigError, match="max_length"):
        motion.straight_tip_path(table1, PHI_FIG3, np.ones(2), max_length=-1.0)


def test_go_and_back_returns_the_base_and_reproduces_fig9_claim(table1):
    """Fig. 8/9: the elbow-down posture (tip motion along the minor axis of J*) turns the
    base more than the elbow-up posture reaching the same point, (2, 2) m in the robot
    frame; out and back along the same line retraces the joint path, so the base comes
    back. (Eight paths, the shapes of the tests above, so nothing new is compiled.)"""
    postures = np.tile(np.array([[0.0, 0.0, 90.0], [0.0, 90.0, -90.0]]) * DEG, (4, 1))
    np.testing.assert_allclose(sa.robot_frame_tip_position(table1, postures[:, 1:]), 2.0, atol=1e-15)
    history, tips, travelled = motion.go_and_back(table1, postures, np.array([0.0, 1.0]), 0.2, n_samples=401)
    history, tips, travelled = np.asarray(history), np.asarray(tips), np.asarray(travelled)
    np.testing.assert_allclose(history[:, -1], postures, atol=1e-9)
    np.testing.assert_allclose(travelled[:, -1], 0.4, atol=1e-9)
    assert np.max(np.abs(tips[:, :, 0] - tips[:, :1, 0])) < 1e-9  # along Y
    peak = np.max(np.abs(history[:, :, 0]), axis=-1)
    assert peak[0] > 3 * peak[1] > 0  # measured 6.99 deg vs 1.41 deg for 0.2 m


def test_default_joint_path_rule_sizes_its_panels_from_the_longest_segment(table1):
    """The default rule (24 nodes per pi/2 of joint excursion) reaches rounding level on
    short and on 4 pi segments, and under jit (traced waypoints: 8 panels)."""
    from spacearm.motion.joint_paths import _default_pieces

    rng = np.random.default_rng(3)
    phi0 = jnp.array([0.0, -1.0, 2.0])
    for span in (0.5, 4 * np.pi):
        waypoints = jnp.concatenate([phi0[None, 1:], phi0[1:] + rng.uniform(-span, span, (3, 2))])
        converged = _posture(sa.integrate_joint_path(table1, phi0, waypoints, nodes=40, pieces=64))
        default = _posture(sa.integrate_joint_path(table1, phi0, waypoints))
        np.testing.assert_allclose(default, converged, atol=1e-13)
        traced = _posture(jax.jit(lambda w: sa.integrate_joint_path(table1, phi0, w))(waypoints))
        np.testing.assert_allclose(traced, converged, atol=1e-13 if span < 4 else 1e-12)
    assert _default_pieces(np.zeros((2, 2)) + [[0, 0], [1.5, 0]], None) == 1
    assert _default_pieces(np.zeros((2, 2)) + [[0, 0], [4 * np.pi, 0]], None) == 8
