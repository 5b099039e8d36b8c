"""Past one machine: two processes joined by jax.distributed (CPU collectives over gloo)
run one sweep together and write the same table as a single process.

This is exactly the recipe of the README and docs/guide/performance.md ("Many processes"):
every process runs ``spacearm sweep FILE --out DIR`` with SPACEARM_COORDINATOR,
SPACEARM_NUM_PROCESSES and SPACEARM_PROCESS_ID set. Each process here exposes one CPU
device (XLA_FLAGS), so the two processes form the same 2-device mesh as the single
process they are compared with, and the tables agree byte for byte.
"""

import json
import os
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from spacearm.cli import main

ROBOT = str(Path("configs/umetani1990.yaml").resolve())
TIMEOUT_S = 120


def _gloo_available() -> bool:
    try:
        import jax
        from jax._src.lib import _jax
    except ImportError:
        return False
    return hasattr(jax.config, "jax_cpu_collectives_implementation") and hasattr(_jax, "make_gloo_tcp_collectives")


pytestmark = pytest.mark.skipif(
    not _gloo_available(), reason="the installed jaxlib has no gloo CPU collectives (jax.distributed on CPU)"
)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _env(devices: int, **extra) -> dict:
    env = dict(
        os.environ,
        XLA_FLAGS=f"--xla_force_host_platform_device_count={devices}",
        PYTHONPATH=str(Path("src").resolve()) + os.pathsep + os.environ.get("PYTHONPATH", ""),
    )
    env.update(extra)
    return env


def _sweep(tmp_path) -> Path:
    config = {
        "name": "distributed",
        "robot": ROBOT,
        "axes": {
            "b0_over_B0": {"field": "base.attach", "relative": True, "range": {"start": 0.0, "stop": 2.0, "num": 7}},
            "ratio": {"field": "arm.mass_ratio", "values": [0.1, 0.2, 0.4]},
        },
        "metrics": ["radii", "S_G"],
        "chunk_size": 4,  # several chunks: every process must run the same ones
    }
    path = tmp_path / "sweep.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


def test_two_processes_write_the_same_table_as_one(tmp_path):
    sweep = _sweep(tmp_path)
    command = [sys.executable, "-m", "spacearm.cli", "sweep", str(sweep), "--quiet", "--out"]
    single = subprocess.run(
        command + [str(tmp_path / "single")], env=_env(2), capture_output=True, text=True, timeout=TIMEOUT_S
    )
    assert single.returncode == 0, single.stderr

    coordinator = f"127.0.0.1:{_free_port()}"
    processes = [
        subprocess.Popen(
            command + [str(tmp_path / "two")],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=_env(1, SPACEARM_COORDINATOR=coordinator, SPACEARM_NUM_PROCESSES="2", SPACEARM_PROCESS_ID=str(rank)),
        )
        for rank in range(2)
    ]
    try:
        outputs = [p.communicate(timeout=TIMEOUT_S) for p in processes]
    finally:
        for p in processes:
            if p.poll() is None:
                p.kill()
    for rank, (p, (_out, err)) in enumerate(zip(processes, outputs, strict=False)):
        assert p.returncode == 0, f"process {rank}: {err}"
    assert "process 1 of 2: done" in outputs[1][0]

    one, two = tmp_path / "single", tmp_path / "two"
    assert (one / "table.csv").read_bytes() == (two / "table.csv").read_bytes()
    with np.load(one / "grids.npz") as a, np.load(two / "grids.npz") as b:
        assert sorted(a.files) == sorted(b.files)
        for key in a.files:
            np.testing.assert_array_equal(a[key], b[key])
    manifest = json.loads((two / "manifest.json").read_text())
    assert manifest["process_count"] == 2 and manifest["device_count"] == 2
    assert manifest["config_sha256"] == json.loads((one / "manifest.json").read_text())["config_sha256"]
    assert not list(two.glob(".partial-*"))  # finished: the chunks were cleaned up


def test_partial_distributed_options_are_refused(tmp_path, monkeypatch, capsys):
    """In this process (the options are checked before any process would join)."""
    sweep = _sweep(tmp_path)
    monkeypatch.setenv("SPACEARM_COORDINATOR", "127.0.0.1:1")  # read as the option's default
    assert main(["sweep", str(sweep), "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert "needs all three" in err and "Traceback" not in err
    assert not (tmp_path / "x").exists()
