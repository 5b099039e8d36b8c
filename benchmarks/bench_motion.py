"""Motion integrators, measured fairly: every method compiled once, on the same paths.

Two problems, each on the same batch of paths for every JAX method (``--paths``, default
10^4), with the accuracy of each method against a converged reference:

1. cyclic joint loops (Table 1 robot, random rectangles in joint space, 4 segments of up
   to 1.5 rad each): ``integrate_joint_path`` (Gauss-Legendre line integral of eq. 5) for
   several rules (nodes per panel x panels per segment), against diffrax (Dopri8 and
   Tsit5, PID step control) integrating the same base rate, one ODE per loop (jumps at
   the corners) or one per segment, at several tolerances; the same on long closed
   paths (3 segments, every joint turning up to 2 pi per segment);
2. straight tip paths (random initial postures x random directions, to the singular
   end): ``straight_tip_path`` (DOP853 with embedded error control and Newton event
   steps in one ``lax.while_loop``, lane refill) against diffrax (Dopri8 / Tsit5 + PID
   controller + ``Event`` with an optimistix bisection root find) on the same regularized
   ODE with the same step cap and step budget, and against fixed steps (RK4, DOP853
   with the error control off), at several tolerances.

How each JAX method is timed: the function is wrapped in ``jax.jit`` once, outside any
timed region, and compiled ahead of time (``.lower(...).compile()``; the design, the
paths and the tolerance are arguments, so nothing is folded into the program). The
compile time is reported apart; the first call of the compiled program is reported
apart too; the run time is the best of ``--repeats`` further warm calls, taken in
interleaved rounds over all the methods of a problem (a shared machine's load changes
during the run; every method gets the same chances).

SciPy (``solve_ivp`` DOP853, a Python loop over paths, no batching and no compile) runs
on the first ``--scipy`` of the same paths; its per-path time is extrapolated.

    /work/venv/bin/python benchmarks/bench_motion.py [--paths 10000] [--scipy 100] [--repeats 3]
"""

from __future__ import annotations

import argparse
import time

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

import itertools

import spacearm as sa
from spacearm import motion
from spacearm.motion import joint_paths, straight_paths

ROWS: list[dict] = []


# Timing ------------------------------------------------------------------------------------


class Tasks:
    """Compiled programs of one problem, timed in interleaved rounds.

    Each program is ``jax.jit``-ed once and compiled ahead of time (timed apart); each
    task (a program with its arguments, e.g. one tolerance) is called once (the first
    call, reported apart), then every task is timed once per round, for ``repeats``
    rounds, and the best warm call is kept. Interleaving gives every method the same
    chances on a shared machine whose load changes during the run.
    """

    def __init__(self, problem, size):
        self.problem, self.size, self.tasks = problem, size, []

    def compile(self, fn, *args):
        start = time.perf_counter()
        compiled = jax.jit(fn).lower(*args).compile()
        return compiled, time.perf_counter() - start

    def add(self, method, tolerance, compiled, call_args, compile_s, describe):
        """``describe(out) -> (err_max, err_med, work, note)``; compile_s None when shared."""
        self.tasks.append(
            dict(
                method=method,
                tolerance=tolerance,
                compiled=compiled,
                args=call_args,
                compile=compile_s,
                describe=describe,
            )
        )

    def run(self, repeats):
        for task in self.tasks:
            start = time.perf_counter()
            task["out"] = jax.block_until_ready(task["compiled"](*task["args"]))
            task["first"] = time.perf_counter() - start
            task["best"] = np.inf
        for _ in range(repeats):
            for task in self.tasks:
                start = time.perf_counter()
                jax.block_until_ready(task["compiled"](*task["args"]))
                task["best"] = min(task["best"], time.perf_counter() - start)
        for task in self.tasks:
            row(
                self.problem,
                task["method"],
                task["tolerance"],
                self.size,
                task["compile"],
                task["first"],
                task["best"],
                repeats,
                *task["describe"](task["out"]),
            )
            del task["out"], task["compiled"]


def row(problem, method, tolerance, size, compile_s, first, run, calls, err_max, err_med, work, note=""):
    entry = dict(
        problem=problem,
        method=method,
        tolerance=tolerance,
        size=size,
        compile=compile_s,
        first=first,
        run=run,
        calls=calls,
        rate=size / run,
        err_max=err_max,
        err_med=err_med,
        work=work,
        note=note,
    )
    ROWS.append(entry)
    compile_text = "-" if compile_s is None else f"{compile_s:6.1f} s"
    first_text = "-" if first is None else f"{first:7.3f} s"
    print(
        f"  {method:<46} {tolerance:>9}  compile {compile_text}  first {first_text}  "
        f"run {run:8.3f} s (best of {calls})  {size / run:>9,.0f}/s  err max {err_max:.1e} med {err_med:.1e}"
        f"  {work}{'  ' + note if note else ''}",
        flush=True,
    )
    return entry


