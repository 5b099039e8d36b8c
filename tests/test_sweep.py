"""Sweep files: validation, batched execution, resume, sharding, the command line."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

import spacearm as sa
from spacearm import io as sio
from spacearm.cli import main
from spacearm.figures.sweep import write_figures
from spacearm.io import manifest as provenance
from spacearm.models.planar import robot_to_mapping
from spacearm.studies import build_designs, load_sweep, run_sweep

ROBOT = str(Path("configs/umetani1990.yaml").resolve())


ROBOT_MAPPING = robot_to_mapping(sa.umetani1990())
THREE_LINKS = {**ROBOT_MAPPING, "links": ROBOT_MAPPING["links"] + [ROBOT_MAPPING["links"][-1]]}


def sweep_config(**changes):
    config = {
        "name": "unit",
        "robot": ROBOT,
        "axes": {"b0_over_B0": {"field": "base.attach", "relative": True, "values": [0.0, 0.5, 1.0, 1.5, 2.0]}},
        "metrics": ["radii"],
        "chunk_size": 2,
    }
    config.update(changes)
    return config


def write(tmp_path, config, name="s.yaml"):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(config))
    return path


def test_designs_follow_the_axes():
    spec = load_sweep(
        sweep_config(
            axes={
                "l1_over_L": {"field": "arm.length_split", "values": [0.25, 0.5, 0.75]},
                "ratio": {"field": "arm.mass_ratio", "values": [0.1, 0.4]},
            }
        )
    )
    robot, points = build_designs(spec)
    assert robot.batch_shape == (6,)
    np.testing.assert_allclose(robot.reach, 4.0, rtol=1e-15)  # L held fixed
    np.testing.assert_allclose(np.asarray(robot.link_length)[:, 0] / 4.0, points["l1_over_L"], rtol=1e-15)
    np.testing.assert_allclose(np.asarray(robot.link_mass).sum(1) / 1000.0, points["ratio"], rtol=1e-15)
    # uniform scaling of a link keeps a/l and I/(m l^2)
    a_over_l = np.asarray(robot.link_a) / np.asarray(robot.link_length)
    np.testing.assert_allclose(a_over_l, 0.5, rtol=1e-15)
    shape = np.asarray(robot.link_inertia) / (np.asarray(robot.link_mass) * np.asarray(robot.link_length) ** 2)
    np.testing.assert_allclose(shape, 33.3 / (100.0 * 4.0), rtol=1e-13)


def test_zip_and_ranges():
    spec = load_sweep(
        sweep_config(
            combine="zip",
            axes={
                "m0": {"field": "base.mass", "range": {"start": 500, "stop": 1500, "num": 3}},
                "l2": {"field": "links[1].length", "range": {"start": 1.0, "stop": 3.0, "step": 1.0}},
            },
        )
    )
    robot, _points = build_designs(spec)
    np.testing.assert_allclose(robot.base_mass, [500, 1000, 1500])
    np.testing.assert_allclose(np.asarray(robot.link_length)[:, 1], [1.0, 2.0, 3.0])


def test_table_matches_single_design_functions(tmp_path):
    spec = load_sweep(sweep_config())
    result = run_sweep(spec, tmp_path / "out", progress=False, outputs=(write_figures,))
    table = sio.read_csv(tmp_path / "out" / "table.csv")
    for i, ratio in enumerate([0.0, 0.5, 1.0, 1.5, 2.0]):
        robot = sa.umetani1990().replace(base_attach=np.float64(1.4 * ratio))
        K = np.asarray(sa.tip_coefficients(robot))
        assert table["b0_over_B0"][i] == ratio
        np.testing.assert_allclose(table["base_attach_m"][i], 1.4 * ratio, rtol=1e-15)
        np.testing.assert_allclose(table["R_max_m"][i], K.sum(), rtol=1e-14)
        np.testing.assert_allclose(table["R_guaranteed_m"][i], abs(K[0] - K[1] - K[2]), rtol=1e-13)
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    for key in ("config", "config_sha256", "packages", "git", "float64", "device_count", "devices", "timings_s"):
        assert key in manifest
    assert manifest["float64"] is True
    assert manifest["config_sha256"] == sio.config_hash(spec.config)
    with np.load(tmp_path / "out" / "grids.npz") as grids:
        np.testing.assert_allclose(grids["metric/R_max_m"], table["R_max_m"])
    assert (tmp_path / "out" / "metrics.png").exists()
    assert not any(p.name.startswith(".partial") for p in (tmp_path / "out").iterdir())
    assert result.manifest["n_designs"] == 5


def test_wbar_options_reach_the_quadrature(tmp_path):
    """A sweep's wbar options (here the fixed-node product rule) are those of spacearm.paper.normalized_wbar."""
    options = {"rule": "product", "phi1_panels": 8, "phi2_panels": 4, "order": 4}
    spec = load_sweep(sweep_config(metrics=[{"name": "wbar", **options}]))
    table = run_sweep(spec, tmp_path / "out", progress=False).table
    for i, ratio in enumerate([0.0, 0.5, 1.0, 1.5, 2.0]):
        robot = sa.umetani1990().replace(base_attach=np.float64(1.4 * ratio))
        coarse = float(sa.paper.normalized_wbar(robot, **options))
        np.testing.assert_allclose(table["wbar"][i], coarse, rtol=1e-13)
        if ratio > 0:  # at b0 = 0 the kinks lie on the strip's edges and both rules are exact
            exact = float(sa.paper.normalized_wbar(robot))
            assert 1e-7 < abs(coarse - exact) / exact < 1e-2  # second order at the kinks


