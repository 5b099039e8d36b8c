"""Defects of the review: figures leave the precision to the caller, and the reach GIF is
written through the one atomic writer (spacearm.io)."""

import subprocess
import sys
import types

import numpy as np
import pytest

import spacearm as sa


def test_figures_do_not_switch_float64_on(tmp_path):
    """Drawing a figure keeps the caller's precision (`spacearm --float32 figures` stays float32)."""
    code = (
        "import jax, sys\n"
        "jax.config.update('jax_enable_x64', False)\n"
        "from spacearm.figures import maps, workspace\n"
        f"maps.fig8({str(tmp_path)!r}); workspace.fig4({str(tmp_path)!r})\n"
        "print(jax.config.jax_enable_x64)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "False"
    assert (tmp_path / "fig8.png").stat().st_size > 0


def _tiny_plan(robot):
    phi = np.array([[0.0, -1.0, 2.0], [0.1, -0.9, 1.9], [0.2, -0.8, 1.8]])
    tips = np.asarray(sa.tip_position(robot, phi))
    return types.SimpleNamespace(postures=phi, tips=tips, target=tips[-1])


def test_animate_reach_writes_atomically(tmp_path, monkeypatch):
    from matplotlib.animation import PillowWriter

    from spacearm.figures.planning import animate_reach

    robot = sa.umetani1990()
    plan = _tiny_plan(robot)
    path = animate_reach(robot, plan, tmp_path / "reach.gif", frames=3)
    assert path.read_bytes()[:4] == b"GIF8"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["reach.gif"]  # no temporary left

    def broken(self):
        raise OSError("disk full")

    monkeypatch.setattr(PillowWriter, "finish", broken)
    with pytest.raises(OSError, match="disk full"):
        animate_reach(robot, plan, tmp_path / "again.gif", frames=3)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["reach.gif"]  # nothing half-written