# NumPy model for the SciPy baselines ------------------------------------------------------------


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
        [
            np.zeros((count, 2)),
            np.stack([a, 0 * a], -1),
            np.stack([0 * a, b], -1),
            np.stack([-a, 0 * a], -1),
            np.stack([0 * a, -b], -1),
        ],
        axis=1,
    )
    waypoints = start[:, None, :] + np.cumsum(steps, axis=1)
    phi_start = np.concatenate([np.zeros((count, 1)), start], axis=-1)
    return phi_start, waypoints


def scipy_loop(model, waypoints, rtol=1e-10, atol=1e-12):
    from scipy.integrate import solve_ivp

    total = 0.0
    for start, end in itertools.pairwise(waypoints):
        step = end - start

        def rate(t, y, start=start, step=step):
            _, _, H = numpy_columns(model, np.r_[0.0, start + t * step])
            return [-(H[1:] @ step) / H[0]]

        sol = solve_ivp(rate, (0.0, 1.0), [0.0], method="DOP853", rtol=rtol, atol=atol)
        total += sol.y[0, -1]
    return total


def diffrax_loops(solver_name, per_segment, max_steps=4096):
    """The base rate along each loop as an ODE, for jit: (robot, phi_start, waypoints, rtol) -> ...

    ``per_segment``: one ODE per straight segment on t in [0, 1], vmapped over loops and
    segments; otherwise one ODE per loop in t in [0, k-1] with the corners as jumps.
    Returns (phi0 at the end (P,), steps per loop (P,), all solves successful (P,)).
    """
    import diffrax

    solver = getattr(diffrax, solver_name)()

    def run(robot, phi_start, waypoints, rtol):
        controller = diffrax.PIDController(rtol=rtol, atol=rtol)

        def segment(start, step):
            def rate(t, y, args):
                i_s, i_m = sa.momentum_inertias(robot, jnp.concatenate([jnp.zeros(1), start + t * step]))
                return -(i_m @ step) / i_s

            sol = diffrax.diffeqsolve(
                diffrax.ODETerm(rate),
                solver,
                0.0,
                1.0,
                0.1,
                jnp.zeros(()),
                stepsize_controller=controller,
                max_steps=max_steps,
                throw=False,
            )
            return sol.ys[-1], sol.stats["num_steps"], sol.result == diffrax.RESULTS.successful

        def loop(phi, wp):
            k = wp.shape[0]

            def rate(t, y, args):
                j = jnp.clip(jnp.floor(t).astype(jnp.int32), 0, k - 2)
                step = wp[j + 1] - wp[j]
                q = wp[j] + (t - j) * step
                i_s, i_m = sa.momentum_inertias(robot, jnp.concatenate([jnp.zeros(1), q]))
                return -(i_m @ step) / i_s

            clipped = diffrax.ClipStepSizeController(controller, jump_ts=jnp.arange(1.0, k - 1.0))
            sol = diffrax.diffeqsolve(
                diffrax.ODETerm(rate),
                solver,
                0.0,
                k - 1.0,
                0.1,
                phi[0],
                stepsize_controller=clipped,
                max_steps=max_steps,
                throw=False,
            )
            return sol.ys[-1], sol.stats["num_steps"], sol.result == diffrax.RESULTS.successful

        if per_segment:
            starts, steps = waypoints[:, :-1], waypoints[:, 1:] - waypoints[:, :-1]
            values, counts, ok = jax.vmap(jax.vmap(segment))(starts, steps)
            return phi_start[:, 0] + jnp.sum(values, -1), jnp.sum(counts, -1), jnp.all(ok, -1)
        return jax.vmap(loop)(phi_start, waypoints)

    return run


def long_paths(rng, count, span=2 * np.pi):
    """start -> start + u1 -> start + u2 -> start, u uniform in +-span/2 per joint: segments up to ``span``."""
    start = rng.uniform(-np.pi, np.pi, (count, 1, 2))
    middle = start + rng.uniform(-span / 2, span / 2, (count, 2, 2))
    waypoints = np.concatenate([start, middle, start], axis=1)
    phi_start = np.concatenate([np.zeros((count, 1)), start[:, 0]], axis=-1)
    return phi_start, waypoints


