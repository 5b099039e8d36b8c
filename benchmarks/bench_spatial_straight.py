"""CPU seconds of the spatial straight tip path on the UR5 smallsat: first call and warm call.

Usage: [MAX_STEPS=k] [TIP_TOL=m] python benchmarks/bench_spatial_straight.py [paths] [out.npz]
       python benchmarks/bench_spatial_straight.py reaction [paths] [out.npz]

Measures process CPU time (user + system, all threads) of the first call of
``sa.straight_tip_path`` (trace + compile + run) and of a second call with the same
shapes (run only), then of a call with one more path (a new batch size). The persistent
compile cache is off. Saves the path ends to ``out.npz`` for comparisons across versions.
``TIP_TOL=-inf MAX_STEPS=120000`` integrates the UR5's creep at the elbow singularity to
the joint limits instead of ending it by the stall by travel (`spacearm.motion.lanes.step_lane`):
the exact ends the stall ends are compared with (75 s of CPU).
"""

import os
import sys
import time

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)

import spacearm as sa
from spacearm.analysis import reaction

HERE = os.path.dirname(os.path.abspath(__file__))


def directions(count: int) -> np.ndarray:
    """``count`` unit vectors on a Fibonacci sphere."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    theta = np.pi * (1.0 + 5**0.5) * k
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(theta), r * np.sin(theta), z], axis=-1)


def timed(fn):
    start = time.process_time()
    out = jax.block_until_ready(fn())
    return out, time.process_time() - start


def reaction_free(count: int) -> None:
    """The same measurement for reaction-free tip paths (200 fixed steps of 1 cm in all)."""
    robot = sa.load_robot(os.path.join(HERE, "..", "configs", "ur5-smallsat.yaml"))
    q0 = np.array([0.3, -1.2, 1.6, -0.9, 1.2, 0.2])
    d = directions(count + 1)
    first, t_first = timed(lambda: reaction.reaction_free_tip_path(robot, q0, d[:count], 0.01))
    _, t_warm = timed(lambda: reaction.reaction_free_tip_path(robot, q0, d[:count], 0.01))
    _, t_more = timed(lambda: reaction.reaction_free_tip_path(robot, q0, d, 0.01))
    print(
        f"reaction-free, {count} paths: first call {t_first:.2f} s CPU, warm {t_warm:.2f} s, "
        f"{count + 1} paths after {t_more:.2f} s"
    )
    if len(sys.argv) > 3:
        np.savez(sys.argv[3], **{k: np.asarray(v) for k, v in vars(first).items()})


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "reaction":
        reaction_free(int(sys.argv[2]) if len(sys.argv) > 2 else 4)
        return
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 64
    robot = sa.load_robot(os.path.join(HERE, "..", "configs", "ur5-smallsat.yaml"))
    q0 = np.array([0.3, -1.2, 1.6, -0.9, 1.2, 0.2])
    d = directions(count + 1)
    q = np.broadcast_to(q0, (count, 6))
    options = {"max_steps": int(os.environ["MAX_STEPS"])} if "MAX_STEPS" in os.environ else {}
    if "TIP_TOL" in os.environ:
        options["tip_tol"] = float(os.environ["TIP_TOL"])
    first, t_first = timed(lambda: sa.straight_tip_path(robot, q, d[:count], **options))
    _, t_warm = timed(lambda: sa.straight_tip_path(robot, q, d[:count], **options))
    _, t_more = timed(lambda: sa.straight_tip_path(robot, np.broadcast_to(q0, (count + 1, 6)), d, **options))
    print(
        f"{count} paths: first call {t_first:.2f} s CPU, warm {t_warm:.2f} s, "
        f"{count + 1} paths after {t_more:.2f} s; steps mean {np.mean(first.steps):.0f} max {np.max(first.steps)}; "
        f"reasons {np.bincount(np.asarray(first.reason), minlength=4)}"
    )
    if len(sys.argv) > 2:
        np.savez(sys.argv[2], **{k: np.asarray(v) for k, v in vars(first).items()})


if __name__ == "__main__":
    main()
