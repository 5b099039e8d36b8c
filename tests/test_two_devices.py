"""A spatial sweep of the joint-box averages finishes on two CPU devices of one process.

jaxlib 0.10.2 hung (all threads asleep) when LAPACK custom calls (eigvalsh, solve) ran
per posture on two forced CPU devices at once; the averages now use closed-form 3 x 3
eigenvalues and the spatial family's closed-form base-rate matrix instead.
"""

import csv
import os
import subprocess
import sys
import textwrap

import pytest

SWEEP = textwrap.dedent(
    """
    name: two-devices
    robot: {root}/configs/arm3dof-100kg.yaml
    axes:
      m: {{field: base.mass, values: [80.0, 120.0]}}
    metrics:
      - {{name: gci, rtol: 1.0e-2, min_samples: 1024, max_samples: 4096}}
      - {{name: base_disturbance, rtol: 1.0e-2, min_samples: 1024, max_samples: 4096}}
    """
)


@pytest.mark.slow
def test_joint_box_averages_finish_on_two_devices(tmp_path):
    root = os.getcwd()
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(SWEEP.format(root=root))
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=2")
    code = "import sys; from spacearm.cli import main; sys.exit(main(sys.argv[1:]))"
    result = subprocess.run(
        [sys.executable, "-c", code, "sweep", str(sweep), "--out", str(tmp_path / "out"), "--quiet"],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr
    with open(tmp_path / "out" / "table.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 2
    assert all(0.0 < float(row["gci"]) < 1.0 for row in rows)
