"""Throughput of the capture and wheel-momentum kernels: the UR5 on its 500 kg smallsat.

Batched `sa.capture` (joints free) and `sa.wheel_momentum` over 65,536 random states
(joints, rates, bus attitude, nonzero system momentum; for the capture a random target per
state: mass, inertia, offset from the tip and twist; float64, one CPU device, warm), compile
time reported apart from run time. In the same run, as baselines, a Pinocchio loop doing
the same work per state:

- capture: the bus velocity from the momentum (``computeCentroidalMap`` and a 6x6 solve, as
  in ``bench_dynamics.py``), then the rigid, perfectly plastic grasp solved with the same
  linear algebra as the kernel, in Pinocchio's coordinates: ``crba`` (H),
  ``computeFrameJacobian`` of the tip (LOCAL_WORLD_ALIGNED, J),
  ``Inertia(mass, offset, inertia).matrix()`` (the target's spatial inertia at the tip
  origin, M_t) and its twist there (``SE3.act``, t_t), then one NumPy solve of
  (H + J^T M_t J) nu+ = H nu- + J^T M_t t_t and F = -M_t (J nu+ - t_t). Not
  ``impulseDynamics``: it would need the target added to the model as a second free body (a
  new model and data per target) and a contact KKT solve, set-up work the kernel does not do;
  the tests compare the kernel with ``impulseDynamics`` (tests/capture_references.py);
- wheel momentum: ``computeCentroidalMap`` alone; from it the bus velocity with the attitude
  held (w = 0, so the linear momentum is m_total R v and v needs no solve), the bodies'
  angular momentum about the system centroid, and h = R^T (L - L_bodies).

A second baseline does the same per-state Pinocchio calls but batches the NumPy algebra over
all the states (as ``bench_tree.py`` does): most of the loop's time is NumPy's per-call
overhead on 6x6 and 12x12 matrices, not Pinocchio.

Wall and CPU time (user + sys of the process) are both printed: on a shared machine the CPU
time depends much less on the other jobs. Both baselines' states are checked against the
batch (max relative difference per state, per output) in the same run. They stay in
Pinocchio's coordinates (its free-flyer velocity is LOCAL at the bus-frame origin, ours
[v of the bus centroid; w]); its bus velocity after the grasp is turned into ours after the
timing.

    PYTHONPATH=src python benchmarks/bench_capture.py [--states 65536] [--pinocchio 4096]
"""

from __future__ import annotations

import argparse
import os
import sys

import jax
import numpy as np
from dynamics_common import (
    BUS,
    CONFIG,
    PinocchioSmallsat,
    max_relative,
    median_of,
    random_rotations,
    random_states,
    time_batch,
    time_loop,
)

import spacearm as sa

TIP = "tool0"


def random_targets(count: int, seed: int = 1) -> dict[str, np.ndarray]:
    """Per state a client to grasp, inertial axes: mass 5 to 200 kg, the inertia of a box of
    sides 0.2 to 1.5 m turned at random, its centroid 0.1 to 0.5 m from the tip origin, and a
    twist [v of its centroid (0.1 m/s scale); w (0.05 rad/s scale)]."""
    rng = np.random.default_rng(seed)
    mass = rng.uniform(5.0, 200.0, count)
    sides = rng.uniform(0.2, 1.5, (count, 3))
    principal = mass[:, None] / 12.0 * (np.sum(sides**2, axis=1, keepdims=True) - sides**2)
    turn = random_rotations(rng, count)
    inertia = np.einsum("kij,kj,klj->kil", turn, principal, turn)
    direction = rng.normal(size=(count, 3))
    offset = direction / np.linalg.norm(direction, axis=1, keepdims=True) * rng.uniform(0.1, 0.5, (count, 1))
    velocity = np.concatenate([0.1 * rng.normal(size=(count, 3)), 0.05 * rng.normal(size=(count, 3))], axis=1)
    return {"mass": mass, "inertia": inertia, "offset": offset, "velocity": velocity}


