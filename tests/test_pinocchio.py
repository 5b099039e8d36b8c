"""J*, w* and the tip against Pinocchio's centroidal momentum map (an independent library).

The same robot is built in Pinocchio with a planar free base joint (x, y, yaw) and
revolute z joints. Zero linear and angular momentum, A_g v = 0 restricted to the
planar rows, eliminates the base velocity; the tip frame Jacobian then gives J*.
"""

import numpy as np
import pytest

import spacearm as sa

from .conftest import random_robot

pin = pytest.importorskip("pinocchio")


def pinocchio_model(robot):
    model = pin.Model()
    rotor = np.diag([1.0, 1.0, 0.0])  # in-plane inertias do not enter a planar motion
    base = model.addJoint(0, pin.JointModelPlanar(), pin.SE3.Identity(), "base")
    model.appendBodyToJoint(
        base,
        pin.Inertia(float(robot.base_mass), np.zeros(3), rotor + np.diag([0, 0, float(robot.base_inertia)])),
        pin.SE3.Identity(),
    )
    parent, offset = base, float(robot.base_attach)
    for i in range(robot.n_links):
        joint = model.addJoint(
            parent, pin.JointModelRZ(), pin.SE3(np.eye(3), np.array([offset, 0.0, 0.0])), f"joint{i + 1}"
        )
        model.appendBodyToJoint(
            joint,
            pin.Inertia(
                float(robot.link_mass[i]),
                np.array([float(robot.link_a[i]), 0.0, 0.0]),
                rotor + np.diag([0, 0, float(robot.link_inertia[i])]),
            ),
            pin.SE3.Identity(),
        )
        parent, offset = joint, float(robot.link_a[i] + robot.link_b[i])
    tip = model.addFrame(
        pin.Frame("tip", parent, 0, pin.SE3(np.eye(3), np.array([offset, 0.0, 0.0])), pin.FrameType.OP_FRAME)
    )
    return model, tip


def pinocchio_quantities(robot, phi, base_xy=(0.37, -1.2)):
    model, tip = pinocchio_model(robot)
    data = model.createData()
    q = np.r_[base_xy, np.cos(phi[0]), np.sin(phi[0]), phi[1:]]
    planar_rows = [0, 1, 5]  # linear x, y and angular z of the centroidal momentum
    Ag = pin.computeCentroidalMap(model, data, q)[planar_rows]
    com = pin.centerOfMass(model, data, q)
    J_tip = pin.computeFrameJacobian(model, data, q, tip, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:2]
    pin.updateFramePlacements(model, data)
    tip_position = data.oMf[tip].translation[:2] - com[:2]
    base_velocity_per_joint_rate = -np.linalg.solve(Ag[:, :3], Ag[:, 3:])
    J_star = J_tip[:, 3:] + J_tip[:, :3] @ base_velocity_per_joint_rate
    # Base angular rate per joint rate: the third row of the eliminated base velocity.
    return tip_position, J_star, base_velocity_per_joint_rate[2]


@pytest.mark.parametrize("n", [2, 3, 4])
def test_against_pinocchio_random_designs(n):
    rng = np.random.default_rng(100 + n)
    worst = 0.0
    for _ in range(20):
        robot = random_robot(rng, n)
        phi = rng.uniform(-np.pi, np.pi, n + 1)
        tip, J_star, base_row = pinocchio_quantities(robot, phi)
        np.testing.assert_allclose(sa.tip_position(robot, phi), tip, atol=1e-10)
        J = np.asarray(sa.generalized_jacobian(robot, phi))
        np.testing.assert_allclose(J, J_star, atol=1e-10)
        i_s, i_m = sa.momentum_inertias(robot, phi)
        np.testing.assert_allclose(-np.asarray(i_m) / float(i_s), base_row, atol=1e-10)
        w = float(sa.manipulability(robot, phi))
        np.testing.assert_allclose(w, np.sqrt(np.linalg.det(J_star @ J_star.T)), atol=1e-10)
        worst = max(worst, float(np.max(np.abs(J - J_star))))
    assert worst < 1e-10


def test_against_pinocchio_table1(table1):
    phi = np.radians([0.0, -60.0, 120.0])
    tip, J_star, _ = pinocchio_quantities(table1, phi)
    np.testing.assert_allclose(sa.tip_position(table1, phi), tip, atol=1e-12)
    np.testing.assert_allclose(sa.generalized_jacobian(table1, phi), J_star, atol=1e-12)
