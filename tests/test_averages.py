"""Joint-box averages (issue 17, item 2): randomized QMC against closed forms, convergence, gradients."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import spacearm as sa
from spacearm.analysis import averages
from spacearm.analysis.joint_box import digital_shifts, joint_box, sobol_direction_numbers

from .conftest import random_robot


def _planar_joint_wbar(robot):
    """The planar joint-uniform w-bar by its Gauss-Legendre rule (exact to ~1e-13), times L^2: mean w*, m^2."""
    return float(sa.paper.normalized_wbar(robot, measure="joint")) * float(robot.reach) ** 2


def test_sobol_directions_match_scipy():
    """All 32 direction numbers against SciPy's table (``Sobol._sv``, its unscrambled
    direction numbers at 32 bits), and the first 12 through SciPy's public points too.

    SciPy draws in Gray-code order, so its point 2^(j+1) - 1 is v_j alone; reaching it takes
    ``fast_forward`` 2^(j+1) steps, so the public check stops at j = 11 (all 32 cost ~90 s).
    """
    qmc = pytest.importorskip("scipy.stats").qmc
    for d in (1, 3, 6, 10, 15, 32):
        V = sobol_direction_numbers(d).astype(np.uint64)
        engine = qmc.Sobol(d, scramble=False, bits=32)
        np.testing.assert_array_equal(np.asarray(engine._sv, dtype=np.uint64), V)
        for j in range(12):
            engine.reset()
            engine.fast_forward(2 ** (j + 1) - 1)
            np.testing.assert_array_equal(np.round(engine.random(1)[0] * 2.0**32).astype(np.uint64), V[:, j])


def test_digital_shifts_on_the_host_equal_jax_random_bits():
    """A concrete seed draws the shifts in NumPy (no program to compile): the same words as
    JAX's Threefry ``jax.random.bits``, which a traced seed uses inside a compiled search."""
    for seed in (0, 1, 12345, 2**31 - 1, 2**33 + 5, -3):
        for shape in ((8, 6), (1, 9), (3, 2)):
            host = digital_shifts(seed, *shape)
            assert isinstance(host, np.ndarray) and host.dtype == np.uint32
            expected = jax.random.bits(jax.random.key(seed), shape, jnp.uint32)
            np.testing.assert_array_equal(host, np.asarray(expected))
            np.testing.assert_array_equal(
                np.asarray(jax.jit(digital_shifts, static_argnums=(1, 2))(seed, *shape)), host
            )


def test_joint_box_one_turn_and_limits():
    robot = sa.load_robot("configs/ur5-smallsat.yaml")
    lower, upper = joint_box(robot)
    np.testing.assert_allclose(np.asarray(upper - lower), 2 * np.pi)  # +-2 pi limits: one turn
    planar = sa.umetani1990()
    lower, upper = joint_box(planar)
    np.testing.assert_allclose(np.asarray(lower), -np.pi)
    np.testing.assert_allclose(np.asarray(upper), np.pi)


def test_one_sided_limits_cover_one_turn_from_the_finite_limit():
    """One rule for every joint-box search: the planar reach grid and the averages share it."""
    planar = sa.umetani1990()
    inf = np.inf
    robot = planar.replace(joint_lower=jnp.array([-0.5, -inf]), joint_upper=jnp.array([inf, 1.0]))
    lower, upper = joint_box(robot)
    np.testing.assert_allclose(np.asarray(lower), [-0.5, 1.0 - 2 * np.pi], rtol=1e-15)
    np.testing.assert_allclose(np.asarray(upper), [-0.5 + 2 * np.pi, 1.0], rtol=1e-15)
    # A one-sided joint covers every angle once: the reach radius equals the free arm's
    # closed form (stretched at phi1 = 2 pi; a box stopping at pi would miss it, 26 % short).
    one_sided = planar.replace(joint_lower=jnp.array([2.0, -inf]), joint_upper=jnp.array([inf, inf]))
    _, outer, _, _ = sa.maximum_reachable_radii(one_sided)
    np.testing.assert_allclose(float(outer), float(sa.maximum_reachable_radius(planar)), rtol=1e-9)


@pytest.mark.parametrize("seed", [None, 4])
def test_mean_manipulability_matches_planar_closed_form(seed):
    robot = sa.umetani1990() if seed is None else random_robot(np.random.default_rng(seed), 2)
    exact = _planar_joint_wbar(robot)
    estimate = averages.joint_average_manipulability(robot)  # default rtol 1e-4
    assert float(estimate.relative_error) <= 1e-4
    assert abs(float(estimate.value) - exact) <= 4.0 * float(estimate.error)
    assert abs(float(estimate.value) - exact) <= 2e-4 * exact


