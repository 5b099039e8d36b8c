"""Throughput of the free-floating dynamics: the UR5 on its 500 kg smallsat.

Batched `sa.forward_dynamics` and `sa.inverse_dynamics(..., base="free")` over 65,536
random states (joints, rates, torques or accelerations, bus attitude, nonzero system
momentum; float64, one CPU device, warm), compile time reported apart from run time.
In the same run, as baselines: a Pinocchio loop doing the same work per state, with the
bus velocity from the momentum (``computeCentroidalMap`` and a 6x6 solve) and then

- forward: ``aba``;
- inverse, bus free: ``crba``, ``nonLinearEffects``, a 6x6 solve for the bus acceleration,
  ``rnea``.

Wall and CPU time (user + sys of the process) are both printed: on a shared machine the
CPU time depends much less on the other jobs. The loop's states are checked against the batch (max relative difference per state)
before anything is timed. The loop stays in Pinocchio's coordinates (its free-flyer
velocity is LOCAL at the bus-frame origin, ours [v of the bus centroid; w]): the joint
rows compared do not depend on the base coordinates.

    PYTHONPATH=src python benchmarks/bench_dynamics.py [--states 65536] [--pinocchio 4096]
"""

from __future__ import annotations

import argparse
import os
import sys

import jax
import numpy as np
from dynamics_common import CONFIG, PinocchioSmallsat, max_relative, random_states, time_batch, time_loop

import spacearm as sa


def pinocchio_loops():
    """``(forward, inverse)``: one state per call, Pinocchio plus NumPy in preallocated arrays."""
    smallsat = PinocchioSmallsat()
    pin, model, data, config, velocity = smallsat.pin, smallsat.model, smallsat.data, smallsat.config, smallsat.velocity
    base_velocity = smallsat.set_state
    effort = np.zeros(model.nv)

    def forward(q, qd, tau, R, m):
        base_velocity(q, qd, R, m)
        effort[6:] = tau
        return pin.aba(model, data, config, velocity, effort)[6:]

    def inverse(q, qd, qdd, R, m):
        base_velocity(q, qd, R, m)
        H = pin.crba(model, data, config)  # the whole symmetric matrix (Pinocchio 3 and later)
        bias = pin.nonLinearEffects(model, data, config, velocity)
        effort[:6] = -np.linalg.solve(H[:6, :6], H[:6, 6:] @ qdd + bias[:6])
        effort[6:] = qdd
        return pin.rnea(model, data, config, velocity, effort)[6:]

    smallsat.check_full_crba("the inverse loop")
    return forward, inverse


def forward(robot, q, qd, tau, R, m):
    return sa.forward_dynamics(robot, q, qd, tau, base_rotation=R, momentum=m)


def inverse_free(robot, q, qd, qdd, R, m):
    return sa.inverse_dynamics(robot, q, qd, qdd, base_rotation=R, momentum=m, base="free")[0]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--states", type=int, default=65_536)
    parser.add_argument("--pinocchio", type=int, default=4_096, help="states for the Pinocchio loop")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)

    robot = sa.load_robot(CONFIG)
    s = random_states(args.states, robot.n_joints)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"spacearm dynamics, UR5 on a 500 kg smallsat: {args.states:,} states, float64, 1 CPU device, "
        f"jax {jax.__version__}, load average {load:.1f}"
    )
    device = jax.devices()[0]
    put = lambda *names: [jax.device_put(s[k], device) for k in names]
    fd, fd_seconds, _ = time_batch("forward_dynamics", forward, robot, put("q", "qd", "tau", "R", "m"), args.repeats)
    idf, id_seconds, _ = time_batch(
        "inverse_dynamics free", inverse_free, robot, put("q", "qd", "qdd", "R", "m"), args.repeats
    )

    try:
        pin_forward, pin_inverse = pinocchio_loops()
    except ImportError:
        print("  Pinocchio: not installed")
        return 0
    few = args.pinocchio
    pick = lambda *names: [s[k][:few] for k in names]
    loop_fd, pin_fd = time_loop(
        "Pinocchio centroidal map + solve + aba", pin_forward, pick("q", "qd", "tau", "R", "m"), 3
    )
    loop_id, pin_id = time_loop(
        "Pinocchio centroidal map + solve + crba + nonLinearEffects + solve + rnea",
        pin_inverse,
        pick("q", "qd", "qdd", "R", "m"),
        3,
    )
    for name, batch, loop, ours, theirs in (
        ("forward", fd, loop_fd, fd_seconds, pin_fd),
        ("inverse free", idf, loop_id, id_seconds, pin_id),
    ):
        ratio = theirs / ours
        print(
            f"  {name}: batch vs loop max relative difference {max_relative(batch[:few], loop):.1e}; "
            f"spacearm is {ratio[0]:.1f}x the Pinocchio loop in wall time, {ratio[1]:.1f}x in CPU time"
        )
    print(f"  load average at the end {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