def pinocchio_loops():
    """``(capture, wheel)``: one state per call, Pinocchio plus NumPy in preallocated arrays.

    ``capture`` returns [nu+ (Pinocchio's coordinates, 6 + n); F (6,), world axes at the tip
    origin]; ``wheel`` returns h (3,), bus axes."""
    smallsat = PinocchioSmallsat()
    pin, model, data, config, velocity = smallsat.pin, smallsat.model, smallsat.data, smallsat.config, smallsat.velocity
    set_state, tip, frame = smallsat.set_state, smallsat.model.getFrameId(TIP), pin.LOCAL_WORLD_ALIGNED
    eye = np.eye(3)

    def capture(q, qd, R, m, mass, inertia, offset, twist):
        set_state(q, qd, R, m)
        H = pin.crba(model, data, config)  # the whole symmetric matrix (Pinocchio 3 and later)
        J = pin.computeFrameJacobian(model, data, config, tip, frame)  # [v of the tip origin; w], world
        M_t = pin.Inertia(mass, offset, inertia).matrix()  # at the tip origin, centroid at offset
        t_t = pin.SE3(eye, offset).act(pin.Motion(twist)).vector  # the target's twist at the tip origin
        coupled = J.T @ M_t
        after = np.linalg.solve(H + coupled @ J, H @ velocity + coupled @ t_t)
        return np.concatenate([after, M_t @ (t_t - J @ after)])

    def wheel(q, qd, R, m):
        config[3:7] = pin.Quaternion(R).coeffs()
        config[7:] = q
        A = pin.computeCentroidalMap(model, data, config)
        # The bus held in attitude (w = 0): its linear momentum is m_total R v, so no solve.
        v = R.T @ (m[:3] - A[:3, 6:] @ qd) / data.mass[0]
        return R.T @ (m[3:] - A[3:, :3] @ v - A[3:, 6:] @ qd)

    smallsat.check_full_crba("the capture loop")
    return capture, wheel


def _hat(d: np.ndarray) -> np.ndarray:
    """``(..., 3, 3)`` cross-product matrices of ``(..., 3)`` vectors."""
    zero = np.zeros(d.shape[:-1])
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return np.stack([np.stack([zero, -z, y], -1), np.stack([z, zero, -x], -1), np.stack([-y, x, zero], -1)], -2)


def _solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.linalg.solve(A, b[..., None])[..., 0]


def pinocchio_batched():
    """``(capture, wheel)`` on all states at once: Pinocchio per state (the centroidal map,
    ``crba``, the frame Jacobian) into preallocated arrays, then the same algebra as
    `pinocchio_loops` batched in NumPy (one call per step for all states). Same outputs."""
    smallsat = PinocchioSmallsat()
    pin, model, data, config = smallsat.pin, smallsat.model, smallsat.data, smallsat.config
    tip, frame, nv = model.getFrameId(TIP), pin.LOCAL_WORLD_ALIGNED, model.nv

    def maps(q, R, full: bool):
        A = np.empty((len(q), 6, nv))
        H, J = (np.empty((len(q), nv, nv)), np.empty((len(q), 6, nv))) if full else (None, None)
        for k in range(len(q)):
            config[3:7] = pin.Quaternion(R[k]).coeffs()
            config[7:] = q[k]
            A[k] = pin.computeCentroidalMap(model, data, config)
            if full:
                H[k] = pin.crba(model, data, config)
                J[k] = pin.computeFrameJacobian(model, data, config, tip, frame)
        return A, H, J

    def capture(q, qd, R, m, mass, inertia, offset, twist):
        A, H, J = maps(q, R, True)
        nu = np.concatenate([_solve(A[:, :, :6], m - np.einsum("kij,kj->ki", A[:, :, 6:], qd)), qd], axis=1)
        skew, mass = _hat(offset), mass[:, None, None]
        eye = np.broadcast_to(np.eye(3), skew.shape)
        M_t = np.concatenate(
            [
                np.concatenate([mass * eye, -mass * skew], -1),
                np.concatenate([mass * skew, inertia - mass * skew @ skew], -1),
            ],
            -2,
        )
        t_t = np.concatenate([twist[:, :3] - np.cross(twist[:, 3:], offset), twist[:, 3:]], axis=1)
        coupled = np.swapaxes(J, 1, 2) @ M_t
        after = _solve(H + coupled @ J, np.einsum("kij,kj->ki", H, nu) + np.einsum("kij,kj->ki", coupled, t_t))
        impulse = np.einsum("kij,kj->ki", M_t, t_t - np.einsum("kij,kj->ki", J, after))
        return np.concatenate([after, impulse], axis=1)

    def wheel(q, qd, R, m):
        A, _, _ = maps(q, R, False)
        Rt = np.swapaxes(R, 1, 2)
        v = np.einsum("kij,kj->ki", Rt, m[:, :3] - np.einsum("kij,kj->ki", A[:, :3, 6:], qd)) / data.mass[0]
        bodies = np.einsum("kij,kj->ki", A[:, 3:, :3], v) + np.einsum("kij,kj->ki", A[:, 3:, 6:], qd)
        return np.einsum("kij,kj->ki", Rt, m[:, 3:] - bodies)

    return capture, wheel


def time_whole(name, function, arrays, repeats):
    """The median time of one call on all the states; returns (results, [wall, CPU] seconds per state)."""
    results = function(*arrays)  # warm-up
    count = len(arrays[0])
    per_state = median_of(lambda: function(*arrays), repeats) / count
    print(
        f"  {name}: {per_state[0] * 1e6:.2f} / {per_state[1] * 1e6:.2f} us/state wall / CPU "
        f"({count:,} states, median of {repeats})"
    )
    return results, per_state


