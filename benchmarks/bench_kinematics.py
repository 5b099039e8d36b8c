"""w* over 10^6 postures of the Table 1 robot: JAX vs NumPy vs the sine-cosine bound.

Run: python benchmarks/bench_kinematics.py [--postures 1000000] [--repeats 5]

Prints postures/s for
  * spacearm.manipulability on random postures (jit, float64),
  * the same formulas in vectorized NumPy (baseline),
  * jnp.sin(x) + jnp.cos(x) over (n+1) angles per posture (the transcendental bound),
  * spacearm.manipulability_on_grid on a structured phi1 x phi2 grid (angle addition),
  * the generic path over the family primitives (kinematics.generic_manipulability: J* by
    a solve, w* by Cauchy-Binet) on the same postures, which is what a new robot family
    gets with no closed form,
and the ratios. Compile time is reported apart from run time.
"""

from __future__ import annotations

import argparse
import time

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)
import spacearm as sa
from spacearm import kinematics


def best_time(fn, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        jax.block_until_ready(out)
        times.append(time.perf_counter() - start)
    return min(times)


def numpy_manipulability(K, W, inertia, phi):
    """eq. (1), (2), (5), (6), (10) in plain vectorized NumPy (robot frame, n = 2)."""
    t1 = phi[:, 1]
    t2 = phi[:, 1] + phi[:, 2]
    c = [np.ones_like(t1), np.cos(t1), np.cos(t2)]
    s = [np.zeros_like(t1), np.sin(t1), np.sin(t2)]
    h = []
    for l in range(3):
        total = inertia[l] + W[l, l]
        for k in range(3):
            if k != l:
                total = total + W[k, l] * (c[k] * c[l] + s[k] * s[l])
        h.append(total)
    H = [h[0] + h[1] + h[2], h[1] + h[2], h[2]]
    jx = [-(K[0] * s[0] + K[1] * s[1] + K[2] * s[2]), -(K[1] * s[1] + K[2] * s[2]), -K[2] * s[2]]
    jy = [K[0] * c[0] + K[1] * c[1] + K[2] * c[2], K[1] * c[1] + K[2] * c[2], K[2] * c[2]]
    g1x, g1y = jx[1] - jx[0] * H[1] / H[0], jy[1] - jy[0] * H[1] / H[0]
    g2x, g2y = jx[2] - jx[0] * H[2] / H[0], jy[2] - jy[0] * H[2] / H[0]
    return np.abs(g1x * g2y - g2x * g1y)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--postures", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    N = args.postures
    robot = sa.umetani1990()
    rng = np.random.default_rng(0)
    phi_np = rng.uniform(-np.pi, np.pi, (N, robot.n_links + 1))
    phi = jnp.asarray(phi_np)
    angles = jnp.asarray(rng.uniform(-np.pi, np.pi, N * (robot.n_links + 1)))

    kernel = jax.jit(sa.manipulability)
    start = time.perf_counter()
    compiled = kernel.lower(robot, phi).compile()
    compile_s = time.perf_counter() - start
    jax_s = best_time(lambda: compiled(robot, phi), args.repeats)

    generic = jax.jit(kinematics.generic_manipulability)
    start = time.perf_counter()
    generic_compiled = generic.lower(robot, phi).compile()
    generic_compile_s = time.perf_counter() - start
    generic_s = best_time(lambda: generic_compiled(robot, phi), args.repeats)
    generic_diff = float(jnp.max(jnp.abs(generic_compiled(robot, phi) - compiled(robot, phi))))

    bound = jax.jit(lambda x: jnp.sin(x) + jnp.cos(x))
    bound(angles).block_until_ready()
    bound_s = best_time(lambda: bound(angles), args.repeats)

    coeffs = sa.design_coefficients(robot)
    K, W, inertia = (np.asarray(x) for x in (coeffs.tip, coeffs.inertia_coupling, coeffs.inertia))
    numpy_s = best_time(lambda: numpy_manipulability(K, W, inertia, phi_np), max(1, args.repeats // 2))
    diff = np.max(np.abs(numpy_manipulability(K, W, inertia, phi_np) - np.asarray(compiled(robot, phi))))

    side = int(round(np.sqrt(N)))
    axis1 = jnp.linspace(-np.pi, np.pi, side, endpoint=False)
    axis2 = jnp.linspace(0.0, np.pi, side)
    grid_kernel = jax.jit(lambda r, a, b: sa.manipulability_on_grid(r, [a, b]))
    start = time.perf_counter()
    grid_compiled = grid_kernel.lower(robot, axis1, axis2).compile()
    grid_compile_s = time.perf_counter() - start
    grid_s = best_time(lambda: grid_compiled(robot, axis1, axis2), args.repeats)

    print(f"devices: {jax.devices()}  float64: {jax.config.jax_enable_x64}")
    print(f"postures: {N:,} (n = {robot.n_links}); best of {args.repeats}")
    print(
        f"  spacearm.manipulability  {N / jax_s:14,.0f} postures/s  (compile {compile_s:.2f} s, run {jax_s * 1e3:.1f} ms)"
    )
    print(
        f"  generic path (no closed form) {N / generic_s:9,.0f} postures/s  (compile {generic_compile_s:.2f} s, max |diff| {generic_diff:.1e})"
    )
    print(f"  NumPy, same formulas     {N / numpy_s:14,.0f} postures/s  (max |diff| {diff:.1e})")
    print(f"  sin+cos bound, {robot.n_links + 1} angles  {N / bound_s:14,.0f} postures/s")
    print(
        f"  grid {side}x{side}, angle addition {side * side / grid_s:14,.0f} postures/s  (compile {grid_compile_s:.2f} s)"
    )
    print(f"ratio closed form / generic     {generic_s / jax_s:6.1f}x")
    print(f"ratio generic / NumPy           {numpy_s / generic_s:6.1f}x")
    print(f"ratio spacearm / NumPy          {numpy_s / jax_s:6.1f}x")
    print(f"ratio spacearm / sin-cos bound  {bound_s / jax_s:6.2f}  (target >= 0.5)")
    print(f"ratio bound / NumPy             {numpy_s / bound_s:6.1f}x")
    print(f"ratio grid / sin-cos bound      {bound_s / (grid_s * N / (side * side)):6.2f}  (target > 1)")


if __name__ == "__main__":
    main()
