"""``spacearm optimize`` and ``spacearm reach`` change their result folders as a whole or
not at all, one writer at a time, and refuse a non-finite result.

The problem is sweeps/pareto-attachment.yaml with tiny budgets (a hybrid of 8 designs over
2 generations, a coarse w-bar rule, no baselines): one run takes a few seconds, compile
included, which is what the subprocess tests below spend.
"""

import dataclasses
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

import spacearm.planning
from spacearm.cli import main
from spacearm.design import run as design_run

ROOT = Path(__file__).resolve().parents[1]
SRC = str(ROOT / "src")
ROBOT = str(ROOT / "configs" / "umetani1990.yaml")
ENV = dict(
    os.environ,
    PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""),
    XLA_FLAGS="--xla_force_host_platform_device_count=1",
)


def problem(population=8, generations=2):
    config = yaml.safe_load((ROOT / "sweeps" / "pareto-attachment.yaml").read_text())
    config.pop("baselines")
    config.update(
        wbar={"rule": "product", "phi1_panels": 4, "phi2_panels": 2, "order": 4},
        hybrid={"population": population, "generations": generations},
    )
    return config


def snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def one_run(folder: Path) -> int:
    """The folder's files are exactly those its manifest lists (plus the user's notes.txt),
    and pareto.csv agrees with summary.json; returns the hybrid's evaluation count."""
    manifest = json.loads((folder / "manifest.json").read_text())
    summary = json.loads((folder / "summary.json").read_text())
    assert sorted(manifest["files"]) == sorted(p.name for p in folder.iterdir() if p.name != "notes.txt")
    assert summary["files"] == manifest["files"] and summary["config"] == manifest["config"]
    rows = (folder / "pareto.csv").read_text().strip().splitlines()
    assert rows[0] == "b0,l1_over_L,wbar,S_G" and len(rows) > 1
    return summary["methods"]["hybrid"]["evaluations"]


@pytest.fixture(scope="module")
def first(tmp_path_factory):
    """One finished run (population 8) with a file of the user's beside the results."""
    base = tmp_path_factory.mktemp("optimize")
    path = base / "small.yaml"
    path.write_text(yaml.safe_dump(problem()))
    out = base / "res"
    assert main(["optimize", str(path), "--out", str(out), "--no-baselines"]) == 0
    (out / "notes.txt").write_text("mine")
    return out


@pytest.fixture
def rerun(first, tmp_path):
    """A copy of the first run's folder and a problem file with other settings (population 12)."""
    out = tmp_path / "res"
    shutil.copytree(first, out)
    path = tmp_path / "other.yaml"
    path.write_text(yaml.safe_dump(problem(population=12)))
    return out, path, snapshot(out)


# The command line as from a terminal: a runner started with a shell's & ignores SIGINT,
# and its children inherit that, so each child takes Python's own handler back first.
_INTERRUPTIBLE = (
    "import runpy, signal; signal.signal(signal.SIGINT, signal.default_int_handler); "
    "runpy.run_module('spacearm.cli', run_name='__main__', alter_sys=True)"
)


_HOOKED = """
import signal, sys
signal.signal(signal.SIGINT, signal.default_int_handler)
from spacearm.cli import main
from spacearm.design import run
run._BEFORE_SWAP = lambda staging: signal.raise_signal(getattr(signal, sys.argv[1]))
sys.exit(main(sys.argv[2:]))
"""


@pytest.mark.parametrize("sig", ["SIGKILL", "SIGINT"])
def test_optimize_killed_or_interrupted_right_before_the_swap_keeps_the_old_folder(rerun, sig):
    """The worst moment: every new file written (in staging). SIGKILL leaves the staging folder,
    Ctrl-C removes it and exits 130 in one line; the old folder is byte-identical either way."""
    out, path, before = rerun
    args = ["optimize", str(path), "--out", str(out), "--no-baselines"]
    done = subprocess.run(
        [sys.executable, "-c", _HOOKED, sig, *args],
        env=ENV,
        capture_output=True,
        text=True,
        timeout=300,
    )
    if sig == "SIGKILL":
        assert done.returncode == -signal.SIGKILL, done.stderr
        assert list(out.parent.glob(".res.staging-*"))  # what the killed run left
    else:
        assert done.returncode == 130, done.stderr
        assert (
            "Traceback" not in done.stderr and done.stderr.strip().splitlines()[-1] == "spacearm optimize: interrupted"
        )
        assert not list(out.parent.glob(".res.staging-*"))
    assert snapshot(out) == before and one_run(out) > 0


