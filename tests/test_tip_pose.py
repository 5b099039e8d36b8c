"""sa.tip_pose: the tip frame a pose target is measured against, against finite differences.

At a fixed bus attitude the tip frame turns with the joints at the fixed-base angular
velocity: dR/dq_j = [w_j]x R with w_j the angular rows of the fixed-base Jacobian; its
origin is sa.tip_position's, and the bus attitude turns both.
"""

import jax
import numpy as np

import spacearm as sa

jax.config.update("jax_enable_x64", True)


def _skew(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def _check(robot, q, R0):
    p, R = (np.asarray(a) for a in sa.tip_pose(robot, q, base_rotation=R0))
    np.testing.assert_allclose(p, sa.tip_position(robot, q, base_rotation=R0), atol=1e-14)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-14)
    J = np.asarray(sa.fixed_base_jacobian(robot, q))  # bus axes, rows [v; w]
    h = 1e-6
    for j in range(q.size):
        step = np.zeros_like(q)
        step[j] = h
        _, plus = sa.tip_pose(robot, q + step, base_rotation=R0)
        _, minus = sa.tip_pose(robot, q - step, base_rotation=R0)
        derivative = (np.asarray(plus) - np.asarray(minus)) / (2 * h)
        np.testing.assert_allclose(derivative, _skew(R0 @ J[3:, j]) @ R, atol=1e-8)


def test_the_ur5_tip_frame_turns_with_the_fixed_base_angular_rows():
    robot = sa.load_robot("configs/ur5-smallsat.yaml")
    rng = np.random.default_rng(3)
    R0 = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    R0 *= np.linalg.det(R0)
    _check(robot, rng.uniform(-2, 2, 6), R0)


def test_a_focused_tree_tip_and_batches():
    robot = sa.load_robot("configs/dual-ur5-servicer.yaml").focus(tip="right/tool0")
    q = np.random.default_rng(4).uniform(-2, 2, (2, 12))
    p, R = sa.tip_pose(robot, q)
    assert p.shape == (2, 3) and R.shape == (2, 3, 3)
    np.testing.assert_allclose(p[1], sa.tip_pose(robot, q[1])[0], atol=1e-15)
    _check(robot, q[0], np.eye(3))
