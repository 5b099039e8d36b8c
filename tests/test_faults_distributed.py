"""Distributed guards: two real processes on 127.0.0.1 (jax.distributed over gloo).

A process run with other settings than process 0 is refused before anything is computed,
naming the differing keys; a process whose peer never starts gives up after
``--peer-timeout``; a peer killed mid-sweep ends the other with exit 1 and one line, within
the timeout. The timeouts are short (20 s, 3 s for the lone process) so the suite stays fast.
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from tests.test_distributed import _env, _free_port, _gloo_available

pytestmark = pytest.mark.skipif(
    not _gloo_available(), reason="the installed jaxlib has no gloo CPU collectives (jax.distributed on CPU)"
)

ROBOT = str(Path("configs/umetani1990.yaml").resolve())
TIMEOUT_S = 120


def _sweep(tmp_path, num=5, chunk_size=4, metrics=("radii",)) -> Path:
    config = {
        "name": "guards",
        "robot": ROBOT,
        "axes": {"x": {"field": "base.attach", "relative": True, "range": {"start": 0.0, "stop": 2.0, "num": num}}},
        "metrics": list(metrics),
        "chunk_size": chunk_size,
    }
    path = tmp_path / "sweep.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


def _start(sweep, out, coordinator, rank, *extra, timeout="20"):
    command = [
        sys.executable,
        "-m",
        "spacearm.cli",
        "sweep",
        str(sweep),
        "--quiet",
        "--out",
        str(out),
        "--peer-timeout",
        timeout,
        *extra,
    ]
    return subprocess.Popen(
        command,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=_env(1, SPACEARM_COORDINATOR=coordinator, SPACEARM_NUM_PROCESSES="2", SPACEARM_PROCESS_ID=str(rank)),
    )


def _finish(processes):
    try:
        return [p.communicate(timeout=TIMEOUT_S) for p in processes]
    finally:
        for p in processes:
            if p.poll() is None:
                p.kill()


def _error_lines(err: str) -> list[str]:
    return [line for line in err.splitlines() if "error:" in line]


def test_a_process_with_other_settings_is_refused_naming_the_keys(tmp_path):
    """The issue's case: process 1 given --set axes.x.range.start=-0.2 (here 0.2, a valid value). Before: both exit 0 and
    7 of 25 rows hold process 1's results under process 0's x values. A mismatch is bad input: exit 2 on both."""
    sweep = _sweep(tmp_path)
    coordinator = f"127.0.0.1:{_free_port()}"
    processes = [
        _start(sweep, tmp_path / "out", coordinator, 0),
        _start(sweep, tmp_path / "out", coordinator, 1, "--set", "axes.x.range.start=0.2"),
    ]
    outputs = _finish(processes)
    for rank, (p, (_, err)) in enumerate(zip(processes, outputs, strict=False)):
        assert p.returncode == 2, f"process {rank}: {err}"
        assert "Traceback" not in err and len(_error_lines(err)) == 1, err
        assert "config.axes.x.values" in err and "refusing to run" in err, err
    assert not (tmp_path / "out" / "table.csv").exists()


def test_a_lone_process_gives_up_after_the_peer_timeout(tmp_path):
    """Before: a process 0 whose peer never starts waits 306 s in silence."""
    sweep = _sweep(tmp_path)
    start = time.monotonic()
    process = _start(sweep, tmp_path / "out", f"127.0.0.1:{_free_port()}", 0, timeout="3")
    ((_, err),) = _finish([process])
    elapsed = time.monotonic() - start
    assert process.returncode == 1, err
    assert "did not all join" in err and "--peer-timeout" in err, err
    assert "Traceback" not in err and len(_error_lines(err)) == 1, err
    assert elapsed < 40, elapsed  # 3 s of waiting, plus start-up on a loaded machine


def test_a_killed_peer_ends_the_other_process_with_one_line(tmp_path):
    """Before: a Gloo traceback, then SIGABRT with a C++ stack after ~90 s."""
    sweep = _sweep(tmp_path, num=60, chunk_size=2, metrics=("S_G",))
    out = tmp_path / "out"
    coordinator = f"127.0.0.1:{_free_port()}"
    processes = [_start(sweep, out, coordinator, 0), _start(sweep, out, coordinator, 1)]
    deadline = time.monotonic() + TIMEOUT_S
    while not list(out.glob(".partial-*/chunk_*.npz")) and time.monotonic() < deadline:
        if any(p.poll() is not None for p in processes):
            break
        time.sleep(0.05)
    if processes[0].poll() is not None:
        _finish(processes)
        pytest.skip("the sweep finished before the peer could be killed")
    processes[1].send_signal(signal.SIGKILL)
    killed_at = time.monotonic()
    (_, err), _ = _finish(processes)
    assert processes[0].returncode == 1, err
    assert "Traceback" not in err and "Abort" not in err and len(_error_lines(err)) == 1, err
    assert "peer" in err, err
    assert time.monotonic() - killed_at < 60  # within the 20 s timeout, plus slack for a loaded machine
    assert list(out.glob(".partial-*/chunk_*.npz"))  # the finished chunks are kept for a resume
    assert not (out / "table.csv").exists()
    assert os.path.isdir(out)


def test_a_locked_folder_refuses_every_process(tmp_path):
    """Another run holds the output folder: process 0 says so, and its peer hears it rather
    than waiting for process 0 until the heartbeat check aborts it. A held folder is bad input
    (exit 2), as it is for one process."""
    from tests.test_faults_folders import _HOLDER, SRC

    sweep = _sweep(tmp_path)
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""))
    holder = subprocess.Popen([sys.executable, "-c", _HOLDER, str(out)], env=env, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        coordinator = f"127.0.0.1:{_free_port()}"
        processes = [_start(sweep, out, coordinator, 0), _start(sweep, out, coordinator, 1)]
        outputs = _finish(processes)
    finally:
        holder.kill()
        holder.wait()
    for rank, (p, (_, err)) in enumerate(zip(processes, outputs, strict=False)):
        assert p.returncode == 2, f"process {rank}: {err}"
        assert f"another spacearm run (PID {holder.pid})" in err and len(_error_lines(err)) == 1, err