def test_optimize_interrupted_during_the_search_keeps_the_old_folder(rerun):
    """Ctrl-C from outside once the search has started: exit 130, one line, old folder whole."""
    out, path, before = rerun
    process = subprocess.Popen(
        [sys.executable, "-u", "-c", _INTERRUPTIBLE, "optimize", str(path), "--out", str(out), "--no-baselines"],
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert process.stdout.readline().startswith("optimize ")  # the search starts (compiles) now
    time.sleep(0.3)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=120)
    if process.returncode == 0:  # finished first: then the new run is whole
        assert one_run(out) > 0 and snapshot(out) != before
        return
    assert process.returncode == 130, err
    assert "Traceback" not in err and err.strip().splitlines()[-1] == "spacearm optimize: interrupted"
    assert snapshot(out) == before and not list(out.parent.glob(".res.staging-*"))


_HOLDER = """
import sys, time
from spacearm.io.folders import lock_folder
with lock_folder(sys.argv[1]):
    print("locked", flush=True)
    time.sleep(60)
"""


def test_a_second_optimize_writer_is_refused_then_the_rerun_replaces_the_folder_whole(rerun, capsys):
    out, path, before = rerun
    holder = subprocess.Popen([sys.executable, "-c", _HOLDER, str(out)], env=ENV, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        started = time.perf_counter()
        code = main(["optimize", str(path), "--out", str(out), "--no-baselines"])
        err = capsys.readouterr().err
        assert code == 2, err
        assert time.perf_counter() - started < 5  # refused before the search
        assert f"PID {holder.pid}" in err and "another spacearm run" in err and err.count("\n") == 1
    finally:
        holder.kill()
        holder.wait()
    assert snapshot(out) == before
    assert main(["optimize", str(path), "--out", str(out), "--no-baselines"]) == 0
    assert one_run(out) > 0 and (out / "notes.txt").read_text() == "mine"  # the user's file kept
    assert (out / "pareto.csv").read_bytes() != before["pareto.csv"]


@pytest.mark.parametrize("bad", [np.inf, np.nan])
def test_optimize_refuses_a_non_finite_objective(rerun, monkeypatch, capsys, bad):
    """An objective that comes out non-finite for one evaluated design (which the front would
    leave out silently): exit 1 naming the objective and the design; nothing written."""
    out, path, before = rerun
    real = design_run.hybrid_search

    def poisoned(*args, **kwargs):
        result = real(*args, **kwargs)
        result.objectives = np.array(result.objectives, dtype=float)
        result.objectives[3, 1] = bad
        poisoned.design = result.designs[3]
        return result

    monkeypatch.setattr(design_run, "hybrid_search", poisoned)
    assert main(["optimize", str(path), "--out", str(out), "--no-baselines"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    b0, split = poisoned.design
    assert len(err) == 1 and f"objective 'S_G' is {bad} for the design b0 = {b0:g}, l1_over_L = {split:g}" in err[0]
    assert "nothing was written" in err[0]
    assert snapshot(out) == before and not list(out.parent.glob(".res.staging-*"))


# reach ---------------------------------------------------------------------------------

REACH = ["reach", ROBOT, "--from", "0,-60,120", "--to", "2,1"]


def test_reach_replaces_its_folder_whole_and_refuses_a_second_writer(tmp_path, capsys):
    out = tmp_path / "r"
    out.mkdir()
    (out / "reach.gif").write_text("an earlier run's animation")
    (out / "notes.txt").write_text("mine")
    # A run without --animate: the old reach.gif goes with the old run, the user's file stays.
    assert main([*REACH, "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "reach.npz", "reach.png"]
    before = snapshot(out)
    capsys.readouterr()
    holder = subprocess.Popen([sys.executable, "-c", _HOLDER, str(out)], env=ENV, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        assert main([*REACH, "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert f"PID {holder.pid}" in err and err.count("\n") == 1
    finally:
        holder.kill()
        holder.wait()
    assert snapshot(out) == before


def test_reach_refuses_a_non_finite_plan(tmp_path, monkeypatch, capsys):
    real = spacearm.planning.plan_reach

    def poisoned(*args, **kwargs):
        plan = real(*args, **kwargs)
        tips = np.array(plan.tips, dtype=float)
        tips[5, 1] = np.nan
        return dataclasses.replace(plan, tips=tips)

    monkeypatch.setattr(spacearm.planning, "plan_reach", poisoned)
    out = tmp_path / "r"
    assert main([*REACH, "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "the plan's tip is nan at index (5, 1)" in err[0] and "nothing was written" in err[0]
    assert not out.exists()
