"""The bus attitude of a UR5 on its smallsat simulated by MuJoCo agrees with the SO(3) integrator.

MuJoCo reads the arm with its own URDF parser (bus + fixed mount + arm, a free joint
on the bus; zero gravity; armature, damping, friction and limits off; RK4 at
dt = 1e-3; recipe in SPATIAL.md). The joints are driven by internal torques
(``qfrc_applied`` on the arm dofs only, so momentum stays zero): computed torques that
make the joints follow a closed loop on a quintic time law, with PD feedback. The
recorded joint samples are then replayed through spacearm's integrator as a polyline,
and the bus attitude at the end compared with MuJoCo's bus quaternion. Nothing but the
URDF and the bus numbers is shared.
"""

import os

import numpy as np
import pytest

import spacearm as sa
from spacearm.motion import attitude

from .spatial_references import combined_urdf, mujoco_model

mujoco = pytest.importorskip("mujoco")

CONFIG = os.path.join(os.path.dirname(__file__), "..", "configs", "ur5-smallsat.yaml")


def _loop(q0, u, v, amplitude, duration, t):
    """Closed loop q(s) = q0 + A[(cos 2 pi s - 1) u + sin(2 pi s) v], s quintic in t: q, q', q''."""
    tau = t / duration
    s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
    ds = (30 * tau**2 - 60 * tau**3 + 30 * tau**4) / duration
    dds = (60 * tau - 180 * tau**2 + 120 * tau**3) / duration**2
    w = 2 * np.pi
    c, sn = np.cos(w * s), np.sin(w * s)
    q = q0 + amplitude * ((c - 1) * u + sn * v)
    dq_ds = amplitude * w * (-sn * u + c * v)
    d2q_ds2 = -amplitude * w * w * (c * u + sn * v)
    return q, dq_ds * ds, d2q_ds2 * ds * ds + dq_ds * dds


def simulate(robot, q0, u, v, amplitude=0.8, duration=4.0, dt=1e-3):
    with open(robot.labels.source) as f:
        text = f.read()
    model = mujoco_model(
        combined_urdf(
            text,
            root_link=robot.labels.root_link,
            base_mass=float(robot.base_mass),
            base_com=np.asarray(robot.base_com),
            base_inertia=np.asarray(robot.base_inertia),
            mount_xyz=np.asarray(robot.mount_xyz),
            mount_rpy=np.asarray(robot.mount_rpy),
        )
    )
    model.opt.timestep = dt
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    data = mujoco.MjData(model)
    qadr = np.array([model.jnt_qposadr[model.joint(name).id] for name in robot.joint_names])
    vadr = np.array([model.jnt_dofadr[model.joint(name).id] for name in robot.joint_names])
    data.qpos[:] = 0.0
    data.qpos[3] = 1.0
    data.qpos[qadr] = q0
    data.qvel[:] = 0.0
    M = np.zeros((model.nv, model.nv))
    steps = int(round(duration / dt))
    samples = [data.qpos[qadr].copy()]
    for k in range(steps):
        t = k * dt
        q_d, v_d, a_d = _loop(q0, u, v, amplitude, duration, t)
        mujoco.mj_forward(model, data)
        mujoco.mj_fullM(model, data, M)
        bias = data.qfrc_bias.copy()
        a_arm = a_d + 400.0 * (q_d - data.qpos[qadr]) + 40.0 * (v_d - data.qvel[vadr])
        base = np.arange(6)
        a_base = -np.linalg.solve(M[np.ix_(base, base)], M[np.ix_(base, vadr)] @ a_arm + bias[base])
        torque = M[np.ix_(vadr, base)] @ a_base + M[np.ix_(vadr, vadr)] @ a_arm + bias[vadr]
        data.qfrc_applied[:] = 0.0
        data.qfrc_applied[vadr] = torque
        mujoco.mj_step(model, data)
        samples.append(data.qpos[qadr].copy())
    mujoco.mj_forward(model, data)
    w, x, y, z = data.qpos[3:7]
    R = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    momentum = M[:6] @ data.qvel  # generalized momentum of the free joint: stays ~0
    return np.array(samples), R, momentum


def test_ur5_loop_matches_mujoco():
    robot = sa.load_robot(CONFIG)
    rng = np.random.default_rng(3)
    q0 = rng.uniform(-1.5, 1.5, robot.n_joints)
    u, v = np.linalg.qr(rng.normal(size=(robot.n_joints, 2)))[0].T
    samples, R_mujoco, momentum = simulate(robot, q0, u, v)
    assert np.max(np.abs(momentum)) < 1e-9
    angle = float(attitude.geodesic_distance(np.eye(3), R_mujoco))
    assert angle > 0.02  # the loop does turn the bus
    # Replaying the samples (1 ms apart) as straight segments departs from MuJoCo's smooth
    # joint path by O(dt^2) (the chords): check that this is all the difference, by
    # replaying every sample and every other sample and extrapolating (Richardson).
    errors = []
    for stride in (1, 2):
        chords = samples[::stride]
        R_end, q_end = sa.integrate_joint_path(robot, chords[0], chords, steps=1)
        np.testing.assert_allclose(q_end, samples[-1])
        errors.append(np.asarray(attitude.log(R_mujoco.T @ np.asarray(R_end))))
    fine, coarse = np.linalg.norm(errors[0]), np.linalg.norm(errors[1])
    assert fine < 1e-7, (angle, fine)
    assert 3.9 < coarse / fine < 4.1  # second order in the chord length
    extrapolated = (4.0 * errors[0] - errors[1]) / 3.0
    assert np.linalg.norm(extrapolated) < 1e-10, (angle, fine, extrapolated)
