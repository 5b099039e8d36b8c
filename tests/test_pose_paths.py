"""Straight pose paths (`sa.straight_pose_path`), `plan_pose_reach` and ``spacearm reach --to-rpy``.

References: the tip frame recomputed from the end joints and bus attitude by the forward
kinematics (`sa.tip_position`, the chain's tip axes), the line and the SO(3) geodesic by
SciPy's rotation vectors, the bus attitude after the joint history by the 6th-order
Magnus integrator of `sa.integrate_joint_path` (zero momentum), the joint limits and
sigma_min of J* by NumPy's SVD of `sa.generalized_jacobian`.
"""

import dataclasses
import re

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

import spacearm as sa
from spacearm._core.groups import rpy_matrix
from spacearm.cli import main
from spacearm.models.family import RobotFamily, family_of
from spacearm.models.spatial import primitives
from spacearm.planning import plan_pose_reach

from .conftest import count_compiles

UR5 = "configs/ur5-smallsat.yaml"
Q_DEG = np.array([10.0, -60.0, 80.0, -110.0, -90.0, 30.0])
BUS_RPY_DEG = np.array([5.0, -3.0, 10.0])
MOVE = np.array([0.1, -0.15, 0.08])  # m, inertial
TURN_RPY_DEG = np.array([20.0, -15.0, 25.0])  # the tip axes turn by this, in tip axes (37 deg)


def _inertial_tip_frame(robot, q, R):
    """(position, axes) of the tip, inertial, by the forward kinematics."""
    p = np.asarray(sa.tip_position(robot, q, base_rotation=R))
    return p, np.asarray(R) @ np.asarray(primitives.tip_pose(robot, q)[0])


@pytest.fixture(scope="session")
def ur5():
    return sa.load_robot(UR5)


@pytest.fixture(scope="session")
def ur5_case(ur5):
    """Start, target and the path (with its history) of a 0.2 m, 37 deg pose move on the UR5."""
    q0 = np.radians(Q_DEG)
    R0 = np.asarray(rpy_matrix(np.radians(BUS_RPY_DEG)))
    p0, T0 = _inertial_tip_frame(ur5, q0, R0)
    p1 = p0 + MOVE
    T1 = T0 @ np.asarray(rpy_matrix(np.radians(TURN_RPY_DEG)))
    path = sa.straight_pose_path(ur5, q0, p1, T1, base_rotation=R0, steps=256, history=True)
    return dict(q0=q0, R0=R0, p0=p0, T0=T0, p1=p1, T1=T1, path=path)


def test_end_pose_is_the_target(ur5, ur5_case):
    path, p1, T1 = ur5_case["path"], ur5_case["p1"], ur5_case["T1"]
    assert path.reached and path.outcome == "reached" and float(path.progress) == 1.0
    # recomputed from the end joints and bus attitude, not read off the integrator
    p, T = _inertial_tip_frame(ur5, np.asarray(path.end_joints), np.asarray(path.end_rotation))
    assert np.linalg.norm(p - p1) < 1e-9
    assert Rotation.from_matrix(T.T @ T1).magnitude() < 1e-9
    assert float(path.position_error) < 1e-9 and float(path.rotation_error) < 1e-9
    # the bus did turn (the path had to account for it)
    assert Rotation.from_matrix(ur5_case["R0"].T @ np.asarray(path.end_rotation)).magnitude() > 5e-3


def test_bus_attitude_is_the_zero_momentum_one(ur5, ur5_case):
    """The bus attitude after the path equals the Magnus integral of eq. (5) along the joint
    history (a polyline of 257 samples: the chord error is ~1e-9 rad, 4x less per halving)."""
    path, R0 = ur5_case["path"], ur5_case["R0"]
    joints = np.asarray(path.history.joints)
    R_end, q_end = sa.integrate_joint_path(ur5, ur5_case["q0"], joints, base_rotation=R0)
    np.testing.assert_allclose(np.asarray(q_end), np.asarray(path.end_joints), atol=1e-15)
    assert Rotation.from_matrix(np.asarray(R_end).T @ np.asarray(path.end_rotation)).magnitude() < 1e-8
    # and along the way: the bus attitude of a middle sample
    R_mid, _ = sa.integrate_joint_path(ur5, ur5_case["q0"], joints[:129], base_rotation=R0)
    R_hist = np.asarray(path.history.base_rotation[128])
    assert Rotation.from_matrix(np.asarray(R_mid).T @ R_hist).magnitude() < 1e-8


