"""Reaching a point in 3-D: the reachability pre-check, straight plans with their history,
every argument of `sa.plan_reach` honoured or refused, and reorienting first."""

import os

import jax
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import spacearm as sa
import spacearm.motion
from spacearm.models.spatial.primitives import as_tree
from spacearm.models.tree.shell import tip_shell as tree_tip_shell, virtual_link_lengths
from spacearm.planning import LoopSettings, SpatialLoopSettings

from .conftest import count_compiles

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")
Q0 = np.array([0.2, 0.6, -1.1])
FAST = SpatialLoopSettings(segments=16, loop_counts=(1, 2, 4), seeds=1, adam_steps=40)


@pytest.fixture(scope="module")
def arm3():
    return sa.load_robot(os.path.join(CONFIGS, "arm3dof-100kg.yaml"))


@pytest.fixture(scope="module")
def near(arm3):
    """A straight plan to a point 5 cm from the start tip (compiles the 32 straight-path lanes
    that every default plan of this arm shares, the reach command's too)."""
    tip0 = np.asarray(sa.tip_position(arm3, Q0))
    return sa.plan_reach(arm3, Q0, tip0 + np.array([0.03, -0.02, 0.035]))


# The shell of every tip position -----------------------------------------------------------


def tip_shell(robot):
    return tree_tip_shell(as_tree(robot), 0)


def test_virtual_link_lengths_equal_the_planar_coefficients():
    """The Table 1 robot as a spatial file: its virtual links are the paper's K0, K1, K2 (eq. 1)."""
    spatial = sa.load_robot(os.path.join(CONFIGS, "umetani1990-spatial.yaml"))
    planar = sa.load_robot(os.path.join(CONFIGS, "umetani1990.yaml"))
    K = np.asarray(sa.tip_coefficients(planar))
    lengths = virtual_link_lengths(as_tree(spatial), 0)[:, 0]  # the bodies after each joint, then the bus
    np.testing.assert_allclose(lengths, np.roll(K, -1), rtol=1e-12)
    np.testing.assert_allclose(tip_shell(spatial), (0.0, K.sum()), rtol=1e-12)


@pytest.mark.parametrize("name", ["ur5-smallsat.yaml", "arm3dof-100kg.yaml", "ets7.yaml"])
def test_no_posture_and_attitude_leaves_the_shell(name):
    robot = sa.load_robot(os.path.join(CONFIGS, name))
    inner, outer = tip_shell(robot)
    lower, upper = np.asarray(robot.joint_lower), np.asarray(robot.joint_upper)
    lower, upper = np.where(np.isfinite(lower), lower, -np.pi), np.where(np.isfinite(upper), upper, np.pi)
    q = lower + (upper - lower) * np.random.default_rng(1).random((4096, robot.n_joints))
    R = Rotation.random(4096, random_state=2).as_matrix()
    radius = np.linalg.norm(np.asarray(jax.jit(sa.tip_position)(robot, q, R)), axis=-1)
    assert inner <= radius.min() and radius.max() <= outer
    assert radius.max() > 0.8 * outer  # a bound, and not a loose one


def test_a_target_outside_the_shell_is_refused_at_once_naming_the_radius(arm3):
    _, outer = tip_shell(arm3)
    with count_compiles() as compiles, pytest.raises(sa.ConfigError, match=f"Maximum Reachable radius {outer:.6g} m"):
        sa.plan_reach(arm3, Q0, [0.0, 0.0, 1.001 * outer])
    assert sum(compiles.values()) == 0, dict(compiles)  # refused before any program is built


# Straight plans and their history ----------------------------------------------------------


def test_straight_plan_holds_the_whole_history(arm3, near):
    assert near.mode == "straight" and near.error < 1e-9 and near.loops == 0
    assert near.joints.shape == (32, 3) and near.base_rotation.shape == (32, 3, 3) and near.tips.shape == (32, 3)
    np.testing.assert_array_equal(near.joints[0], Q0)
    np.testing.assert_allclose(near.base_rotation[0], np.eye(3), atol=1e-15)
    np.testing.assert_allclose(near.tips[-1], near.target, atol=1e-9)
    # the samples lie on the segment, evenly spaced, and each is the tip of its posture
    steps = np.diff(near.tips, axis=0)
    np.testing.assert_allclose(steps, np.broadcast_to(steps[0], steps.shape), atol=1e-9)
    tips = np.einsum("sij,sj->si", near.base_rotation, np.asarray(sa.tip_position(arm3, near.joints)))
    np.testing.assert_allclose(tips, near.tips, atol=1e-12)
    # the bus turns along the straight path: the plan's turn is the history's
    turn = Rotation.from_matrix(near.base_rotation[0].T @ near.base_rotation[-1]).magnitude()
    assert turn > 1e-4
    assert near.bus_turn == pytest.approx(turn, abs=1e-12)