def bench_loops(args, rng, robot, model, long=False):
    count = args.paths
    phi_start, waypoints = (long_paths if long else random_loops)(rng, count)
    phi_start, waypoints = jnp.asarray(phi_start), jnp.asarray(waypoints)
    problem = "long" if long else "loops"
    reference = np.asarray(sa.integrate_joint_path(robot, phi_start, waypoints, nodes=40, pieces=64)[0])
    check = np.asarray(sa.integrate_joint_path(robot, phi_start, waypoints, nodes=64, pieces=64)[0])
    segments = waypoints.shape[1] - 1
    segment_max = float(np.max(np.abs(np.diff(np.asarray(waypoints), axis=1))))
    title = "long closed paths" if long else "cyclic loops (rectangles)"
    print(f"\n[{title}: {count} paths x {segments} segments (<= {segment_max:.2f} rad per joint), Table 1 robot]")
    print(
        f"  reference: Gauss-Legendre 40 x 64 per segment (agrees with 64 x 64 to "
        f"{np.max(np.abs(reference - check)):.0e} rad); |phi0 change| up to {np.max(np.abs(reference)):.2f} rad"
    )

    def errors(values):
        err = np.abs(np.asarray(values) - reference)
        return float(err.max()), float(np.median(err))

    # The default picks its panels from the longest segment of the concrete batch (inside
    # a jit the waypoints are traced and it would take 8): resolve it here, outside.
    auto = joint_paths._default_pieces(waypoints, None)
    rules = [(24, auto, f"GL default: 24 nodes x {auto} panel(s) (auto)"), (24, 8, "GL 24 x 8 (former default)")]
    extra = [(24, 2), (16, 4), (16, 2)] if long else [(16, 1), (12, 1), (10, 1), (8, 1)]
    rules += [(n, p, f"GL {n} x {p}") for n, p in extra if (n, p) != (24, auto)]
    tasks = Tasks(problem, count)
    for nodes, pieces, label in rules:

        def fn(robot, phi, wp, nodes=nodes, pieces=pieces):
            return sa.integrate_joint_path(robot, phi, wp, nodes=nodes, pieces=pieces)[0]

        compiled, compile_s = tasks.compile(fn, robot, phi_start, waypoints)
        tasks.add(
            label,
            "-",
            compiled,
            (robot, phi_start, waypoints),
            compile_s,
            lambda values, work=f"{nodes * pieces} rate evals/segment": (*errors(values), work),
        )

    if long:
        variants = (("Dopri8", True, (1e-10, 1e-12, 1e-14)),)
    else:
        variants = (
            ("Dopri8", True, (1e-8, 1e-10, 1e-12, 1e-14)),
            ("Dopri8", False, (1e-8, 1e-10, 1e-12, 1e-14)),
            ("Tsit5", True, (1e-8, 1e-10, 1e-12)),
            ("Tsit5", False, (1e-8, 1e-10, 1e-12)),
        )
    for solver_name, per_segment, tolerances in variants:
        compiled, compile_s = tasks.compile(
            diffrax_loops(solver_name, per_segment), robot, phi_start, waypoints, jnp.asarray(1e-8)
        )
        stages = {"Dopri8": 12, "Tsit5": 6}[solver_name]
        layout = "per segment" if per_segment else "per loop, corners as jumps"

        def describe(out, stages=stages):
            values, steps, ok = out
            per = np.mean(steps) / segments
            note = "" if np.all(ok) else f"{int(np.sum(~np.asarray(ok)))} failed"
            return (*errors(values), f"{per:.1f} steps/segment (~{stages * per:.0f} rate evals)", note)

        for rtol in tolerances:
            # one compiled program for every tolerance (rtol is an argument)
            tasks.add(
                f"diffrax {solver_name} PID, {layout}",
                f"rtol {rtol:.0e}",
                compiled,
                (robot, phi_start, waypoints, jnp.asarray(rtol)),
                compile_s,
                describe,
            )
            compile_s = None  # reported once per compiled program
    tasks.run(args.repeats)

    if long:
        return
    subset = min(args.scipy, count)
    scipy_loop(model, np.asarray(waypoints[0]))  # imports and warms SciPy outside the timed region
    start = time.perf_counter()
    scipy_values = np.array([scipy_loop(model, np.asarray(waypoints[i])) for i in range(subset)])
    per_loop = (time.perf_counter() - start) / subset
    err = np.abs(scipy_values - reference[:subset])
    row(
        problem,
        f"SciPy solve_ivp DOP853 loop ({subset} loops)",
        "rtol 1e-10",
        count,
        None,
        None,
        per_loop * count,
        1,
        float(err.max()),
        float(np.median(err)),
        "extrapolated from the subset",
    )


