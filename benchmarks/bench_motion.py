"""Motion integrators: 10^4 cyclic joint loops and 10^4 straight tip paths in one batch.

Prints compile time apart from run time, paths/s, the accuracy against a converged
reference, and ratios against baselines measured in the same run:

1. cyclic loops (Table 1 robot, random rectangles in joint space, 4 segments each):
   ``integrate_joint_path`` (Gauss-Legendre line integral of eq. 5) against a SciPy
   ``solve_ivp`` (DOP853) loop over a subset of the same loops, and against diffrax
   (Dopri8, PID step control) integrating the same base rate in one vmapped call;
2. straight tip paths (random initial postures x random directions, to the singular
   end): ``straight_tip_path`` (DOP853 with embedded error control and Newton event
   steps in one ``lax.while_loop``) against a SciPy ``solve_ivp`` loop with a terminal
   event on the same regularized ODE, against diffrax (Dopri8 / Tsit5 + PID controller
   + ``Event`` with an optimistix Newton root find), and against fixed steps (RK4, and
   DOP853 with the error control off).

The SciPy loops run on a subset (``--scipy``) and are extrapolated per path.

    /work/venv/bin/python benchmarks/bench_motion.py [--paths 10000] [--scipy 100] [--diffrax 1000]
"""

from __future__ import annotations

import argparse
import time

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

import spacearm as sa  # noqa: E402
from spacearm import motion  # noqa: E402

DEG = np.pi / 180.0


def timed(fn, *args, repeats=3, **kwargs):
    """(first-call seconds incl. compile, best run seconds, result)."""
    start = time.perf_counter()
    out = jax.block_until_ready(fn(*args, **kwargs))
    first = time.perf_counter() - start
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        out = jax.block_until_ready(fn(*args, **kwargs))
        best = min(best, time.perf_counter() - start)
    return first, best, out


def numpy_model(robot):
    """Design coefficients as NumPy arrays for the SciPy baselines (computed once)."""
    coeffs = sa.design_coefficients(robot)
    return np.asarray(coeffs.tip), np.asarray(coeffs.inertia_coupling), np.asarray(coeffs.inertia)


def numpy_columns(model, phi):
    K, W, inertia = model
    theta = np.cumsum(phi)
    c, s = np.cos(theta), np.sin(theta)
    xs = -np.cumsum((K * s)[::-1])[::-1]
    ys = np.cumsum((K * c)[::-1])[::-1]
    h = inertia + np.sum(W * (np.outer(c, c) + np.outer(s, s)), axis=0)
    H = np.cumsum(h[::-1])[::-1]
    return xs, ys, H


# Cyclic loops ------------------------------------------------------------------------------


def random_loops(rng, count):
    """Rectangles in (phi1, phi2): start, +a on phi1, +b on phi2, -a, -b (rad)."""
    start = np.stack([rng.uniform(-np.pi, np.pi, count), rng.uniform(0.2, 2.9, count)], -1)
    a = rng.uniform(-1.5, 1.5, count)
    b = rng.uniform(-1.0, 1.0, count)
    steps = np.stack(
        [np.zeros((count, 2)), np.stack([a, 0 * a], -1), np.stack([0 * a, b], -1), np.stack([-a, 0 * a], -1),
         np.stack([0 * a, -b], -1)], axis=1,
    )
    waypoints = start[:, None, :] + np.cumsum(steps, axis=1)
    phi_start = np.concatenate([np.zeros((count, 1)), start], axis=-1)
    return phi_start, waypoints


def scipy_loop(model, waypoints, rtol=1e-10, atol=1e-12):
    from scipy.integrate import solve_ivp

    total = 0.0
    for start, end in zip(waypoints[:-1], waypoints[1:]):
        step = end - start

        def rate(t, y, start=start, step=step):
            _, _, H = numpy_columns(model, np.r_[0.0, start + t * step])
            return [-(H[1:] @ step) / H[0]]

        sol = solve_ivp(rate, (0.0, 1.0), [0.0], method="DOP853", rtol=rtol, atol=atol)
        total += sol.y[0, -1]
    return total


def diffrax_loops(robot, phi_start, waypoints, rtol, solver_name="Dopri8"):
    """The base rate along each loop as an ODE in the path parameter t in [0, k-1]."""
    import diffrax

    solver = getattr(diffrax, solver_name)()

    def one(phi, wp):
        def rate(t, y, args):
            k = jnp.clip(jnp.floor(t).astype(jnp.int32), 0, wp.shape[0] - 2)
            step = wp[k + 1] - wp[k]
            q = wp[k] + (t - k) * step
            i_s, i_m = sa.momentum_inertias(robot, jnp.concatenate([jnp.zeros(1), q]))
            return -(i_m @ step) / i_s

        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(rate), solver, 0.0, wp.shape[0] - 1.0, 0.05, phi[0],
            stepsize_controller=diffrax.PIDController(
                rtol=rtol, atol=rtol, jump_ts=jnp.arange(1.0, wp.shape[0] - 1.0)
            ),
            max_steps=4096,
        )
        return sol.ys[-1], sol.stats["num_steps"]

    return jax.jit(jax.vmap(one))(phi_start, waypoints)


