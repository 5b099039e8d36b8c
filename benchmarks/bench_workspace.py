"""Straight-Path workspaces: 1,000 initial postures x 360 directions in one batch (Table 1 robot).

Prints compile time apart from run time, paths/s, and the ratio against a SciPy
``solve_ivp`` (DOP853 with a terminal event at det J* = 0) loop over a random subset
of the same paths, measured in the same run; then the Area 3 / Area 5 numbers that
the batch yields (sec. 3.2), beside the closed forms.

    /work/venv/bin/python benchmarks/bench_workspace.py [--postures 1000] [--directions 360] [--scipy 200]
"""

from __future__ import annotations

import argparse
import time

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)

from bench_motion import scipy_straight

import spacearm as sa
from spacearm import paper
from spacearm.paper import straight_workspace as spw


def scipy_straight_path(coeffs, phi_start, direction, max_arc=60.0, rtol=1e-10, atol=1e-12):
    """End posture of the SciPy reference straight path (the motion benchmark's baseline)."""
    return scipy_straight(coeffs, phi_start, direction, rtol=rtol, atol=atol, max_arc=max_arc)[:3]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--postures", type=int, default=1000)
    parser.add_argument("--directions", type=int, default=360)
    parser.add_argument("--scipy", type=int, default=200, help="paths in the SciPy baseline subset")
    args = parser.parse_args()

    robot = sa.umetani1990()
    phis = paper.random_joint_postures(robot, args.postures, seed=0)
    n_paths = args.postures * args.directions
    print(f"{args.postures} postures x {args.directions} directions = {n_paths} straight tip paths, {jax.devices()[0]}")

    # straight_path_ends is a plain function over the compiled straight_tip_path: the first
    # call compiles and runs, the second only runs; compile time = their difference.
    t0 = time.perf_counter()
    jax.block_until_ready(spw.straight_path_ends(robot, phis, args.directions))
    t_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    ends = jax.block_until_ready(spw.straight_path_ends(robot, phis, args.directions))
    t_run = time.perf_counter() - t0
    t_compile = max(t_first - t_run, 0.0)
    steps = np.asarray(ends.steps)
    print(
        f"JAX   compile {t_compile:7.2f} s   run {t_run:7.2f} s   {n_paths / t_run:9.0f} paths/s"
        f"   (steps per path mean {steps.mean():.0f}, max {steps.max()})"
    )

    # SciPy baseline on a random subset of the same paths.
    rng = np.random.default_rng(1)
    pick = rng.choice(n_paths, size=args.scipy, replace=False)
    p_idx, d_idx = np.unravel_index(pick, (args.postures, args.directions))
    directions = np.asarray(paper.evenly_spaced_directions(args.directions))
    c = sa.design_coefficients(robot)
    coeffs = (np.asarray(c.tip), np.asarray(c.inertia_coupling), np.asarray(c.inertia))
    t0 = time.perf_counter()
    reference = np.array(
        [scipy_straight_path(coeffs, phis[p], directions[d]) for p, d in zip(p_idx, d_idx, strict=False)]
    )
    t_scipy = time.perf_counter() - t0
    scipy_rate = args.scipy / t_scipy
    print(f"SciPy solve_ivp DOP853 (rtol 1e-10), {args.scipy} paths: {t_scipy:7.2f} s   {scipy_rate:9.0f} paths/s")
    print(f"ratio JAX / SciPy (run time): {n_paths / t_run / scipy_rate:8.1f}x")
    tip_jax = np.asarray(ends.end_tip)[p_idx, d_idx]
    tip_ref = np.asarray(sa.tip_position(robot, reference))
    gap = np.linalg.norm(tip_jax - tip_ref, axis=-1)
    print(
        f"end-point agreement with SciPy: median {np.median(gap):.1e} m, 99% {np.quantile(gap, 0.99):.1e} m, max {gap.max():.1e} m"
    )

    print("\nArea 3 (union) and Area 5 (intersection) of the Straight-Path Workspaces in this batch:")
    study = paper.summarize_straight_paths(robot, phis, ends)
    for key, value in study.items():
        print(f"  {key:48s} {value}")


if __name__ == "__main__":
    main()
