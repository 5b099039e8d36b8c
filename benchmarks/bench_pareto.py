"""Benchmark: the hybrid design search against NSGA-II on every shipped design problem.

Plain script (not collected by pytest):

    python benchmarks/bench_pareto.py                          # every problem, file settings
    python benchmarks/bench_pareto.py --max-seconds 20 --factor 3 pareto-attachment

Per problem: the hybrid search runs (its compile counted), then NSGA-II (pymoo, the same
batch function, population as in the file) for ``factor`` times the hybrid's wall time,
its own compile counted too (a compile cache hit is charged the hybrid's compile of the
shared value program). Printed: NSGA-II's final hypervolume, the wall time each method
took to reach it (compile included) and their ratio (hybrid / NSGA-II: below 1 the hybrid
is faster; "never" when the hybrid did not reach it), each method's share of the best
known hypervolume (every design either evaluated) and the target: the
hybrid's final hypervolume at least NSGA-II's after ``factor`` x its wall time, and at
least 99.5 % of the best known. Timings on a shared machine are noisy; ratios within one
run are the numbers to quote.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import resource
import time
from pathlib import Path

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)

from spacearm._core.schema import read_yaml
from spacearm.design.baselines import nsga2_search
from spacearm.design.fronts import hypervolume
from spacearm.design.hybrid import JACOBIANS, hybrid_search, parse_hybrid
from spacearm.design.problem import load_problem as load_design_problem

ROOT = Path(__file__).resolve().parents[1]
PROBLEMS = ("pareto-attachment", "pareto-6var", "pareto-mount-ur5", "pareto-ur5-arm")


def wall_to(result, level):
    seconds = result.seconds_to(level)
    return None if seconds is None else result.compile_seconds + seconds


def cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def show(value, unit=" s"):
    return "never" if value is None else f"{value:.3g}{unit}"


def bench(
    name: str,
    max_seconds: float | None,
    population: int | None,
    factor: float,
    tolerance: float | None = None,
    generations: int | None = None,
    jacobian: str | None = None,
    gradient_share: float | None = None,
    seed: int | None = None,
) -> dict:
    path = ROOT / "sweeps" / f"{name}.yaml"
    config = read_yaml(path, what="design problem file")
    problem = load_design_problem(path)
    settings = parse_hybrid(str(path), config.get("hybrid"))
    if max_seconds is not None:
        settings = dataclasses.replace(settings, max_seconds=max_seconds)
    if population is not None:
        settings = dataclasses.replace(settings, population=population)
    if tolerance is not None:
        settings = dataclasses.replace(settings, tolerance=tolerance)
    if generations is not None:
        settings = dataclasses.replace(settings, generations=generations)
    if jacobian is not None:
        settings = dataclasses.replace(settings, jacobian=jacobian)
    if gradient_share is not None:
        settings = dataclasses.replace(settings, gradient_share=gradient_share)
    if seed is not None:
        settings = dataclasses.replace(settings, seed=seed)
    print(f"== {name}: {len(problem.variables)} variables, objectives {', '.join(problem.objectives)}", flush=True)
    print(f"  load average {' '.join(f'{v:.1f}' for v in os.getloadavg())}", flush=True)
    cpu = cpu_seconds()
    hybrid = hybrid_search(problem, settings)
    hybrid_cpu = cpu_seconds() - cpu
    reference = hybrid.extra["reference_point"]
    hybrid_wall = hybrid.compile_seconds + hybrid.run_seconds
    print(
        f"  hybrid: compile {hybrid.compile_seconds:.1f} s, run {hybrid.run_seconds:.1f} s, "
        f"{hybrid.evaluations} evaluations, {hybrid.extra['generations']} generations, {hybrid.extra['jacobian']} J ({hybrid.extra['stop_reason']}), "
        f"{hybrid_cpu:.1f} CPU s",
        flush=True,
    )
    nsga_population = int((problem.nsga2 or {}).get("population", settings.population))
    charged = hybrid.extra["compile_seconds_by_program"]["value"] if nsga_population == settings.population else 0.0
    tic, cpu = time.perf_counter(), cpu_seconds()
    nsga = nsga2_search(
        problem,
        population=nsga_population,
        evaluations=10**12,
        seed=0,
        time_limit=max(factor * hybrid_wall - charged, 1e-3),
        reference=reference,
    )
    nsga.compile_seconds = max(nsga.compile_seconds, charged)
    print(
        f"  nsga2: compile {nsga.compile_seconds:.1f} s, run {nsga.run_seconds:.1f} s, {nsga.evaluations} "
        f"evaluations ({time.perf_counter() - tic:.1f} s, {cpu_seconds() - cpu:.1f} CPU s)",
        flush=True,
    )
    best = hypervolume(np.concatenate([hybrid.objectives, nsga.objectives]), reference)
    target = nsga.checkpoints[-1]["hypervolume"]
    hybrid_to, nsga_to = wall_to(hybrid, target), wall_to(nsga, target)
    hybrid_hv = hybrid.checkpoints[-1]["hypervolume"]
    row = dict(
        problem=name,
        nsga2_final=target,
        hybrid_final=hybrid_hv,
        hybrid_wall=hybrid_wall,
        nsga2_wall=nsga.compile_seconds + nsga.run_seconds,
        hybrid_to=hybrid_to,
        nsga2_to=nsga_to,
        ratio=None if hybrid_to is None or not nsga_to else hybrid_to / nsga_to,
        hybrid_share=hybrid_hv / best,
        nsga2_share=target / best,
        nsga2_at_hybrid_wall=nsga.hypervolume_at(hybrid_wall - nsga.compile_seconds),
    )
    row["met"] = hybrid_hv >= target and row["hybrid_share"] >= 0.995
    print(
        f"  NSGA-II final hypervolume {target:.8g} after {row['nsga2_wall']:.1f} s wall "
        f"({row['nsga2_wall'] / hybrid_wall:.2f}x the hybrid's {hybrid_wall:.1f} s)"
    )
    print(
        f"  wall time to reach it: hybrid {show(hybrid_to)}, NSGA-II {show(nsga_to)}, ratio hybrid/NSGA-II "
        f"{show(row['ratio'], '')}"
    )
    print(
        f"  hybrid final hypervolume {hybrid_hv:.10g}, best known {best:.10g}\n"
        f"  share of best known: hybrid {row['hybrid_share']:.5%}, NSGA-II {row['nsga2_share']:.5%}; NSGA-II at "
        f"the hybrid's wall time {row['nsga2_at_hybrid_wall'] / best:.5%}; target met: {row['met']}",
        flush=True,
    )
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("problems", nargs="*", default=list(PROBLEMS), help="shipped problem names (sweeps/NAME.yaml)")
    parser.add_argument("--max-seconds", type=float, default=None, help="cap the hybrid's run time (s)")
    parser.add_argument("--population", type=int, default=None, help="the hybrid's population (default: the file's)")
    parser.add_argument("--tolerance", type=float, default=None, help="the hybrid's stopping tolerance")
    parser.add_argument("--generations", type=int, default=None, help="the hybrid's most generations")
    parser.add_argument("--jacobian", choices=JACOBIANS, default=None, help="the hybrid's design-space gradients")
    parser.add_argument("--gradient-share", type=float, default=None, help="the hybrid's stepping share")
    parser.add_argument("--seed", type=int, default=None, help="the hybrid's seed (default: the file's)")
    parser.add_argument("--factor", type=float, default=3.0, help="NSGA-II's wall time / the hybrid's (default 3)")
    args = parser.parse_args()
    rows = [
        bench(
            name,
            args.max_seconds,
            args.population,
            args.factor,
            args.tolerance,
            args.generations,
            args.jacobian,
            args.gradient_share,
            args.seed,
        )
        for name in args.problems
    ]
    print("\nproblem              NSGA-II end HV   hybrid/best  NSGA-II/best  hybrid wall  to NSGA-II end  ratio  met")
    for row in rows:
        print(
            f"{row['problem']:<20}{row['nsga2_final']:>15.8g}{row['hybrid_share']:>13.4%}{row['nsga2_share']:>14.4%}"
            f"{row['hybrid_wall']:>11.1f} s{show(row['hybrid_to']):>16}{show(row['ratio'], ''):>7}  {row['met']}"
        )


if __name__ == "__main__":
    main()
