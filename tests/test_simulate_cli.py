"""``spacearm simulate``: the files it writes, their agreement with `spacearm.simulate`, and its refusals.

The planar runs share one program (both events armed, 20 intervals): the bus-rate bound is
traced, so a run that stops and one that does not compile once.
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import numpy as np
import pytest

import spacearm as sa
from spacearm.cli import main
from spacearm.figures.views import view_extra_available
from spacearm.motion.simulation import STOP_BUS_RATE, STOP_NONE

ROOT = Path(__file__).resolve().parents[1]
PLANAR = str(ROOT / "configs" / "umetani1990.yaml")
DT = 0.01
SAMPLES = 20


@pytest.fixture(scope="module")
def torques_file(tmp_path_factory):
    """20 intervals of torques for the paper's two joints, with a header row."""
    path = tmp_path_factory.mktemp("torques") / "torques.csv"
    values = np.random.default_rng(5).normal(size=(SAMPLES, 2)) * 40.0
    path.write_text("tau1,tau2\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in values))
    return path, values


def _run(torques: Path, out: Path, *more: str) -> int:
    return main(
        [
            "simulate",
            PLANAR,
            "--torques",
            str(torques),
            "--dt",
            str(DT),
            "--posture",
            "10,-60,120",
            "--rates",
            "5,-3",
            "--momentum",
            "4,-2,6",
            "--stop-at-limits",
            *more,
            "--out",
            str(out),
        ]
    )


def test_writes_the_run(torques_file, tmp_path, capsys):
    """npz, csv, png, the replay and the manifest; the trajectory is sa.simulate's for the same inputs."""
    path, values = torques_file
    out = tmp_path / "run"
    assert _run(path, out, "--max-bus-rate", "1000") == 0
    printed = capsys.readouterr().out
    assert "intervals      20 of 0.01 s" in printed and "stopped" not in printed
    expected = {"simulation.npz", "simulation.csv", "simulation.png", "manifest.json"}
    if view_extra_available():
        expected.add("simulation.html")
    assert {p.name for p in out.iterdir()} == expected

    robot = sa.umetani1990()
    start = np.radians([10.0, -60.0, 120.0])
    phi, qd, _ = sa.simulate(
        robot,
        start,
        np.radians([5.0, -3.0]),
        values,
        DT,
        momentum=np.array([4.0, -2.0, 6.0]),
        stop_at_limits=True,
        max_bus_rate=np.radians(1000.0),
    )
    with np.load(out / "simulation.npz") as archive:
        np.testing.assert_array_equal(archive["phi"], phi)
        np.testing.assert_array_equal(archive["rates"], qd)
        np.testing.assert_array_equal(archive["torques"], values)
        np.testing.assert_allclose(archive["time"], DT * np.arange(SAMPLES + 1), rtol=1e-15)
        assert int(archive["stop_reason"]) == STOP_NONE and int(archive["stop_step"]) == SAMPLES
        base = sa.base_velocity(robot, phi, qd, momentum=np.array([4.0, -2.0, 6.0]))
        np.testing.assert_allclose(archive["bus_rate"][:, 0], base[:, 2], rtol=0, atol=1e-15)
        np.testing.assert_allclose(archive["tip"], sa.tip_position(robot, phi), rtol=0, atol=1e-15)

    with open(out / "simulation.csv", newline="") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == ["time_s", "phi0_rad", "q1_rad", "q2_rad", "qd1_rad_s", "qd2_rad_s", "wz_rad_s"]
    table = np.array(rows[1:], dtype=float)
    assert table.shape == (SAMPLES + 1, 7)
    np.testing.assert_array_equal(table[:, 1:4], phi)  # 17 digits: exact

    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["kind"] == "simulate" and manifest["float64"] is True
    assert manifest["config"]["dt_s"] == DT and manifest["config"]["torques"]["intervals"] == SAMPLES
    assert len(manifest["config"]["torques"]["sha256"]) == 64
    assert set(manifest["files"]) == expected


def test_stops_at_the_bus_rate_bound(torques_file, tmp_path, capsys):
    """A bound the run crosses: it stops at the first sample above it, says so, and the later
    rows hold that state."""
    path, _ = torques_file
    free, out = tmp_path / "free", tmp_path / "run"
    assert _run(path, free, "--max-bus-rate", "1000", "--no-html") == 0
    with np.load(free / "simulation.npz") as archive:
        speed = np.degrees(np.abs(archive["bus_rate"][:, 0]))
        phi = archive["phi"]
    bound = 0.5 * (speed[0] + speed.max())
    capsys.readouterr()
    assert _run(path, out, "--max-bus-rate", repr(float(bound)), "--no-html") == 0
    assert "stopped        at sample" in capsys.readouterr().out
    with np.load(out / "simulation.npz") as archive:
        step = int(archive["stop_step"])
        assert int(archive["stop_reason"]) == STOP_BUS_RATE and step == np.argmax(speed > bound)
        np.testing.assert_array_equal(archive["phi"][: step + 1], phi[: step + 1])
        np.testing.assert_array_equal(archive["phi"][step:], np.broadcast_to(phi[step], (SAMPLES + 1 - step, 3)))
    assert not (out / "simulation.html").exists()


@pytest.mark.parametrize(
    "text, dt, field",
    [
        ("1,2,3\n", "0.01", "line 1 has 3 columns"),
        ("tau1,tau2\n1,2\n3,nan\n", "0.01", "line 3, joint 2"),
        ("1,2\n\n4,x\n", "0.01", "line 3, joint 2"),
        ("tau1,tau2\n", "0.01", "no rows"),
        ("1,2\n", "0", "--dt"),
        ("1,2\n", "-0.01", "--dt"),
        ("1,2\n", "nan", "--dt"),
    ],
)
def test_refuses_bad_input(tmp_path, capsys, text, dt, field):
    """One line naming the file (or option) and the field, exit 2, nothing written."""
    path = tmp_path / "bad.csv"
    path.write_text(text)
    out = tmp_path / "out"
    code = main(["simulate", PLANAR, "--torques", str(path), f"--dt={dt}", "--out", str(out)])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and field in err
    if field != "--dt":
        assert str(path) in err
    assert not out.exists()


def test_a_non_finite_run_writes_nothing(torques_file, tmp_path, capsys):
    """Torques that blow the state up: exit 1 naming the quantity; the old folder stays as it was."""
    path = tmp_path / "huge.csv"
    path.write_text("".join("1e300,-1e300\n" for _ in range(SAMPLES)))
    out = tmp_path / "run"
    good, _ = torques_file
    assert _run(good, out, "--max-bus-rate", "1000", "--no-html") == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    capsys.readouterr()
    assert _run(path, out, "--max-bus-rate", "1000", "--no-html") == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "non-finite" in err and "nothing was written" in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_without_plotly_the_replay_is_left_out(torques_file, tmp_path, capsys, monkeypatch):
    """Without the 'view' extra the run still writes its other files and names the extra."""
    for module in [m for m in sys.modules if m == "plotly" or m.startswith("plotly.")]:
        monkeypatch.delitem(sys.modules, module)
    monkeypatch.setitem(sys.modules, "plotly", None)
    path, _ = torques_file
    out = tmp_path / "run"
    assert _run(path, out, "--max-bus-rate", "1000") == 0
    assert "'view' extra" in capsys.readouterr().out
    assert {p.name for p in out.iterdir()} == {"simulation.npz", "simulation.csv", "simulation.png", "manifest.json"}
