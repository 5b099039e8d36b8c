"""Every registered sweep metric finishes on two CPU devices of one process, in bounded time.

The sweep runner shards each chunk over the devices. jaxlib 0.10.0-0.10.2 ran batched
LAPACK kernels on XLA's intra-op pool and waited for them there, so two devices that
factor a large batch at once (a joint-box average at 1,024 postures) slept forever;
pyproject.toml excludes those releases, and a stalled chunk ends the run with one line.
Each family's sweep holds every metric defined for it, read from the registry, so a
metric added later is run here too.
"""

import csv
import math
import os
import subprocess
import sys

import pytest
import yaml

import spacearm as sa
from spacearm.models.family import family_of
from spacearm.studies import load_sweep
from spacearm.studies.metrics import METRICS, metric_columns

ROBOTS = {
    "planar": "configs/umetani1990.yaml",
    "spatial": "configs/ur5-smallsat.yaml",
    "tree": "configs/dual-ur5-servicer.yaml",
}
# Small settings where a metric has them; the averages keep 1,024 postures per batch (the
# size at which the old jaxlib's two devices deadlocked).
_AVERAGE = {"rtol": 1.0e-2, "min_samples": 1024, "max_samples": 2048}
FAST_OPTIONS = {
    "w_avg": _AVERAGE,
    "gci": _AVERAGE,
    "base_disturbance": _AVERAGE,
    "dynamic_manipulability": _AVERAGE,
    "reach_radii": {"starts": 8, "steps": 20},
    "path_independent_radius": {"samples": 1024, "keep": 4, "candidates": 4, "descent_steps": 5, "newton_steps": 2},
    "straight_path_area": {"n_directions": 16},
    "virtual_mass": _AVERAGE,
    "bus_rate_jump": _AVERAGE,
    "capture_bus_rate": _AVERAGE,
}
# The reference target of capture_bus_rate: a 20 kg client drifting and tumbling (in the plane
# for the planar arm).
TARGETS = {
    "planar": {"mass": 20.0, "inertia": 1.5, "offset": [0.2, 0.0], "velocity": [0.05, 0.0, 0.1]},
    "spatial": {"mass": 20.0, "inertia": [[1, 0, 0], [0, 1.5, 0], [0, 0, 2]], "velocity": [0.05, 0, 0, 0, 0, 0.1]},
}
BOUND_S = 420  # the whole run, cold compile included, on a loaded 2-core machine
STALL_S = 60  # a chunk with no CPU used for this long ends the run with one line


# Metrics of one tip: on the two-arm tree, the second arm's.
PER_TIP = {"posture", "w_avg", "gci", "dynamic_manipulability", "virtual_mass", "bus_rate_jump", "capture_bus_rate"}


def _metrics(family: str) -> list[dict]:
    tip = {"tip": "right/tool0"} if family == "tree" else {}
    target = {"target": TARGETS["planar" if family == "planar" else "spatial"]}
    return [
        {
            "name": name,
            **FAST_OPTIONS.get(name, {}),
            **(tip if name in PER_TIP else {}),
            **(target if name == "capture_bus_rate" else {}),
        }
        for name, metric in METRICS.items()
        if family in metric.families
    ]


def _task(path: str) -> dict:
    """Two segments through every joint of the robot (rad, s)."""
    robot = sa.load_robot(path)
    n = family_of(robot).joint_count(robot)
    return {"waypoints": [[0.0] * n, [0.3] * n, [0.1] * n], "duration": 2.0}


@pytest.mark.slow
@pytest.mark.parametrize("family", sorted(ROBOTS))
def test_every_metric_finishes_on_two_devices(tmp_path, family):
    root = os.getcwd()
    sweep = {
        "name": f"two-devices-{family}",
        "robot": os.path.join(root, ROBOTS[family]),
        "axes": {"m": {"field": "base.mass", "relative": True, "values": [0.8, 1.2]}},
        "metrics": _metrics(family),
        "chunk_size": 2,
        "task": _task(os.path.join(root, ROBOTS[family])),  # for the metrics along a timed task
    }
    path = tmp_path / "sweep.yaml"
    path.write_text(yaml.safe_dump(sweep))
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=2")
    code = "import sys; from spacearm.cli import main; sys.exit(main(sys.argv[1:]))"
    command = [sys.executable, "-c", code, "sweep", str(path), "--out", str(tmp_path / "out"), "--quiet"]
    result = subprocess.run(
        [*command, "--stall-timeout", str(STALL_S)], env=env, capture_output=True, text=True, timeout=BOUND_S
    )
    assert result.returncode == 0, result.stderr
    with open(tmp_path / "out" / "table.csv") as handle:
        rows = list(csv.DictReader(handle))
    manifest = yaml.safe_load((tmp_path / "out" / "manifest.json").read_text())
    assert manifest["device_count"] == 2
    assert len(rows) == 2
    columns = metric_columns(load_sweep(path).metrics)
    assert set(columns) <= set(rows[0])
    assert not any(math.isnan(float(row[column])) for row in rows for column in columns)  # inf: a radius not found
