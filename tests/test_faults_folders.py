"""Result folders change as a whole or not at all; one writer at a time.

A run that dies at any moment (while computing chunks, while drawing figures, right
before the swap, by SIGKILL) leaves the previous results exactly as they were, and the
next run resumes to the same table byte for byte. A second writer is refused with exit
status 2 naming the first one's PID.
"""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from spacearm.cli import main
from spacearm.io import folders
from spacearm.studies import load_sweep, run_sweep, runner

ROBOT = str(Path("configs/umetani1990.yaml").resolve())
SRC = str(Path("src").resolve())


def config(num=4, **changes):
    data = {
        "name": "faults",
        "robot": ROBOT,
        "axes": {
            "b0_over_B0": {"field": "base.attach", "relative": True, "range": {"start": 0.0, "stop": 2.0, "num": num}}
        },
        "metrics": ["radii"],
        "chunk_size": 2,
    }
    data.update(changes)
    return data


def snapshot(folder: Path) -> dict[str, bytes]:
    """Every visible file of a folder, by name (hidden partial chunks left out)."""
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file() and not p.name.startswith(".")}


def consistent(folder: Path) -> int:
    """The folder's table, grids and manifest come from one run; returns its design count."""
    manifest = json.loads((folder / "manifest.json").read_text())
    rows = (folder / "table.csv").read_text().strip().splitlines()[1:]
    with np.load(folder / "grids.npz") as grids:
        cells = grids["metric/R_max_m"].size
    assert len(rows) == cells == manifest["n_designs"]
    return manifest["n_designs"]


@pytest.fixture
def first_run(tmp_path):
    out = tmp_path / "res"
    run_sweep(load_sweep(config(num=4)), out, progress=False)
    assert consistent(out) == 4
    return out, snapshot(out)


class Boom(Exception):
    pass


def _raise(*args):
    raise Boom("injected")


@pytest.mark.parametrize("moment", ["chunks", "figures", "before_swap"])
def test_a_rerun_that_dies_leaves_the_old_folder_whole(first_run, monkeypatch, moment):
    """The issue's repro (a rerun with other settings dies after writing its table) at three moments."""
    out, before = first_run
    spec = load_sweep(config(num=6))
    kwargs = {}
    if moment == "chunks":
        kwargs["stop_after_chunks"] = 1
    elif moment == "figures":
        kwargs["outputs"] = (_raise,)
    else:
        monkeypatch.setattr(runner, "_BEFORE_SWAP", _raise)
    with pytest.raises((Boom, KeyboardInterrupt)):
        run_sweep(spec, out, progress=False, **kwargs)
    assert snapshot(out) == before and consistent(out) == 4
    assert not list(out.parent.glob(".res.staging-*"))  # the staging folder is gone
    monkeypatch.setattr(runner, "_BEFORE_SWAP", None)
    result = run_sweep(spec, out, progress=False)
    assert consistent(out) == 6
    fresh = run_sweep(spec, out.parent / "fresh", progress=False)
    assert (out / "table.csv").read_bytes() == (fresh.out_dir / "table.csv").read_bytes()
    assert result.manifest["resumed_chunks"] == (1 if moment == "chunks" else 3)


_KILLED_RUN = """
import os, signal, sys
import jax
jax.config.update("jax_enable_x64", True)
from spacearm.studies import load_sweep, run_sweep, runner
runner._BEFORE_SWAP = lambda staging: os.kill(os.getpid(), signal.SIGKILL)
run_sweep(load_sweep(sys.argv[1]), sys.argv[2], progress=False)
"""


def test_sigkill_right_before_the_swap_keeps_the_old_folder_and_resumes(first_run, tmp_path):
    """SIGKILL after the new table, grids and manifest are written (in staging): the old folder
    is whole, the lock is free again, and the rerun resumes every chunk byte for byte."""
    out, before = first_run
    sweep = tmp_path / "six.yaml"
    sweep.write_text(yaml.safe_dump(config(num=6)))
    env = dict(os.environ, PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""))
    killed = subprocess.run(
        [sys.executable, "-c", _KILLED_RUN, str(sweep), str(out)], env=env, capture_output=True, text=True, timeout=120
    )
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    assert list(out.parent.glob(".res.staging-*"))  # what the killed run left
    assert snapshot(out) == before and consistent(out) == 4
    result = run_sweep(load_sweep(sweep), out, progress=False)
    assert result.manifest["resumed_chunks"] == 3 and consistent(out) == 6
    assert not list(out.parent.glob(".res.staging-*"))  # cleaned by the next writer
    fresh = run_sweep(load_sweep(sweep), tmp_path / "fresh", progress=False)
    assert (out / "table.csv").read_bytes() == (fresh.out_dir / "table.csv").read_bytes()


