"""Hostile numbers end in one line, never a traceback, a hang or an allocation past memory.

The probe's cases: a NaN time factor that ran NSGA-II forever, a reference point above the
front that divided by a zero hypervolume, a ``hybrid:`` section that ``validate`` passed
and ``optimize`` refused, a population within the old limit that ran out of memory, and
an unbounded number of objectives.
"""

from pathlib import Path

import numpy as np
import pytest
import yaml

import spacearm as sa
from spacearm.cli import main
from spacearm.design.run import summary_table

ROOT = Path(__file__).resolve().parents[1]
PROBLEM = ROOT / "sweeps" / "pareto-attachment.yaml"


def problem_file(tmp_path: Path, **changes) -> Path:
    data = yaml.safe_load(PROBLEM.read_text())
    data.update(changes)
    path = tmp_path / "problem.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "error:" in line]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.mark.parametrize("option", ["--nsga2-factor", "--max-seconds"])
@pytest.mark.parametrize("value", ["nan", "inf", "0", "-1"])
def test_a_time_option_that_is_not_a_positive_number_is_refused(tmp_path, capsys, option, value):
    assert main(["optimize", str(PROBLEM), f"{option}={value}", "--out", str(tmp_path / "out")]) == 2
    assert option in one_error_line(capsys)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("section", "field"),
    [
        ({"population": 1_000_000_000}, "hybrid.population"),
        ({"generations": -1}, "hybrid.generations"),
        ({"populaton": 64}, "populaton"),
        ({"population": 100_000}, "hybrid.population"),
    ],
)
def test_validate_reads_the_hybrid_section_as_optimize_does(tmp_path, capsys, section, field):
    path = problem_file(tmp_path, hybrid=section)
    assert main(["validate", str(path)]) == 2
    assert field in one_error_line(capsys)
    assert main(["optimize", str(path), "--no-baselines", "--out", str(tmp_path / "out")]) == 2
    assert field in one_error_line(capsys)


def test_the_number_of_objectives_is_bounded(tmp_path, capsys):
    path = problem_file(tmp_path, objectives=["wbar", "S_G"] * 4, reference_point=[0.0] * 8)
    assert main(["validate", str(path)]) == 2
    assert "at most 6" in one_error_line(capsys)