def test_workspace_areas_metric(tmp_path):
    from spacearm import paper

    spec = load_sweep(sweep_config(metrics=["workspace_areas", "S_M", "S_G"]))
    table = run_sweep(spec, tmp_path / "out", progress=False).table
    for i, ratio in enumerate([0.0, 0.5, 1.0, 1.5, 2.0]):
        robot = sa.umetani1990().replace(base_attach=np.float64(1.4 * ratio))
        areas = paper.normalized_workspace_areas(robot)
        for column, key in [
            ("S_fixed_vehicle", "fixed_vehicle"),
            ("S_attitude_constraint", "attitude_constraint"),
            ("S_maximum_reachable", "maximum_reachable"),
            ("S_guaranteed", "guaranteed"),
        ]:
            np.testing.assert_allclose(table[column][i], float(areas[key]), rtol=1e-14)
        np.testing.assert_allclose(table["S_guaranteed"][i], table["S_G"][i], rtol=1e-14)
        assert table["eq9_holds"][i] == float(paper.attachment_condition(robot))
    # Table 1: eq. 9 fails with the arm on the base centroid and holds at b0 = 2 B0.
    assert table["eq9_holds"][0] == 0.0 and table["eq9_holds"][-1] == 1.0


def test_straight_path_area_metric(tmp_path):
    """The sweep column is the area enclosed by the straight-path ends (trapezoid formula here)."""
    from spacearm import paper

    phi_deg = [0.0, -60.0, 120.0]
    spec = load_sweep(
        sweep_config(
            axes={"b0_over_B0": {"field": "base.attach", "relative": True, "values": [0.5, 1.5]}},
            metrics=[{"name": "straight_path_area", "phi_start_deg": phi_deg, "n_directions": 24}],
        )
    )
    table = run_sweep(spec, tmp_path / "out", progress=False).table
    for i, ratio in enumerate([0.5, 1.5]):
        robot = sa.umetani1990().replace(base_attach=np.float64(1.4 * ratio))
        ends = np.asarray(paper.straight_path_workspace(robot, np.radians(phi_deg), 24))
        x, y = ends[:, 0], ends[:, 1]
        area = 0.5 * abs(np.sum((x + np.roll(x, -1)) * (np.roll(y, -1) - y)))
        np.testing.assert_allclose(table["S_straight"][i], area / (np.pi * 4.0**2), rtol=1e-10)
        assert 0.05 < table["S_straight"][i] < 2.25  # inside Area 3 (S_M <= 2.25 for b0 <= 2 B0)


