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

import spacearm as sa  # noqa: E402
from spacearm import workspace as ws  # noqa: E402


def scipy_straight_path(coeffs, phi_start, direction, max_arc=60.0, rtol=1e-10, atol=1e-12):
    """Reference straight tip path for n = 2 in NumPy + solve_ivp.

    The same regularized formulation as the package (joint-space arc length sigma as
    the variable, joint direction adj(J*) d, base from eq. 5, tip advance
    ds/dsigma = det J* / |adj(J*) d|), with a terminal event where ds/dsigma = 0.
    """
    from scipy.integrate import solve_ivp

    K, W, inertia = coeffs
    dx, dy = direction

    def columns(phi):
        theta = np.cumsum(phi)
        c, s = np.cos(theta), np.sin(theta)
        xs = -np.cumsum((K * s)[::-1])[::-1]
        ys = np.cumsum((K * c)[::-1])[::-1]
        h = inertia + np.sum(W * (np.outer(c, c) + np.outer(s, s)), axis=0)
        H = np.cumsum(h[::-1])[::-1]
        gx = xs[1:] - xs[0] * H[1:] / H[0]
        gy = ys[1:] - ys[0] * H[1:] / H[0]
        return gx, gy, H

    gx, gy, _ = columns(phi_start)
    sign0 = -1.0 if gx[0] * gy[1] - gx[1] * gy[0] < 0 else 1.0

    def field(_, y):
        gx, gy, H = columns(y[:3])
        det = gx[0] * gy[1] - gx[1] * gy[0]
        v = sign0 * np.array([gy[1] * dx - gx[1] * dy, -gy[0] * dx + gx[0] * dy])
        norm = np.hypot(*v)
        dq = v / norm
        return [-(H[1] * dq[0] + H[2] * dq[1]) / H[0], dq[0], dq[1], sign0 * det / norm]

    def singular(_, y):
        return field(0.0, y)[3]

    singular.terminal = True
    singular.direction = -1
    sol = solve_ivp(field, (0.0, max_arc), np.r_[phi_start, 0.0], method="DOP853", rtol=rtol, atol=atol, events=singular)
    return sol.y[:3, -1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--postures", type=int, default=1000)
    parser.add_argument("--directions", type=int, default=360)
    parser.add_argument("--scipy", type=int, default=200, help="paths in the SciPy baseline subset")
    args = parser.parse_args()

    robot = sa.umetani1990()
    phis = ws.random_joint_postures(robot, args.postures, seed=0)
    n_paths = args.postures * args.directions
    print(f"{args.postures} postures x {args.directions} directions = {n_paths} straight tip paths, {jax.devices()[0]}")

    t0 = time.perf_counter()
    compiled = ws._straight_path_ends.lower(robot, phis, args.directions, ()).compile()
    t_compile = time.perf_counter() - t0
    t0 = time.perf_counter()
    ends = jax.block_until_ready(compiled(robot, phis))
    t_run = time.perf_counter() - t0
    steps = np.asarray(ends.steps)
    print(f"JAX   compile {t_compile:7.2f} s   run {t_run:7.2f} s   {n_paths / t_run:9.0f} paths/s"
          f"   (steps per path mean {steps.mean():.0f}, max {steps.max()})")

    # SciPy baseline on a random subset of the same paths.
    rng = np.random.default_rng(1)
    pick = rng.choice(n_paths, size=args.scipy, replace=False)
    p_idx, d_idx = np.unravel_index(pick, (args.postures, args.directions))
    directions = np.asarray(ws.evenly_spaced_directions(args.directions))
    c = sa.design_coefficients(robot)
    coeffs = (np.asarray(c.tip), np.asarray(c.inertia_coupling), np.asarray(c.inertia))
    t0 = time.perf_counter()
    reference = np.array([scipy_straight_path(coeffs, phis[p], directions[d]) for p, d in zip(p_idx, d_idx)])
    t_scipy = time.perf_counter() - t0
    scipy_rate = args.scipy / t_scipy
    print(f"SciPy solve_ivp DOP853 (rtol 1e-10), {args.scipy} paths: {t_scipy:7.2f} s   {scipy_rate:9.0f} paths/s")
    print(f"ratio JAX / SciPy (run time): {n_paths / t_run / scipy_rate:8.1f}x")
    tip_jax = np.asarray(ends.end_tip)[p_idx, d_idx]
    tip_ref = np.asarray(sa.tip_position(robot, reference))
    gap = np.linalg.norm(tip_jax - tip_ref, axis=-1)
    print(f"end-point agreement with SciPy: median {np.median(gap):.1e} m, 99% {np.quantile(gap, 0.99):.1e} m, max {gap.max():.1e} m")

    print("\nArea 3 (union) and Area 5 (intersection) of the Straight-Path Workspaces in this batch:")
    study = ws.summarize_straight_paths(robot, phis, ends)
    for key, value in study.items():
        print(f"  {key:48s} {value}")


if __name__ == "__main__":
    main()
