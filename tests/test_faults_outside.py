"""Nothing is written outside the chosen folder, nothing another command wrote is lost.

Each case of a hostile-input probe: a name that would become a path outside the output
folder, a command pointed at another command's results, a lock file planted as a link,
a result folder's permissions, an input that is a FIFO, a NUL byte in a name or a path.
Each ends with exit status 2 and one line naming the file and the field, or runs
correctly, and leaves every file it was not asked to write as it was.
"""

import json
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from spacearm.cli import main
from spacearm.io import folders

ROOT = Path(__file__).resolve().parents[1]
ROBOT = ROOT / "configs" / "umetani1990.yaml"
PROBLEM = ROOT / "sweeps" / "pareto-attachment.yaml"


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "error:" in line]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def small_sweep(tmp_path: Path, **changes) -> Path:
    data = {
        "name": "probe",
        "robot": str(ROBOT),
        "axes": {"b0": {"field": "base.attach", "relative": True, "values": [0.5, 1.0]}},
        "metrics": ["radii"],
        "chunk_size": 2,
    }
    data.update(changes)
    path = tmp_path / "sweep.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def tree_of(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


# -- names that would leave the output folder ------------------------------------------------


@pytest.mark.parametrize("name", ["ABSOLUTE", "../../escaped", "a/b", "..", "x\x1b[31m", "n\0ul"])
def test_a_problem_name_that_is_a_path_is_refused(tmp_path, monkeypatch, capsys, name):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    monkeypatch.chdir(work)
    problem = yaml.safe_load(PROBLEM.read_text())
    problem["name"] = str(tmp_path / "outside") if name == "ABSOLUTE" else name
    path = tmp_path / "problem.yaml"
    path.write_text(yaml.safe_dump(problem))
    assert main(["optimize", str(path), "--no-baselines"]) == 2
    line = one_error_line(capsys)
    assert "problem.yaml: name:" in line
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == [  # nothing written anywhere
        Path("a"),
        Path("a/b"),
        Path("problem.yaml"),
    ]


@pytest.mark.parametrize("name", ["ABSOLUTE", "../escaped", "<!--/x", "\x1b]0;t\x07"])
def test_a_robot_name_that_is_a_path_is_refused_by_view(tmp_path, monkeypatch, capsys, name):
    pytest.importorskip("plotly")
    monkeypatch.chdir(tmp_path)
    robot = yaml.safe_load(ROBOT.read_text())
    robot["name"] = str(tmp_path / "outside") if name == "ABSOLUTE" else name
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(robot))
    assert main(["view", str(path), "--out", str(tmp_path / "views")]) == 2
    assert "robot.yaml: name:" in one_error_line(capsys)
    assert sorted(tmp_path.iterdir()) == [path]  # neither views/ nor outside.html


def test_a_nul_byte_in_a_sweep_output_or_a_urdf_path_is_one_line(tmp_path, capsys):
    sweep = small_sweep(tmp_path, output="res\0ults")
    assert main(["validate", str(sweep)]) == 2
    assert "output:" in one_error_line(capsys)
    arm = yaml.safe_load((ROOT / "configs" / "ur5-smallsat.yaml").read_text())
    arm["arm"]["urdf"] = "ur5\0.urdf"
    robot = tmp_path / "arm.yaml"
    robot.write_text(yaml.safe_dump(arm))
    assert main(["validate", str(robot)]) == 2
    assert "NUL byte" in one_error_line(capsys)


# -- another command's results ---------------------------------------------------------------


@pytest.mark.parametrize(
    ("owner", "files"),
    [
        ("sweep", ["table.csv", "grids.npz", "metrics.png", "table.md", "fig10.png"]),
        ("reach", ["reach.png", "reach.npz"]),
    ],
)
def test_optimize_refuses_a_folder_holding_another_commands_results(tmp_path, capsys, owner, files):
    """Before: optimize --out on a sweep's folder deleted table.csv, grids.npz and metrics.png."""
    out = tmp_path / "res"
    out.mkdir()
    for name in files:
        (out / name).write_bytes(os.urandom(64))
    if owner == "sweep":  # the committed Table 2 manifest, written before manifests held a kind
        shutil.copy(ROOT / "results" / "table2" / "manifest.json", out / "manifest.json")
    before = tree_of(out)
    assert main(["optimize", str(PROBLEM), "--no-baselines", "--out", str(out)]) == 2
    line = one_error_line(capsys)
    assert f"'spacearm {owner}'" in line and str(out) in line
    assert tree_of(out) == before
    assert not (tmp_path / ".res.lock").exists()


