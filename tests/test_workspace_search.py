"""Workspaces by search over the joint box (issue 17, item 1), checked on the planar closed forms."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import spacearm as sa
from spacearm.analysis import workspace_search as sw
from spacearm.models.planar import singularities
from spacearm.paper import workspaces

from .conftest import count_compiles, random_robot


@pytest.mark.parametrize("n", [2, 3])
def test_reachable_radii_match_planar_closed_forms(n):
    robot = sa.umetani1990() if n == 2 else random_robot(np.random.default_rng(11), 3)
    radii = sw.reachable_radii(robot)
    with count_compiles() as compiled:  # the number of starts is traced: 100 runs the program of 128
        fewer = sw.reachable_radii(robot, starts=100)
    assert sum(compiled.values()) == 0, compiled
    for r in (radii, fewer):
        np.testing.assert_allclose(float(r.outer), float(workspaces.maximum_reachable_radius(robot)), rtol=1e-10)
        assert abs(float(r.inner) - float(workspaces.maximum_reachable_inner_radius(robot))) < 1e-8


def test_reachable_radius_gradient_is_the_envelope():
    robot = sa.umetani1990()
    grad = jax.grad(lambda r: sw.reachable_radii(r).outer)(robot)
    exact = jax.grad(lambda r: workspaces.maximum_reachable_radius(r))(robot)
    for field in ("base_mass", "base_attach", "link_mass", "link_a", "link_b"):
        np.testing.assert_allclose(
            np.asarray(getattr(grad, field)), np.asarray(getattr(exact, field)), rtol=1e-7, atol=1e-12
        )


def test_path_independent_radius_dispatches_by_family():
    """sa.path_independent_radius: the planar root tracing for two links, singular_radius otherwise."""
    planar = sa.umetani1990()
    assert float(sa.path_independent_radius(planar)) == float(singularities.path_independent_radius(planar))
    arm3 = random_robot(np.random.default_rng(11), 3)  # a planar arm with no n = 2 scan: the search
    assert float(sa.path_independent_radius(arm3)) == float(sw.singular_radius(arm3, "generalized")[0])


def test_public_dispatch_keeps_the_planar_closed_form():
    robot = sa.umetani1990()
    assert float(sw.maximum_reachable_radius(robot)) == float(workspaces.maximum_reachable_radius(robot))


@pytest.mark.parametrize("seed", [None, 3])
def test_singular_radii_match_planar_references(seed):
    robot = sa.umetani1990() if seed is None else random_robot(np.random.default_rng(seed), 2)
    dynamic, joints = sw.singular_radius(robot, "generalized")
    np.testing.assert_allclose(float(dynamic), float(singularities.path_independent_radius(robot)), rtol=1e-8)
    assert abs(float(sw.singularity_measure(robot, joints))) < 1e-10
    kinematic, _ = sw.singular_radius(robot, "fixed_base")
    np.testing.assert_allclose(float(kinematic), float(workspaces.kinematic_singularity_radius(robot)), rtol=1e-8)


def test_singular_radius_sizes_are_traced_within_a_bucket():
    """``samples`` and ``keep`` are traced bounds in power-of-two buckets: sizes in one bucket
    share one program (the one the default sizes compile), each finds the planar reference, and
    a size's result does not depend on its bucket (the rows past it are never used), to the bit."""
    robot = sa.umetani1990()
    reference = float(singularities.path_independent_radius(robot))
    first = sw.singular_radius(robot, samples=10_000, keep=1_500)  # buckets 2^14 and 2048: the defaults'
    with count_compiles() as compiled:
        second = sw.singular_radius(robot, samples=12_000, keep=1_800)
        default = sw.singular_radius(robot)
    assert sum(compiled.values()) == 0, compiled
    for radius, joints in (first, second, default):
        np.testing.assert_allclose(float(radius), reference, rtol=1e-8)
        assert abs(float(sw.singularity_measure(robot, joints))) < 1e-10
    roomier = sw._singular_radius(
        robot,
        "generalized",
        np.int32(10_000),
        np.int32(1_500),
        32,
        150,
        16,
        4,
        0,
        False,
        sample_room=2**15,
        keep_room=4096,
    )
    for a, b in zip(roomier, first, strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    with pytest.raises(sa.ConfigError, match=r"keep: from 1 to samples \(100\) postures, got 200"):
        sw.singular_radius(robot, samples=100, keep=200)


def test_singular_postures_lie_on_the_dynamic_set():
    robot = sa.umetani1990()
    postures = sw.singular_postures(robot)
    with count_compiles() as compiled:  # the number of samples is traced: 10,000 runs the program of 2^14
        fewer = sw.singular_postures(robot, samples=10_000)
    assert sum(compiled.values()) == 0, compiled
    for found in (postures, fewer):
        on = np.asarray(found.on_set)
        assert on.mean() > 0.9
        phi = jnp.concatenate([jnp.zeros((on.sum(), 1)), found.joints[on]], axis=-1)
        det = np.asarray(jnp.linalg.det(sa.generalized_jacobian(robot, phi)))
        assert np.max(np.abs(det)) < 1e-9
    assert not np.array_equal(np.asarray(fewer.joints), np.asarray(postures.joints))  # other samples kept


def test_spatial_guaranteed_workspace_is_ordered():
    robot = sa.load_robot("configs/arm3dof-100kg.yaml")
    g = sw.guaranteed_workspace(robot)
    assert 0 <= float(g.inner) < float(g.path_independent) < float(g.outer)
    assert float(g.kinematic) < float(g.outer)
    # No sampled posture reaches farther than the searched outer radius, or nearer than the inner one.
    q = np.random.default_rng(0).uniform(np.asarray(robot.joint_lower), np.asarray(robot.joint_upper), (20000, 3))
    r = np.linalg.norm(np.asarray(sa.tip_position(robot, q)), axis=-1)
    assert r.max() <= float(g.outer) + 1e-9 and r.min() >= float(g.inner) - 1e-9
    assert r.max() > float(g.outer) - 0.02


def test_icosphere_directions():
    d = sw.icosphere_directions(4)
    assert d.shape == (2562, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0, rtol=1e-14)
    cos = d @ d.T - 2 * np.eye(len(d))
    nearest = np.arccos(np.clip(cos.max(axis=1), -1, 1))
    assert nearest.max() / nearest.min() < 1.3  # nearly uniform


def test_straight_path_workspace_ends_on_lines_and_outside_the_path_independent_sphere():
    robot = sa.load_robot("configs/arm3dof-100kg.yaml")
    area4 = sw.spatial_straight_path_workspace(robot, np.array([0.3, 0.5, 1.2]), subdivisions=1)
    d = np.asarray(area4.directions)
    travel = np.asarray(area4.ends) - np.asarray(area4.start)
    along = np.sum(travel * d, axis=-1)
    np.testing.assert_allclose(along, np.asarray(area4.lengths), rtol=1e-9, atol=1e-12)
    assert np.max(np.linalg.norm(travel - along[:, None] * d, axis=-1)) < 1e-9
    singular = np.asarray(area4.reasons) == 0
    assert singular.sum() > 0
    # Paths that stop at a dynamic singularity stop on a singular tip, never inside the
    # singularity-free sphere found by the independent search over the singular set.
    radius, _ = sw.singular_radius(robot, "generalized")
    ends = np.linalg.norm(np.asarray(area4.ends)[singular], axis=-1)
    assert ends.min() >= float(radius) - 1e-6


@pytest.mark.parametrize("seed", [None, 3])
def test_path_independent_radius_gradient_follows_the_moving_singular_set(seed):
    robot = sa.umetani1990() if seed is None else random_robot(np.random.default_rng(seed), 2)
    grad = jax.grad(lambda r: sw.singular_radius(r, "generalized")[0])(robot)
    # For these designs the closest singular tip is at a collinear posture: min over the
    # branches of |K0 -+ ...| (kinematic_singularity_radius), differentiable in closed form.
    exact = jax.grad(workspaces.kinematic_singularity_radius)(robot)
    for field in ("base_mass", "base_attach", "link_mass", "link_a", "link_b"):
        np.testing.assert_allclose(
            np.asarray(getattr(grad, field)), np.asarray(getattr(exact, field)), rtol=1e-6, atol=1e-10
        )


def test_path_independent_radius_gradient_spatial_against_finite_differences():
    # The 3-DOF arm's closest dynamic-singular tip sits on the shoulder's upper limit with
    # the set moving with the design: the multiplier term matters here (without it the
    # base-mass derivative is 18 % off).
    robot = sa.load_robot("configs/arm3dof-100kg.yaml")

    def radius(r):
        return sw.singular_radius(r, "generalized")[0]

    grad = jax.grad(radius)(robot)
    for field, index, h in (("base_mass", (), 0.125), ("mount_xyz", (2,), 2.5e-4)):

        def shifted(delta, field=field, index=index):
            return robot.replace(**{field: jnp.asarray(getattr(robot, field)).at[index].add(delta)})

        fd = (float(radius(shifted(h))) - float(radius(shifted(-h)))) / (2 * h)
        np.testing.assert_allclose(float(np.asarray(getattr(grad, field))[index]), fd, rtol=2e-3)