def test_axes_apply_in_a_fixed_order():
    """arm.mass_ratio is taken against the final base mass, whichever axis the file lists first."""
    axes = {
        "ratio": {"field": "arm.mass_ratio", "values": [0.2]},
        "m0": {"field": "base.mass", "values": [500.0, 2000.0]},
    }
    robot, _ = build_designs(load_sweep(sweep_config(axes=axes)))
    reordered, _ = build_designs(load_sweep(sweep_config(axes=dict(reversed(list(axes.items()))))))
    np.testing.assert_allclose(
        np.asarray(robot.link_mass).sum(axis=1) / np.asarray(robot.base_mass), [0.2, 0.2], rtol=1e-15
    )
    np.testing.assert_allclose(np.sort(np.asarray(reordered.link_mass).sum(axis=1)), [100.0, 400.0], rtol=1e-15)


def test_manifest_config_is_a_sweep_file_that_reruns(tmp_path):
    spec = load_sweep(sweep_config(metrics=["S_M"]))
    result = run_sweep(spec, tmp_path / "out", progress=False)
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert manifest["robot_file"] == ROBOT
    again = load_sweep(write(tmp_path, manifest["config"], "again.yaml"))
    assert sio.config_hash(again.config) == manifest["config_sha256"]
    assert run_sweep(again, tmp_path / "again", progress=False).table["S_M"].tolist() == result.table["S_M"].tolist()


def test_manifest_git_state_is_taken_before_the_run_writes(tmp_path, monkeypatch):
    """Regenerating committed results modifies tracked files; that must not mark the code dirty."""
    states = iter([{"revision": "abc", "dirty": False}, {"revision": "abc", "dirty": True}])
    monkeypatch.setattr(provenance, "git_state", lambda *a: next(states))
    run_sweep(load_sweep(sweep_config(metrics=["S_M"])), tmp_path / "out", progress=False)
    assert json.loads((tmp_path / "out" / "manifest.json").read_text())["git"] == {"revision": "abc", "dirty": False}


def test_reordered_axes_never_reuse_chunks(tmp_path):
    """The axis order decides which design is in which row, so it is part of the resume key."""
    axes = {
        "r": {"field": "base.attach", "values": [0.0, 1.0, 2.0]},
        "b": {"field": "base.mass", "values": [500.0, 900.0]},
    }
    spec = load_sweep(sweep_config(axes=axes, metrics=["S_G"]))
    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, tmp_path / "o", progress=False, stop_after_chunks=2)
    swapped = load_sweep(sweep_config(axes=dict(reversed(list(axes.items()))), metrics=["S_G"]))
    assert sio.config_hash(swapped.config) != sio.config_hash(spec.config)
    result = run_sweep(swapped, tmp_path / "o", progress=False)
    assert result.manifest["resumed_chunks"] == 0
    fresh = run_sweep(swapped, tmp_path / "fresh", progress=False)
    assert result.table["S_G"].tolist() == fresh.table["S_G"].tolist()
    manifest = json.loads((tmp_path / "o" / "manifest.json").read_text())
    assert list(manifest["config"]["axes"]) == ["b", "r"]


def test_cleanup_touches_only_what_a_sweep_wrote(tmp_path):
    out = tmp_path / "foreign"
    (out / ".partial-mine").mkdir(parents=True)
    (out / ".partial-mine" / "important.txt").write_text("keep")
    for name in ("notes.txt", "data.csv", "heatmap_x.png"):
        (out / name).write_text("user data")
    (out / "manifest.json").write_text(
        json.dumps({"name": "my-dataset", "files": ["notes.txt", "data.csv", "heatmap_x.png"]})
    )
    run_sweep(load_sweep(sweep_config(metrics=["S_M"])), out, progress=False)
    for name in ("notes.txt", "data.csv", "heatmap_x.png", ".partial-mine/important.txt"):
        assert (out / name).exists(), name


