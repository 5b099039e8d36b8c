"""Reaching a point in 3-D: straight when possible, else turn the bus by a closed loop first."""

import os

import numpy as np
import pytest

import spacearm as sa
from spacearm.planning import SpatialLoopSettings

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")


@pytest.mark.slow  # compiles a DOP853 loop or the planner: minutes on 2 shared cores
def test_straight_then_reorient_first():
    robot = sa.load_robot(os.path.join(CONFIGS, "arm3dof-100kg.yaml"))
    q0 = np.array([0.2, 0.6, -1.1])
    tip0 = np.asarray(sa.tip_position(robot, q0))
    d = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    end = sa.motion.spatial_straight_tip_path(robot, q0, d)
    assert int(end.reason) == sa.motion.REASON_SINGULAR
    near = sa.plan_reach(robot, q0, tip0 + 0.5 * float(end.length) * d)
    assert near.mode == "straight" and near.error < 1e-9
    # just beyond the singular end of the straight path: the bus must turn first
    far = tip0 + 1.02 * float(end.length) * d
    plan = sa.plan_reach(robot, q0, far, settings=SpatialLoopSettings(segments=16, loop_counts=(1, 2, 4), seeds=1, adam_steps=40))
    assert plan.mode == "reorient" and plan.error < 1e-9
    np.testing.assert_array_equal(plan.loop_waypoints[0], q0)
    np.testing.assert_array_equal(plan.loop_waypoints[-1], q0)
    R_loop, _ = sa.integrate_joint_path(robot, q0, plan.loop_waypoints, steps=32)
    assert float(sa.motion.geodesic_distance(plan.bus_rotation, R_loop)) < 1e-9
