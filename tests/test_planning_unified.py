"""Every family plans reaching and reorientation through the one control flow.

`spacearm.planning.reach.plan_reach` and `spacearm.planning._loop_steps.plan_loop` hold
the steps once; the groups SO(2) and SO(3) only supply the numerics. These tests spy on
the shared functions and check both families pass through them, with the group's steps
(the plans themselves are checked against references in test_planning.py,
test_spatial_reach.py and test_spatial_reorientation.py). Each test takes a few seconds: it compiles the smallest
straight-path and loop programs of both families.
"""

import os

import numpy as np
import pytest

import spacearm as sa
from spacearm._core.groups import SO2, SO3
from spacearm.planning import _loop_steps, reach, reorientation, spatial_reorientation

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")
PHI_START = np.radians([0.0, -60.0, 120.0])
Q0 = np.array([0.2, 0.6, -1.1])


@pytest.fixture(scope="module")
def arm3():
    return sa.load_robot(os.path.join(CONFIGS, "arm3dof-100kg.yaml"))


def test_both_families_reach_through_the_one_planner(monkeypatch, arm3):
    seen = []
    check = reach._check_request

    def spy(robot, family, steps, *args):
        seen.append((family.attitude.name, steps))
        return check(robot, family, steps, *args)

    monkeypatch.setattr(reach, "_check_request", spy)
    planar = sa.plan_reach(sa.umetani1990(), PHI_START, [2.0, 1.0], history_samples=5)
    tip0 = np.asarray(sa.tip_position(arm3, Q0))
    spatial = sa.plan_reach(arm3, Q0, tip0 + np.array([0.03, -0.02, 0.035]), history_samples=4)
    assert planar.mode == spatial.mode == "straight"
    assert planar.error < 1e-9 and spatial.error < 1e-9
    assert seen == [(SO2.name, reach._REACH_STEPS[SO2.name]), (SO3.name, reach._REACH_STEPS[SO3.name])]
    # the shell pre-check is the same code for both: the same message shape
    for robot, start, target in [(sa.umetani1990(), PHI_START, [0.0, 50.0]), (arm3, Q0, [0.0, 0.0, 50.0])]:
        with pytest.raises(sa.ConfigError, match=r"50 m from the system centroid, beyond the Maximum Reachable radius"):
            sa.plan_reach(robot, start, target)


def test_candidate_rotations_come_from_the_group(arm3):
    """Planar: ``rotation_grid`` angles on the circle; spatial: the Fibonacci-sphere vectors, smallest first."""
    job = type("Job", (), {"options": {}, "rotation_grid": 8})()
    np.testing.assert_allclose(np.sort(reach._candidates(SO2, job)[:, 0]), np.pi / 4 * np.arange(-4, 4), atol=1e-15)
    job.rotation_grid = 10
    vectors = reach._candidates(SO3, job)
    assert vectors.shape == (10, 3)
    np.testing.assert_allclose(np.linalg.norm(vectors, axis=1), [0.02] * 3 + [0.05] * 3 + [0.1] * 3 + [0.2])


def test_both_families_reorient_through_the_one_planner(monkeypatch, arm3):
    seen = []
    plan_loop = _loop_steps.plan_loop

    def spy(steps, *args, **kwargs):
        seen.append(steps)
        return plan_loop(steps, *args, **kwargs)

    monkeypatch.setattr(reorientation, "plan_loop", spy)
    monkeypatch.setattr(spatial_reorientation, "plan_loop", spy)
    still = sa.plan_reorientation(sa.umetani1990(), PHI_START, 0.0)
    np.testing.assert_array_equal(still, [PHI_START[1:], PHI_START[1:]])
    with pytest.raises(sa.ConfigError, match="no loop reached the target rotation"):  # a hopeless budget, fast
        sa.plan_reorientation(
            arm3,
            Q0,
            np.array([0.5, 0.0, 0.0]),
            segments=4,
            harmonics=1,
            loop_counts=(1,),
            seeds=1,
            adam_steps=1,
            newton_steps=0,
        )
    assert seen == [reorientation._PLANAR_LOOP_STEPS, spatial_reorientation._SPATIAL_LOOP_STEPS]
