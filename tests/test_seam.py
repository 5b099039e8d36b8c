"""The robot-family seam: every planar closed form equals the generic path over the primitives."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import spacearm as sa
from spacearm import kinematics
from spacearm.models.planar import closed_forms

from .conftest import random_robot


def _postures(rng, n, count=64):
    return rng.uniform(-np.pi, np.pi, (count, n + 1))


@pytest.mark.parametrize("n", [2, 3, 5])
def test_planar_closed_forms_equal_the_generic_path(n):
    rng = np.random.default_rng(n)
    for _ in range(5):
        robot = random_robot(rng, n)
        phi = _postures(rng, n)
        np.testing.assert_allclose(
            kinematics.generic_generalized_jacobian(robot, phi), sa.generalized_jacobian(robot, phi), rtol=0, atol=1e-13
        )
        np.testing.assert_allclose(
            kinematics.generic_manipulability(robot, phi), sa.manipulability(robot, phi), rtol=0, atol=1e-13
        )
        np.testing.assert_allclose(kinematics.generic_tip_position(robot, phi), sa.tip_position(robot, phi), atol=1e-13)
        rates = rng.normal(size=(64, n))
        C = sa.base_rate_matrix(robot, phi)
        assert C.shape == (64, 1, n)
        np.testing.assert_allclose(
            C[:, 0, :] @ np.ones(n), closed_forms.base_rate(robot, phi, np.ones((64, n))), atol=1e-13
        )
        np.testing.assert_allclose(
            jnp.einsum("bij,bj->bi", C, rates)[:, 0], sa.base_rate(robot, phi, rates), atol=1e-13
        )


def test_ellipsoid_axes_match_the_planar_ellipse(table1):
    rng = np.random.default_rng(7)
    phi = _postures(rng, 2)
    semi_axes, directions = sa.manipulability_ellipsoid(table1, phi)
    major, minor, angle = sa.manipulability_ellipse(table1, phi)
    np.testing.assert_allclose(semi_axes[:, 0], major, atol=1e-13)
    np.testing.assert_allclose(semi_axes[:, 1], minor, atol=1e-13)
    # the major axis direction, up to sign
    along = np.abs(directions[:, 0, 0] * np.cos(angle) + directions[:, 1, 0] * np.sin(angle))
    np.testing.assert_allclose(along, 1.0, atol=1e-10)
    np.testing.assert_allclose(np.prod(semi_axes, axis=-1), sa.manipulability(table1, phi), atol=1e-13)


def test_generic_path_is_differentiable_and_finite_at_singular_postures(table1):
    robot = table1.replace(base_attach=np.float64(0.0))  # b0 = 0: the stretched arm is singular
    phi = jnp.array([0.0, 0.3, 0.0])
    assert float(kinematics.generic_manipulability(robot, phi)) < 1e-15
    grad = jax.grad(lambda p: kinematics.generic_manipulability(robot, p))(phi)
    assert np.all(np.isfinite(grad))
    J = jnp.ones((2, 2))
    assert float(kinematics.gram_root_determinant(J)) == 0.0
    assert np.all(np.isfinite(jax.grad(lambda J: kinematics.gram_root_determinant(J))(J)))


def test_renaming_a_design_does_not_recompile(table1):
    phi = jnp.array([0.1, -1.0, 2.0])
    sa.generalized_jacobian(table1, phi)
    before = sa.generalized_jacobian._cache_size()
    renamed = table1.replace(name="another name")
    np.testing.assert_array_equal(sa.generalized_jacobian(renamed, phi), sa.generalized_jacobian(table1, phi))
    assert sa.generalized_jacobian._cache_size() == before
    assert renamed.name == "another name"


def test_base_rotation_is_refused_for_planar_robots(table1):
    with pytest.raises(TypeError, match="base_rotation"):
        sa.generalized_jacobian(table1, jnp.zeros(3), jnp.eye(3))


@pytest.mark.parametrize("n", [2, 3])
def test_planar_straight_path_field_equals_the_generic_field(n):
    from spacearm.models.planar.closed_forms import straight_path_field
    from spacearm.motion.straight_paths import generic_straight_field

    rng = np.random.default_rng(10 + n)
    robot = random_robot(rng, n)
    for _ in range(20):
        y = np.concatenate([rng.uniform(-np.pi, np.pi, n + 1), [0.3]])
        angle = rng.uniform(0, 2 * np.pi)
        direction = jnp.array([np.cos(angle), np.sin(angle)])
        sign0 = jnp.asarray(rng.choice([-1.0, 1.0]) if n == 2 else 1.0)
        np.testing.assert_allclose(
            generic_straight_field(robot, direction, sign0)(y),
            straight_path_field(robot, direction, sign0)(y),
            atol=1e-13,
        )