# Straight paths ----------------------------------------------------------------------------


def scipy_straight(model, phi_start, direction, rtol=1e-10, atol=1e-12, max_arc=60.0, max_step=0.25):
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
    sol = solve_ivp(
        field,
        (0.0, max_arc),
        np.r_[phi_start, 0.0],
        method="DOP853",
        rtol=rtol,
        atol=atol,
        events=singular,
        max_step=max_step,
    )
    return sol.y[:, -1]


def diffrax_straight(solver_name, max_steps=4096):
    """For jit: (robot, phi_start (P, 3), directions (P, 2), rtol, max_step) -> (states, steps, ok)."""
    import diffrax
    import optimistix as optx

    solver = getattr(diffrax, solver_name)()

    def run(robot, phi_start, directions, rtol, max_step):
        def one(phi, direction):
            direction = direction / jnp.linalg.norm(direction)
            sign0 = straight_paths._initial_sign(robot, phi)
            field = straight_paths._straight_field(robot, direction, sign0)

            def cond(t, y, args, **kwargs):
                return field(y)[-1]

            sol = diffrax.diffeqsolve(
                diffrax.ODETerm(lambda t, y, args: field(y)),
                solver,
                0.0,
                60.0,
                0.05,
                jnp.concatenate([phi, jnp.zeros(1)]),
                stepsize_controller=diffrax.PIDController(rtol=rtol, atol=rtol, dtmax=max_step),
                # Bisection: optx.Newton (rtol = atol = 1e-13 or 1e-10) stops without
                # converging (nonlinear_max_steps_reached) on some grazing ends
                event=diffrax.Event(cond, root_finder=optx.Bisection(rtol=1e-12, atol=1e-12)),
                max_steps=max_steps,
                throw=False,
            )
            ok = (sol.result == diffrax.RESULTS.successful) | (sol.result == diffrax.RESULTS.event_occurred)
            return sol.ys[-1], sol.stats["num_steps"], ok

        return jax.vmap(one)(phi_start, directions)

    return run


def ours_straight(**options):
    def run(robot, phi_start, directions, rtol, max_step):
        p = motion.straight_tip_path(robot, phi_start, directions, rtol=rtol, max_step=max_step, **options)
        state = jnp.concatenate([p.end_posture, p.length[:, None]], -1)
        return state, p.steps, p.reason == motion.REASON_SINGULAR

    return run


