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


@pytest.mark.parametrize("name", ["pareto-attachment.yaml", "pareto-6var.yaml", "table2.yaml", "masses.yaml",
                                  "link-lengths.yaml"])
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
        (dict(objectives=["wbar", "S_GG"]), "objectives[1]: must be one of wbar, S_G, S_M, got 'S_GG' (did you mean 'S_G'?)"),
        (dict(reference_point=[0.0, "x"]), "reference_point[1]: must be a number"),
        (dict(guaranteed="clampd"), "guaranteed: must be one of clamped, paper, got 'clampd' (did you mean 'clamped'?)"),
        (dict(search={"stpes": 3}), "search: unknown key 'stpes' (did you mean 'steps'?)"),
        (dict(search={"schedule": "linear"}), "search.schedule: must be one of geometric, cosine"),
        (dict(search={"learning_rate": -1.0}), "search.learning_rate: must be positive"),
        (dict(baselines={"grid": {"points": [5, 5], "chunk": "big"}}), "baselines.grid.chunk: must be an integer >= 1"),
        (dict(baselines={"nsga2": {"population": 0}}), "baselines.nsga2.population: must be an integer >= 2"),
        (dict(baselines={"nsga2": {"evaluations": 10.5}}), "baselines.nsga2.evaluations: must be an integer >= 1"),
        (dict(baselines={"nsga2": {"time_limit": "soon"}}), "baselines.nsga2.time_limit: must be a number"),
        (dict(baselines={"nsga": {}}), "baselines: unknown key 'nsga' (did you mean 'nsga2'?)"),
        (dict(baselines={"grid": {"points": [10**6, 10**6]}}), "baselines.grid.points: 1,000,000,000,000 grid designs"),
        (dict(fixed={"base_mass": 1000.0, "base_inertia": 635.3, "arm_mass": 200.0, "reach": 4.0, "links": 3},
              variables={"b0": [0.0, 3.0]}),
         "wbar: the area average (eq. 12) is defined for 2 links, fixed.links is 3"),
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
        (dict(metrics=[{"name": "straight_path_area", "n_directions": 4}]), "metrics[0].n_directions: must be an integer >= 8"),
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
