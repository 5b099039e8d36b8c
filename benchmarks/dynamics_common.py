"""What the dynamics benchmarks share: the UR5 smallsat, its random states, its Pinocchio model
and the timers (`bench_dynamics.py`, `bench_capture.py`).

Each benchmark compiles its batch once with compile time reported apart, takes the median of
warm runs in wall and CPU time (user + sys of the process: on a shared machine it depends much
less on the other jobs), and times a Pinocchio loop doing the same work per state in the same
run. Pinocchio reads the URDF the test references read (`tests.spatial_references.combined_urdf`:
the bus, the fixed mount and the arm), with a free flyer on the bus and zero gravity; its
free-flyer velocity is LOCAL at the bus-frame origin (ours is [v of the bus centroid; w]).
"""

from __future__ import annotations

import os
import sys
import time

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np

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


def random_rotations(rng, count: int) -> np.ndarray:
    """``(count, 3, 3)`` rotations from uniformly random unit quaternions."""
    quaternions = rng.normal(size=(count, 4))
    w, x, y, z = (quaternions / np.linalg.norm(quaternions, axis=1, keepdims=True)).T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


def random_states(count: int, n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Joints, rates, torques, accelerations, attitudes (bus -> inertial) and momenta."""
    rng = np.random.default_rng(seed)
    rotation = random_rotations(rng, count)
    return {
        "q": rng.uniform(-np.pi, np.pi, (count, n)),
        "qd": rng.normal(size=(count, n)),
        "tau": 10.0 * rng.normal(size=(count, n)),
        "qdd": rng.normal(size=(count, n)),
        "R": rotation,
        "m": 5.0 * rng.normal(size=(count, 6)),
    }


class PinocchioSmallsat:
    """Pinocchio's free-flyer model of the UR5 smallsat with preallocated state buffers
    (``config``, ``velocity``); raises ImportError without Pinocchio."""

    def __init__(self):
        import pinocchio as pin

        urdf = locate_package_file("bench", "example-robot-data", "robots/ur_description/urdf/ur5_robot.urdf")
        with open(urdf) as handle:
            text = handle.read()
        self.pin = pin
        self.model = pin.buildModelFromXML(combined_urdf(text, root_link="base_link", **BUS), pin.JointModelFreeFlyer())
        self.model.gravity.linear[:] = 0.0
        self.data = self.model.createData()
        self.config, self.velocity = pin.neutral(self.model), np.zeros(self.model.nv)

    def set_state(self, q, qd, R, m) -> None:
        """Configuration (q, attitude R, bus origin at the origin) into ``config``, and into
        ``velocity`` the one whose centroidal momentum (inertial axes) is m."""
        pin, model, data, config, velocity = self.pin, self.model, self.data, self.config, self.velocity
        config[3:7] = pin.Quaternion(R).coeffs()
        config[7:] = q
        centroidal = pin.computeCentroidalMap(model, data, config)
        velocity[:6] = np.linalg.solve(centroidal[:, :6], m - centroidal[:, 6:] @ qd)
        velocity[6:] = qd

    def check_full_crba(self, what: str) -> None:
        """Refuse a Pinocchio whose ``crba`` fills only a triangle (``what`` needs all of it)."""
        config = self.pin.neutral(self.model)
        config[7:] = 1.0
        H = self.pin.crba(self.model, self.data, config)
        if not np.array_equal(H, H.T):
            raise RuntimeError(f"this Pinocchio fills only a triangle of crba's matrix; {what} needs all of it")


def max_relative(batch: np.ndarray, loop: np.ndarray) -> float:
    """Largest per-state max |difference| / max |loop value|."""
    scale = np.maximum(np.max(np.abs(loop), axis=-1), 1e-300)
    return float(np.max(np.max(np.abs(batch - loop), axis=-1) / scale))


def time_batch(name, function, robot, arrays, repeats):
    """Compile apart, then the median warm run; returns (result as NumPy, [wall, CPU] seconds
    per state, compile seconds)."""
    start = time.perf_counter()
    compiled = jax.jit(function).lower(robot, *arrays).compile()
    compile_seconds = time.perf_counter() - start
    result = jax.block_until_ready(compiled(robot, *arrays))
    seconds = median_of(lambda: jax.block_until_ready(compiled(robot, *arrays)), repeats)
    per_state = seconds / arrays[0].shape[0]
    print(
        f"  {name}: compile {compile_seconds:.2f} s, run {seconds[0] * 1e3:.0f} ms wall, {seconds[1] * 1e3:.0f} ms CPU "
        f"({per_state[0] * 1e6:.2f} / {per_state[1] * 1e6:.2f} us/state, median of {repeats})"
    )
    return jax.tree.map(np.asarray, result), per_state, compile_seconds


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
