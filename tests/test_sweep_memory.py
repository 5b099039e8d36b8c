"""A sweep's memory is bounded by default: the designs computed side by side come from a
memory estimate of the robot and its metrics, and the manifest says how many.

The probe's case: two Talos arms (14 joints) on a bus, cut from one humanoid file, with
the joint-box averages; at the old fixed step (up to 8 designs per device) the process
held several GB.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from spacearm.models.spatial import locate_package_file
from spacearm.studies import load_sweep
from spacearm.studies.runner import STEP_MEMORY_BYTES, designs_per_step

ROOT = Path(__file__).resolve().parents[1]
TALOS = "robots/talos_data/robots/talos_reduced.urdf"
AVERAGE = {"rtol": 1.0e-3, "min_samples": 4096, "max_samples": 65536}


def talos_sweep(tmp_path: Path) -> Path:
    try:
        locate_package_file("test", "example-robot-data", TALOS)
    except Exception:
        pytest.skip("example-robot-data is not installed")
    arm = {"urdf": {"package": "example-robot-data", "path": TALOS}, "root_link": "torso_2_link"}
    robot = {
        "name": "dual-talos",
        "base": {"mass": 800.0, "com": [0, 0, 0], "inertia": [[300, 0, 0], [0, 300, 0], [0, 0, 300]]},
        "arms": [
            {"name": "left", "tip": "arm_left_7_link", "lock_others": True, "inertia_as_written": True, **arm},
            {"name": "right", "tip": "arm_right_7_link", "lock_others": True, "inertia_as_written": True, **arm},
        ],
    }
    (tmp_path / "robot.yaml").write_text(yaml.safe_dump(robot))
    sweep = {
        "name": "dual-talos-mount",
        "robot": "robot.yaml",
        "axes": {
            "y": {"field": "arms.right.mount.xyz[1]", "range": {"start": -0.3, "stop": 0.3, "num": 3}},
            "z": {"field": "arms.right.mount.xyz[2]", "range": {"start": -0.3, "stop": 0.3, "num": 3}},
        },
        "metrics": [
            {"name": "w_avg", "tip": "left/arm_left_7_link", **AVERAGE},
            {"name": "w_avg", "tip": "right/arm_right_7_link", **AVERAGE},
            {"name": "base_disturbance", **AVERAGE},
            {"name": "dynamic_manipulability", "tip": "left/arm_left_7_link", **AVERAGE},
        ],
    }
    path = tmp_path / "sweep.yaml"
    path.write_text(yaml.safe_dump(sweep))
    return path


def test_designs_side_by_side_shrink_with_the_working_set(tmp_path):
    talos = load_sweep(talos_sweep(tmp_path))
    per_step, design_bytes = designs_per_step(talos, 2)
    assert 2 * per_step * design_bytes <= STEP_MEMORY_BYTES
    assert per_step == 2  # 14 joints: 126 MB estimated per design
    table2 = load_sweep(ROOT / "sweeps" / "table2.yaml")
    assert designs_per_step(table2, 2)[0] > per_step  # the planar quadratures are small


@pytest.mark.slow
def test_the_dual_talos_sweep_stays_under_2_gb_at_its_defaults(tmp_path):
    sweep = talos_sweep(tmp_path)
    # The peak of this process's own memory (VmHWM): ru_maxrss would also count the pages
    # of the test process it was forked from.
    code = (
        "import sys; from spacearm.cli import main; status = main(sys.argv[1:]); "
        "hwm = [line for line in open('/proc/self/status') if line.startswith('VmHWM')][0]; "
        "print('peak_kib', hwm.split()[1]); sys.exit(status)"
    )
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=2")
    done = subprocess.run(
        [sys.executable, "-c", code, "sweep", str(sweep), "--out", str(tmp_path / "out"), "--quiet"],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    peak_kib = int(done.stdout.split("peak_kib")[-1])
    assert peak_kib < 2 * 2**20, f"peak {peak_kib / 2**20:.2f} GiB"
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert manifest["designs_per_step"] == 2 and manifest["device_count"] == 2
    assert manifest["memory_estimate_bytes"] <= STEP_MEMORY_BYTES * 1.01