def test_interrupted_sweep_resumes_to_the_same_table(tmp_path):
    spec = load_sweep(sweep_config())
    run_sweep(spec, tmp_path / "full", progress=False)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, tmp_path / "cut", progress=False, stop_after_chunks=2)
    assert not (tmp_path / "cut" / "table.csv").exists()
    partial = [p for p in (tmp_path / "cut").iterdir() if p.name.startswith(".partial")]
    assert len(partial) == 1 and len(list(partial[0].glob("chunk_*.npz"))) == 2
    resumed = run_sweep(spec, tmp_path / "cut", progress=False)
    assert resumed.manifest["resumed_chunks"] == 2
    assert (tmp_path / "full" / "table.csv").read_text() == (tmp_path / "cut" / "table.csv").read_text()


def test_resume_ignores_chunks_of_another_chunk_size_and_damaged_chunks(tmp_path):
    spec = load_sweep(sweep_config())
    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, tmp_path / "cut", progress=False, stop_after_chunks=2)
    old_partial = next((tmp_path / "cut").glob(".partial-*"))
    bigger = load_sweep(sweep_config(chunk_size=4))  # same designs, other chunking: start afresh
    assert run_sweep(bigger, tmp_path / "cut", progress=False).manifest["resumed_chunks"] == 0
    assert [p.name for p in (tmp_path / "cut").glob(".partial-*")] == [old_partial.name]  # not ours to delete
    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, tmp_path / "again", progress=False, stop_after_chunks=2)
    damaged = sorted((tmp_path / "again").glob(".partial-*/chunk_*.npz"))[0]
    damaged.write_bytes(damaged.read_bytes()[:40])
    resumed = run_sweep(spec, tmp_path / "again", progress=False)
    assert resumed.manifest["resumed_chunks"] == 1
    assert (tmp_path / "again" / "table.csv").read_text() == (tmp_path / "cut" / "table.csv").read_text()


def test_rerun_into_the_same_folder_removes_its_stale_figures(tmp_path):
    axes = {
        "b0": {"field": "base.attach", "values": [0.0, 1.0]},
        "m0": {"field": "base.mass", "values": [500.0, 900.0]},
    }
    run_sweep(
        load_sweep(sweep_config(axes=axes, metrics=["S_M", "S_G"])),
        tmp_path / "o",
        progress=False,
        outputs=(write_figures,),
    )
    assert (tmp_path / "o" / "heatmap_S_G.png").exists()
    (tmp_path / "o" / "mine.txt").write_text("a user's file")
    run_sweep(
        load_sweep(sweep_config(axes=axes, metrics=["S_M"])), tmp_path / "o", progress=False, outputs=(write_figures,)
    )
    assert not (tmp_path / "o" / "heatmap_S_G.png").exists()
    assert (tmp_path / "o" / "heatmap_S_M.png").exists() and (tmp_path / "o" / "mine.txt").exists()


