"""Designs per second of a spatial sweep through the sweep runner.

A sweep file over a spatial robot (default: the 3-DOF arm on its 100 kg bus; the mount
position x and the arm-to-bus mass ratio varied, D designs, default 10^4) with the mean
translational w* over the joint box to a relative standard error of 1e-3
(``{name: w_avg, rtol: 1.0e-3}``), run by :func:`spacearm.studies.run_sweep`: designs
built and validated, chunks sharded over the devices (``shard_map``), results gathered,
the table, grids and manifest written. Compile time is reported apart.

Scaling with devices: the same sweep in subprocesses with
``XLA_FLAGS=--xla_force_host_platform_device_count=N``. Forced host devices share the
machine's cores: past the core count no speed-up is expected.

Baseline in the same run (1 device): the library call alone,
``analysis.averages.joint_average(batch, rtol=1e-3)`` under one ``jit`` over the same
designs, so the ratio shows what the runner costs or saves.

``benchmarks/bench_spatial_sweep.py`` times the estimator itself; this one
times the whole runner.

Usage: PYTHONPATH=src python benchmarks/bench_spatial_sweep_runner.py [--designs 10000]
[--devices 1 2 4] [--robot arm3dof-100kg] [--timeout 1800]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _config(designs: int, robot: str) -> dict:
    ratios = 10
    positions = max(1, designs // ratios)
    return {
        "name": "bench-spatial-runner",
        "robot": str(Path("configs").resolve() / f"{robot}.yaml"),
        "axes": {
            "x": {"field": "mount.xyz[0]", "range": {"start": -0.3, "stop": 0.3, "num": positions}},
            "ratio": {"field": "arm.mass_ratio", "range": {"start": 0.05, "stop": 0.5, "num": ratios}},
        },
        "metrics": [{"name": "w_avg", "rtol": 1.0e-3}],
        "chunk_size": 256,
    }


def _child(designs: int, robot: str, direct: bool) -> dict:
    import jax

    jax.config.update("jax_enable_x64", True)
    from spacearm.analysis.averages import joint_average
    from spacearm.studies import build_designs, load_sweep, run_sweep

    spec = load_sweep(_config(designs, robot))
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        result = run_sweep(spec, Path(folder) / "out", progress=False)
        wall = time.perf_counter() - start
    timings = result.manifest["timings_s"]
    out = dict(
        devices=jax.device_count(),
        designs=spec.n_designs,
        compile_s=timings["compile"],
        run_s=timings["run"],
        wall_s=wall,
        designs_per_s=spec.n_designs / timings["run"],
    )
    if direct:
        batch, _ = build_designs(spec)
        function = jax.jit(lambda robot: joint_average(robot, "manipulability", rtol=1e-3).value)
        t0 = time.perf_counter()
        compiled = function.lower(batch).compile()
        compile_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        jax.block_until_ready(compiled(batch))
        run_s = time.perf_counter() - t0
        out["direct"] = dict(compile_s=compile_s, run_s=run_s, designs_per_s=spec.n_designs / run_s)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--designs", type=int, default=10_000)
    parser.add_argument("--devices", type=int, nargs="+", default=[1, 2, 4])
    parser.add_argument("--robot", default="arm3dof-100kg")
    parser.add_argument("--timeout", type=float, default=1800.0, help="per device count, s")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--direct", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(_child(args.designs, args.robot, args.direct)))
        return
    rows = []
    for count in args.devices:
        env = dict(os.environ, XLA_FLAGS=f"--xla_force_host_platform_device_count={count}")
        command = [sys.executable, __file__, "--child", "--designs", str(args.designs), "--robot", args.robot]
        if count == args.devices[0]:
            command.append("--direct")
        try:
            done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=args.timeout)
        except subprocess.TimeoutExpired:
            print(f"{count} device(s): no result within {args.timeout:.0f} s")
            continue
        if done.returncode != 0:
            print(f"{count} device(s): failed\n{done.stderr[-2000:]}")
            continue
        row = json.loads(done.stdout.strip().splitlines()[-1])
        rows.append(row)
        print(
            f"{row['devices']} device(s): {row['designs']} designs, compile {row['compile_s']:.1f} s, "
            f"run {row['run_s']:.2f} s -> {row['designs_per_s']:.1f} designs/s (wall {row['wall_s']:.1f} s)"
        )
        if "direct" in row:
            d = row["direct"]
            print(
                f"  baseline joint_average alone (1 jit): compile {d['compile_s']:.1f} s, run {d['run_s']:.2f} s -> "
                f"{d['designs_per_s']:.1f} designs/s; runner / baseline = "
                f"{row['designs_per_s'] / d['designs_per_s']:.2f}"
            )
    if len(rows) > 1:
        first = rows[0]["designs_per_s"]
        print("scaling: " + ", ".join(f"{r['devices']} dev {r['designs_per_s'] / first:.2f}x" for r in rows))


if __name__ == "__main__":
    main()