def pinocchio_capture_to_ours(loop: np.ndarray, R: np.ndarray) -> np.ndarray:
    """[qd+; base+ (v of the bus centroid; w), inertial axes; F] from the capture loop's
    [nu+ (Pinocchio: v of the bus origin, w, bus axes; qd+); F]."""
    v, w, rest = loop[:, :3], loop[:, 3:6], loop[:, 6:]
    centroid = v + np.cross(w, np.asarray(BUS["base_com"]))
    base = np.concatenate([np.einsum("kij,kj->ki", R, centroid), np.einsum("kij,kj->ki", R, w)], axis=1)
    return np.concatenate([rest[:, :-6], base, rest[:, -6:]], axis=1)


def capture_free(robot, q, qd, R, m, mass, inertia, offset, velocity):
    target = {"mass": mass, "inertia": inertia, "offset": offset, "velocity": velocity}
    return sa.capture(robot, q, qd, target, base_rotation=R, momentum=m, joints="free")


def wheel_momentum(robot, q, qd, R, m):
    return sa.wheel_momentum(robot, q, qd, base_rotation=R, momentum=m)


def compare(name, parts, batch, loop, ours, theirs) -> None:
    """Print the largest per-state relative difference of each output and the ratios."""
    differences, start = [], 0
    for part, width in parts:
        differences.append(
            f"{part} {max_relative(batch[:, start : start + width], loop[:, start : start + width]):.1e}"
        )
        start += width
    ratio = theirs / ours
    print(
        f"  {name}: max relative difference {', '.join(differences)}; "
        f"spacearm is {ratio[0]:.1f}x the Pinocchio baseline in wall time, {ratio[1]:.1f}x in CPU time"
    )


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--states", type=int, default=65_536)
    parser.add_argument("--pinocchio", type=int, default=4_096, help="states for the Pinocchio loop")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)

    robot = sa.load_robot(CONFIG)
    s = random_states(args.states, robot.n_joints) | random_targets(args.states)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"spacearm capture and wheels, UR5 on a 500 kg smallsat: {args.states:,} states, float64, "
        f"1 CPU device, jax {jax.__version__}, load average {load:.1f}"
    )
    device = jax.devices()[0]
    put = lambda *names: [jax.device_put(s[k], device) for k in names]
    target = ("mass", "inertia", "offset", "velocity")
    grasp, grasp_seconds, _ = time_batch(
        "capture free", capture_free, robot, put("q", "qd", "R", "m", *target), args.repeats
    )
    h, h_seconds, _ = time_batch("wheel_momentum", wheel_momentum, robot, put("q", "qd", "R", "m"), args.repeats)

    try:
        pin_capture, pin_wheel = pinocchio_loops()
    except ImportError:
        print("  Pinocchio: not installed")
        return 0
    few = args.pinocchio
    pick = lambda *names: [s[k][:few] for k in names]
    loop_grasp, pin_grasp = time_loop(
        "Pinocchio centroidal map + solve + crba + frame Jacobian + target inertia + solve",
        pin_capture,
        pick("q", "qd", "R", "m", *target),
        3,
    )
    loop_h, pin_h = time_loop("Pinocchio centroidal map", pin_wheel, pick("q", "qd", "R", "m"), 3)
    batched_capture, batched_wheel = pinocchio_batched()
    whole_grasp, whole_grasp_seconds = time_whole(
        "Pinocchio per state, the algebra batched in NumPy: capture",
        batched_capture,
        pick("q", "qd", "R", "m", *target),
        3,
    )
    whole_h, whole_h_seconds = time_whole(
        "Pinocchio per state, the algebra batched in NumPy: wheel momentum", batched_wheel, pick("q", "qd", "R", "m"), 3
    )
    n, ours_grasp = robot.n_joints, np.concatenate([part[:few] for part in grasp], axis=1)
    parts = (("qd+", n), ("bus+", 6), ("impulse", 6))
    for name, loop, seconds in (("loop", loop_grasp, pin_grasp), ("batched algebra", whole_grasp, whole_grasp_seconds)):
        compare(
            f"capture free vs {name}",
            parts,
            ours_grasp,
            pinocchio_capture_to_ours(loop, s["R"][:few]),
            grasp_seconds,
            seconds,
        )
    for name, loop, seconds in (("loop", loop_h, pin_h), ("batched algebra", whole_h, whole_h_seconds)):
        compare(f"wheel_momentum vs {name}", (("h", 3),), h[:few], loop, h_seconds, seconds)
    print(f"  load average at the end {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