def test_error_estimate_tracks_the_error_as_samples_grow():
    robot = sa.umetani1990()
    exact = _planar_joint_wbar(robot)
    rows = []
    for m in (13, 15, 17):
        actual, estimated = [], []
        for seed in range(3):
            a = averages.joint_average_manipulability(robot, rtol=1e-15, min_samples=2**m, max_samples=2**m, seed=seed)
            assert int(a.samples) == 2**m
            actual.append(float(a.value) - exact)
            estimated.append(float(a.error))
        rows.append((np.sqrt(np.mean(np.square(actual))) / exact, np.mean(estimated) / exact))
    # Measured (Table 1): rms relative error 1.1e-4, 1.3e-5, 5.6e-7 at 2^13, 2^15, 2^17 postures.
    assert rows[1][0] < rows[0][0] / 3 and rows[2][0] < rows[1][0] / 3
    for actual, estimated in rows:
        assert actual <= 4.0 * estimated


def test_average_manipulability_is_one_quantity_for_every_robot():
    """Planar robots too: the joint-box mean of w* (m^2), not the paper's normalized area w-bar;
    against the closed-form quadrature of the joint-uniform mean, to the QMC error."""
    robot = sa.umetani1990()
    estimate = averages.joint_average_manipulability(robot, rtol=1e-5)
    assert float(sa.average_manipulability(robot, rtol=1e-5)) == float(estimate.value)
    assert abs(float(estimate.value) - _planar_joint_wbar(robot)) <= 4.0 * float(estimate.error)
    area = float(sa.paper.normalized_wbar(robot))  # eq. 12: another quantity, dimensionless
    assert abs(area * float(robot.reach) ** 2 - float(estimate.value)) > 0.1 * float(estimate.value)


def test_base_disturbance_and_conditioning_against_a_grid():
    robot = sa.umetani1990()
    k = 256
    angles = -np.pi + 2 * np.pi * np.arange(k) / k
    p1, p2 = np.meshgrid(angles, angles, indexing="ij")
    phi = jnp.stack([jnp.zeros_like(p1), p1, p2], axis=-1)
    # ||C_w|| is smooth and periodic: the periodic trapezoid is spectrally accurate.
    grid = float(jnp.mean(averages.base_disturbance_metric(robot, phi)))
    estimate = averages.average_base_disturbance(robot)
    assert abs(float(estimate.value) - grid) <= max(4.0 * float(estimate.error), 1e-12 * grid)
    # 1/kappa has kinks at the singular postures: compare at the grid's accuracy.
    grid = float(jnp.mean(averages.inverse_condition_metric(robot, phi)))
    estimate = averages.global_conditioning_index(robot)
    assert float(estimate.relative_error) <= 1e-4
    assert abs(float(estimate.value) - grid) <= 1e-3 * grid


def test_batched_designs_each_stop_on_their_own():
    rng = np.random.default_rng(7)
    robots = [random_robot(rng, 2), random_robot(rng, 2)]
    batch = sa.stack_robots(robots)
    together = averages.joint_average_manipulability(batch)
    for i, robot in enumerate(robots):
        alone = averages.joint_average_manipulability(robot)
        np.testing.assert_allclose(float(together.value[i]), float(alone.value), rtol=1e-13)
        assert int(together.samples[i]) == int(alone.samples)


def _finite_difference(f, robot, field, h):
    def shifted(delta):
        return robot.replace(**{field: jnp.asarray(getattr(robot, field)) + delta})

    return (f(shifted(h)) - f(shifted(-h))) / (2 * h)


def test_gradient_matches_finite_differences_planar():
    robot = sa.umetani1990()
    options = dict(rtol=1e-15, min_samples=2**13, max_samples=2**13)

    def mean(r):
        return averages.joint_average_manipulability(r, **options).value

    grad = jax.grad(mean)(robot)
    fd = _finite_difference(mean, robot, "base_mass", 1e-2)
    np.testing.assert_allclose(float(grad.base_mass), float(fd), rtol=1e-6)
    e = jnp.zeros(2).at[1].set(1.0)
    fd = (
        mean(robot.replace(link_a=robot.link_a + 1e-5 * e)) - mean(robot.replace(link_a=robot.link_a - 1e-5 * e))
    ) / 2e-5
    np.testing.assert_allclose(float(grad.link_a[1]), float(fd), rtol=1e-6)


def test_spatial_averages_and_gradient():
    robot = sa.load_robot("configs/arm3dof-100kg.yaml")
    options = dict(rtol=1e-15, min_samples=2**12, max_samples=2**12)

    def mean(r):
        return averages.joint_average_manipulability(r, **options).value

    value, grad = jax.value_and_grad(mean)(robot)
    assert value > 0
    fd = _finite_difference(mean, robot, "base_mass", 1e-2)
    np.testing.assert_allclose(float(grad.base_mass), float(fd), rtol=1e-6)
    e = jnp.zeros(3).at[2].set(1.0)
    fd = (
        mean(robot.replace(mount_xyz=robot.mount_xyz + 1e-6 * e))
        - mean(robot.replace(mount_xyz=robot.mount_xyz - 1e-6 * e))
    ) / 2e-6
    np.testing.assert_allclose(float(grad.mount_xyz[2]), float(fd), rtol=1e-5)
    # The public dispatch returns an array for either family (joint_average adds the error).
    estimate = averages.average_manipulability(robot, rtol=1e-3)
    reference = averages.joint_average_manipulability(robot, rtol=1e-3)
    assert np.shape(estimate) == () and float(estimate) == float(reference.value)


