"""Reproduces a hang seen with the spatial joint-box averages (not a benchmark; kept for the bug report).

With exactly two forced CPU devices in one process, the mean 1/kappa(J*_v) of the 3-DOF arm
(``analysis.averages``, metric "conditioning") under ``shard_map`` over both devices compiles
and then never returns (all threads asleep); one device or four devices finish, and so does
``metric 2048`` below. Seen with jax/jaxlib 0.10.2 on a 2-core machine.

    XLA_FLAGS=--xla_force_host_platform_device_count=2 PYTHONPATH=src timeout 60 \
        python benchmarks/repro_two_device_hang.py block 1024     # hangs (exit 124)
    XLA_FLAGS=--xla_force_host_platform_device_count=4 ...  block 1024  # finishes
    XLA_FLAGS=--xla_force_host_platform_device_count=2 ...  metric 2048 # finishes

The ``spacearm`` command line exposes one device per core, so on a 2-core machine a sweep with
``gci`` or ``base_disturbance`` hangs the same way; run it with
``XLA_FLAGS=--xla_force_host_platform_device_count=1`` (sweeps/ets7-mount.yaml and
sweeps/ur5-mass-ratio.yaml were run so).
"""
import sys, jax, jax.numpy as jnp, numpy as np
jax.config.update("jax_enable_x64", True)
import os
if os.environ.get("NOASYNC"): jax.config.update("jax_cpu_enable_async_dispatch", False)
from jax.sharding import PartitionSpec as P
mesh = jax.sharding.Mesh(np.array(jax.devices()), ("d",))
import spacearm as sa
from spacearm.analysis import averages as av
from spacearm.analysis.joint_box import digital_shifts
r = sa.load_robot("configs/arm3dof-100kg.yaml")
rb = jax.tree_util.tree_map(lambda x: np.repeat(np.asarray(x)[None], jax.device_count(), 0), r)
mode, B = sys.argv[1], int(sys.argv[2])
plan = av._Plan("conditioning", 1e-2, 8, B, 1, 4)
def f(b):
    one = jax.tree_util.tree_map(lambda x: x[0], b)
    shifts = digital_shifts(0, 8, 3)
    if mode == "block":
        return av._block_sums(plan, one, shifts, 0)[None]
    if mode == "metric":
        q = jnp.linspace(0, 1, B * 3).reshape(B, 3)
        return av.inverse_condition_metric(one, q).sum()[None]
    return av._forward(plan, one, shifts)[0][None]
g = jax.jit(jax.shard_map(f, mesh=mesh, in_specs=P("d"), out_specs=P("d"), check_vma=False))
c = g.lower(rb).compile(); print("compiled", flush=True)
print(c(rb), flush=True)