_HOLDER = """
import sys, time
from spacearm.io.folders import lock_folder
with lock_folder(sys.argv[1]):
    print("locked", flush=True)
    time.sleep(60)
"""


def test_a_second_writer_is_refused_naming_the_holder(first_run, tmp_path, capsys):
    out, before = first_run
    sweep = tmp_path / "six.yaml"
    sweep.write_text(yaml.safe_dump(config(num=6)))
    env = dict(os.environ, PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""))
    holder = subprocess.Popen([sys.executable, "-c", _HOLDER, str(out)], env=env, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        code = main(["sweep", str(sweep), "--out", str(out), "--quiet"])
        err = capsys.readouterr().err
        assert code == 2, err
        assert f"PID {holder.pid}" in err and "another spacearm run" in err
        assert err.count("\n") == 2  # the sweep's summary line, then the one error line
    finally:
        holder.kill()
        holder.wait()
    assert snapshot(out) == before
    # The kernel dropped the killed holder's lock: the next writer goes ahead.
    assert main(["sweep", str(sweep), "--out", str(out), "--quiet"]) == 0
    assert consistent(out) == 6


def test_lock_is_exclusive_between_open_descriptions_and_released_on_exit(tmp_path):
    with (
        folders.lock_folder(tmp_path / "x"),
        pytest.raises(folders.FolderLocked, match=f"PID {os.getpid()}"),
        folders.lock_folder(tmp_path / "x"),
    ):
        pass
    with folders.lock_folder(tmp_path / "x"):  # released
        pass


def test_swap_without_renameat2_recovers_a_folder_moved_aside(tmp_path, monkeypatch):
    """The two-rename fallback: a writer killed between the renames leaves the old folder
    aside; the next writer puts it back before anything else."""
    out = tmp_path / "r"
    out.mkdir()
    (out / "a.txt").write_text("old")
    monkeypatch.setattr(folders, "_exchange", lambda a, b: False)
    with folders.lock_folder(out):
        staging = folders.stage_folder(out, keep=lambda name: True)
        (staging / "b.txt").write_text("new")
        folders.swap_in(staging, out)
    assert sorted(p.name for p in out.iterdir()) == ["a.txt", "b.txt"]
    os.rename(out, tmp_path / ".r.old-1")  # as if killed between the two renames
    with folders.lock_folder(out):
        assert (out / "a.txt").read_text() == "old"


# The command line as from a terminal: a runner started with a shell's & ignores SIGINT,
# and its children inherit that, so the child takes Python's own handler back first.
_INTERRUPTIBLE = (
    "import runpy, signal; signal.signal(signal.SIGINT, signal.default_int_handler); "
    "runpy.run_module('spacearm.cli', run_name='__main__', alter_sys=True)"
)


def test_sigint_during_a_sweep_is_one_line_and_resumable(tmp_path):
    """Ctrl-C while the sweep computes: exit 130, no traceback, the chunks kept."""
    sweep = tmp_path / "long.yaml"
    sweep.write_text(yaml.safe_dump(config(num=64, chunk_size=1, metrics=["S_G"])))
    env = dict(
        os.environ,
        PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""),
        XLA_FLAGS="--xla_force_host_platform_device_count=1",
    )
    process = subprocess.Popen(
        [sys.executable, "-c", _INTERRUPTIBLE, "sweep", str(sweep), "--out", str(tmp_path / "o")],
        env=env,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120
    while not list((tmp_path / "o").glob(".partial-*/chunk_*.npz")) and time.monotonic() < deadline:
        time.sleep(0.1)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    if process.returncode == 0:
        pytest.skip("the sweep finished before the interrupt")
    assert process.returncode == 130, err
    assert "Traceback" not in err and "interrupted" in err
    assert not (tmp_path / "o" / "table.csv").exists()


def test_a_folder_reached_through_a_symlink_is_swapped_where_it_lives(tmp_path):
    real = tmp_path / "real"
    run_sweep(load_sweep(config(num=4)), real, progress=False)
    (tmp_path / "link").symlink_to(real, target_is_directory=True)
    run_sweep(load_sweep(config(num=6)), tmp_path / "link", progress=False)
    assert (tmp_path / "link").is_symlink() and consistent(real) == 6


def test_the_current_folder_is_never_swapped(tmp_path, monkeypatch, capsys):
    """The results replace their folder as a whole: --out . (or a folder above it) is refused."""
    sweep = tmp_path / "s.yaml"
    sweep.write_text(yaml.safe_dump(config(num=2)))
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    for out in (".", str(tmp_path)):
        assert main(["sweep", str(sweep), "--out", out, "--quiet"]) == 2
        assert "need a folder of their own" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.yaml", "work"]
