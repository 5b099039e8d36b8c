"""`spacearm reach` and `sa.straight_tip_path` for spatial robot files."""

import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import spacearm as sa
from spacearm.cli import main

from .conftest import count_compiles

ARM = "configs/arm3dof-100kg.yaml"
Q_DEG = np.array([10.0, 40.0, -70.0])


@pytest.fixture(scope="module")
def arm():
    return sa.load_robot(ARM)


def test_straight_tip_path_dispatches_spatial_robots(arm):
    q = np.radians(Q_DEG)
    path = sa.straight_tip_path(arm, q, np.array([0.0, 0.0, 1.0]), max_length=0.05)
    assert isinstance(path, sa.motion.SpatialStraightPath)
    assert int(path.reason) == sa.motion.REASON_MAX_LENGTH
    start = np.asarray(sa.tip_position(arm, q))
    np.testing.assert_allclose(np.asarray(path.end_tip), start + [0.0, 0.0, 0.05], atol=1e-9)
    # The lane integrator is shared by every family: lanes are honoured, same end.
    laned = sa.straight_tip_path(arm, q, np.array([0.0, 0.0, 1.0]), max_length=0.05, lanes=8)
    np.testing.assert_allclose(np.asarray(laned.end_tip), np.asarray(path.end_tip), atol=1e-12)


def test_reach_command_plans_a_spatial_target(arm, tmp_path, capsys):
    q = np.radians(Q_DEG)
    target = np.asarray(sa.tip_position(arm, q)) + np.array([0.0, 0.02, 0.03])
    to = ",".join(f"{v:.12f}" for v in target)
    status = main(["reach", ARM, "--from", ",".join(map(str, Q_DEG)), f"--to={to}", "--out", str(tmp_path)])
    assert status == 0
    out = capsys.readouterr().out
    assert "mode           straight" in out
    saved = np.load(tmp_path / "reach.npz")
    # the whole history: joints (k, n), base_rotation (k, 3, 3), tip (k, 3)
    k = saved["joints"].shape[0]
    assert k > 2 and saved["joints"].shape == (k, 3)
    assert saved["base_rotation"].shape == (k, 3, 3) and saved["tip"].shape == (k, 3)
    np.testing.assert_allclose(saved["joints"][0], q, atol=1e-15)
    np.testing.assert_allclose(saved["base_rotation"][0], np.eye(3), atol=1e-15)
    assert np.linalg.norm(saved["tip"][-1] - target) < 1e-9
    # the summary's bus rotation is the file's, start to end (scipy's rotation angle)
    printed = float(re.search(r"bus rotation\s+([0-9.]+) deg", out).group(1))
    R = saved["base_rotation"]
    turn = np.degrees(Rotation.from_matrix(R[0].T @ R[-1]).magnitude())
    assert turn > 1e-3 and abs(printed - turn) < 1e-6
    assert (tmp_path / "reach.png").stat().st_size > 0


def test_reach_command_refuses_a_target_beyond_the_reachable_radius(tmp_path, capsys):
    """Refused before planning (no program compiled; the UR5 answered after 2 minutes before)."""
    args = [
        "reach",
        "configs/ur5-smallsat.yaml",
        "--from",
        "0,-60,90,-30,90,0",
        "--to",
        "5,0,0",
        "--out",
        str(tmp_path),
    ]
    with count_compiles() as compiles:
        assert main(args) == 2
    assert sum(compiles.values()) == 0, dict(compiles)
    err = capsys.readouterr().err
    assert "5 m from the system centroid, beyond the Maximum Reachable radius 2.2269 m" in err
    assert not (tmp_path / "reach.npz").exists()


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--to=0.1,0.2"], "--to: expected 3"),
        (["--to=0.1,0.2,0.3", "--from", "1,2"], "--from: expected 3"),
        (["--to=0.1,0.2,0.3", "--animate"], "--animate"),
    ],
)
def test_reach_command_refuses_bad_spatial_input(extra, message, tmp_path, capsys):
    args = ["reach", ARM, "--from", "10,40,-70", "--out", str(tmp_path)]
    # a later --from replaces the first
    assert main(args + extra) == 2
    assert message in capsys.readouterr().err
