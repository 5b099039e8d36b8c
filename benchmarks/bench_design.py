"""Benchmark: gradient Pareto search vs NSGA-II vs a dense grid.

Plain script (not collected by pytest):

    python benchmarks/bench_design.py            # both problems, 3 seeds each
    python benchmarks/bench_design.py --quick    # 121 x 101 grid, 1 seed

Reference problem (sweeps/pareto-attachment.yaml): the target is 99.9% of the dense
grid's hypervolume; prints each method's run time and evaluations to reach it and the
ratio NSGA-II / gradient. Six-variable problem (sweeps/pareto-6var.yaml): prints the
hypervolume NSGA-II's archive holds at the gradient search's run time. Compile times are
printed apart from run times. Timings on a shared machine are noisy: the medians over
seeds are the numbers to quote.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

from spacearm import design

ROOT = Path(__file__).resolve().parents[1]


def median(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def show(value, unit=""):
    return "never" if value is None else f"{value:.3g}{unit}"


def reference(seeds, grid_points):
    problem = design.load_problem(ROOT / "sweeps" / "pareto-attachment.yaml")
    print(f"== {problem.name}: variables {problem.variable_names}, objectives {problem.objectives}")
    grid = design.grid_search(problem, points=grid_points)
    grid_hv = grid.checkpoints[-1]["hypervolume"]
    target = design.TARGET_FRACTION * grid_hv
    print(
        f"grid {grid_points[0]}x{grid_points[1]}: {grid.evaluations} evaluations, compile "
        f"{grid.compile_seconds:.2f} s, run {grid.run_seconds:.2f} s, hypervolume {grid_hv:.8f}"
    )
    print(f"target: {design.TARGET_FRACTION:.1%} of it = {target:.8f}")
    rows = {"gradient": [], "nsga2": []}
    for seed in seeds:
        settings = dataclasses.replace(problem.search, seed=seed)
        gradient = design.pareto_search(problem, settings)
        nsga = design.nsga2_search(problem, population=40, evaluations=6000, seed=seed)
        for name, result in (("gradient", gradient), ("nsga2", nsga)):
            rows[name].append(result)
            print(
                f"  seed {seed} {name:8s}: compile {result.compile_seconds:6.2f} s | to target "
                f"{show(result.seconds_to(target), ' s')} / {show(result.evaluations_to(target))} evaluations | "
                f"final HV / grid {result.checkpoints[-1]['hypervolume'] / grid_hv:.6f} after "
                f"{result.evaluations} evaluations, {result.run_seconds:.2f} s"
            )
    t_gradient = median([r.seconds_to(target) for r in rows["gradient"]])
    t_nsga = median([r.seconds_to(target) for r in rows["nsga2"]])
    e_gradient = median([r.evaluations_to(target) for r in rows["gradient"]])
    e_nsga = median([r.evaluations_to(target) for r in rows["nsga2"]])
    print(
        f"median time to target: gradient {show(t_gradient, ' s')}, NSGA-II {show(t_nsga, ' s')}"
        + (f", ratio NSGA-II / gradient = {t_nsga / t_gradient:.2f}x" if t_gradient and t_nsga else "")
    )
    print(
        f"median evaluations to target: gradient {show(e_gradient)}, NSGA-II {show(e_nsga)}"
        + (f", ratio {e_nsga / e_gradient:.2f}x" if e_gradient and e_nsga else "")
    )
    ratio = design.value_and_grad_cost_ratio(problem, batch=64)
    print(f"value-and-gradient / value cost (batch 64, reverse mode): {ratio:.2f}")


def six_variables(seeds):
    problem = design.load_problem(ROOT / "sweeps" / "pareto-6var.yaml")
    print(f"== {problem.name}: variables {problem.variable_names}")
    wins = []
    for seed in seeds:
        settings = dataclasses.replace(problem.search, seed=seed)
        gradient = design.pareto_search(problem, settings)
        budget = gradient.run_seconds
        nsga = design.nsga2_search(problem, population=100, evaluations=10**7, seed=seed, time_limit=3 * budget)
        hv_gradient = gradient.checkpoints[-1]["hypervolume"]
        hv_nsga = nsga.hypervolume_at(budget)
        wins.append(hv_gradient > hv_nsga)
        print(
            f"  seed {seed}: gradient HV {hv_gradient:.8f} in {budget:.2f} s ({gradient.evaluations} evaluations, "
            f"compile {gradient.compile_seconds:.1f} s) | NSGA-II HV at that time {hv_nsga:.8f}, "
            f"after 3x the time {nsga.checkpoints[-1]['hypervolume']:.8f} ({nsga.evaluations} evaluations, "
            f"compile {nsga.compile_seconds:.1f} s) | NSGA-II needs "
            f"{show(nsga.seconds_to(hv_gradient), ' s')} for the gradient's HV"
        )
    print(f"gradient ahead at equal run time in {sum(wins)} of {len(wins)} seeds")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="121 x 101 grid and one seed")
    parser.add_argument("--seeds", type=int, default=3)
    args = parser.parse_args()
    seeds = range(1 if args.quick else args.seeds)
    start = time.perf_counter()
    reference(seeds, (121, 101) if args.quick else (241, 201))
    six_variables(seeds)
    print(f"total {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
