"""Spatial reorientation: a closed joint path turns the bus by a target rotation (3 DOF)."""

import dataclasses
import os

import jax.numpy as jnp
import numpy as np
import pytest

import spacearm as sa
from spacearm.motion import attitude
from spacearm.planning import SpatialLoopSettings, plan_spatial_reorientation_details

from .conftest import count_compiles

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")
FAST = SpatialLoopSettings(segments=16, loop_counts=(1, 2, 4), seeds=1, adam_steps=40)


@pytest.fixture(scope="module")
def arm3():
    return sa.load_robot(os.path.join(CONFIGS, "arm3dof-100kg.yaml"))


@pytest.mark.slow  # compiles a DOP853 loop or the planner: minutes on 2 shared cores
def test_three_rotation_components_to_1e_9(arm3):
    q0 = np.array([0.2, 0.6, -1.1])
    lower, upper = np.asarray(arm3.joint_lower), np.asarray(arm3.joint_upper)
    R0 = np.asarray(attitude.expm(jnp.array([0.3, -0.2, 0.9])))
    for phi in ([0.02, -0.03, 0.04], [-0.05, 0.01, 0.0]):
        target = np.asarray(attitude.expm(jnp.asarray(phi)))
        plan = plan_spatial_reorientation_details(arm3, q0, target, FAST)
        path = plan.waypoints
        np.testing.assert_array_equal(path[0], q0)
        np.testing.assert_array_equal(path[-1], q0)
        assert np.all(path >= lower) and np.all(path <= upper)
        # checked independently of the planner: the public integrator, refined steps
        R_end, q_end = sa.integrate_joint_path(arm3, q0, path, base_rotation=R0, steps=64)
        assert float(attitude.geodesic_distance(R0 @ target, R_end)) < 1e-9
        np.testing.assert_array_equal(q_end, q0)
        assert plan.rotation_error < 1e-9


@pytest.mark.slow  # compiles a DOP853 loop or the planner: minutes on 2 shared cores
def test_public_dispatch_and_limits(arm3):
    q0 = np.array([0.2, 0.6, -1.1])
    target = np.asarray(attitude.expm(jnp.array([0.0, 0.03, -0.02])))
    tight = arm3.replace(joint_lower=np.array([-0.6, -0.2, -1.9]), joint_upper=np.array([1.0, 1.4, -0.3]))
    path = sa.plan_reorientation(
        tight, q0, target, **{k: getattr(FAST, k) for k in ("segments", "seeds", "adam_steps")}
    )
    assert np.all(path >= np.asarray(tight.joint_lower)) and np.all(path <= np.asarray(tight.joint_upper))
    R_end, _ = sa.integrate_joint_path(tight, q0, path, steps=64)
    assert float(attitude.geodesic_distance(target, R_end)) < 1e-9
    with pytest.raises(sa.ConfigError, match="rotation"):
        sa.plan_reorientation(arm3, q0, np.diag([1.0, 1.0, -1.0]))


@pytest.mark.slow  # compiles the planner: about a minute on 2 shared cores
def test_rates_weights_and_step_counts_are_traced_not_compiled(arm3):
    """Only the shape settings key the optimizer's program: new step counts, rates,
    weights, margins and tolerances reuse it (and still change the result)."""
    q0 = np.array([0.2, 0.6, -1.1])
    target = np.array([0.02, -0.03, 0.04])
    first = plan_spatial_reorientation_details(arm3, q0, target, FAST)
    other = dataclasses.replace(
        FAST, adam_steps=25, newton_steps=9, learning_rate=0.03, travel_weight=2e-3, limit_margin=0.04, tolerance=1e-8
    )
    with count_compiles() as compiles:
        second = plan_spatial_reorientation_details(arm3, q0, target, other)
    assert compiles["_optimize"] == 0, dict(compiles)
    assert second.rotation_error < 1e-8
    assert not np.array_equal(first.loop, second.loop)
