"""`spacearm reach` and `sa.straight_tip_path` for spatial robot files."""

import numpy as np
import pytest

import spacearm as sa
from spacearm.cli import main

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
    with pytest.raises(TypeError, match="planar robots only"):
        sa.straight_tip_path(arm, q, np.array([0.0, 0.0, 1.0]), lanes=8)


def test_reach_command_plans_a_spatial_target(arm, tmp_path, capsys):
    q = np.radians(Q_DEG)
    target = np.asarray(sa.tip_position(arm, q)) + np.array([0.0, 0.02, 0.03])
    to = ",".join(f"{v:.12f}" for v in target)
    status = main(["reach", ARM, "--from", ",".join(map(str, Q_DEG)), f"--to={to}", "--out", str(tmp_path)])
    assert status == 0
    out = capsys.readouterr().out
    assert "mode           straight" in out
    saved = np.load(tmp_path / "reach.npz")
    assert np.linalg.norm(saved["end_tip_m"] - target) < 1e-9
    assert (tmp_path / "reach.png").stat().st_size > 0


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
