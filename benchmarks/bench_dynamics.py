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
import time

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np

import spacearm as sa
from spacearm.models.spatial import locate_package_file

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..")
CONFIG = os.path.join(ROOT, "configs", "ur5-smallsat.yaml")
sys.path.insert(0, ROOT)
from tests.spatial_references import combined_urdf  # the URDF the references use

BUS = {
    "base_mass": 500.0,
    "base_com": [-0.2, 0.05, -0.1],
    "base_inertia": [[80.0, 1, 0], [1, 95, 2], [0, 2, 120]],
    "mount_xyz": [0.6, 0.1, 0.5],
    "mount_rpy": [0.1, -0.2, 0.3],
}


def median_of(function, repeats: int) -> np.ndarray:
    """Median [wall, CPU (user + sys) of this process] seconds of ``repeats`` calls."""
    times = []
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.process_time()
        function()
        times.append((time.perf_counter() - wall, time.process_time() - cpu))
    return np.median(np.array(times), axis=0)


def random_states(count: int, n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Joints, rates, torques, accelerations, attitudes (bus -> inertial) and momenta."""
    rng = np.random.default_rng(seed)
    quaternions = rng.normal(size=(count, 4))
    w, x, y, z = (quaternions / np.linalg.norm(quaternions, axis=1, keepdims=True)).T
    rotation = np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )
    return {
        "q": rng.uniform(-np.pi, np.pi, (count, n)),
        "qd": rng.normal(size=(count, n)),
        "tau": 10.0 * rng.normal(size=(count, n)),
        "qdd": rng.normal(size=(count, n)),
        "R": rotation,
        "m": 5.0 * rng.normal(size=(count, 6)),
    }


def pinocchio_loops():
    """``(forward, inverse)``: one state per call, Pinocchio plus NumPy in preallocated arrays."""
    import pinocchio as pin

    urdf = locate_package_file("bench", "example-robot-data", "robots/ur_description/urdf/ur5_robot.urdf")
    with open(urdf) as handle:
        text = handle.read()
    model = pin.buildModelFromXML(combined_urdf(text, root_link="base_link", **BUS), pin.JointModelFreeFlyer())
    model.gravity.linear[:] = 0.0
    data = model.createData()
    config, velocity, effort = pin.neutral(model), np.zeros(model.nv), np.zeros(model.nv)

    def base_velocity(q, qd, R, m):
        """The bus velocity whose centroidal momentum (inertial axes) is m, into ``velocity``."""
        config[3:7] = pin.Quaternion(R).coeffs()
        config[7:] = q
        centroidal = pin.computeCentroidalMap(model, data, config)
        velocity[:6] = np.linalg.solve(centroidal[:, :6], m - centroidal[:, 6:] @ qd)
        velocity[6:] = qd

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

    config[7:] = 1.0
    H = pin.crba(model, data, config)
    if not np.array_equal(H, H.T):
        raise RuntimeError("this Pinocchio fills only a triangle of crba's matrix; the inverse loop needs all of it")
    return forward, inverse


def max_relative(batch: np.ndarray, loop: np.ndarray) -> float:
    """Largest per-state max |difference| / max |loop value|."""
    scale = np.maximum(np.max(np.abs(loop), axis=-1), 1e-300)
    return float(np.max(np.max(np.abs(batch - loop), axis=-1) / scale))


def time_batch(name, function, robot, arrays, repeats):
    """Compile apart, then the median warm run; returns (result, [wall, CPU] seconds per state)."""
    start = time.perf_counter()
    compiled = jax.jit(function).lower(robot, *arrays).compile()
    compile_seconds = time.perf_counter() - start
    result = compiled(robot, *arrays).block_until_ready()
    seconds = median_of(lambda: compiled(robot, *arrays).block_until_ready(), repeats)
    per_state = seconds / arrays[0].shape[0]
    print(
        f"  {name}: compile {compile_seconds:.2f} s, run {seconds[0] * 1e3:.0f} ms wall, {seconds[1] * 1e3:.0f} ms CPU "
        f"({per_state[0] * 1e6:.2f} / {per_state[1] * 1e6:.2f} us/state, median of {repeats})"
    )
    return np.asarray(result), per_state


def time_loop(name, function, arrays, repeats):
    """The median time of a Python loop over the states; returns (results, [wall, CPU] seconds per state)."""
    results = np.stack([np.array(function(*state)) for state in zip(*arrays, strict=True)])  # warm-up
    count = len(arrays[0])
    per_state = median_of(lambda: [function(*state) for state in zip(*arrays, strict=True)], repeats) / count
    print(
        f"  {name}: {per_state[0] * 1e6:.2f} / {per_state[1] * 1e6:.2f} us/state wall / CPU "
        f"({count:,} states, median of {repeats})"
    )
    return results, per_state


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
    fd, fd_seconds = time_batch("forward_dynamics", forward, robot, put("q", "qd", "tau", "R", "m"), args.repeats)
    idf, id_seconds = time_batch(
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
