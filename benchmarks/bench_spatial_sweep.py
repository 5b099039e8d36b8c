"""Designs per second of a spatial sweep of the mean manipulability w-bar to 1e-3.

One SpatialRobot batch of D designs (default 10^4: the bus mass and the mount position
varied about configs/<robot>.yaml) goes through
``spacearm.analysis.averages.joint_average(batch, rtol=1e-3)``: randomized QMC per design
(each design stops at its own sample count), ``lax.map`` over chunks of designs. Compile
time is reported apart (AOT: ``jit(...).lower(...).compile()``).

Scaling with devices: the same sweep in subprocesses with
``XLA_FLAGS=--xla_force_host_platform_device_count=N``, the design axis sharded over the
N CPU devices with ``jax.sharding`` (``shard_map``: each device maps its own designs).
Forced host devices share the machine's cores, so past the core count no speed-up is
expected; the point is that the program shards and scales up to the cores.

Baseline in the same run: a plain Monte Carlo estimate (uniform random postures, same
sample count per design) of the same mean, to show what QMC buys at equal cost.

Usage: PYTHONPATH=src python benchmarks/bench_spatial_sweep.py [--designs 10000]
[--robot arm3dof-100kg] [--devices 1 2 4] [--chunk 64]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time


def _sweep(designs: int, robot_name: str, chunk: int, rtol: float) -> dict:
    import jax
    import numpy as np
    from jax.sharding import Mesh, NamedSharding, PartitionSpec as P

    jax.config.update("jax_enable_x64", True)
    import spacearm as sa
    from spacearm.analysis import averages

    try:
        from jax import shard_map
    except ImportError:  # older JAX
        from jax.experimental.shard_map import shard_map

    robot = sa.load_robot(os.path.join("configs", f"{robot_name}.yaml"))
    rng = np.random.default_rng(0)
    batch = jax.tree_util.tree_map(lambda x: np.broadcast_to(np.asarray(x), (designs, *np.shape(x))).copy(), robot)
    batch = batch.replace(
        base_mass=np.asarray(robot.base_mass) * rng.uniform(0.5, 2.0, designs),
        mount_xyz=np.asarray(robot.mount_xyz) + rng.uniform(-0.3, 0.3, (designs, 3)),
    )
    devices = jax.devices()
    mesh = Mesh(np.array(devices), ("designs",))
    spec = NamedSharding(mesh, P("designs"))
    batch = jax.device_put(batch, spec)
    options = dict(rtol=rtol, min_samples=2**11, block=128, randomizations=8, designs_per_chunk=chunk)

    def local(designs_here):
        estimate = averages.joint_average(designs_here, **options)
        return estimate.value, estimate.error, estimate.samples

    # check_vma=False: the estimator's while_loop starts from unsharded constants.
    sweep = jax.jit(shard_map(local, mesh=mesh, in_specs=P("designs"), out_specs=P("designs"), check_vma=False))
    start = time.perf_counter()
    compiled = sweep.lower(batch).compile()
    compile_s = time.perf_counter() - start
    start = time.perf_counter()
    value, error, samples = jax.block_until_ready(compiled(batch))
    run_s = time.perf_counter() - start
    value, error, samples = np.asarray(value), np.asarray(error), np.asarray(samples)
    return {
        "devices": len(devices),
        "designs": designs,
        "robot": robot_name,
        "compile_s": compile_s,
        "run_s": run_s,
        "designs_per_s": designs / run_s,
        "postures_per_s": float(samples.sum()) / run_s,
        "mean_samples": float(samples.mean()),
        "max_relative_error": float(np.max(error / np.abs(value))),
        "wbar_range_m3": [float(value.min()), float(value.max())],
    }


def _monte_carlo_baseline(robot_name: str, samples: int, trials: int = 64) -> dict:
    """Relative spread of plain Monte Carlo vs randomized QMC at the same sample count (one design)."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    jax.config.update("jax_enable_x64", True)
    import spacearm as sa
    from spacearm.analysis import averages
    from spacearm.analysis.joint_box import joint_box

    robot = sa.load_robot(os.path.join("configs", f"{robot_name}.yaml"))
    lower, upper = joint_box(robot)
    keys = jax.random.split(jax.random.key(1), trials)

    @jax.jit
    def plain(key):
        q = lower + (upper - lower) * jax.random.uniform(key, (samples, lower.shape[-1]))
        return jnp.mean(sa.manipulability(robot, q))

    mc = np.asarray(jax.vmap(plain)(keys))
    qmc = averages.joint_average(robot, rtol=1e-15, min_samples=samples, max_samples=samples, block=128)
    return {
        "samples": samples,
        "monte_carlo_relative_sd": float(mc.std(ddof=1) / mc.mean()),
        "rqmc_relative_error_estimate": float(qmc.relative_error),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--designs", type=int, default=10_000)
    parser.add_argument("--robot", default="arm3dof-100kg")
    parser.add_argument("--devices", type=int, nargs="+", default=[1, 2, 4])
    parser.add_argument("--chunk", type=int, default=64)
    parser.add_argument("--rtol", type=float, default=1e-3)
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(_sweep(args.designs, args.robot, args.chunk, args.rtol)))
        return
    print(
        f"spatial sweep: {args.designs} designs of {args.robot}, w-bar to rtol {args.rtol} (one sigma), os.cpu_count() = {os.cpu_count()}"
    )
    rows = []
    for n in args.devices:
        env = dict(os.environ, XLA_FLAGS=f"--xla_force_host_platform_device_count={n}")
        command = [sys.executable, __file__, "--child", "--designs", str(args.designs), "--robot", args.robot,
                   "--chunk", str(args.chunk), "--rtol", str(args.rtol)]  # fmt: skip
        out = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
        row = json.loads(out.stdout.strip().splitlines()[-1])
        rows.append(row)
        print(
            f"  devices {row['devices']}: compile {row['compile_s']:.1f} s, run {row['run_s']:.1f} s, "
            f"{row['designs_per_s']:.0f} designs/s ({row['postures_per_s'] / 1e6:.2f} M postures/s, "
            f"{row['mean_samples']:.0f} postures per design, max rel. error {row['max_relative_error']:.1e})"
        )
    base = rows[0]["designs_per_s"]
    print("  speed-up vs 1 device: " + ", ".join(f"{r['devices']}: {r['designs_per_s'] / base:.2f}x" for r in rows))
    baseline = _monte_carlo_baseline(args.robot, int(round(rows[0]["mean_samples"] / 1024)) * 1024 or 1024)
    print(
        f"  baseline at {baseline['samples']} postures per design: plain Monte Carlo relative sd "
        f"{baseline['monte_carlo_relative_sd']:.1e} vs randomized QMC {baseline['rqmc_relative_error_estimate']:.1e} "
        f"({baseline['monte_carlo_relative_sd'] / baseline['rqmc_relative_error_estimate']:.1f}x)"
    )


if __name__ == "__main__":
    main()