@pytest.mark.parametrize(
    "change, message",
    [
        (dict(axes={}), r"axes: must be a non-empty mapping"),
        (dict(axes={"x": {"field": "base.attach", "values": []}}), r"axes\.x\.values: is empty"),
        (
            dict(axes={"x": {"field": "base.atach", "values": [1]}}),
            r"unknown design field 'base.atach' \(did you mean 'base.attach'\?\)",
        ),
        (
            dict(axes={"x": {"field": "base.attach", "valeus": [1]}}),
            r"unknown key 'valeus' \(did you mean 'values'\?\)",
        ),
        (dict(metircs=["radii"]), r"unknown key 'metircs' \(did you mean 'metrics'\?\)"),
        (dict(metrics=["wbra"]), r"unknown metric 'wbra' \(did you mean 'wbar'\?\)"),
        (dict(robot="nowhere.yaml"), r"robot: no such robot file 'nowhere.yaml'"),
        (
            dict(axes={"x": {"field": "base.attach", "values": ["far"]}}),
            r"axes\.x\.values\[0\]: must be a finite number",
        ),
        (dict(axes={"x": {"field": "links[2].mass", "values": [1.0]}}), r"link index 2 out of range"),
        (dict(chunk_size=0), r"chunk_size: must be a positive integer"),
        (dict(metrics=[{"name": "wbar", "phi1_panels": 7}]), r"metrics\[0\]\.phi1_panels: must be even"),
        (dict(metrics=[{"name": "wbar", "rule": "simpson"}]), r"metrics\[0\]\.rule: must be one of adaptive, product"),
        (dict(metrics=[{"name": "wbar", "order": True}]), r"metrics\[0\]\.order: must be an integer >= 1"),
        (dict(metrics=[{"name": "wbar", "ordre": 4}]), r"unknown key 'ordre' \(did you mean 'order'\?\)"),
        (
            dict(axes={"m1": {"field": "links[0].mass", "values": [100.0, -5.0]}}),
            r"sweep point 1 \(m1=-5\) gives an invalid robot: links\[0\]\.mass: must be positive",
        ),
        (
            dict(axes={"r": {"field": "base.attach", "values": [1.0]}, "q": {"field": "base.attach", "values": [2.0]}}),
            r"axes\.r \(base\.attach\) and axes\.q \(base\.attach\) both set base\.attach",
        ),
        (
            dict(
                axes={
                    "i0": {"field": "links[0].inertia", "values": [9.0]},
                    "m": {"field": "arm.mass", "values": [300.0]},
                }
            ),
            r"both set links\[0\]\.inertia; give each design number one axis",
        ),
        (
            dict(axes={"b": {"field": "base.attach", "range": {"start": 0.0, "stop": 1.0, "step": 1e-300}}}),
            r"axes\.b\.range\.step: 1e-300 from 0 to 1 gives too many values",
        ),
        (
            dict(axes={"b": {"field": "base.attach", "range": {"start": -1e308, "stop": 1e308, "num": 3}}}),
            r"axes\.b\.range\.start: must be at most 1e\+15 in magnitude, got -1e\+308",
        ),
        (
            dict(
                report="table2",
                metrics=[{"name": "wbar", "measure": "joint"}, "S_M", "S_G"],
                axes={"b0_over_B0": {"field": "base.attach", "relative": True, "values": [0.0]}},
            ),
            r"report: table2 compares the area average of eq\. 12; drop wbar's measure: joint",
        ),
        (
            dict(report="table2", metrics=["S_M", "S_G"]),
            r"report: table2 needs the metrics wbar, S_M and S_G \(missing: wbar\)",
        ),
        (
            dict(
                report="table2", metrics=["wbar", "S_M", "S_G"], axes={"b0": {"field": "base.attach", "values": [0.0]}}
            ),
            r"report: table2 needs exactly one axis, b0_over_B0",
        ),
        (
            dict(
                report="table2",
                metrics=["wbar", "S_M", "S_G"],
                robot={**ROBOT_MAPPING, "base": {**ROBOT_MAPPING["base"], "mass": 900.0}},
            ),
            r"report: table2 compares with the paper's Table 1 robot; this robot's base_mass differs",
        ),
        (
            dict(metrics=[{"name": "straight_path_area", "phi_start_deg": [0, 1]}]),
            r"metrics\[0\]\.phi_start_deg: needs 3 angles \[phi0, phi1, \.\.\., phi2\] for a 2-link robot, got 2",
        ),
        (
            dict(robot=THREE_LINKS, metrics=["wbar"]),
            r"metrics\[0\]: wbar's area average \(eq\. 12\) is defined for 2 links, the robot has 3",
        ),
        (
            dict(axes={"b": {"field": "base.attach", "range": {"start": 0.0, "stop": 1.0, "num": 10**12}}}),
            r"axes\.b\.range: 1,000,000,000,000 designs \(num: 1000000000000\) need about [\d,]+ GiB",
        ),
        (
            dict(
                axes={
                    a: {"field": f, "range": {"start": 0.1, "stop": 1.0, "num": 10**4}}
                    for a, f in (("x", "base.attach"), ("y", "arm.mass_ratio"), ("z", "arm.length_split"))
                }
            ),
            r"axes: 1,000,000,000,000 designs \(10000 x 10000 x 10000\) need about",
        ),
    ],
)
def test_invalid_sweeps_name_the_problem(change, message):
    with pytest.raises(sa.ConfigError, match=message):
        load_sweep(sweep_config(**change))