@pytest.mark.parametrize("metric", ["conditioning", "base_disturbance", "dynamic_manipulability"])
def test_other_averages_are_differentiable(metric):
    robot = sa.load_robot("configs/arm3dof-100kg.yaml")
    options = dict(rtol=1e-15, min_samples=2**11, max_samples=2**11, block=256)

    def mean(r):
        return averages.joint_average(r, metric, **options).value

    value, grad = jax.value_and_grad(mean)(robot)
    assert np.isfinite(float(value)) and float(value) > 0
    fd = _finite_difference(mean, robot, "base_mass", 1e-2)
    np.testing.assert_allclose(float(grad.base_mass), float(fd), rtol=1e-5)
    e = jnp.zeros(3).at[0].set(1.0)
    fd = (
        mean(robot.replace(mount_xyz=robot.mount_xyz + 1e-6 * e))
        - mean(robot.replace(mount_xyz=robot.mount_xyz - 1e-6 * e))
    ) / 2e-6
    np.testing.assert_allclose(float(grad.mount_xyz[0]), float(fd), rtol=1e-5, atol=1e-9 * abs(float(value)))


def test_dynamic_manipulability_needs_a_spatial_robot():
    with pytest.raises(sa.ConfigError, match="spatial"):
        averages.average_dynamic_manipulability(sa.umetani1990())


_ALL = ("manipulability", "conditioning", "base_disturbance", "dynamic_manipulability")


def test_vector_estimator_fixed_rule_equals_each_metric_alone():
    """One chain pass for four metrics on a fixed rule: the same numbers as four runs alone."""
    robot = sa.load_robot("configs/arm3dof-100kg.yaml")
    options = dict(min_samples=2**11, max_samples=2**11, block=256, seed=3)
    together = averages.joint_averages(robot, _ALL, **options)
    for metric in _ALL:
        alone = averages.joint_average(robot, metric, **options)
        np.testing.assert_allclose(float(together[metric].value), float(alone.value), rtol=1e-14)
        np.testing.assert_allclose(float(together[metric].error), float(alone.error), rtol=1e-10)
        assert int(together[metric].samples) == 2**11
    # Old per-metric loop (before the vector estimator), UR5 smallsat, 1024 samples, block 128:
    ur5 = sa.load_robot("configs/ur5-smallsat.yaml")
    fixed = averages.joint_averages(ur5, _ALL, min_samples=1024, max_samples=1024, block=128)
    old = (0.03961456353673799, 0.26280499087925124, 0.04694221726346475, 0.1444978907953863)
    np.testing.assert_allclose([float(fixed[m].value) for m in _ALL], old, rtol=1e-13)


def test_vector_estimator_stops_when_every_metric_meets_its_tolerance():
    robot = sa.load_robot("configs/arm3dof-100kg.yaml")
    metrics = ("manipulability", "conditioning", "base_disturbance")
    together = averages.joint_averages(robot, metrics, rtol=1e-3, block=256, min_samples=2**11)
    for metric in metrics:
        alone = averages.joint_average(robot, metric, rtol=1e-3, block=256, min_samples=2**11)
        estimate = together[metric]
        assert float(estimate.relative_error) <= 1e-3
        assert int(estimate.samples) >= int(alone.samples)  # the slowest metric sets the count
        if int(estimate.samples) == int(alone.samples):
            np.testing.assert_allclose(float(estimate.value), float(alone.value), rtol=1e-14)
        assert abs(float(estimate.value) - float(alone.value)) <= 4.0 * (float(estimate.error) + float(alone.error))


def test_adaptive_options_are_traced_and_the_custom_vjp_matches_finite_differences():
    """The adaptive loop (min < max) keeps its custom VJP; a new rtol or budget reuses the program."""
    robot = sa.load_robot("configs/arm3dof-100kg.yaml")
    options = dict(rtol=1e-15, min_samples=2**10, max_samples=2**11, block=128)

    def mean(r):
        return averages.joint_averages(r, ("manipulability", "base_disturbance"), **options)["base_disturbance"].value

    _value, grad = jax.value_and_grad(mean)(robot)
    fd = _finite_difference(mean, robot, "base_mass", 1e-2)
    np.testing.assert_allclose(float(grad.base_mass), float(fd), rtol=1e-6)
    before = averages._estimate_batched._cache_size()
    averages.joint_averages(
        robot, ("manipulability", "base_disturbance"), rtol=3e-3, min_samples=2**9, max_samples=2**12, block=128, seed=5
    )
    averages.joint_averages(
        robot,
        ("manipulability", "base_disturbance"),
        rtol=1e-2,
        min_samples=2**10,
        max_samples=2**13,
        block=128,
        seed=6,
    )
    assert averages._estimate_batched._cache_size() == before + 1  # one program for both calls
