"""Accuracy against cost of the bus-attitude integrators (docs/explanation/spatial-attitude.md).

UR5 on its 500 kg smallsat (configs/ur5-smallsat.yaml); random closed joint loops
(16 straight segments on an ellipse through q0 in a random 2-plane of joint space,
semi-axes 0.5-1.5 rad, so segments move the joints by up to ~0.6 rad) and random
polylines with large segments (8 segments, every joint moving up to 2 rad per segment).
Reference: 6th-order Magnus with 512 steps per segment, checked against SciPy's
DOP853 on the 9 entries of R at rtol = atol = 1e-13 (independent code).

For each scheme and step count: the largest geodesic error over the paths (rad), C_w
evaluations per segment, and the warm time of one batch of 1,000 loops (compile
excluded, best of 3). Also a quaternion RK4 with normalization after each step
(the non-Lie baseline) and diffrax's Dopri8 on quaternions with a PID controller.

Run: PYTHONPATH=src python benchmarks/attitude_schemes.py
"""

from __future__ import annotations

import functools
import os
import sys
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
    basis = np.linalg.qr(rng.normal(size=(count, n, 2)))[0]  # (count, n, 2) orthonormal pair
    axes = rng.uniform(low, high, (count, 2))
    theta = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    plane = np.stack([axes[:, None, 0] * (np.cos(theta) - 1.0), axes[:, None, 1] * np.sin(theta)], -1)
    loops = q0[:, None, :] + np.einsum("cnk,csk->csn", basis, plane)
    loops[:, -1] = q0  # closed exactly
    return loops


def polylines(rng, count, n, segments=8, step=2.0):
    q0 = rng.uniform(-2.0, 2.0, (count, 1, n))
    moves = rng.uniform(-step, step, (count, segments, n))
    return np.concatenate([q0, q0 + np.cumsum(moves, axis=1)], axis=1)


def scipy_reference(robot, waypoints, rtol=1e-13):
    omega = jax.jit(functools.partial(attitude.bus_rate_map, robot))

    def rhs(t, y, a, d):
        w = np.asarray(omega(a + t * d)) @ d
        R = y.reshape(3, 3)
        return (R @ np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])).ravel()

    R = np.eye(3)
    for a, b in itertools.pairwise(waypoints):
        sol = solve_ivp(rhs, (0.0, 1.0), R.ravel(), method="DOP853", rtol=rtol, atol=rtol, args=(a, b - a))
        R = sol.y[:, -1].reshape(3, 3)
    u, _, vt = np.linalg.svd(R)
    return u @ vt


# The quaternion baseline: q' = q (0, omega) / 2, classical RK4, normalized after each step.


def _quat_mul(p, q):
    w1, x1, y1, z1 = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    w2, x2, y2, z2 = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return jnp.stack(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ],
        -1,
    )


def _quat_matrix(q):
    w, x, y, z = q[0], q[1], q[2], q[3]
    return jnp.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def quaternion_rk4(omega_map, waypoints, steps):
    """``waypoints (P, k, n)`` -> ``(P, 3, 3)``; all generator values in one batched call."""
    nodes = attitude.step_nodes(waypoints, steps, "rkmk4")  # (P, k-1, steps, 3, n): t, t + h/2, t + h
    moves = waypoints[:, 1:] - waypoints[:, :-1]
    omega = jnp.einsum("pkjsin,pkn->pkjsi", omega_map(nodes), moves)
    omega = jnp.moveaxis(omega.reshape(omega.shape[0], -1, 3, 3), 1, 0)  # (steps total, P, node, 3)
    pure = jnp.concatenate([jnp.zeros(omega.shape[:-1] + (1,)), omega], -1)
    h = 1.0 / steps

    def step(qu, w):
        f = lambda x, k: 0.5 * _quat_mul(x, w[:, k])
        k1 = f(qu, 0)
        k2 = f(qu + 0.5 * h * k1, 1)
        k3 = f(qu + 0.5 * h * k2, 1)
        k4 = f(qu + h * k3, 2)
        new = qu + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        return new / jnp.linalg.norm(new, axis=-1, keepdims=True), None

    start = jnp.broadcast_to(jnp.array([1.0, 0.0, 0.0, 0.0]), (waypoints.shape[0], 4))
    qu, _ = jax.lax.scan(step, start, pure)
    return jax.vmap(_quat_matrix)(qu)


