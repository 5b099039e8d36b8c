"""Throughput of the spatial Generalized Jacobian: the UR5 on its 500 kg smallsat.

J* (6 x 6, float64) over 10^6 random postures, compile time reported apart from run
time, one XLA CPU device per core (the postures split across them with shard_map).
In the same run, as baselines: the same J* from Pinocchio in a Python loop (crba +
frame Jacobian + a 6x6 solve per posture, the SPATIAL.md recipe), and MuJoCo MJX
``jit(vmap(...))`` when ``mujoco.mjx`` is installed. The first postures are checked
against Pinocchio before anything is timed.

    PYTHONPATH=src python benchmarks/bench_spatial.py [--postures 1000000] [--pinocchio 20000]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

CORES = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
os.environ.setdefault("XLA_FLAGS", f"--xla_force_host_platform_device_count={CORES}")

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np
from jax.sharding import Mesh, PartitionSpec

import spacearm as sa
from spacearm.models.spatial import primitives

HERE = os.path.dirname(os.path.abspath(__file__))
CONFIG = os.path.join(HERE, "..", "configs", "ur5-smallsat.yaml")
BUS = {
    "mass": 500.0,
    "com": [-0.2, 0.05, -0.1],
    "inertia": [[80.0, 1, 0], [1, 95, 2], [0, 2, 120]],
    "xyz": [0.6, 0.1, 0.5],
    "rpy": [0.1, -0.2, 0.3],
}


def best_of(function, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def pinocchio_setup():
    import pinocchio as pin

    from spacearm.models.spatial import locate_package_file

    urdf = locate_package_file("bench", "example-robot-data", "robots/ur_description/urdf/ur5_robot.urdf")
    model = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
    X_mount = pin.SE3(pin.rpy.rpyToMatrix(*BUS["rpy"]), np.array(BUS["xyz"]))
    model.appendBodyToJoint(
        1, pin.Inertia(BUS["mass"], np.array(BUS["com"]), np.array(BUS["inertia"])), X_mount.inverse()
    )
    data = model.createData()
    tip = model.getFrameId("tool0")
    base = pin.neutral(model)
    base[:3] = X_mount.translation
    base[3:7] = pin.Quaternion(X_mount.rotation).coeffs()

    def jstar(joint_q):
        q = base.copy()
        q[7:] = joint_q
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        J = pin.computeFrameJacobian(model, data, q, tip, pin.LOCAL_WORLD_ALIGNED)
        return J[:, 6:] - J[:, :6] @ np.linalg.solve(M[:6, :6], M[:6, 6:])

    return jstar


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--postures", type=int, default=1_000_000)
    parser.add_argument("--pinocchio", type=int, default=20_000, help="postures for the Pinocchio loop")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)

    robot = sa.load_robot(CONFIG)
    devices = jax.devices()
    count = args.postures - args.postures % len(devices)
    rng = np.random.default_rng(0)
    postures = rng.uniform(-np.pi, np.pi, (count, robot.n_joints))
    print(
        f"spacearm J*, UR5 on a 500 kg smallsat: {count:,} postures, float64, {len(devices)} CPU device(s), "
        f"{CORES} core(s), jax {jax.__version__}"
    )

    # Correctness first: the first postures against Pinocchio.
    try:
        pinocchio_jstar = pinocchio_setup()
    except ImportError:
        pinocchio_jstar = None
    if pinocchio_jstar is not None:
        check = np.asarray(sa.generalized_jacobian(robot, postures[:20]))
        error = max(np.max(np.abs(check[i] - pinocchio_jstar(postures[i]))) for i in range(20))
        print(f"  agreement with Pinocchio on 20 postures: max |diff| = {error:.1e}")

    mesh = Mesh(np.array(devices), ("postures",))
    sharded = jax.jit(
        jax.shard_map(
            lambda r, q: primitives.generalized_jacobian(r, q),
            mesh=mesh,
            in_specs=(PartitionSpec(), PartitionSpec("postures")),
            out_specs=PartitionSpec("postures"),
            check_vma=False,  # scan carries start replicated and become per-shard
        )
    )
    q_device = jax.device_put(postures, jax.sharding.NamedSharding(mesh, PartitionSpec("postures")))
    start = time.perf_counter()
    compiled = sharded.lower(robot, q_device).compile()
    compile_seconds = time.perf_counter() - start
    compiled(robot, q_device).block_until_ready()
    seconds = best_of(lambda: compiled(robot, q_device).block_until_ready(), args.repeats)
    rate = count / seconds
    print(
        f"  spacearm, {len(devices)} device(s): compile {compile_seconds:.2f} s, run {seconds:.3f} s "
        f"-> {rate:,.0f} postures/s ({seconds / count * 1e9:.0f} ns per posture)"
    )

    single = jax.jit(primitives.generalized_jacobian)
    q_one = jax.device_put(postures, devices[0])
    start = time.perf_counter()
    single_compiled = single.lower(robot, q_one).compile()
    single_compile = time.perf_counter() - start
    single_compiled(robot, q_one).block_until_ready()
    single_seconds = best_of(lambda: single_compiled(robot, q_one).block_until_ready(), args.repeats)
    print(
        f"  spacearm, 1 device: compile {single_compile:.2f} s, run {single_seconds:.3f} s "
        f"-> {count / single_seconds:,.0f} postures/s"
    )

    generic = jax.jit(jax.vmap(lambda q: sa.kinematics._jstar_one(sa.models.spatial.SPATIAL, robot, q)))
    sample = jax.device_put(postures[:100_000], devices[0])
    start = time.perf_counter()
    generic_compiled = generic.lower(sample).compile()
    generic_compile = time.perf_counter() - start
    generic_compiled(sample).block_until_ready()
    generic_seconds = best_of(lambda: generic_compiled(sample).block_until_ready(), args.repeats)
    print(
        f"  generic J_M - J_S solve(I_S, I_M) under vmap, 1 device, 100,000 postures: compile {generic_compile:.2f} s "
        f"-> {100_000 / generic_seconds:,.0f} postures/s"
    )

    if pinocchio_jstar is not None:
        subset = postures[: args.pinocchio]
        start = time.perf_counter()
        for q in subset:
            pinocchio_jstar(q)
        pin_seconds = time.perf_counter() - start
        pin_rate = len(subset) / pin_seconds
        print(
            f"  Pinocchio Python loop ({len(subset):,} postures): {pin_rate:,.0f} postures/s "
            f"-> spacearm is {rate / pin_rate:.0f}x faster"
        )
    else:
        print("  Pinocchio: not installed")

    try:
        from mujoco import mjx  # noqa: F401 (only whether it imports)
    except ImportError:
        print("  MuJoCo MJX: not installed (mujoco.mjx missing); skipped")
    else:
        print("  MuJoCo MJX: installed, but no MJX baseline is wired in this script yet")
    return 0


if __name__ == "__main__":
    sys.exit(main())
