"""Cost and accuracy of the default (adaptive) w-bar rule of spacearm.paper.normalized_wbar.

Run: python benchmarks/bench_wbar_rule.py [--designs 1000] [--random 400] [--baseline OLD_METRICS.py]

Timing: ``--designs`` Table 1 designs (base.attach and the arm mass varied, as in the
sweep benchmark) evaluated by ``jit(vmap(normalized_wbar))`` (how the sweep
engine calls it) and by ``normalized_wbar(batch, designs_per_chunk=64)``, per
design; one design by a jitted single call; compile times apart. ``rule="product"``
with the same node counts is timed as the floor (fixed nodes, no root finding).

Accuracy: the Table 2 designs (b0/B0 = 0, 0.5, 1, 1.5, 2) against the regression
values of tests/test_metrics.py, and ``--random`` random designs (tests/conftest.py's
random_robot, a quarter of them with light bases: base mass 20-60 kg, inertia
2-20 kg m^2, b0 0-4 m) against a converged reference (phi1_panels=16, phi2_panels=8,
order=16, newton_steps=8).

``--baseline`` takes another version of src/spacearm/analysis/manipulability_average.py (for example
``git show <commit>:src/spacearm/analysis/manipulability_average.py > /tmp/old_metrics.py``), loads it as a
module of the installed package and times and checks it in the same run, interleaved
with the current one (timings on a shared machine are noisy: compare within one run).
"""

from __future__ import annotations

import argparse
import importlib.util
import pathlib
import sys
import time

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)
import spacearm as sa
from spacearm import paper as metrics
from spacearm.studies import build_designs, load_sweep

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from tests.conftest import random_robot

TABLE2_EXPECTED = (0.0876862727874975, 0.0907243239426461, 0.0970120167785581, 0.1014599860992248, 0.1023088639013738)
CONVERGED = {"phi1_panels": 16, "phi2_panels": 8, "order": 16, "newton_steps": 8}