@pytest.mark.slow
def test_a_reference_point_above_the_front_is_reported_not_a_traceback(tmp_path, capsys):
    """Before: ZeroDivisionError in the convergence figure."""
    path = problem_file(tmp_path, name="zero-hv", reference_point=[10.0, 10.0])
    out = tmp_path / "out"
    assert main(["optimize", str(path), "--no-baselines", "--max-seconds", "1", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "no design dominates the reference point" in printed
    assert "of best" not in printed  # no share of a best measured against itself
    assert (out / "convergence.png").exists()


def test_without_baselines_the_table_gives_the_hypervolume_not_a_share(tmp_path, capsys):
    row = {"hypervolume": 2.5, "evaluations": 10, "run_seconds": 1.0, "compile_seconds": 1.0}
    alone = {
        "best_known_hypervolume": 2.5,
        "methods": {"hybrid": row},
        "method": "hybrid",
        "reference_point": [0.0, 0.0],
        "reference_point_from": "problem",
    }
    table = summary_table(alone)
    assert "of best" not in table and "100.0000%" not in table and "hypervolume 2.5" in table
    grid = dict(row, hypervolume=3.0)
    both = dict(alone, best_known_hypervolume=3.0, methods={"hybrid": row, "grid": grid})
    table = summary_table(both)
    assert "83.3333%" in table and "the grid baseline beat the hybrid search" in table


def test_robots_past_the_stated_sizes_are_refused_by_validate(tmp_path, capsys):
    """Before: a 2,048-joint planar chain passed validate and 15 GB; a 256-joint tree went for 170 GB."""
    planar = yaml.safe_load((ROOT / "configs" / "umetani1990.yaml").read_text())
    planar["links"] = planar["links"] * 9  # 18 links
    path = tmp_path / "planar.yaml"
    path.write_text(yaml.safe_dump(planar))
    assert main(["validate", str(path)]) == 2
    assert "links: 2 to 16 links" in one_error_line(capsys)

    links = ['<link name="l0"><inertial><mass value="5"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/>']
    links[0] += "</inertial></link>"
    joints = []
    for i in range(1, 41):
        links.append(
            f'<link name="l{i}"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" '
            'iyz="0"/></inertial></link>'
        )
        joints.append(
            f'<joint name="j{i}" type="revolute"><parent link="l{i - 1}"/><child link="l{i}"/>'
            f'<origin xyz="0 0 0.1"/><axis xyz="0 {i % 2} {1 - i % 2}"/>'
            '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        )
    (tmp_path / "chain.urdf").write_text('<robot name="chain">' + "".join(links + joints) + "</robot>")
    arm = {"urdf": "chain.urdf", "root_link": "l0", "tip": "l40"}
    tree = {
        "name": "two-long-arms",
        "base": {"mass": 500.0, "com": [0, 0, 0], "inertia": [[80, 0, 0], [0, 80, 0], [0, 0, 80]]},
        "arms": [{"name": "a", **arm}, {"name": "b", **arm, "mount": {"xyz": [0, 1, 0]}}],
    }
    path = tmp_path / "tree.yaml"
    path.write_text(yaml.safe_dump(tree))
    assert main(["validate", str(path)]) == 2
    assert "80 movable joints in all; at most 64" in one_error_line(capsys)
    tree["arms"] = tree["arms"][:1]
    path.write_text(yaml.safe_dump(tree))
    assert main(["validate", str(path)]) == 0  # one 40-joint arm is within the limits


def test_joint_limit_errors_answer_in_the_units_typed(tmp_path, capsys):
    ur5 = str(ROOT / "configs" / "ur5-smallsat.yaml")
    out = str(tmp_path / "out")
    assert main(["reach", ur5, "--from", "0,400,0,0,0,0", "--to=0.3,0.2,0.8", "--out", out]) == 2
    assert "joint 2 (shoulder_lift_joint) = 400 deg is outside its limits [-360, 360] deg" in one_error_line(capsys)
    assert main(["reach", ur5, "--from", "0,7,0,0,0,0", "--radians", "--to=0.3,0.2,0.8", "--out", out]) == 2
    assert "= 7 rad is outside its limits [-6.28319, 6.28319] rad" in one_error_line(capsys)
    planar = yaml.safe_load((ROOT / "configs" / "umetani1990.yaml").read_text())
    planar["links"][1]["limit_deg"] = [-150, 150]
    path = tmp_path / "limited.yaml"
    path.write_text(yaml.safe_dump(planar))
    assert main(["reach", str(path), "--from", "0,-60,170", "--to=-2.5,-3", "--out", out]) == 2
    assert "joint 2 = 170 deg is outside its limits [-150, 150] deg" in one_error_line(capsys)
    assert not (tmp_path / "out").exists() and not (tmp_path / ".out.lock").exists()


def test_the_reach_loop_settings_are_options_checked_up_front(tmp_path, capsys):
    paper = str(ROOT / "configs" / "umetani1990.yaml")
    ur5 = str(ROOT / "configs" / "ur5-smallsat.yaml")
    out = ["--out", str(tmp_path / "out")]
    reach = ["reach", paper, "--from", "0,-60,120", "--to=-2.5,-3", *out]
    assert main([*reach, "--loop-counts", "0,2"]) == 2
    assert "--loop-counts 0,2" in one_error_line(capsys)
    assert main([*reach, "--harmonics", "99"]) == 2
    assert "--harmonics 99" in one_error_line(capsys)
    pose = ["reach", ur5, "--from", "0,-60,90,0,60,0", "--to=0.3,0.2,0.8", "--to-rpy", "0,0,0", *out]
    assert main([*pose, "--harmonics", "3"]) == 2
    assert "--harmonics" in one_error_line(capsys)
    for robot in (paper, ur5):
        settings = sa.loop_settings(sa.load_robot(robot), loop_counts=(2, 3), harmonics=5)
        assert settings.loop_counts == (2, 3) and settings.harmonics == 5
    with pytest.raises(sa.ConfigError, match="no_such"):
        sa.loop_settings(sa.load_robot(paper), no_such=1)


def test_a_target_at_the_current_tip_on_the_reach_boundary_is_reached(tmp_path, capsys):
    """Before: the stretched arm's own tip, on the Maximum Reachable radius, was 'unreachable'."""
    robot = sa.load_robot(ROOT / "configs" / "umetani1990.yaml")
    tip = np.asarray(sa.tip_position(robot, np.zeros(3)))
    assert np.linalg.norm(tip) == pytest.approx(sa.family_of(robot).tip_shell(robot)[1], rel=1e-15)
    target = f"--to={float(tip[0])!r},{float(tip[1])!r}"
    assert (
        main(["reach", str(ROOT / "configs" / "umetani1990.yaml"), "--from", "0,0,0", target, "--out", str(tmp_path)])
        == 0
    )
    assert "tip error      0.000e+00 m" in capsys.readouterr().out
