"""The JAX exact hypervolume against moocore (values, exclusive contributions) and its
autodiff gradient against finite differences of moocore's hypervolume."""

import jax
import moocore
import numpy as np
import pytest

from spacearm.design.fronts import layer_face_areas
from spacearm.design.hybrid import nondominated_ranks
from spacearm.design.hypervolume import (
    exact_hypervolume,
    hypervolume_contributions,
    hypervolume_gradient,
    layer_hypervolume_gradients,
)

hypervolume_jit = jax.jit(exact_hypervolume)
gradient_jit = jax.jit(hypervolume_gradient)


def _reference_hv(points, reference):
    return moocore.hypervolume(np.asarray(points), ref=np.asarray(reference), maximise=True)


def _point_set(m, count, seed, ties=False):
    """Random points with some dominated ones, and (``ties``) shared coordinates and duplicates."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(0.0, 1.0, size=(count, m))
    if ties:
        points[1, 0] = points[2, 0]  # a tie in f1
        points[4, m - 1] = points[5, m - 1]  # a tie in the slicing objective
        points[7] = points[6]  # a duplicate
        points[8] = points[6] * 0.5  # dominated
        points[9, 0] = -0.5  # below the reference in f1
    return points


@pytest.mark.parametrize("m", [2, 3, 4])
@pytest.mark.parametrize("ties", [False, True])
def test_value_equals_moocore(m, ties):
    for seed in range(3):
        points = _point_set(m, 30 if m < 4 else 16, seed, ties)
        reference = np.full(m, 0.05)
        expected = _reference_hv(points, reference)
        assert float(hypervolume_jit(points, reference)) == pytest.approx(expected, rel=1e-12, abs=0)


@pytest.mark.parametrize("m", [2, 3, 4])
def test_contributions_equal_moocore(m):
    points = _point_set(m, 24 if m < 4 else 12, 7, ties=True)
    reference = np.full(m, 0.05)
    ours = np.asarray(hypervolume_contributions(points, reference))
    # ignore_dominated=False: HV(set) - HV(set without i) for every row, as ours.
    theirs = moocore.hv_contributions(points, ref=reference, maximise=True, ignore_dominated=False)
    np.testing.assert_allclose(ours, theirs, rtol=1e-12, atol=1e-12 * _reference_hv(points, reference))


def test_mask_leaves_rows_out():
    points = _point_set(3, 20, 3)
    mask = np.arange(20) % 3 != 0
    expected = _reference_hv(points[mask], np.zeros(3))
    assert float(exact_hypervolume(points, np.zeros(3), mask)) == pytest.approx(expected, rel=1e-12)


def _finite_difference(points, reference, i, j, step, side=0):
    """Central (side 0) or one-sided (+1, -1) difference of moocore's hypervolume."""
    up, down = points.copy(), points.copy()
    up[i, j] += step if side >= 0 else 0.0
    down[i, j] -= step if side <= 0 else 0.0
    width = step * (2 if side == 0 else 1)
    return (_reference_hv(up, reference) - _reference_hv(down, reference)) / width


@pytest.mark.parametrize("m", [2, 3, 4])
def test_gradient_equals_finite_differences(m):
    """The hypervolume is multilinear in each coordinate near a generic point, so a central
    difference is exact up to rounding: 1e-7 relative to the largest derivative."""
    points = _point_set(m, 20 if m < 4 else 10, 11)
    points[3] = points[2] * 0.9  # dominated: zero gradient
    reference = np.full(m, 0.05)
    gradient = np.asarray(gradient_jit(points, reference))
    expected = np.array(
        [[_finite_difference(points, reference, i, j, 1e-6) for j in range(m)] for i in range(points.shape[0])]
    )
    assert np.abs(expected).max() > 0.01
    np.testing.assert_allclose(gradient, expected, atol=1e-7 * np.abs(expected).max())
    assert np.all(gradient[3] == 0.0)