def test_tip_follows_the_line_and_the_geodesic(ur5, ur5_case):
    path, p0, T0, p1, T1 = (ur5_case[k] for k in ("path", "p0", "T0", "p1", "T1"))
    history = path.history
    xi = Rotation.from_matrix(T0.T @ T1).as_rotvec()
    for k in (0, 37, 128, 201, 256):
        s = k / 256
        assert float(history.progress[k]) == s
        q, R = np.asarray(history.joints[k]), np.asarray(history.base_rotation[k])
        p, T = _inertial_tip_frame(ur5, q, R)
        assert np.linalg.norm(p - (p0 + s * (p1 - p0))) < 1e-10
        expected = T0 @ Rotation.from_rotvec(s * xi).as_matrix()
        assert Rotation.from_matrix(T.T @ expected).magnitude() < 1e-10
        np.testing.assert_allclose(np.asarray(history.tip[k]), p, atol=1e-12)
        np.testing.assert_allclose(np.asarray(history.tip_rotation[k]), T, atol=1e-12)
        p_ref, T_ref = sa.motion.pose_on_path(p0, T0, p1, T1, s)
        np.testing.assert_allclose(np.asarray(p_ref), p0 + s * (p1 - p0), atol=1e-15)
        np.testing.assert_allclose(np.asarray(T_ref), expected, atol=1e-14)


def test_spatial_pose_maps_equal_the_generic_seam_default(ur5, ur5_case):
    """The spatial one-pass pose maps equal the seam's default over the primitives
    (J_M - J_S I_S^-1 I_M and the attitude-rate map), and the tip frame the chain's."""
    family, q = family_of(ur5), ur5_case["q0"]
    J, A = (np.asarray(x) for x in family.pose_maps(ur5, q))
    J_generic, A_generic = (np.asarray(x) for x in RobotFamily.pose_maps(family, ur5, q))
    np.testing.assert_allclose(J, J_generic, atol=1e-13)
    np.testing.assert_allclose(A, A_generic, atol=1e-13)
    np.testing.assert_allclose(J, np.asarray(sa.generalized_jacobian(ur5, q)), atol=1e-13)
    p, T = _inertial_tip_frame(ur5, q, np.eye(3))
    np.testing.assert_allclose(np.asarray(family.tip_frame(ur5, q)[0]), p, atol=1e-14)
    np.testing.assert_allclose(np.asarray(family.tip_frame(ur5, q)[1]), T, atol=1e-14)


def test_a_second_target_does_not_compile_again(ur5, ur5_case):
    """The fixture's program (256 steps) runs a new start, target and bus attitude."""
    with count_compiles() as compiles:
        path = sa.straight_pose_path(
            ur5, ur5_case["q0"] + 0.01, ur5_case["p0"] - 0.5 * MOVE, ur5_case["T0"], base_rotation=np.eye(3), steps=256
        )
    assert path.reached
    assert sum(compiles.values()) == 0, dict(compiles)


def test_stops_before_a_joint_limit(ur5, ur5_case):
    """Joint 1 runs from 10 deg down to -5.2 deg: a lower limit at 0 stops the path on it."""
    full = ur5_case["path"]
    q_full = np.asarray(full.history.joints)
    assert q_full[0, 0] > 0 > q_full[-1, 0]
    lower = np.array(np.broadcast_to(np.asarray(ur5.joint_lower), (6,)))
    lower[0] = 0.0
    limited = dataclasses.replace(ur5, joint_lower=lower)
    path = sa.straight_pose_path(
        limited, ur5_case["q0"], ur5_case["p1"], ur5_case["T1"], base_rotation=ur5_case["R0"], steps=256
    )
    assert path.outcome == "joint limit" and int(path.limit_joint) == 0
    first_past = int(np.argmax(q_full[:, 0] < 0))
    s = float(path.progress)
    assert (first_past - 1) / 256 <= s < first_past / 256
    # the event located inside its step: joint 1 on its limit, the tip still on the line
    q_end = np.asarray(path.end_joints)
    assert 0.0 <= q_end[0] < 1e-10
    p = _inertial_tip_frame(ur5, q_end, np.asarray(path.end_rotation))[0]
    p0, p1 = ur5_case["p0"], ur5_case["p1"]
    assert np.linalg.norm(p - (p0 + s * (p1 - p0))) < 1e-10
    assert float(path.position_error) > 1e-3