def diffrax_dopri8(omega_map, waypoints, rtol):
    import diffrax

    def segment(qu, ab):
        a, d = ab

        def field(t, y, args):
            w = omega_map(a + t * d) @ d
            return 0.5 * _quat_mul(y, jnp.concatenate([jnp.zeros(1), w]))

        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(field),
            diffrax.Dopri8(),
            0.0,
            1.0,
            0.1,
            qu,
            stepsize_controller=diffrax.PIDController(rtol=rtol, atol=rtol),
            max_steps=4096,
        )
        y = sol.ys[-1]
        return y / jnp.linalg.norm(y), sol.stats["num_steps"]

    qu, counts = jax.lax.scan(
        segment, jnp.array([1.0, 0.0, 0.0, 0.0]), (waypoints[:-1], waypoints[1:] - waypoints[:-1])
    )
    return _quat_matrix(qu), jnp.sum(counts)


def timed(function, *args, repeats=3):
    jax.block_until_ready(function(*args))
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(function(*args))
        best = min(best, time.perf_counter() - start)
    return best


def main():
    robot = sa.load_robot(ROBOT)
    rng = np.random.default_rng(15)
    n = robot.n_joints
    sets = {"loops": ellipse_loops(rng, 64, n), "polylines": polylines(rng, 64, n)}
    omega_map = functools.partial(attitude.bus_rate_map, robot)

    @functools.partial(jax.jit, static_argnames=("steps", "order"))
    def magnus(wp, steps, order):
        return attitude.path_rotation(omega_map, wp, steps, order)

    @functools.partial(jax.jit, static_argnames=("steps",))
    def quat(wp, steps):
        return quaternion_rk4(omega_map, wp, steps)

    references = {}
    for name, paths in sets.items():
        wp = jnp.asarray(paths)
        references[name] = magnus(wp, 512, 6)
        check = np.array([scipy_reference(robot, p) for p in paths[:4]])
        gap = float(jnp.max(attitude.geodesic_distance(references[name][:4], jnp.asarray(check))))
        self_gap = float(jnp.max(attitude.geodesic_distance(references[name], magnus(wp, 256, 6))))
        angle = np.asarray(attitude.geodesic_distance(jnp.eye(3), references[name]))
        print(
            f"# {name}: net rotation {angle.min():.3g}..{angle.max():.3g} rad; reference vs DOP853 {gap:.2g} rad, "
            f"vs 256 steps {self_gap:.2g} rad",
            flush=True,
        )

    timing_paths = jnp.asarray(ellipse_loops(np.random.default_rng(1), 1000, n))
    print(
        "| scheme | steps/segment | C_w evaluations/segment | max error, loops (rad) | max error, 2-rad polylines (rad) | 1,000 loops, warm (s) |"
    )
    print("|---|---|---|---|---|---|")
    schemes = [("Magnus 4 (2 Gauss nodes)", 4, 2), ("Magnus 6 (3 Gauss nodes)", 6, 3), ("RKMK4", "rkmk4", 3)]
    for label, order, evals in schemes:
        for steps in (1, 2, 4, 8, 16, 32):
            errors = [
                float(jnp.max(attitude.geodesic_distance(magnus(jnp.asarray(p), steps, order), references[k])))
                for k, p in sets.items()
            ]
            seconds = timed(magnus, timing_paths, steps, order)
            print(
                f"| {label} | {steps} | {evals * steps} | {errors[0]:.1e} | {errors[1]:.1e} | {seconds:.3f} |",
                flush=True,
            )
    for steps in (4, 8, 16, 32):
        errors = [
            float(jnp.max(attitude.geodesic_distance(quat(jnp.asarray(p), steps), references[k])))
            for k, p in sets.items()
        ]
        seconds = timed(quat, timing_paths, steps)
        print(
            f"| quaternion RK4, normalized | {steps} | {3 * steps} | {errors[0]:.1e} | {errors[1]:.1e} | {seconds:.3f} |",
            flush=True,
        )
    if "--no-diffrax" not in sys.argv:
        for rtol in (1e-10, 1e-12):
            run = jax.jit(jax.vmap(lambda w, r=rtol: diffrax_dopri8(omega_map, w, r)))
            errors, counts = [], []
            for k, p in sets.items():
                R, steps = run(jnp.asarray(p))
                errors.append(float(jnp.max(attitude.geodesic_distance(R, references[k]))))
                counts.append(float(jnp.mean(steps)) / (p.shape[1] - 1))
            seconds = timed(run, timing_paths)
            print(
                f"| diffrax Dopri8, quaternion, rtol {rtol:.0e} | adaptive ({counts[0]:.1f}) | ~{12 * counts[0]:.0f} | "
                f"{errors[0]:.1e} | {errors[1]:.1e} | {seconds:.3f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