# Straight paths ----------------------------------------------------------------------------


def scipy_straight(model, phi_start, direction, rtol=1e-10, atol=1e-12, max_arc=60.0):
    """The same regularized ODE in joint arc length, solve_ivp DOP853 + terminal event ds/dsigma = 0."""
    from scipy.integrate import solve_ivp

    dx, dy = direction

    def jstar(phi):
        xs, ys, H = numpy_columns(model, phi)
        gx = xs[1:] - xs[0] * H[1:] / H[0]
        gy = ys[1:] - ys[0] * H[1:] / H[0]
        return gx, gy, H

    gx, gy, _ = jstar(phi_start)
    sign0 = -1.0 if gx[0] * gy[1] - gx[1] * gy[0] < 0 else 1.0

    def field(_, y):
        gx, gy, H = jstar(y[:3])
        det = gx[0] * gy[1] - gx[1] * gy[0]
        v = sign0 * np.array([gy[1] * dx - gx[1] * dy, -gy[0] * dx + gx[0] * dy])
        norm = np.hypot(*v)
        dq = v / norm
        return [-(H[1] * dq[0] + H[2] * dq[1]) / H[0], dq[0], dq[1], sign0 * det / norm]

    def singular(_, y):
        return field(0.0, y)[3]

    singular.terminal = True
    singular.direction = -1
    sol = solve_ivp(field, (0.0, max_arc), np.r_[phi_start, 0.0], method="DOP853", rtol=rtol, atol=atol,
                    events=singular)
    return sol.y[:, -1]