def test_sweep_and_reach_refuse_an_optimization_folder(tmp_path, capsys):
    out = tmp_path / "res"
    out.mkdir()
    (out / "pareto.csv").write_text("x\n1\n")
    (out / "manifest.json").write_text(json.dumps({"kind": "optimize", "files": ["pareto.csv", "manifest.json"]}))
    before = tree_of(out)
    assert main(["sweep", str(small_sweep(tmp_path)), "--out", str(out), "--quiet"]) == 2
    assert "'spacearm optimize'" in one_error_line(capsys)
    assert main(["reach", str(ROBOT), "--from", "0,-60,120", "--to=-2.5,-3", "--out", str(out)]) == 2
    assert "'spacearm optimize'" in one_error_line(capsys)
    assert tree_of(out) == before


# -- the lock file ---------------------------------------------------------------------------


@pytest.mark.parametrize("plant", ["symlink", "hardlink", "foreign text"])
def test_a_planted_lock_file_is_refused_and_left_alone(tmp_path, capsys, plant):
    """Before: with .out.lock linked to another file, reach truncated it and wrote its PID there."""
    victim = tmp_path / "precious.txt"
    victim.write_text("keep me\n")
    lock = tmp_path / ".res.lock"
    if plant == "symlink":
        lock.symlink_to(victim)
    elif plant == "hardlink":
        os.link(victim, lock)
    else:
        lock.write_text("not a lock, a user's notes\n")
    code = main(["reach", str(ROBOT), "--from", "0,-60,120", "--to=-2.5,-3", "--out", str(tmp_path / "res")])
    assert code == 2
    line = one_error_line(capsys)
    assert ".res.lock" in line
    assert victim.read_text() == "keep me\n"
    assert not (tmp_path / "res").exists()
    if plant == "foreign text":
        assert lock.read_text() == "not a lock, a user's notes\n"


def test_the_lock_is_removed_when_released_and_refuses_while_held(tmp_path):
    out = tmp_path / "res"
    with folders.lock_folder(out):
        lock = folders.lock_path(out)
        assert lock.read_text().strip() == str(os.getpid())
        with pytest.raises(folders.FolderLocked, match=str(os.getpid())), folders.lock_folder(out):
            pass
    assert not lock.exists()
    with folders.lock_folder(out):  # an empty lock file left by an older version is taken over
        pass
    lock.write_text("")
    with folders.lock_folder(out):
        assert lock.read_text().strip() == str(os.getpid())


# -- permissions -----------------------------------------------------------------------------


def test_a_sweep_keeps_its_folder_mode(tmp_path):
    """Before: a successful run turned a chmod 700 result folder into 755."""
    out = tmp_path / "res"
    out.mkdir()
    out.chmod(0o700)
    assert main(["sweep", str(small_sweep(tmp_path)), "--out", str(out), "--quiet"]) == 0
    assert (out / "table.csv").exists()
    assert stat.S_IMODE(out.stat().st_mode) == 0o700


# -- inputs that are not regular files ------------------------------------------------------


@pytest.mark.parametrize("what", ["robot", "urdf"])
def test_a_fifo_given_as_a_file_is_refused_without_blocking(tmp_path, what):
    """Before: a FIFO given as a URDF or YAML file blocked forever."""
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    target = fifo
    if what == "urdf":
        arm = yaml.safe_load((ROOT / "configs" / "ur5-smallsat.yaml").read_text())
        arm["arm"]["urdf"] = str(fifo)
        target = tmp_path / "arm.yaml"
        target.write_text(yaml.safe_dump(arm))
    code = "import sys; from spacearm.cli import main; sys.exit(main(sys.argv[1:]))"
    result = subprocess.run(
        [sys.executable, "-c", code, "validate", str(target)], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 2, result.stderr
    assert "not a regular file" in result.stderr and "Traceback" not in result.stderr


def test_a_path_that_cannot_be_a_folder_is_exit_2(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    loop = tmp_path / "loop"
    loop.symlink_to(loop)
    sweep = str(small_sweep(tmp_path))
    for out in [tmp_path / "file" / "sub", loop / "x", tmp_path / ("n" * 300)]:
        assert main(["sweep", sweep, "--out", str(out), "--quiet"]) == 2
        one_error_line(capsys)
    assert main(["view", str(ROBOT), "--out", str(tmp_path / "file")]) == 2
    assert "is a file" in one_error_line(capsys)
