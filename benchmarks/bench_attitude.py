"""10^4 closed joint loops of the UR5 on its 500 kg smallsat: the bus attitude in one batch.

spacearm: ``sa.integrate_joint_path(robot, q0, loops)`` on all loops at once (6th-order
Magnus, steps from the segment lengths), jitted once; compile time reported apart, run
time best of ``--repeats`` warm calls.

Baseline: SciPy's ``solve_ivp`` (DOP853) looping over the paths, one call per straight
segment, on a single-path right-hand side R' = R [C_w(q) q']x whose C_w comes from the
same kernel jitted for one posture (compiled once, outside the timing); tolerances
chosen so that its error against the converged reference is at the level of
spacearm's. The baseline runs ``--scipy`` paths; its time is scaled to all paths.

Both are checked against a converged reference (Magnus 6 with 64 steps per segment;
it agrees with DOP853 at rtol 1e-13 to ~1e-14 rad, benchmarks/attitude_schemes.py).

Run: PYTHONPATH=src python benchmarks/bench_attitude.py [--paths 10000] [--scipy 20]
"""

from __future__ import annotations

import argparse
import functools
import os
import time

import jax

jax.config.update("jax_enable_x64", True)

import itertools

import jax.numpy as jnp
import numpy as np
from scipy.integrate import solve_ivp

import spacearm as sa
from spacearm.motion import attitude

HERE = os.path.dirname(os.path.abspath(__file__))
ROBOT = os.path.join(HERE, "..", "configs", "ur5-smallsat.yaml")


def ellipse_loops(rng, count, n, segments=16, low=0.5, high=1.5):
    """``(count, segments + 1, n)`` closed loops: ellipses through q0 in random joint 2-planes."""
    q0 = rng.uniform(-2.0, 2.0, (count, n))
    basis = np.linalg.qr(rng.normal(size=(count, n, 2)))[0]
    axes = rng.uniform(low, high, (count, 2))
    theta = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    plane = np.stack([axes[:, None, 0] * (np.cos(theta) - 1.0), axes[:, None, 1] * np.sin(theta)], -1)
    loops = q0[:, None, :] + np.einsum("cnk,csk->csn", basis, plane)
    loops[:, -1] = q0
    return loops


def scipy_path(omega, waypoints, rtol, atol):
    """Bus attitude over one path by solve_ivp, one call per straight segment."""

    def rhs(t, y, a, d):
        w = np.asarray(omega(a + t * d)) @ d
        R = y.reshape(3, 3)
        return (R @ np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])).ravel()

    R = np.eye(3)
    evaluations = 0
    for a, b in itertools.pairwise(waypoints):
        sol = solve_ivp(rhs, (0.0, 1.0), R.ravel(), method="DOP853", rtol=rtol, atol=atol, args=(a, b - a))
        R = sol.y[:, -1].reshape(3, 3)
        evaluations += sol.nfev
    u, _, vt = np.linalg.svd(R)
    return u @ vt, evaluations


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--paths", type=int, default=10_000)
    parser.add_argument("--scipy", type=int, default=20, help="paths run by the SciPy baseline")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--rtol", type=float, default=1e-12, help="SciPy DOP853 rtol (atol = rtol / 10)")
    args = parser.parse_args()

    robot = sa.load_robot(ROBOT)
    loops = ellipse_loops(np.random.default_rng(2026), args.paths, robot.n_joints)
    q0 = loops[:, 0]
    steps = attitude.choose_steps(loops, None)

    start = time.perf_counter()
    R_end, _ = sa.integrate_joint_path(robot, q0, loops)
    jax.block_until_ready(R_end)
    first = time.perf_counter() - start
    best = np.inf
    for _ in range(args.repeats):
        start = time.perf_counter()
        jax.block_until_ready(sa.integrate_joint_path(robot, q0, loops)[0])
        best = min(best, time.perf_counter() - start)
    compile_seconds = first - best

    reference_paths = loops[: max(args.scipy, 200)]
    reference = jax.jit(
        functools.partial(attitude.path_rotation, functools.partial(attitude.bus_rate_map, robot), steps=64)
    )(jnp.asarray(reference_paths))
    spacearm_error = float(jnp.max(attitude.geodesic_distance(R_end[: len(reference_paths)], reference)))

    omega = jax.jit(functools.partial(attitude.bus_rate_map, robot))
    jax.block_until_ready(omega(jnp.asarray(q0[0])))  # compiled once, outside the timing
    scipy_errors, evaluations = [], 0
    start = time.perf_counter()
    for path in loops[: args.scipy]:
        R, count = scipy_path(omega, path, args.rtol, args.rtol / 10)
        scipy_errors.append(R)
        evaluations += count
    scipy_seconds = time.perf_counter() - start
    scipy_error = float(
        jnp.max(attitude.geodesic_distance(jnp.asarray(np.array(scipy_errors)), reference[: args.scipy]))
    )
    scipy_all = scipy_seconds / args.scipy * args.paths

    segments = loops.shape[1] - 1
    print(
        f"UR5 on a 500 kg smallsat, {args.paths} closed loops of {segments} straight joint segments; "
        f"{jax.device_count()} device(s), {os.cpu_count()} CPU(s), float64"
    )
    print(
        f"spacearm  Magnus 6, {steps} steps/segment ({3 * steps * segments} C_w evaluations/loop): "
        f"compile {compile_seconds:.2f} s, run {best:.3f} s (best of {args.repeats}) = "
        f"{args.paths / best:,.0f} loops/s; max error {spacearm_error:.1e} rad"
    )
    print(
        f"SciPy     solve_ivp DOP853 rtol {args.rtol:g}, {args.scipy} loops: {scipy_seconds:.2f} s "
        f"({evaluations / args.scipy:.0f} RHS evaluations/loop) -> {scipy_all:.1f} s for {args.paths}; "
        f"max error {scipy_error:.1e} rad"
    )
    print(f"speed-up {scipy_all / best:.0f}x (warm run against warm run)")


if __name__ == "__main__":
    main()