def diffrax_straight(robot, phi_start, directions, rtol, solver_name="Dopri8"):
    import diffrax
    import optimistix as optx

    solver = getattr(diffrax, solver_name)()

    def one(phi, direction):
        sign0 = motion._initial_sign(robot, phi)
        field = motion._straight_field(robot, direction, sign0)

        def cond(t, y, args, **kwargs):
            return field(y)[-1]

        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(lambda t, y, args: field(y)), solver, 0.0, 60.0, 0.05,
            jnp.concatenate([phi, jnp.zeros(1)]),
            stepsize_controller=diffrax.PIDController(rtol=rtol, atol=rtol, dtmax=0.1),
            event=diffrax.Event(cond, root_finder=optx.Newton(rtol=1e-13, atol=1e-13)),
            max_steps=4096,
        )
        return sol.ys[-1], sol.stats["num_steps"]

    return jax.jit(jax.vmap(one))(phi_start, directions)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--paths", type=int, default=10_000)
    parser.add_argument("--scipy", type=int, default=100)
    parser.add_argument("--diffrax", type=int, default=1000)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    robot = sa.umetani1990()
    model = numpy_model(robot)
    count = args.paths
    print(f"device: {jax.devices()[0]}, float64, {count} paths per batch")

    # 1. cyclic loops ------------------------------------------------------------------
    phi_start, waypoints = random_loops(rng, count)
    first, run, ends = timed(sa.integrate_joint_path, robot, phi_start, waypoints)
    reference = np.asarray(sa.integrate_joint_path(robot, phi_start, waypoints, nodes=40, pieces=32))[:, 0]
    error = np.max(np.abs(np.asarray(ends)[:, 0] - reference))
    print("\n[cyclic loops, 4 segments each]")
    print(f"  spacearm GL quadrature (default 8 panels x 24 nodes): compile+first {first:.2f} s, run {run:.4f} s, "
          f"{count / run:,.0f} loops/s, max error {error:.1e} rad")
    first_c, run_c, ends_c = timed(sa.integrate_joint_path, robot, phi_start, waypoints, nodes=16, pieces=2)
    error_c = np.max(np.abs(np.asarray(ends_c)[:, 0] - reference))
    print(f"  spacearm GL quadrature (2 panels x 16 nodes): compile+first {first_c:.2f} s, run {run_c:.4f} s, "
          f"{count / run_c:,.0f} loops/s, max error {error_c:.1e} rad")
    subset = rng.choice(count, args.scipy, replace=False)
    start = time.perf_counter()
    scipy_values = np.array([scipy_loop(model, waypoints[i]) for i in subset])
    scipy_time = (time.perf_counter() - start) / args.scipy
    scipy_error = np.max(np.abs(scipy_values - reference[subset]))
    print(f"  SciPy solve_ivp DOP853 (rtol 1e-10) loop: {scipy_time * 1e3:.2f} ms/loop "
          f"({1 / scipy_time:,.0f} loops/s), max error {scipy_error:.1e} rad")
    print(f"  ratio spacearm / SciPy: {scipy_time * count / run:,.0f}x (SciPy timed on {args.scipy} loops)")
    m = min(args.diffrax, count)
    for rtol in (1e-8, 1e-12):
        first_d, run_d, (values, steps) = timed(
            diffrax_loops, robot, phi_start[:m], waypoints[:m], rtol, repeats=1
        )
        err_d = np.max(np.abs(np.asarray(values) - reference[:m]))
        print(f"  diffrax Dopri8 PID rtol {rtol:.0e}: compile+first {first_d:.2f} s, run {run_d:.4f} s "
              f"for {m} ({m / run_d:,.0f} loops/s), mean steps {np.mean(steps):.1f}, max error {err_d:.1e} rad; "
              f"spacearm is {(count / run) / (m / run_d):.1f}x faster per loop")

    # 2. straight tip paths -----------------------------------------------------------
    q = np.stack([rng.uniform(-np.pi, np.pi, count), rng.uniform(0.3, 2.8, count)], -1)
    phi0 = np.concatenate([np.zeros((count, 1)), q], axis=-1)
    angle = rng.uniform(0, 2 * np.pi, count)
    directions = np.stack([np.cos(angle), np.sin(angle)], -1)
    print("\n[straight tip paths to the singular end]")
    converged = motion.straight_tip_path(robot, phi0, directions, max_step=0.02, rtol=1e-14)
    ref_state = np.concatenate([np.asarray(converged.end_posture), np.asarray(converged.length)[:, None]], -1)

    def report(name, first, run, state, steps, size=count):
        err = np.abs(state - ref_state[:size])
        print(f"  {name}: compile+first {first:.2f} s, run {run:.4f} s for {size} "
              f"({size / run:,.0f} paths/s), mean steps {np.mean(steps):.1f}, "
              f"error max {err.max():.1e} / median {np.median(err.max(-1)):.1e}")
        return size / run

    first, run, path = timed(motion.straight_tip_path, robot, phi0, directions)
    ours_rate = report(
        "spacearm DOP853 adaptive (rtol 1e-12)", first, run,
        np.concatenate([np.asarray(path.end_posture), np.asarray(path.length)[:, None]], -1), path.steps,
    )
    print(f"    reasons: {np.bincount(np.asarray(path.reason), minlength=4).tolist()} "
          f"(0 singular, 1 length, 2 limit, 3 budget); kinematic ends: {int(np.sum(path.kinematic))}")
    for rtol in (1e-8,):
        first, run, p = timed(motion.straight_tip_path, robot, phi0, directions, rtol=rtol)
        report(f"spacearm DOP853 adaptive (rtol {rtol:.0e})", first, run,
               np.concatenate([np.asarray(p.end_posture), np.asarray(p.length)[:, None]], -1), p.steps)
    for name, kwargs in (
        ("spacearm DOP853 adaptive, plain vmap (all lanes wait for the longest path)", dict(lanes=count)),
        ("spacearm DOP853 fixed step 0.05", dict(max_step=0.05, rtol=1e30)),
        ("spacearm RK4 fixed step 0.02", dict(max_step=0.02, tableau="rk4")),
        ("spacearm RK4 fixed step 0.005", dict(max_step=0.005, tableau="rk4")),
    ):
        first, run, p = timed(motion.straight_tip_path, robot, phi0, directions, repeats=1, **kwargs)
        report(name, first, run, np.concatenate([np.asarray(p.end_posture), np.asarray(p.length)[:, None]], -1),
               p.steps)

    subset = rng.choice(count, args.scipy, replace=False)
    start = time.perf_counter()
    scipy_states = np.array([scipy_straight(model, phi0[i], directions[i]) for i in subset])
    scipy_time = (time.perf_counter() - start) / args.scipy
    scipy_err = np.abs(scipy_states - ref_state[subset])
    print(f"  SciPy solve_ivp DOP853 + event (rtol 1e-10) loop: {scipy_time * 1e3:.2f} ms/path "
          f"({1 / scipy_time:,.0f} paths/s), error max {scipy_err.max():.1e} / median "
          f"{np.median(scipy_err.max(-1)):.1e}")
    print(f"  ratio spacearm / SciPy: {ours_rate * scipy_time:,.0f}x (SciPy timed on {args.scipy} paths)")
    start = time.perf_counter()
    scipy_states = np.array([scipy_straight(model, phi0[i], directions[i], rtol=1e-12, atol=1e-14) for i in subset])
    scipy_time = (time.perf_counter() - start) / args.scipy
    scipy_err = np.abs(scipy_states - ref_state[subset])
    print(f"  SciPy solve_ivp DOP853 + event (rtol 1e-12) loop: {scipy_time * 1e3:.2f} ms/path, error max "
          f"{scipy_err.max():.1e}; ratio spacearm / SciPy: {ours_rate * scipy_time:,.0f}x")
    m = min(args.diffrax, count)
    for solver_name, rtol in (("Dopri8", 1e-12), ("Tsit5", 1e-10)):
        try:
            first_d, run_d, (states, steps) = timed(
                diffrax_straight, robot, phi0[:m], directions[:m], rtol, solver_name, repeats=1
            )
        except Exception as error:  # noqa: BLE001 - report and go on
            print(f"  diffrax {solver_name}: failed: {type(error).__name__}: {error}")
            continue
        rate = report(f"diffrax {solver_name} PID rtol {rtol:.0e} + Event/Newton", first_d, run_d,
                      np.asarray(states), steps, size=m)
        print(f"    spacearm is {ours_rate / rate:.1f}x faster per path")


if __name__ == "__main__":
    main()
