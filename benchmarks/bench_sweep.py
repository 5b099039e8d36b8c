"""10^4 designs of the Table 1 robot with w-bar, S_M and S_G in one sweep vs a Python loop.

Run: python benchmarks/bench_sweep.py [--designs 10000] [--loop-designs 200]

The sweep stacks all designs into one batched pytree and evaluates them in compiled,
vmapped chunks (spacearm.sweep.run_sweep, files written to a temporary folder). The
baseline is the loop a user would write: for each design, call the single-design
functions (average_manipulability jitted once, normalized_areas), timed on a subset and
reported per design. Compile time is reported apart.
"""

from __future__ import annotations

import argparse
import tempfile
import time

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)
import spacearm as sa  # noqa: E402
from spacearm.metrics import average_manipulability, normalized_areas  # noqa: E402
from spacearm.sweep import build_designs, load_sweep, run_sweep  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--designs", type=int, default=10_000)
    parser.add_argument("--loop-designs", type=int, default=200)
    parser.add_argument("--chunk-size", type=int, default=1000)
    args = parser.parse_args()
    side = int(round(np.sqrt(args.designs)))
    spec = load_sweep({
        "name": "bench",
        "robot": "configs/umetani1990.yaml",
        "axes": {
            "b0_over_B0": {"field": "base.attach", "relative": True, "range": {"start": 0.0, "stop": 2.0, "num": side}},
            "arm_to_base_mass": {"field": "arm.mass_ratio", "range": {"start": 0.05, "stop": 0.6, "num": side}},
        },
        "metrics": ["wbar", "S_M", "S_G"],
        "chunk_size": args.chunk_size,
    })
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        result = run_sweep(spec, out, progress=False)
        wall = time.perf_counter() - start
    timings = result.manifest["timings_s"]
    total = spec.n_designs

    robots, _ = build_designs(spec)
    pick = np.linspace(0, total - 1, args.loop_designs).astype(int)
    singles = [jax.tree_util.tree_map(lambda x: np.asarray(x)[i], robots) for i in pick]
    wbar_single = jax.jit(average_manipulability)
    t0 = time.perf_counter()
    wbar_single(singles[0]).block_until_ready()
    loop_compile = time.perf_counter() - t0
    t0 = time.perf_counter()
    loop_values = []
    for robot in singles:
        s_m, s_g = normalized_areas(robot)
        loop_values.append((float(wbar_single(robot)), float(s_m), float(s_g)))
    loop_per_design = (time.perf_counter() - t0) / len(singles)
    diff = max(abs(loop_values[k][0] - result.table["wbar"][i]) for k, i in enumerate(pick))

    sweep_rate = total / (timings["run"] + 1e-12)
    print(f"devices: {jax.devices()}  float64: {jax.config.jax_enable_x64}")
    print(f"sweep: {total:,} designs (wbar, S_M, S_G), chunk {result.manifest['chunk_size']}")
    print(f"  compile {timings['compile']:.2f} s, run {timings['run']:.2f} s, wall incl. files {wall:.2f} s")
    print(f"  {sweep_rate:,.0f} designs/s (run), {total / wall:,.0f} designs/s (wall)")
    print(f"python loop over single-design calls (jitted once; {len(singles)} designs timed)")
    print(f"  compile {loop_compile:.2f} s, {1 / loop_per_design:,.0f} designs/s; max |wbar diff| {diff:.1e}")
    print(f"ratio sweep / loop (run)   {sweep_rate * loop_per_design:8.1f}x  (target >= 100x)")
    print(f"ratio sweep / loop (wall)  {total / wall * loop_per_design:8.1f}x")


if __name__ == "__main__":
    main()