def load_baseline(path: str):
    spec = importlib.util.spec_from_file_location("spacearm._wbar_baseline", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    if not hasattr(module, "normalized_wbar"):  # a baseline from before the rename
        module.normalized_wbar = module.average_manipulability
    return module


def table1_designs(count: int) -> sa.PlanarRobot:
    side_a = int(round(np.sqrt(count * 1.6)))
    side_b = max(1, count // side_a)
    spec = load_sweep(
        {
            "name": "bench",
            "robot": str(ROOT / "configs" / "umetani1990.yaml"),
            "axes": {
                "b0_over_B0": {
                    "field": "base.attach",
                    "relative": True,
                    "range": {"start": 0.0, "stop": 2.0, "num": side_a},
                },
                "arm_to_base_mass": {"field": "arm.mass_ratio", "range": {"start": 0.05, "stop": 0.6, "num": side_b}},
            },
            "metrics": ["wbar"],
        }
    )
    robots, _ = build_designs(spec)
    return robots


def random_designs(count: int) -> sa.PlanarRobot:
    rng = np.random.default_rng(2024)
    light = count // 4
    robots = [random_robot(rng, 2) for _ in range(count - light)]
    for _ in range(light):
        robot = random_robot(rng, 2)
        robots.append(
            robot.replace(
                base_mass=np.float64(rng.uniform(20.0, 60.0)),
                base_inertia=np.float64(rng.uniform(2.0, 20.0)),
                base_attach=np.float64(rng.uniform(0.0, 4.0)),
            )
        )
    return sa.stack_robots(robots)


def timed(fn, *args, repeats: int):
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(fn(*args))
        best = min(best, time.perf_counter() - start)
    return best


class Candidate:
    def __init__(self, name, module, **options):
        self.name = name
        fn = module.normalized_wbar
        self.vmapped = jax.jit(jax.vmap(lambda r: fn(r, **options)))
        self.chunked = jax.jit(lambda r: fn(r, designs_per_chunk=64, **options))
        self.single = jax.jit(lambda r: fn(r, **options))
        self.module = module
        self.options = options
        self.compile = {}
        self.best = {"vmap": np.inf, "chunk": np.inf, "single": np.inf}

    def warm(self, batch, one):
        for key, fn, arg in (
            ("vmap", self.vmapped, batch),
            ("chunk", self.chunked, batch),
            ("single", self.single, one),
        ):
            start = time.perf_counter()
            jax.block_until_ready(fn(arg))
            self.compile[key] = time.perf_counter() - start

    def run(self, batch, one, singles):
        self.best["vmap"] = min(self.best["vmap"], timed(self.vmapped, batch, repeats=2))
        self.best["chunk"] = min(self.best["chunk"], timed(self.chunked, batch, repeats=1))
        start = time.perf_counter()
        for robot in singles:
            jax.block_until_ready(self.single(robot))
        self.best["single"] = min(self.best["single"], (time.perf_counter() - start) / len(singles))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--designs", type=int, default=1000)
    parser.add_argument("--random", type=int, default=400)
    parser.add_argument("--rounds", type=int, default=3, help="interleaved timing rounds (best kept)")
    parser.add_argument("--baseline", help="another manipulability_average.py to compare with in the same run")
    args = parser.parse_args()
    print(f"devices: {jax.devices()}  float64: {jax.config.jax_enable_x64}")

    modules = [("current", metrics)]
    if args.baseline:
        modules.append(("baseline", load_baseline(args.baseline)))
    batch = table1_designs(args.designs)
    size = int(batch.batch_shape[0])
    pick = np.linspace(0, size - 1, 50).astype(int)
    singles = [jax.tree_util.tree_map(lambda x, i=i: np.asarray(x)[i], batch) for i in pick]
    candidates = [Candidate(f"{name} adaptive", module) for name, module in modules]
    candidates.append(Candidate("current product", metrics, rule="product"))
    for candidate in candidates:
        candidate.warm(batch, singles[0])
    for _ in range(args.rounds):
        for candidate in candidates:
            candidate.run(batch, singles[0], singles)
    print(
        f"timing: {size} Table 1 designs (b0/B0 0-2 x arm mass ratio 0.05-0.6), best of {args.rounds} interleaved rounds"
    )
    print(
        f"{'':22s} {'jit(vmap) us/design':>20s} {'chunk 64 us/design':>19s} {'single call us':>15s}   compile s (vmap, chunk, single)"
    )
    for c in candidates:
        print(
            f"{c.name:22s} {c.best['vmap'] / size * 1e6:20.1f} {c.best['chunk'] / size * 1e6:19.1f} {c.best['single'] * 1e6:15.1f}"
            f"   {c.compile['vmap']:.2f}, {c.compile['chunk']:.2f}, {c.compile['single']:.2f}"
        )

    table1 = sa.umetani1990()
    table2 = sa.stack_robots([table1.replace(base_attach=np.float64(1.4 * r)) for r in (0.0, 0.5, 1.0, 1.5, 2.0)])
    print("accuracy on the Table 2 designs (b0/B0 = 0, 0.5, 1, 1.5, 2)")
    values = {name: np.asarray(jax.jit(module.normalized_wbar)(table2)) for name, module in modules}
    for name, value in values.items():
        rel = np.max(np.abs(value / np.asarray(TABLE2_EXPECTED) - 1))
        print(
            f"  {name}: {np.array2string(value, precision=16)}  max rel diff vs the test's regression values {rel:.1e}"
        )
    if len(values) == 2:
        rel = np.max(np.abs(values["current"] / values["baseline"] - 1))
        print(f"  max rel diff current vs baseline {rel:.1e}")

    robots = random_designs(args.random)
    print(
        f"accuracy on {args.random} random designs (a quarter with light bases) vs the converged reference {CONVERGED}"
    )
    references = {
        name: np.asarray(jax.jit(jax.vmap(lambda r, m=module: m.normalized_wbar(r, **CONVERGED)))(robots))
        for name, module in modules
    }
    for ref_name, reference in references.items():
        for name, module in modules:
            value = np.asarray(jax.jit(jax.vmap(module.normalized_wbar))(robots))
            rel = np.abs(value / reference - 1)
            worst = int(np.argmax(rel))
            print(
                f"  {name} default vs {ref_name} reference: max {rel.max():.1e} (design {worst}), "
                f"p99 {np.quantile(rel, 0.99):.1e}, median {np.median(rel):.1e}"
            )
    if len(references) == 2:
        rel = np.abs(references["current"] / references["baseline"] - 1)
        print(f"  current vs baseline reference: max {rel.max():.1e}")


if __name__ == "__main__":
    main()