def bench_straight(args, rng, robot, model):
    count = args.paths
    q = np.stack([rng.uniform(-np.pi, np.pi, count), rng.uniform(0.3, 2.8, count)], -1)
    phi0 = jnp.asarray(np.concatenate([np.zeros((count, 1)), q], axis=-1))
    angle = rng.uniform(0, 2 * np.pi, count)
    directions = jnp.asarray(np.stack([np.cos(angle), np.sin(angle)], -1))
    converged = motion.straight_tip_path(robot, phi0, directions, max_step=0.02, rtol=1e-14)
    ref_state = np.concatenate([np.asarray(converged.end_posture), np.asarray(converged.length)[:, None]], -1)
    print(f"\n[straight tip paths to the singular end: {count} paths (random postures x directions), Table 1 robot]")
    print(
        f"  reference: spacearm DOP853 max_step 0.02 rtol 1e-14; joint arc up to "
        f"{float(np.max(converged.joint_arc)):.1f} rad, mean {float(np.mean(converged.joint_arc)):.2f} rad; "
        f"error = max over (phi0, phi1, phi2 rad, length m) at the end"
    )
    cap = jnp.asarray(args.max_step)

    def errors(states):
        err = np.max(np.abs(np.asarray(states) - ref_state), axis=-1)
        return float(err.max()), float(np.median(err))

    programs = [
        ("spacearm DOP853 adaptive, 512 lanes + refill (default)", ours_straight(), "rtol", (1e-8, 1e-10, 1e-12)),
        ("spacearm DOP853 adaptive, plain vmap", ours_straight(lanes=count), "rtol", (1e-12,)),
        ("diffrax Dopri8 PID + Event/bisection", diffrax_straight("Dopri8"), "rtol", (1e-8, 1e-10, 1e-12)),
        ("diffrax Tsit5 PID + Event/bisection", diffrax_straight("Tsit5"), "rtol", (1e-8, 1e-10)),
        ("spacearm DOP853 fixed step (error control off)", ours_straight(), "step", (0.05,)),
        ("spacearm RK4 fixed step", ours_straight(tableau="rk4"), "step", (0.02, 0.005)),
    ]

    def describe(out):
        states, steps, ok = out
        notes = [] if np.all(ok) else [f"{int(np.sum(~np.asarray(ok)))} not at a singular end"]
        err = np.max(np.abs(np.asarray(states) - ref_state), axis=-1)
        wrong = err > 1e-6  # ended somewhere else than the reference (e.g. an event stepped over)
        if np.any(wrong):
            notes.append(f"{int(wrong.sum())} wrong ends (> 1e-6), the rest within {err[~wrong].max():.1e}")
        return (*errors(states), f"{np.mean(steps):.1f} steps/path (max {int(np.max(steps))})", "; ".join(notes))

    tasks = Tasks("straight", count)
    for name, fn, kind, values in programs:
        compiled, compile_s = tasks.compile(fn, robot, phi0, directions, jnp.asarray(1e-8), cap)
        for value in values:
            rtol, step = (value, cap) if kind == "rtol" else (1e30, value)
            tolerance = f"rtol {value:.0e}" if kind == "rtol" else f"h {value:g}"
            tasks.add(
                name,
                tolerance,
                compiled,
                (robot, phi0, directions, jnp.asarray(rtol), jnp.asarray(step)),
                compile_s,
                describe,
            )
            compile_s = None
    tasks.run(args.repeats)

    subset = min(args.scipy, count)
    scipy_straight(model, np.asarray(phi0[0]), np.asarray(directions[0]))  # imports SciPy outside the timing
    for rtol, atol in ((1e-10, 1e-12), (1e-12, 1e-14)):
        start = time.perf_counter()
        states = np.array(
            [
                scipy_straight(
                    model, np.asarray(phi0[i]), np.asarray(directions[i]), rtol=rtol, atol=atol, max_step=args.max_step
                )
                for i in range(subset)
            ]
        )
        per_path = (time.perf_counter() - start) / subset
        err = np.max(np.abs(states - ref_state[:subset]), axis=-1)
        row(
            "straight",
            f"SciPy solve_ivp DOP853 + event loop ({subset} paths)",
            f"rtol {rtol:.0e}",
            count,
            None,
            None,
            per_path * count,
            1,
            float(err.max()),
            float(np.median(err)),
            "extrapolated from the subset",
        )


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--paths", type=int, default=10_000, help="paths per batch, the same for every JAX method")
    parser.add_argument("--scipy", type=int, default=100, help="SciPy runs on the first N of the same paths")
    parser.add_argument("--repeats", type=int, default=3, help="timing rounds (best warm call of each method taken)")
    parser.add_argument("--max-step", type=float, default=0.25, help="step cap of every adaptive straight solver")
    parser.add_argument("--only", choices=("loops", "long", "straight"), default=None)
    parser.add_argument("--json", default=None, help="also write the rows to this JSON file")
    args = parser.parse_args()
    robot = sa.umetani1990()
    model = numpy_model(robot)
    print(
        f"device: {jax.devices()[0]} ({jax.device_count()} devices), float64, jax {jax.__version__}, "
        f"{args.paths} paths per batch"
    )
    if args.only in (None, "loops"):
        bench_loops(args, np.random.default_rng(0), robot, model)
    if args.only in (None, "long"):
        bench_loops(args, np.random.default_rng(2), robot, model, long=True)
    if args.only in (None, "straight"):
        bench_straight(args, np.random.default_rng(1), robot, model)
    summary()
    if args.json:
        import json

        with open(args.json, "w") as handle:
            json.dump(ROWS, handle, indent=1)


def summary():
    """The rows as one Markdown table; ratio = run time / run time of the spacearm default on that problem."""
    print(
        "\n| problem | method | tolerance | paths | max error | median error | compile s | warm run s | paths/s "
        "| time / spacearm default |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for entry in ROWS:
        base = next(
            e
            for e in ROWS
            if e["problem"] == entry["problem"]
            and "default" in e["method"]
            and "former" not in e["method"]
            and e["tolerance"] in ("-", "rtol 1e-12")
        )
        compile_text = "-" if entry["compile"] is None else f"{entry['compile']:.1f}"
        print(
            f"| {entry['problem']} | {entry['method']} | {entry['tolerance']} | {entry['size']} "
            f"| {entry['err_max']:.1e} | {entry['err_med']:.1e} | {compile_text} | {entry['run']:.3f} "
            f"| {entry['rate']:,.0f} | {entry['run'] / base['run']:.2f} |"
        )


if __name__ == "__main__":
    main()