def test_base_rotation_and_history_samples_are_honoured(arm3, near):
    R0 = Rotation.from_rotvec([0.3, -0.2, 0.9]).as_matrix()
    target = R0 @ (near.target)  # the same plan seen from a turned bus
    turned = sa.plan_reach(arm3, Q0, target, base_rotation=R0)
    np.testing.assert_allclose(turned.base_rotation, np.einsum("ij,sjk->sik", R0, near.base_rotation), atol=1e-9)
    np.testing.assert_allclose(turned.joints, near.joints, atol=1e-9)
    fewer = sa.plan_reach(arm3, Q0, near.target, history_samples=4)  # a new lane count: compiles again
    assert fewer.joints.shape == (4, 3)
    np.testing.assert_allclose(fewer.joints[[0, -1]], near.joints[[0, -1]], atol=1e-9)


def test_tolerance_and_modes_are_honoured(arm3, near):
    with pytest.raises(sa.ConfigError, match="modes"):
        sa.plan_reach(arm3, Q0, near.target, tolerance=1e-300, modes=("straight",))
    loose = sa.plan_reach(arm3, Q0, near.target, tolerance=1e-3, modes=("straight",))
    assert loose.error < 1e-9


@pytest.mark.parametrize(
    "options, message",
    [
        ({"settings": LoopSettings()}, "settings: expected SpatialLoopSettings"),
        ({"modes": ("reposition",)}, "modes"),
        ({"rotation_grid": 0}, "rotation_grid"),
        ({"rotation_grid": 8, "rotations": np.zeros((2, 3))}, "rotation_grid"),
        ({"history_samples": 1}, "history_samples"),
        ({"tolerance": -1.0}, "tolerance"),
        ({"base_rotation": np.diag([1.0, 1.0, -1.0])}, "base_rotation"),
        ({"loop_samples": 0}, "loop_samples"),
    ],
)
def test_bad_arguments_are_refused_by_name(arm3, options, message):
    with pytest.raises(sa.ConfigError, match=message):
        sa.plan_reach(arm3, Q0, [0.3, 0.2, 0.1], **options)


def test_planar_robots_refuse_spatial_options():
    robot = sa.umetani1990()
    phi = np.radians([0.0, -60.0, 120.0])
    with pytest.raises(sa.ConfigError, match="base_rotation"):
        sa.plan_reach(robot, phi, [2.0, 1.0], base_rotation=np.eye(3))
    with pytest.raises(sa.ConfigError, match="settings: expected LoopSettings"):
        sa.plan_reach(robot, phi, [2.0, 1.0], settings=FAST)


# Turning the bus first ---------------------------------------------------------------------


@pytest.mark.slow  # compiles the loop optimizer: about a minute of CPU
def test_reorient_first_then_straight(arm3):
    tip0 = np.asarray(sa.tip_position(arm3, Q0))
    d = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    end = spacearm.motion.spatial_straight_tip_path(arm3, Q0, d)
    assert int(end.reason) == spacearm.motion.REASON_SINGULAR
    # just beyond the singular end of the straight path: the bus must turn first
    far = tip0 + 1.02 * float(end.length) * d
    with pytest.raises(sa.ConfigError, match="modes"):
        sa.plan_reach(arm3, Q0, far, modes=("straight",))
    plan = sa.plan_reach(arm3, Q0, far, settings=FAST, loop_samples=2)
    assert plan.mode == "reorient" and plan.error < 1e-9
    # the settings are used: loops of FAST.segments segments
    assert len(plan.loop_waypoints) == plan.loops * FAST.segments + 1
    np.testing.assert_array_equal(plan.loop_waypoints[0], Q0)
    np.testing.assert_array_equal(plan.loop_waypoints[-1], Q0)
    R_loop, _ = sa.integrate_joint_path(arm3, Q0, plan.loop_waypoints, steps=32)
    assert float(spacearm.motion.geodesic_distance(plan.loop_rotation, R_loop)) < 1e-9
    # history: loop samples (2 per segment), then the straight path's
    loop_rows = np.flatnonzero(plan.phase == 1)
    assert len(loop_rows) == plan.loops * FAST.segments * 2 + 1
    np.testing.assert_allclose(plan.base_rotation[loop_rows[-1]], np.asarray(R_loop), atol=1e-9)
    np.testing.assert_allclose(plan.joints[loop_rows[-1]], Q0, atol=1e-15)
    assert plan.joints.shape == (len(loop_rows) + 31, 3)
    np.testing.assert_allclose(plan.tips[-1], far, atol=1e-9)
    turn = Rotation.from_matrix(plan.base_rotation[0].T @ plan.base_rotation[-1]).magnitude()
    assert plan.bus_turn == pytest.approx(turn, abs=1e-12)
    # a rotation grid too small to hold a useful rotation: refused after the search
    with pytest.raises(sa.ConfigError, match="candidate bus rotations"):
        sa.plan_reach(arm3, Q0, far, rotations=np.zeros((1, 3)), settings=FAST)