def test_stops_before_a_singular_posture(ur5, ur5_case):
    """sigma_min(J*) falls along the way back from the target to the start (NumPy's SVD of
    J* along that path's history): a threshold between its first and smallest values stops
    the path where sigma_min reaches it, inside the step where it crosses."""
    full = ur5_case["path"]
    back = dict(q_start=np.asarray(full.end_joints), base_rotation=np.asarray(full.end_rotation), steps=256)
    way_back = sa.straight_pose_path(
        ur5, **back, target_position=ur5_case["p0"], target_rotation=ur5_case["T0"], sing_threshold=0.0, history=True
    )
    assert way_back.reached
    joints = np.asarray(way_back.history.joints)
    sigma = np.linalg.svd(np.asarray(sa.generalized_jacobian(ur5, joints)), compute_uv=False)[:, -1]
    assert abs(float(way_back.min_singular) - sigma.min()) < 1e-12
    threshold = 0.5 * (sigma[0] + sigma.min())
    below = sigma < threshold
    assert not below[0] and below.any()
    path = sa.straight_pose_path(
        ur5, **back, target_position=ur5_case["p0"], target_rotation=ur5_case["T0"], sing_threshold=threshold
    )
    assert path.outcome == "singular"
    first_below = int(np.argmax(below))
    assert (first_below - 1) / 256 <= float(path.progress) < first_below / 256
    # the event located inside its step: sigma_min(J*) at the end is the threshold
    J_end = np.asarray(sa.generalized_jacobian(ur5, np.asarray(path.end_joints)))
    sigma_end = np.linalg.svd(J_end, compute_uv=False)[-1]
    assert 0.0 <= sigma_end - threshold < 1e-10
    assert abs(float(path.min_singular) - sigma_end) < 1e-12


def test_redundant_arm_uses_minimum_norm_rates():
    """Baxter's 7-joint left arm reaches a pose; its first step follows the minimum-norm
    rates pinv(J*) [v; w] (NumPy): within O(h) = 1/64 of them, and with almost no part
    along the null space of J* (another right inverse, joint 7 held, has 77 % there).
    About 8 s: it loads the Baxter URDF and compiles the 7-joint program."""
    robot = sa.load_robot("configs/baxter-smallsat.yaml")
    q0 = np.array([0.5, -0.5, -0.6, 1.4, 0.6, 0.5, -0.4])
    p0, T0 = _inertial_tip_frame(robot, q0, np.eye(3))
    p1 = p0 + np.array([0.05, 0.04, -0.03])
    T1 = T0 @ np.asarray(rpy_matrix(np.radians([10.0, 5.0, -8.0])))
    path = sa.straight_pose_path(robot, q0, p1, T1, steps=64, history=True)
    assert path.reached
    p, T = _inertial_tip_frame(robot, np.asarray(path.end_joints), np.asarray(path.end_rotation))
    assert np.linalg.norm(p - p1) < 1e-9 and Rotation.from_matrix(T.T @ T1).magnitude() < 1e-9
    J = np.asarray(sa.generalized_jacobian(robot, q0))
    twist = np.concatenate([p1 - p0, T0 @ Rotation.from_matrix(T0.T @ T1).as_rotvec()])
    rates = np.linalg.pinv(J) @ twist
    step = 64 * (np.asarray(path.history.joints[1]) - q0)
    assert np.linalg.norm(step - rates) < 2e-2 * np.linalg.norm(rates)
    null = np.linalg.svd(J)[2][-1]
    assert abs(null @ step) < 5e-3 * np.linalg.norm(step)


