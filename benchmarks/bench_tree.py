"""Throughput of the tree Generalized Jacobian: two UR5 on a 400 kg cube (12 joints, 2 tips).

J* of both tips over all joints ``(2, 6, 12)``, float64, for a batch of random postures
(one jitted call, warm; on one XLA CPU device, and split over one device per core with
shard_map), against Pinocchio in a Python loop in the same run (warm too):
per posture crba, computeJointJacobians, the two frame Jacobians and one 6x6 solve (the
momentum-based J*, free-flyer on the bus, one URDF with prefixed copies of the arm).
The first postures are checked against Pinocchio before anything is timed. Wall and
CPU time are both printed: on a loaded machine the CPU-time ratio is the fairer one.

    PYTHONPATH=src python benchmarks/bench_tree.py [--postures 100000] [--pinocchio 5000]
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
from jax.sharding import Mesh, NamedSharding, PartitionSpec

import spacearm as sa
from spacearm.models.spatial import locate_package_file, read_urdf
from spacearm.models.tree import primitives, tree_from_chains

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, ROOT)
from tests.tree_references import system_urdf  # the URDF the references use

UR5 = "robots/ur_description/urdf/ur5_robot.urdf"
ARMS = ("left", "right")
MOUNT_XYZ = [[0.3, 0.5526, 0.08], [0.3, -0.5526, 0.08]]
MOUNT_RPY = [[-np.pi / 2, 0.0, 0.0], [np.pi / 2, 0.0, 0.0]]
BUS = {"mass": 400.0, "com": [0.0, 0.0, 0.0], "inertia": 400.0 * (2 * 0.4726) ** 2 / 6 * np.eye(3)}


def timed(function, repeats: int) -> tuple[float, float]:
    """Best (wall, CPU) seconds over ``repeats`` calls."""
    walls, cpus = [], []
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.process_time()
        function()
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    return min(walls), min(cpus)


def build():
    path = locate_package_file("bench", "example-robot-data", UR5)
    chain = read_urdf(path, root_link="base_link", tip="tool0")
    robot = tree_from_chains(
        [chain, chain],
        arm_names=list(ARMS),
        mount_xyz=MOUNT_XYZ,
        mount_rpy=MOUNT_RPY,
        base_mass=BUS["mass"],
        base_com=BUS["com"],
        base_inertia=BUS["inertia"],
    )
    with open(path, encoding="utf-8") as handle:
        text = handle.read()
    urdf = system_urdf(
        base_mass=BUS["mass"],
        base_com=BUS["com"],
        base_inertia=BUS["inertia"],
        arms=[(f"{a}/", text, "base_link", x, r) for a, x, r in zip(ARMS, MOUNT_XYZ, MOUNT_RPY, strict=True)],
    )
    return robot, urdf


def pinocchio_loop(urdf: str, robot):
    import pinocchio as pin

    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    data = model.createData()
    q_index = np.array([model.joints[model.getJointId(n)].idx_q for n in robot.joint_names])
    v_index = np.array([model.joints[model.getJointId(n)].idx_v for n in robot.joint_names])
    frames = [model.getFrameId(n) for n in robot.tip_names]
    config = pin.neutral(model)

    def jstar(q):
        config[q_index] = q
        M = pin.crba(model, data, config)
        M = np.triu(M) + np.triu(M, 1).T
        pin.computeJointJacobians(model, data, config)
        solve = np.linalg.solve(M[:6, :6], M[:6, v_index])
        out = np.empty((len(frames), 6, len(q)))
        for t, frame in enumerate(frames):
            J = pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
            out[t] = J[:, v_index] - J[:, :6] @ solve
        return out

    return jstar


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--postures", type=int, default=100_000)
    parser.add_argument("--pinocchio", type=int, default=5_000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)

    robot, urdf = build()
    devices = jax.devices()
    rng = np.random.default_rng(0)
    count = args.postures - args.postures % len(devices)
    q = rng.uniform(-np.pi, np.pi, size=(count, robot.n_joints))
    print(f"two UR5 on a 400 kg cube: {count:,} postures, float64, {len(devices)} CPU device(s), {CORES} core(s)")
    jstar = pinocchio_loop(urdf, robot)

    kernel = jax.jit(sa.generalized_jacobian)
    start = time.perf_counter()
    ours = np.asarray(kernel(robot, q[:8]))
    print(f"compile (8 postures): {time.perf_counter() - start:.2f} s")
    error = max(np.max(np.abs(ours[i] - jstar(q[i]))) for i in range(8))
    print(f"max |J* - Pinocchio| over 8 postures: {error:.2e}")
    assert error < 1e-10, error

    kernel(robot, q).block_until_ready()  # warm at the timed shape
    wall, cpu = timed(lambda: kernel(robot, q).block_until_ready(), args.repeats)
    mesh = Mesh(np.array(devices), ("postures",))
    sharded = jax.jit(
        jax.shard_map(
            primitives.generalized_jacobian,
            mesh=mesh,
            in_specs=(PartitionSpec(), PartitionSpec("postures")),
            out_specs=PartitionSpec("postures"),
            check_vma=False,  # scan carries start replicated and become per-shard
        )
    )
    q_sharded = jax.device_put(q, NamedSharding(mesh, PartitionSpec("postures")))
    np.testing.assert_allclose(np.asarray(sharded(robot, q_sharded))[:8], ours, atol=1e-14)
    all_wall, _ = timed(lambda: sharded(robot, q_sharded).block_until_ready(), args.repeats)
    n_pin = min(args.pinocchio, len(q))
    for i in range(min(100, n_pin)):  # warm
        jstar(q[i])

    def loop():
        for i in range(n_pin):
            jstar(q[i])

    pin_wall, pin_cpu = timed(loop, args.repeats)
    rate = lambda count, seconds: count / seconds
    print(f"spacearm  J* (2, 6, 12): {rate(len(q), wall):12,.0f} postures/s wall, {rate(len(q), cpu):12,.0f} per CPU s")
    print(f"  split over {len(devices)} device(s): {rate(len(q), all_wall):12,.0f} postures/s wall")
    print(
        f"Pinocchio J* loop      : {rate(n_pin, pin_wall):12,.0f} postures/s wall, {rate(n_pin, pin_cpu):12,.0f} per CPU s"
    )
    print(
        f"ratio, one device: {rate(len(q), wall) / rate(n_pin, pin_wall):.1f}x wall, "
        f"{rate(len(q), cpu) / rate(n_pin, pin_cpu):.1f}x CPU time; "
        f"all {len(devices)} device(s): {rate(len(q), all_wall) / rate(n_pin, pin_wall):.1f}x wall"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