@pytest.mark.parametrize(
    "override, message",
    [
        ("chunksize=4", r"--set chunksize: unknown key 'chunksize' \(did you mean 'chunk_size'\?\)"),
        ("=3", r"--set =3: the key must be a dotted path"),
        ("a..b=3", r"--set a\.\.b=3: the key must be a dotted path"),
        ("chunk_size=[1,", r"--set chunk_size: malformed YAML at line 1, column 4"),
    ],
)
def test_bad_overrides_name_themselves(override, message):
    with pytest.raises(sa.ConfigError, match=message):
        load_sweep(sweep_config(), overrides=[override])


def test_length_and_arm_mass_axes_combine():
    axes = {"l": {"field": "links[*].length", "values": [1.5]}, "m": {"field": "arm.mass", "values": [300.0]}}
    robot, _ = build_designs(load_sweep(sweep_config(axes=axes)))
    # Table 1 links: 2 m, 100 kg, 33.3 kg m^2 each -> 1.5 m, 150 kg: I = 33.3 (1.5/2)^2 (150/100).
    np.testing.assert_allclose(np.asarray(robot.link_inertia), [[33.3 * 0.75**2 * 1.5] * 2], rtol=1e-14)


def test_override_null_of_a_missing_key_changes_nothing():
    assert load_sweep(sweep_config(), overrides=["axes.zz.range=null"]).config == load_sweep(sweep_config()).config


def test_override_null_removes_a_key_and_ranges_may_descend():
    spec = load_sweep(
        sweep_config(),
        overrides=["axes.b0_over_B0.values=null", "axes.b0_over_B0.range={start: 2.0, stop: 1.0, step: -0.5}"],
    )
    assert spec.axes[0].values.tolist() == [2.0, 1.5, 1.0]


def test_malformed_yaml_is_one_line(tmp_path, capsys):
    path = tmp_path / "broken.yaml"
    path.write_text("name: x\nrobot: [a\n")
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "malformed YAML at line 3, column 1" in err


def test_cli_invalid_sweep_exits_2_and_writes_nothing(tmp_path, capsys):
    path = write(tmp_path, sweep_config(axes={"m1": {"field": "links[0].mass", "values": [-1.0]}}))
    out = tmp_path / "never"
    assert main(["sweep", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "links[0].mass: must be positive" in err and "Traceback" not in err
    assert not out.exists()
    assert main(["validate", str(path)]) == 2


def test_cli_sweep_with_set_override(tmp_path, capsys):
    path = write(tmp_path, sweep_config())
    out = tmp_path / "o"
    code = main(["sweep", str(path), "--out", str(out), "--quiet", "--set", "axes.b0_over_B0.values=[0.0, 2.0]"])
    assert code == 0
    table = sio.read_csv(out / "table.csv")
    assert table["b0_over_B0"] == [0.0, 2.0]
    assert main(["validate", str(path)]) == 0
    assert "valid sweep" in capsys.readouterr().out


def test_sharded_sweep_equals_single_device(tmp_path):
    path = write(
        tmp_path,
        sweep_config(
            axes={
                "b0_over_B0": {"field": "base.attach", "relative": True, "range": {"start": 0, "stop": 2, "num": 7}},
                "m0": {"field": "base.mass", "values": [500.0, 1000.0, 2000.0]},
            },
            chunk_size=5,
        ),
    )
    single = tmp_path / "single"
    assert main(["sweep", str(path), "--out", str(single), "--quiet"]) == 0
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=4")
    code = (
        "import sys, jax; from spacearm.cli import main; "
        "assert jax.device_count() == 4, jax.devices(); "
        f"sys.exit(main(['sweep', {str(path)!r}, '--out', {str(tmp_path / 'sharded')!r}, '--quiet']))"
    )
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    manifest = json.loads((tmp_path / "sharded" / "manifest.json").read_text())
    assert manifest["device_count"] == 4
    a = sio.read_csv(single / "table.csv")
    b = sio.read_csv(tmp_path / "sharded" / "table.csv")
    for column in a:
        np.testing.assert_allclose(b[column], a[column], rtol=1e-14, err_msg=column)
    assert (tmp_path / "sharded" / "heatmap_R_max_m.png").exists()