@pytest.mark.parametrize("m", [2, 3])
def test_gradient_at_ties_lies_between_one_sided_differences(m):
    """Where ties make the hypervolume non-differentiable, the autodiff derivative of every
    coordinate lies between its one-sided difference quotients (a generalized gradient); the
    duplicate, the dominated point and the point below the reference get zero."""
    points = _point_set(m, 16, 5, ties=True)
    reference = np.full(m, 0.05)
    gradient = np.asarray(gradient_jit(points, reference))
    for i in range(points.shape[0]):
        for j in range(m):
            right = _finite_difference(points, reference, i, j, 1e-7, side=1)
            left = _finite_difference(points, reference, i, j, 1e-7, side=-1)
            low, high = min(left, right), max(left, right)
            assert low - 1e-6 <= gradient[i, j] <= high + 1e-6, (i, j, left, gradient[i, j], right)
    assert np.all(gradient[8] == 0.0) and np.all(gradient[9] == 0.0)
    # Moving the duplicate pair together is differentiable: the two rows' derivatives add up to it.
    for j in range(m):
        up, down = points.copy(), points.copy()
        up[[6, 7], j] += 1e-6
        down[[6, 7], j] -= 1e-6
        together = (_reference_hv(up, reference) - _reference_hv(down, reference)) / 2e-6
        assert gradient[6, j] + gradient[7, j] == pytest.approx(together, rel=1e-6)


def test_layer_gradients_move_dominated_points():
    """The second layer's gradient is its own hypervolume gradient, not zero."""
    front = np.array([[1.0, 3.0], [2.0, 2.0], [3.0, 1.0]])
    second = front - 0.5
    points = np.concatenate([front, second])
    layer = np.array([0, 0, 0, 1, 1, 1])
    reference = np.zeros(2)
    gradient = np.asarray(layer_hypervolume_gradients(points, reference, layer))
    np.testing.assert_allclose(gradient[:3], np.asarray(hypervolume_gradient(front, reference)), rtol=1e-14)
    np.testing.assert_allclose(gradient[3:], np.asarray(hypervolume_gradient(second, reference)), rtol=1e-14)
    assert np.all(gradient[3:] > 0)


@pytest.mark.parametrize("m", [2, 3])
def test_layer_face_areas_match_autodiff_and_moocore_differences(m):
    """The NumPy faces of each layer's exclusive regions (the hybrid search's gradient, no
    compiled program) equal the autodiff of the exact hypervolume layer by layer, and the
    front's entries equal central differences of moocore's hypervolume; points below the
    reference get zero."""
    rng = np.random.default_rng(7 + m)
    points = rng.normal(size=(30, m))
    reference = np.full(m, -1.2)  # some points lie below it in some objective
    layer = nondominated_ranks(points)
    areas = layer_face_areas(points, reference, layer)
    np.testing.assert_allclose(areas, np.asarray(layer_hypervolume_gradients(points, reference, layer)), atol=1e-13)
    front = np.flatnonzero((layer == 0) & np.all(points > reference, axis=1))
    for i in front:
        for j in range(m):
            up, down = points[layer == 0].copy(), points[layer == 0].copy()
            row = int(np.flatnonzero(np.flatnonzero(layer == 0) == i)[0])
            up[row, j] += 1e-7
            down[row, j] -= 1e-7
            difference = (_reference_hv(up, reference) - _reference_hv(down, reference)) / 2e-7
            assert areas[i, j] == pytest.approx(difference, rel=1e-6, abs=1e-9)
    below = np.any(points < reference, axis=1)
    assert below.any() and np.all(areas[np.any(points < reference, axis=1)][points[below] < reference] == 0.0)
    second = (layer == 1) & ~below
    assert second.any() and np.all(areas[second].sum(axis=1) > 0)  # dominated, yet moved


def test_layer_face_areas_two_points_closed_form():
    """Two points (1, 3) and (3, 1) above the origin: the faces are 3 - 1 and 1 each way."""
    areas = layer_face_areas(np.array([[1.0, 3.0], [3.0, 1.0]]), np.zeros(2), np.array([0, 0]))
    np.testing.assert_allclose(areas, [[2.0, 1.0], [1.0, 2.0]])
