"""10^4 designs of the Table 1 robot with w-bar, S_M and S_G in one sweep vs a Python loop.

Run: python benchmarks/bench_sweep.py [--designs 10000] [--loop-designs 200] [--rules adaptive,product]

The sweep stacks all designs into one batched pytree and evaluates them in compiled,
vmapped chunks (spacearm.studies.run_sweep, files written to a temporary folder). The
baseline is the loop a user would write: for each design, call the single-design
functions (normalized_wbar and normalized_areas, both jitted entry points) and
read the numbers, timed on a subset and reported per design. Compile time is reported
apart. The loop's cost per design is split into its parts (building the design with
PlanarRobot.replace, which validates; the two calls; a bare jitted call on the same
pytree, i.e. the dispatch floor), so the ratio's ceiling can be read off.

Each w-bar rule is measured on its own: "adaptive" (the default, ~1e-13 on Table 2's
designs: Gauss-Legendre panels split at the roots of det J*, so its nodes depend on the
design) and "product" (a fixed 192 x 64 node grid, second order at the kinks, whose
sine/cosine tables a batch shares across designs; its deviation from the default is
printed).
"""

from __future__ import annotations

import argparse
import tempfile
import time

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)
import spacearm as sa
from spacearm.paper import normalized_areas, normalized_wbar
from spacearm.studies import build_designs, load_sweep, run_sweep

RULES = {
    "adaptive": {},
    "product": {"rule": "product", "phi1_panels": 8, "phi2_panels": 4, "order": 8},
}


def sweep_spec(side: int, chunk_size: int, options: dict):
    return load_sweep(
        {
            "name": "bench",
            "robot": "configs/umetani1990.yaml",
            "axes": {
                "b0_over_B0": {
                    "field": "base.attach",
                    "relative": True,
                    "range": {"start": 0.0, "stop": 2.0, "num": side},
                },
                "arm_to_base_mass": {"field": "arm.mass_ratio", "range": {"start": 0.05, "stop": 0.6, "num": side}},
            },
            "metrics": [{"name": "wbar", **options}, "S_M", "S_G"],
            "chunk_size": chunk_size,
        }
    )


def per_call(fn, items) -> float:
    """Mean seconds of fn(item) over items (after one warm-up call)."""
    fn(items[0])
    start = time.perf_counter()
    for item in items:
        fn(item)
    return (time.perf_counter() - start) / len(items)


def measure(name: str, options: dict, args, reference: dict | None) -> dict:
    side = int(round(np.sqrt(args.designs)))
    spec = sweep_spec(side, args.chunk_size, options)
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        result = run_sweep(spec, out, progress=False)
        wall = time.perf_counter() - start
    timings, total = result.manifest["timings_s"], spec.n_designs

    robots, _points = build_designs(spec)
    pick = np.linspace(0, total - 1, args.loop_designs).astype(int)
    singles = [jax.tree_util.tree_map(lambda x, i=i: np.asarray(x)[i], robots) for i in pick]
    base = sa.umetani1990()
    attach = [float(robots.base_attach[i]) for i in pick]

    def calls(robot):
        s_m, s_g = normalized_areas(robot)
        return float(normalized_wbar(robot, **options)), float(s_m), float(s_g)

    t0 = time.perf_counter()
    calls(singles[0])
    loop_compile = time.perf_counter() - t0
    t_calls = per_call(calls, singles)
    t_wbar = per_call(lambda r: float(normalized_wbar(r, **options)), singles)
    t_areas = per_call(lambda r: [float(v) for v in normalized_areas(r)], singles)
    bare = jax.jit(lambda r: r.base_mass + r.link_mass[0])
    t_bare = per_call(lambda r: float(bare(r)), singles)
    t_build = per_call(lambda b0: base.replace(base_attach=np.float64(b0)), attach)
    loop_values = np.array([calls(r)[0] for r in singles])
    diff = np.max(np.abs(loop_values - result.table["wbar"][pick]))

    run_rate = total / timings["run"]
    print(f"\n== w-bar rule: {name} {options or '(default)'}")
    print(
        f"sweep: {total:,} designs (wbar, S_M, S_G), chunk {result.manifest['chunk_size']}, "
        f"compile {timings['compile']:.2f} s, run {timings['run']:.2f} s, wall incl. files {wall:.2f} s"
    )
    print(f"  {run_rate:,.0f} designs/s run ({1e6 / run_rate:,.1f} us/design), {total / wall:,.0f} designs/s wall")
    print(
        f"loop of single-design calls ({len(singles)} designs timed, compile {loop_compile:.2f} s): "
        f"{1 / t_calls:,.0f} designs/s ({t_calls * 1e6:,.0f} us/design); max |wbar loop - sweep| {diff:.1e}"
    )
    print(
        f"  parts per design: w-bar call {t_wbar * 1e6:,.0f} us, areas call {t_areas * 1e6:,.0f} us, "
        f"bare jitted call on the pytree {t_bare * 1e6:,.0f} us; building a design (replace) {t_build * 1e6:,.0f} us"
    )
    print(f"ratio sweep / loop (run)             {run_rate * t_calls:8.1f}x  (target >= 100x)")
    print(f"ratio sweep / loop (wall)            {total / wall * t_calls:8.1f}x")
    print(
        f"ratio incl. building each design     {total / wall * (t_calls + t_build):8.1f}x  (sweep wall incl. its own build)"
    )
    if reference is not None:
        dev = np.abs(result.table["wbar"] - reference["wbar"]) / reference["wbar"]
        print(
            f"  w-bar vs the default rule over all {total:,} designs: max rel {dev.max():.1e}, median {np.median(dev):.1e}"
        )
    return {"wbar": result.table["wbar"]}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--designs", type=int, default=10_000)
    parser.add_argument("--loop-designs", type=int, default=200)
    parser.add_argument("--chunk-size", type=int, default=1000)
    parser.add_argument("--rules", default="adaptive,product", help="comma-separated: adaptive, product")
    args = parser.parse_args()
    print(f"devices: {jax.devices()}  float64: {jax.config.jax_enable_x64}")
    reference = None
    for name in args.rules.split(","):
        values = measure(name, RULES[name], args, reference)
        if name == "adaptive":
            reference = values


if __name__ == "__main__":
    main()
