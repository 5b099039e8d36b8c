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

Wall and CPU time (user + sys of the process) are both printed: on a shared machine the CPU
time depends much less on the other jobs. The loop's states are checked against the batch
(max relative difference per state, per output) in the same run. The loop stays in
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
        f"  {name}: batch vs loop max relative difference {', '.join(differences)}; "
        f"spacearm is {ratio[0]:.1f}x the Pinocchio loop in wall time, {ratio[1]:.1f}x in CPU time"
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
    n = robot.n_joints
    compare(
        "capture free",
        (("qd+", n), ("bus+", 6), ("impulse", 6)),
        np.concatenate([part[:few] for part in grasp], axis=1),
        pinocchio_capture_to_ours(loop_grasp, s["R"][:few]),
        grasp_seconds,
        pin_grasp,
    )
    compare("wheel_momentum", (("h", 3),), h[:few], loop_h, h_seconds, pin_h)
    print(f"  load average at the end {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
