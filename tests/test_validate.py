"""`spacearm validate` refuses what a run would refuse: exit 2, the field named, no traceback."""

import copy
from pathlib import Path

import pytest
import yaml

from spacearm.cli import main

ROOT = Path(__file__).resolve().parents[1]


def problem(**changes):
    config = yaml.safe_load((ROOT / "sweeps" / "pareto-attachment.yaml").read_text())
    config.update(copy.deepcopy(changes))
    return config


def sweep(**changes):
    config = {
        "name": "unit",
        "robot": str(ROOT / "configs" / "umetani1990.yaml"),
        "axes": {"b0": {"field": "base.attach", "values": [0.0, 1.0]}},
        "metrics": ["S_M"],
    }
    config.update(copy.deepcopy(changes))
    return config


def validate(tmp_path, config, capsys):
    path = tmp_path / "file.yaml"
    path.write_text(yaml.safe_dump(config))
    code = main(["validate", str(path)])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.mark.parametrize(
    "name", ["pareto-attachment.yaml", "pareto-6var.yaml", "table2.yaml", "masses.yaml", "link-lengths.yaml"]
)
def test_shipped_files_validate(name, capsys):
    assert main(["validate", str(ROOT / "sweeps" / name)]) == 0
    assert "valid" in capsys.readouterr().out


@pytest.mark.parametrize(
    "changes, field",
    [
        (dict(wbar={"ordr": 4}), "wbar: unknown key 'ordr' (did you mean 'order'?)"),
        (dict(wbar={"order": 0}), "wbar.order: must be an integer >= 1, got 0"),
        (dict(wbar={"phi1_panels": 3}), "wbar.phi1_panels: must be even"),
        (dict(wbar={"rule": "simpson"}), "wbar.rule: must be one of adaptive, product"),
        (dict(wbar={"measure": "volume"}), "wbar.measure: must be one of area, joint"),
        (dict(wbar=[4]), "wbar: must be a mapping"),
        (dict(objectives="wbar"), "objectives: must be a list"),
        (
            dict(objectives=["wbar", "S_GG"]),
            "objectives[1]: must be one of wbar, S_G, S_M, low_virtual_mass, low_bus_rate_jump, low_capture_bus_rate, "
            "reach_radius, got 'S_GG' (did you mean 'S_G'?)",
        ),
        (dict(reference_point=[0.0, "x"]), "reference_point[1]: must be a number"),
        (
            dict(guaranteed="clampd"),
            "guaranteed: must be one of clamped, paper, got 'clampd' (did you mean 'clamped'?)",
        ),
        (dict(search={"stpes": 3}), "search: unknown key 'stpes' (did you mean 'steps'?)"),
        (dict(search={"schedule": "linear"}), "search.schedule: must be one of geometric, cosine"),
        (dict(search={"learning_rate": -1.0}), "search.learning_rate: must be positive"),
        (dict(baselines={"grid": {"points": [5, 5], "chunk": "big"}}), "baselines.grid.chunk: must be an integer >= 1"),
        (dict(baselines={"nsga2": {"population": 0}}), "baselines.nsga2.population: must be an integer >= 2"),
        (dict(baselines={"nsga2": {"evaluations": 10.5}}), "baselines.nsga2.evaluations: must be an integer >= 1"),
        (dict(baselines={"nsga2": {"time_limit": "soon"}}), "baselines.nsga2.time_limit: must be a number"),
        (dict(baselines={"nsga": {}}), "baselines: unknown key 'nsga' (did you mean 'nsga2'?)"),
        (dict(baselines={"grid": {"points": [10**6, 10**6]}}), "baselines.grid.points: 1,000,000,000,000 grid designs"),
        (
            dict(
                fixed={"base_mass": 1000.0, "base_inertia": 635.3, "arm_mass": 200.0, "reach": 4.0, "links": 3},
                variables={"b0": [0.0, 3.0]},
            ),
            "wbar: the area average (eq. 12) is defined for 2 links, fixed.links is 3",
        ),
        (dict(variables={"b0": [0.0, "3"]}), "variables.b0[1]: must be a number"),
    ],
)
def test_invalid_design_problem_fails_validate(tmp_path, capsys, changes, field):
    code, out, err = validate(tmp_path, problem(**changes), capsys)
    assert code == 2, out
    assert field in err and "Traceback" not in err
    assert err.count("\n") == 1  # one line


@pytest.mark.parametrize(
    "changes, field",
    [
        (dict(metrics=[{"name": "wbar", "ordr": 4}]), "metrics[0]: unknown key 'ordr' (did you mean 'order'?)"),
        (dict(metrics=[{"name": "wbar", "order": 0}]), "metrics[0].order: must be an integer >= 1, got 0"),
        (
            dict(metrics=[{"name": "straight_path_area", "n_directions": 4}]),
            "metrics[0].n_directions: must be an integer >= 8",
        ),
        (dict(metrics=[{"name": "radii", "scale": 2}]), "metrics[0]: this metric takes no options"),
        (dict(combine="zipped"), "combine: must be 'product' or 'zip'"),
        (dict(report="table3"), "report: unknown report 'table3'"),
        (dict(output=3), "output: must be a folder path"),
        (dict(name="a b"), "name: must be a plain name"),
    ],
)
def test_invalid_sweep_fails_validate(tmp_path, capsys, changes, field):
    code, out, err = validate(tmp_path, sweep(**changes), capsys)
    assert code == 2, out
    assert field in err and "Traceback" not in err


