"""The manifest's provenance: a hash of every input file, the package a URDF came from, and a
git state that a rerun of a committed result does not mark dirty."""

from __future__ import annotations

import hashlib
import subprocess
from importlib import metadata
from pathlib import Path

import pytest

from spacearm.io.manifest import git_state, input_files

ROOT = Path(__file__).resolve().parents[1]


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_inputs_of_a_planar_sweep_are_the_sweep_file_and_its_robot_file(monkeypatch):
    monkeypatch.chdir(ROOT)
    inputs = input_files(["spacearm", "sweep", "sweeps/table2.yaml", "--out", "/tmp/x"])
    by_role = {entry["role"]: entry for entry in inputs}
    assert by_role["command line"]["path"] == "sweeps/table2.yaml"
    assert by_role["command line"]["sha256"] == _sha(ROOT / "sweeps/table2.yaml")
    robot = by_role["robot file"]
    assert robot["path"] == "configs/umetani1990.yaml" and robot["sha256"] == _sha(ROOT / robot["path"])
    assert "urdf" not in by_role and len(inputs) == 2


def test_a_urdf_from_a_package_records_the_package_its_version_and_the_file_hash(monkeypatch):
    try:
        version = metadata.version("example-robot-data")
    except metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed")
    monkeypatch.chdir(ROOT)
    inputs = input_files(["spacearm", "sweep", "sweeps/ur5-mass-ratio.yaml"])
    urdf = next(entry for entry in inputs if entry["role"] == "urdf")
    assert urdf["package"] == "example-robot-data" and urdf["package_version"] == version
    assert urdf["package_path"] == "robots/ur_description/urdf/ur5_robot.urdf"
    assert Path(urdf["path"]).name == "ur5_robot.urdf" and urdf["sha256"] == _sha(Path(urdf["path"]))
    assert [e["role"] for e in inputs] == ["command line", "robot file", "urdf"]


def test_a_urdf_by_path_is_hashed_relative_to_its_robot_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "urdf").mkdir()
    (tmp_path / "urdf" / "arm.urdf").write_text("<robot name='a'/>")
    (tmp_path / "robot.yaml").write_text("name: r\narm: {urdf: urdf/arm.urdf, root_link: a, tip: b}\n")
    inputs = input_files(["spacearm", "validate", "robot.yaml"])
    assert [(e["role"], e["path"]) for e in inputs] == [("command line", "robot.yaml"), ("urdf", "urdf/arm.urdf")]
    assert inputs[1]["sha256"] == hashlib.sha256(b"<robot name='a'/>").hexdigest()


def test_git_state_leaves_the_result_folders_out(tmp_path):
    def git(*args):
        subprocess.run(["git", *args], cwd=tmp_path, check=True, capture_output=True)

    git("init", "-q")
    git("config", "user.email", "t@example.org")
    git("config", "user.name", "t")
    for name in ("src/code.py", "results/table2/manifest.json", "configs/robot.yaml"):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("one\n")
    git("add", "-A")
    git("commit", "-qm", "start")
    (tmp_path / "results/table2/manifest.json").write_text("rerun\n")  # a rerun of a committed result
    state = git_state(tmp_path / "src")
    assert state["dirty"] is False and state["dirty_files"] == [] and len(state["revision"]) == 40
    (tmp_path / "configs/robot.yaml").write_text("changed input\n")
    state = git_state(tmp_path / "src")
    assert state["dirty"] is True and state["dirty_files"] == ["configs/robot.yaml"]
