"""Defects of the review: figures leave the precision to the caller, and the reach GIF is
written through the one atomic writer (spacearm.io)."""

import itertools
import subprocess
import sys
import types
from importlib import metadata
from pathlib import Path

import matplotlib
import matplotlib.container
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

import spacearm as sa
from spacearm.cli.sweep import format_table
from spacearm.figures import spatial, sweep as sweep_figures
from spacearm.figures.sweep import COLUMN_LABELS, column_label
from spacearm.studies import load_sweep
from spacearm.studies.metrics import METRICS

matplotlib.use("Agg")


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


# --- Outputs a person reads: labels, error bars, equal 3-D scales, the printed table ----------

SRC = Path(__file__).resolve().parents[1] / "src" / "spacearm"


def test_no_library_module_changes_a_global_jax_setting():
    """Only `enable_x64` (the documented switch, in _core) and the command line may set JAX's config."""
    allowed = {"_core/numeric.py", "cli"}
    offenders = []
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        if rel in allowed or rel.split("/")[0] in allowed:
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            if "jax.config.update(" in line and not line.lstrip().startswith(("#", '"', "'")):
                offenders.append(f"{rel}:{number}: {line.strip()}")
    assert not offenders, "\n".join(offenders)


def test_every_sweep_column_has_a_label_in_words():
    for name, metric in METRICS.items():
        for column in metric.columns({}):
            if column.endswith("_error"):
                continue
            if column.endswith("_samples"):  # an average's posture count, named after it
                assert column_label(column) == f"postures averaged, {column_label(column[: -len('_samples')])}"
                continue
            assert column in COLUMN_LABELS, f"metric {name}: column {column} has no label"
            assert column_label(column) != column
    assert column_label("w_avg_m3").endswith("m³") and column_label("C_w_avg").endswith("rad/rad")


def test_sweep_plots_draw_errors_as_bars_not_as_panels(tmp_path, monkeypatch):
    """A 1-D sweep with averages: one panel per metric, each with error bars (2 standard
    errors) and its label in words; the `_error` columns get no panel of their own."""
    try:
        metadata.version("example-robot-data")
    except metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed")
    root = SRC.parents[1]
    spec = load_sweep(root / "sweeps" / "ur5-mass-ratio.yaml")
    n = len(spec.axes[0].values)
    table = {
        "w_avg_m3": np.linspace(0.045, 0.016, n),
        "w_avg_m3_error": np.full(n, 1e-5),
        "C_w_avg": np.linspace(0.01, 0.3, n),
        "C_w_avg_error": np.full(n, 2e-5),
        "gci": np.linspace(0.265, 0.259, n),
        "gci_error": np.full(n, 2e-4),
    }
    drawn = []
    monkeypatch.setattr(sweep_figures, "save_figure", lambda fig, path, **kw: drawn.append(fig) or path)
    sweep_figures.sweep_figures(spec, tmp_path, table)
    (fig,) = drawn
    axes = fig.axes
    assert len(axes) == 3
    for ax, column in zip(axes, ("w_avg_m3", "C_w_avg", "gci"), strict=False):
        bars = [c for c in ax.containers if isinstance(c, matplotlib.container.ErrorbarContainer)]
        assert len(bars) == 1
        segments = bars[0].lines[2][0].get_segments()
        heights = [abs(s[1][1] - s[0][1]) for s in segments]
        np.testing.assert_allclose(heights, 4 * table[f"{column}_error"], rtol=1e-9)  # +- 2 standard errors
        assert ax.get_ylabel() == sweep_figures.column_label(column)
    assert axes[0].get_xlabel() == "ratio = arm.mass_ratio"


def test_line_plot_axis_labels_stay_in_their_panels(tmp_path, monkeypatch):
    """Table 2's metrics.png: the long x label ("b0_over_B0 = base.attach, relative to the base
    design") goes on two lines, so no panel's label runs into the next one's or off the figure."""
    spec = load_sweep(SRC.parents[1] / "sweeps" / "table2.yaml")
    n = len(spec.axes[0].values)
    table = {"wbar": np.linspace(0.08, 0.1, n), "S_M": np.linspace(0.8, 2.2, n), "S_G": np.linspace(0.8, 0.1, n)}
    drawn = []
    monkeypatch.setattr(sweep_figures, "save_figure", lambda fig, path, **kw: drawn.append(fig) or path)
    sweep_figures.sweep_figures(spec, tmp_path, table)
    (fig,) = drawn
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)  # constrained layout places the panels
    boxes = [ax.xaxis.label.get_window_extent(renderer) for ax in fig.axes]
    for left, right in itertools.pairwise(boxes):
        assert left.x1 < right.x0
    assert boxes[0].x0 >= 0 and boxes[-1].x1 <= fig.bbox.width
    assert fig.axes[0].get_xlabel() == "b0_over_B0 = base.attach,\nrelative to the base design"
    plt.close(fig)


def test_3d_figures_have_equal_scales_and_keep_the_bus_inside():
    """The bus is drawn as the uniform box of its mass and inertia, and the axes hold it."""
    rotation = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    robot = sa.load_robot("configs/ur5-smallsat.yaml")
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    drawing = spatial.draw_robot(ax, robot, np.full(6, 0.4), rotation)
    points = spatial.drawn_points(drawing)
    spatial._equal(ax, points)
    limits = np.array([ax.get_xlim(), ax.get_ylim(), ax.get_zlim()])
    np.testing.assert_allclose(np.diff(limits, axis=1), np.diff(limits[:1], axis=1).repeat(3, 0))  # equal spans
    assert np.all(points >= limits[:, 0]) and np.all(points <= limits[:, 1])
    np.testing.assert_allclose(ax.get_box_aspect() / ax.get_box_aspect()[0], 1.0)
    # The box's sides from the bus inertia: side_i = sqrt(6 (I_j + I_k - I_i) / m) (a uniform box).
    moments = np.linalg.eigvalsh(np.asarray(robot.base_inertia))
    sides = np.sqrt(6.0 * (moments.sum() - 2.0 * moments) / float(robot.base_mass))
    edges = np.linalg.norm(drawing.bus_corners[1:] - drawing.bus_corners[0], axis=1)
    np.testing.assert_allclose(np.sort(edges)[:3], np.sort(sides), rtol=1e-12)
    plt.close(fig)


def test_sweep_prints_its_table_with_errors_and_summarizes_long_ones():
    short = {
        "design": np.arange(3.0),
        "x": np.array([0.1, 0.2, 0.3]),
        "w_avg_m3": np.array([0.5, 0.25, 0.125]),
        "w_avg_m3_error": np.array([1e-4, 2e-4, 3e-4]),
    }
    lines = format_table(short).splitlines()
    assert lines[0].split() == ["design", "x", "w_avg_m3"]
    assert lines[2].split() == ["1", "0.2", "0.25", "±", "0.0002"] and len(lines) == 4
    n = 50
    long = {"design": np.arange(float(n)), "S_G": np.linspace(1.0, 2.0, n)}
    lines = format_table(long, max_rows=20).splitlines()
    assert len(lines) == 1 + 20 + 1 + 3 + 1
    assert lines[22].split() == ["min", "1"] and lines[23].split() == ["median", "1.5"]
    assert lines[24].split() == ["max", "2"] and "50 rows" in lines[-1]