def test_valid_problem_summary(tmp_path, capsys):
    code, out, _ = validate(tmp_path, problem(), capsys)
    assert code == 0
    assert "valid design problem (pareto-attachment: variables b0, l1_over_L)" in out


def test_unknown_kind_and_missing_file(tmp_path, capsys):
    code, _, err = validate(tmp_path, {"colour": "red"}, capsys)
    assert code == 2 and "neither a robot file" in err
    assert main(["validate", str(tmp_path / "missing.yaml")]) == 2
    assert "no such" in capsys.readouterr().err


def _chain_urdf(joints: int) -> str:
    links = "".join(
        f'<link name="l{i}"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" '
        f'iyz="0"/></inertial></link>'
        for i in range(joints + 1)
    )
    chain = "".join(
        f'<joint name="j{i}" type="revolute"><origin xyz="0 0 0.1"/><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<axis xyz="0 {i % 2} {(i + 1) % 2}"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        for i in range(joints)
    )
    return f'<robot name="chain">{links}{chain}</robot>'


def _chain_robot(tmp_path, joints: int, **arm) -> Path:
    (tmp_path / "chain.urdf").write_text(_chain_urdf(joints))
    path = tmp_path / "robot.yaml"
    path.write_text(
        yaml.safe_dump(
            {
                "name": "chain",
                "base": {"mass": 100.0, "inertia": [[10, 0, 0], [0, 10, 0], [0, 0, 10]]},
                "arm": {"urdf": "chain.urdf", "root_link": "l0", "tip": f"l{joints}", **arm},
            }
        )
    )
    return path


def test_joint_box_metrics_on_more_than_32_joints_fail_validate(tmp_path, capsys):
    """Before: validate accepted them and the run refused without naming file or metric."""
    robot = _chain_robot(tmp_path, 33)
    code, _, err = validate(
        tmp_path,
        {
            "name": "many",
            "robot": str(robot),
            "metrics": ["w_avg"],
            "axes": {"m": {"field": "base.mass", "values": [100.0]}},
        },
        capsys,
    )
    assert code == 2
    assert "file.yaml: metrics[0]: joints: the joint-box averages support 1 to 32 joints, the robot has 33" in err


def test_arm_fields_are_named_in_the_robot_file(tmp_path, capsys):
    """Before: errors about arm.tip / arm.lock_joints named only the URDF (for a package URDF,
    a path in site-packages)."""
    robot = _chain_robot(tmp_path, 2, tip="l9", lock_joints={"j7": 0.0})
    assert main(["validate", str(robot)]) == 2
    err = capsys.readouterr().err
    assert f"{robot}: arm.lock_joints: (in {tmp_path / 'chain.urdf'}) unknown joint 'j7'" in err
    robot = _chain_robot(tmp_path, 2, tip="l9")
    assert main(["validate", str(robot)]) == 2
    err = capsys.readouterr().err
    assert f"{robot}: arm.tip: (in {tmp_path / 'chain.urdf'}) link 'l9' is not in the URDF" in err


def test_numbers_yaml_reads_as_strings_get_the_reason(tmp_path, capsys):
    path = tmp_path / "robot.yaml"
    path.write_text((ROOT / "configs" / "umetani1990.yaml").read_text().replace("mass: 1000.0", "mass: 1.0e12"))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "base.mass: must be a number, got the string '1.0e12' (YAML 1.1 reads a number with an exponent" in err
    assert "e.g. 1.0e+12" in err
    path.write_text(path.read_text().replace("1.0e12", "1.0e+12"))
    assert main(["validate", str(path)]) == 0


def test_size_options_have_upper_bounds(tmp_path, capsys):
    """Before: wbar order 1e9 took 3.4 GB in 2 s; a phi1_panels of 1e6 ended in RESOURCE_EXHAUSTED."""
    code, _, err = validate(tmp_path, sweep(metrics=[{"name": "wbar", "order": 10**9}]), capsys)
    assert code == 2 and "metrics[0].order: must be at most 64" in err
    code, _, err = validate(tmp_path, problem(search={"directions": 10**8}), capsys)
    assert code == 2 and "search.directions: must be at most 4,096" in err
    # within every bound, yet too big together: the memory estimate and the fix
    code, _, err = validate(
        tmp_path, sweep(metrics=[{"name": "wbar", "order": 64, "phi1_panels": 4096, "phi2_panels": 4096}]), capsys
    )
    assert code == 2 and "GiB" in err and "lower metric 'wbar' option order or phi1_panels/phi2_panels" in err


def test_a_search_too_big_for_memory_is_refused_with_the_estimate(tmp_path, capsys):
    """directions and starts each within bounds, but 4096 x 65536 runs of w-bar side by side."""
    code, _, err = validate(tmp_path, problem(search={"directions": 4096, "starts": 65536}), capsys)
    assert code == 2 and "search: 268,435,456 search runs (directions x starts) need about" in err
    assert "lower search.directions or search.starts, or wbar.order" in err
