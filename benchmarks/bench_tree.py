"""Throughput of the tree Generalized Jacobian: two UR5 on a 400 kg cube (12 joints, 2 tips).

J* of both tips over all joints ``(2, 6, 12)``, float64, for a batch of random postures
(one jitted call, warm; on one XLA CPU device, and split over one device per core with
shard_map), against Pinocchio in a Python loop in the same run (warm too, every J*
stored in one array, as the batch stores it). The loop is the fastest exact one found:
per posture ``pin.ccrba`` (the centroidal momentum matrix A_g, which also fills the
joint Jacobians), the two frame Jacobians and one 6x6 solve, J* = J_q - J_b A_b^-1 A_q
(free-flyer on the bus, one URDF with prefixed copies of the arm); ``crba`` plus
``computeJointJacobians`` (the whole mass matrix, and a second pass) is slower. A second baseline calls Pinocchio in the loop and does the algebra for all
postures at once in NumPy (batched solve): most of the loop's time is NumPy's per-call
overhead, not Pinocchio's. The first postures are checked against Pinocchio before
anything is timed. Wall and CPU time are both printed, and the load average: on a loaded
machine the CPU-time ratio is the fairer one. Compile time is printed apart.

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
    """Two J* routines on Pinocchio: per posture, and Pinocchio per posture with the algebra batched."""
    import pinocchio as pin

    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    data = model.createData()
    q_index = np.array([model.joints[model.getJointId(n)].idx_q for n in robot.joint_names])
    v_index = np.array([model.joints[model.getJointId(n)].idx_v for n in robot.joint_names])
    frames = [model.getFrameId(n) for n in robot.tip_names]
    config, rate = pin.neutral(model), np.zeros(model.nv)
    frame = pin.LOCAL_WORLD_ALIGNED

    def jstar(q, out):
        config[q_index] = q
        A = pin.ccrba(model, data, config, rate)  # also fills the joint Jacobians
        solve = np.linalg.solve(A[:, :6], A[:, v_index])
        for t, f in enumerate(frames):
            J = pin.getFrameJacobian(model, data, f, frame)
            out[t] = J[:, v_index] - J[:, :6] @ solve

    def loop(q):
        out = np.empty((len(q), len(frames), 6, len(q_index)))
        for i in range(len(q)):
            jstar(q[i], out[i])
        return out

    def batched(q):
        A = np.empty((len(q), 6, model.nv))
        J = np.empty((len(q), len(frames), 6, model.nv))
        for i in range(len(q)):
            config[q_index] = q[i]
            A[i] = pin.ccrba(model, data, config, rate)
            for t, f in enumerate(frames):
                J[i, t] = pin.getFrameJacobian(model, data, f, frame)
        solve = np.linalg.solve(A[:, :, :6], A[:, :, v_index])
        return J[..., v_index] - J[..., :6] @ solve[:, None]

    return loop, batched


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
    print("load average (1, 5, 15 min): " + ", ".join(f"{x:.1f}" for x in os.getloadavg()))
    loop, pin_batched = pinocchio_loop(urdf, robot)

    kernel = jax.jit(sa.generalized_jacobian)
    start = time.perf_counter()
    ours = np.asarray(kernel(robot, q[:8]))
    print(f"compile (8 postures): {time.perf_counter() - start:.2f} s")
    error = np.max(np.abs(ours - loop(q[:8])))
    error_batched = np.max(np.abs(ours - pin_batched(q[:8])))
    print(f"max |J* - Pinocchio| over 8 postures: {error:.2e} (loop), {error_batched:.2e} (batched algebra)")
    assert max(error, error_batched) < 1e-10, (error, error_batched)

    start = time.perf_counter()
    kernel(robot, q).block_until_ready()  # warm at the timed shape
    print(f"compile and first run at {len(q):,} postures: {time.perf_counter() - start:.2f} s")
    wall, cpu = timed(lambda: kernel(robot, q).block_until_ready(), args.repeats)
    mesh = Mesh(np.array(devices), ("postures",))
    sharded = jax.jit(
        jax.shard_map(
            primitives.generalized_jacobian,
            mesh=mesh,
            in_specs=(PartitionSpec(), PartitionSpec("postures")),
            out_specs=PartitionSpec("postures"),
            check_vma=False,  # loop carries start replicated and become per-shard
        )
    )
    q_sharded = jax.device_put(q, NamedSharding(mesh, PartitionSpec("postures")))
    np.testing.assert_allclose(np.asarray(sharded(robot, q_sharded))[:8], ours, atol=1e-14)
    all_wall, _ = timed(lambda: sharded(robot, q_sharded).block_until_ready(), args.repeats)
    n_pin = min(args.pinocchio, len(q))
    loop(q[:100])  # warm
    pin_batched(q[:100])
    pin_wall, pin_cpu = timed(lambda: loop(q[:n_pin]), args.repeats)
    batched_wall, batched_cpu = timed(lambda: pin_batched(q[:n_pin]), args.repeats)
    rate = lambda count, seconds: count / seconds
    print(f"spacearm  J* (2, 6, 12): {rate(len(q), wall):12,.0f} postures/s wall, {rate(len(q), cpu):12,.0f} per CPU s")
    print(f"  split over {len(devices)} device(s): {rate(len(q), all_wall):12,.0f} postures/s wall")
    print(
        f"Pinocchio J* loop      : {rate(n_pin, pin_wall):12,.0f} postures/s wall, {rate(n_pin, pin_cpu):12,.0f} per CPU s"
    )
    print(
        f"  algebra batched      : {rate(n_pin, batched_wall):12,.0f} postures/s wall, "
        f"{rate(n_pin, batched_cpu):12,.0f} per CPU s"
    )
    print(
        f"ratio to the loop, one device: {rate(len(q), wall) / rate(n_pin, pin_wall):.1f}x wall, "
        f"{rate(len(q), cpu) / rate(n_pin, pin_cpu):.1f}x CPU time; "
        f"all {len(devices)} device(s): {rate(len(q), all_wall) / rate(n_pin, pin_wall):.1f}x wall"
    )
    print(
        f"ratio to the batched-algebra baseline, one device: {rate(len(q), cpu) / rate(n_pin, batched_cpu):.1f}x CPU time"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
