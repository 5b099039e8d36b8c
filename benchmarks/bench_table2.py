"""Table 2 end to end from the command line (cold and warm), and w-bar for many designs in one batch.

Run: python benchmarks/bench_table2.py [--designs 10000] [--skip-cli]

1. ``spacearm sweep sweeps/table2.yaml``: cold = a fresh subprocess (interpreter start,
   imports, compilation, run, report and figures), target < 10 s; warm = the same command
   run twice through ``spacearm.cli.main`` in this process, the second time timed
   (compiled functions cached in memory).
2. w-bar (eq. 12, adaptive quadrature, default options) for N designs in one batched
   call (``normalized_wbar(batch)``, ``jax.lax.map`` over chunks of designs),
   compile time apart from run time, against two baselines measured in the same run:
   a Python loop over single designs (jitted once; timed on a subset) and the plain
   product rule at the resolution that reaches the same ~1e-6 accuracy as the
   paper-level comparison needs (256 x 128 points per design).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)
import spacearm as sa
from spacearm.paper import normalized_wbar

ROOT = Path(__file__).resolve().parents[1]


def run_cli(out_dir: Path) -> float:
    env = dict(os.environ)
    command = [sys.executable, "-m", "spacearm.cli", "sweep", "sweeps/table2.yaml", "--out", str(out_dir), "--quiet"]
    start = time.perf_counter()
    done = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True)
    elapsed = time.perf_counter() - start
    if done.returncode != 0:
        print(done.stdout, done.stderr, sep="\n")
        raise SystemExit(f"spacearm sweep failed with exit status {done.returncode}")
    print("   ", done.stdout.strip().splitlines()[-1] if done.stdout.strip() else "")
    return elapsed


def design_batch(count: int, seed: int = 0) -> sa.PlanarRobot:
    rng = np.random.default_rng(seed)
    base = sa.umetani1990()
    batch = jax.tree_util.tree_map(lambda x: np.repeat(np.asarray(x)[None], count, axis=0), base)
    return batch.replace(
        base_attach=rng.uniform(0.0, 2.8, count),
        base_mass=rng.uniform(500.0, 2000.0, count),
    )


def timed(fn, *args):
    start = time.perf_counter()
    value = jax.block_until_ready(fn(*args))
    return value, time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--designs", type=int, default=10_000)
    parser.add_argument("--loop-designs", type=int, default=100)
    parser.add_argument("--designs-per-chunk", type=int, default=64)
    parser.add_argument("--skip-cli", action="store_true")
    args = parser.parse_args()
    print(f"devices: {jax.devices()}  (2-core machine, shared: expect noise)")

    if not args.skip_cli:
        print("1. spacearm sweep sweeps/table2.yaml (subprocess, float64)")
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            cold = run_cli(tmp / "cold")
            from spacearm.cli import main as cli_main

            argv = ["sweep", "sweeps/table2.yaml", "--quiet", "--out"]
            here = os.getcwd()
            os.chdir(ROOT)
            try:
                cli_main(argv + [str(tmp / "warm0")])
                start = time.perf_counter()
                cli_main(argv + [str(tmp / "warm1")])
                warm = time.perf_counter() - start
            finally:
                os.chdir(here)
        print(
            f"   cold {cold:.2f} s (target < 10 s: {'met' if cold < 10 else 'NOT met'}), warm {warm:.2f} s, cold/warm {cold / warm:.2f}"
        )

    count = args.designs
    batch = design_batch(count)
    print(f"2. w-bar for {count} designs in one batch")
    batched = jax.jit(lambda r: normalized_wbar(r, designs_per_chunk=args.designs_per_chunk))
    small = jax.tree_util.tree_map(lambda x: x[:1], batch)
    _, first = timed(batched, small)
    _, _compile_only = timed(batched, batch)  # new shape: trace + compile + run
    values, run = timed(batched, batch)
    print(
        f"   adaptive (default): first call (compile, 1 design) {first:.2f} s; run {run:.2f} s = {1e3 * run / count:.3f} ms/design"
    )

    single = jax.jit(normalized_wbar)
    designs = [jax.tree_util.tree_map(lambda x, i=i: x[i], batch) for i in range(args.loop_designs)]
    jax.block_until_ready(single(designs[0]))
    start = time.perf_counter()
    loop_values = [float(single(d)) for d in designs]
    loop = (time.perf_counter() - start) / args.loop_designs
    error = np.max(np.abs(np.asarray(loop_values) - np.asarray(values[: args.loop_designs])))
    print(
        f"   Python loop over single designs (jitted once): {1e3 * loop:.3f} ms/design -> batch is {loop * count / run:.1f}x faster; max |diff| {error:.1e}"
    )

    product = jax.jit(
        lambda r: normalized_wbar(
            r, rule="product", phi1_panels=32, phi2_panels=16, order=8, designs_per_chunk=args.designs_per_chunk
        )
    )
    timed(product, small)
    product_values, product_run = timed(product, batch)
    reference = jax.jit(lambda r: normalized_wbar(r, order=16, designs_per_chunk=args.designs_per_chunk))(
        jax.tree_util.tree_map(lambda x: x[:200], batch)
    )
    err_adaptive = np.max(np.abs(np.asarray(values[:200]) / np.asarray(reference) - 1))
    err_product = np.max(np.abs(np.asarray(product_values[:200]) / np.asarray(reference) - 1))
    print(
        f"   product rule 256 x 128: run {product_run:.2f} s ({product_run / run:.2f}x the adaptive time); "
        f"max rel. error vs order-16 reference: adaptive {err_adaptive:.1e}, product {err_product:.1e}"
    )


if __name__ == "__main__":
    main()