def test_refused_for_planar_robots_and_arms_under_six_joints(table1, ur5_case):
    with pytest.raises(sa.ConfigError, match=r"pose targets need a spatial arm .* a planar robot's tip"):
        sa.straight_pose_path(table1, np.zeros(3), np.zeros(3), np.eye(3))
    with open(UR5) as file:
        spec = yaml.safe_load(file)
    spec["arm"]["lock_joints"] = {"wrist_3_joint": 0.0}
    five = sa.load_robot(spec)
    with pytest.raises(sa.ConfigError, match=r"at least 6 joints .* the arm has 5"):
        sa.straight_pose_path(five, np.zeros(5), ur5_case["p1"], ur5_case["T1"])
    with pytest.raises(sa.ConfigError, match="the arm has 5"):
        plan_pose_reach(five, np.zeros(5), ur5_case["p1"], ur5_case["T1"])


def test_plan_refuses_a_point_outside_the_shell_before_integrating(ur5):
    with count_compiles() as compiles, pytest.raises(sa.ConfigError, match="beyond the Maximum Reachable radius"):
        plan_pose_reach(ur5, np.radians(Q_DEG), np.array([5.0, 0.0, 0.0]), np.eye(3))
    assert sum(compiles.values()) == 0, dict(compiles)


@pytest.mark.parametrize(
    "robot_file, start, message",
    [
        ("configs/umetani1990.yaml", "0,30,60", "--to-rpy: pose targets need a spatial arm"),
        ("configs/arm3dof-100kg.yaml", "10,40,-70", "--to-rpy: pose targets need at least 6 joints"),
    ],
)
def test_reach_command_refuses_pose_targets_it_cannot_aim(robot_file, start, message, tmp_path, capsys):
    args = ["reach", robot_file, f"--from={start}", "--to=0.1,0.2,0.3", "--to-rpy=0,0,0", "--out", str(tmp_path)]
    assert main(args) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "reach.npz").exists()


def test_reach_command_reports_a_path_that_stops(tmp_path, capsys):
    """Joint 3 of the UR5 reaches its limit (pi) on the way: exit 2, where and why, nothing written."""
    args = ["reach", UR5, "--from=10,-60,80,-110,-90,30", "--attitude-rpy=5,-3,10", "--to=1.2,0.4,1.1"]
    assert main(args + ["--to-rpy=30,20,-40", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert re.search(r"the straight pose path stops at s = 0\.\d+ of the way: joint 3 reaches its limit", err)
    assert not (tmp_path / "out").exists()


def test_reach_command_reaches_a_pose_end_to_end(ur5_case, tmp_path, capsys):
    """``spacearm reach`` on the UR5 file, to a pose: summary, reach.npz and reach.png."""
    p1 = ur5_case["p1"]
    rpy = Rotation.from_matrix(ur5_case["T1"]).as_euler("xyz", degrees=True)  # URDF rpy = extrinsic xyz
    args = [
        "reach",
        UR5,
        "--from=" + ",".join(map(str, Q_DEG)),
        "--attitude-rpy=" + ",".join(map(str, BUS_RPY_DEG)),
        "--to=" + ",".join(f"{v:.15f}" for v in p1),
        "--to-rpy=" + ",".join(f"{v:.15f}" for v in rpy),
        "--out",
        str(tmp_path),
    ]
    code = main(args)
    captured = capsys.readouterr()
    assert code == 0, captured.err
    out = captured.out
    assert "mode           pose" in out
    saved = np.load(tmp_path / "reach.npz")
    k = saved["joints"].shape[0]
    assert saved["joints"].shape == (k, 6) and saved["tip"].shape == (k, 3)
    assert saved["base_rotation"].shape == (k, 3, 3) and saved["tip_rotation"].shape == (k, 3, 3)
    np.testing.assert_allclose(saved["joints"][0], np.radians(Q_DEG), atol=1e-15)
    assert np.linalg.norm(saved["tip"][-1] - p1) < 1e-9
    assert Rotation.from_matrix(saved["tip_rotation"][-1].T @ ur5_case["T1"]).magnitude() < 1e-9
    # the printed bus rotation is the file's, start to end (SciPy's angle), and the same as the library's
    printed = float(re.search(r"bus rotation\s+([0-9.]+) deg", out).group(1))
    R = saved["base_rotation"]
    turn = np.degrees(Rotation.from_matrix(R[0].T @ R[-1]).magnitude())
    assert abs(printed - turn) < 1e-6
    library = np.asarray(ur5_case["path"].end_rotation)
    assert Rotation.from_matrix(R[-1].T @ library).magnitude() < 1e-9
    assert (tmp_path / "reach.png").stat().st_size > 0
