"""``spacearm capture``: its numbers against `spacearm.capture`, the rigid grasp it reports, its files and refusals.

Beyond equality with the kernel (the same inputs in SI units), two physical checks that do not
use the command's arithmetic: the robot's momentum after the grasp that capture.json reports
gives, through `spacearm.base_velocity`, the bus velocity `spacearm.capture` reports; and the
target's velocity after the grasp equals the tip frame's (`spacearm.tip_velocity`) carried to
the target's centroid, as a rigid grasp requires. The replay holds the target: the combined
system's momentum it starts from equals the robot's and the target's before the grasp (summed
here about their common centroid), and gives the combined robot capture's bus velocity.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import spacearm as sa
from spacearm._core.groups import rpy_matrix
from spacearm.cli import main
from spacearm.figures.views import view_extra_available

from .test_payload import _momentum_before

ROOT = Path(__file__).resolve().parents[1]
PLANAR = str(ROOT / "configs" / "umetani1990.yaml")
UR5 = str(ROOT / "configs" / "ur5-smallsat.yaml")
DUAL = str(ROOT / "configs" / "dual-ur5-servicer.yaml")
CLIENT = str(ROOT / "configs" / "targets" / "client-50kg.yaml")

PLANAR_TARGET = "mass: 80.0\ninertia: 12.5\noffset: [0.4, -0.1]\nvelocity: [0.05, -0.02, 0.03]\n"


def _target(path: Path, text: str) -> str:
    path.write_text(text)
    return str(path)


def _run(robot: str, target: str, out: Path, *more: str) -> int:
    return main(["capture", robot, "--target", target, *more, "--out", str(out)])


def _client() -> dict:
    """The reference client, typed here from configs/targets/client-50kg.yaml."""
    inertia = np.diag([2.5416666667, 2.1666666667, 1.7083333333])
    return dict(
        mass=50.0,
        inertia=inertia,
        offset=np.array([0.25, 0.05, 0.0]),
        velocity=np.array([0.02, -0.01, 0.0, 0.01, 0.02, 0.03]),
    )


def _printed(text: str, label: str) -> np.ndarray:
    """The first numbers after ``label`` on its line of the summary."""
    line = next(line for line in text.splitlines() if line.startswith(label))
    return np.array(
        [float(v) for v in line[len(label) :].split(" rad/s")[0].split(" m/s")[0].split(" N s")[0].split(",")]
    )


def _check_rigid_grasp(robot, q, R, after: dict, target: dict, tip: int | None = None) -> None:
    """The bus velocity from the reported momentum, and the target moving with the tip frame."""
    m_after = np.asarray(after["momentum_after"])
    qd = np.asarray(after["qd_after"])
    nu = np.asarray(sa.base_velocity(robot, q, qd, base_rotation=R, momentum=m_after))
    tw = np.asarray(sa.tip_velocity(robot, q, qd, base_rotation=R, momentum=m_after))
    tw = tw if tip is None else tw[tip]
    base, t_after = np.asarray(after["base_after"]), np.asarray(after["target_after"])
    if nu.shape[-1] == 3:  # planar: bus axes turned by phi0; the tip's point moved to the centroid
        c, s = np.cos(q[0]), np.sin(q[0])
        np.testing.assert_allclose(np.r_[c * nu[0] - s * nu[1], s * nu[0] + c * nu[1], nu[2]], base, rtol=0, atol=1e-13)
        o = target["offset"]
        carried = np.r_[tw[0] - tw[2] * o[1], tw[1] + tw[2] * o[0], tw[2]]
    else:
        np.testing.assert_allclose(np.r_[R @ nu[:3], R @ nu[3:]], base, rtol=0, atol=1e-13)
        carried = np.r_[tw[:3] + np.cross(tw[3:], target["offset"]), tw[3:]]
    np.testing.assert_allclose(t_after, carried, rtol=0, atol=1e-12)


def _check_replay_start(robot, q, R, m, data: dict, target: dict, tip: int = 0) -> None:
    """The replay's first state: robot and target welded, momentum conserved through the grasp."""
    after = data["after"]
    before = _momentum_before(robot, q, R, m, target, tip)
    np.testing.assert_allclose(
        after["momentum_with_target"], before, rtol=0, atol=1e-10 * max(1.0, np.abs(before).max())
    )
    payload = sa.target_in_tip_frame(robot, q, target, base_rotation=R, tip=tip)
    for key, value in payload.items():
        np.testing.assert_allclose(data["inputs"]["replay"]["payload"][key], value, rtol=1e-14, atol=1e-15)
    carried = sa.grasped_robot(robot, q, target, base_rotation=R, tip=tip)
    nu = np.asarray(
        sa.base_velocity(carried, q, after["qd_after"], base_rotation=R, momentum=after["momentum_with_target"])
    )
    if R is None:
        c, s = np.cos(q[0]), np.sin(q[0])
        nu = np.r_[c * nu[0] - s * nu[1], s * nu[0] + c * nu[1], nu[2]]
    else:
        nu = np.r_[R @ nu[:3], R @ nu[3:]]
    np.testing.assert_allclose(nu, after["base_after"], rtol=0, atol=1e-12)


@pytest.mark.parametrize("joints", ["free", "locked"])
def test_ur5_numbers_are_the_kernels(tmp_path, capsys, joints):
    """capture.json holds sa.capture's result at the same state (rtol 1e-12); the summary prints it."""
    out = tmp_path / "run"
    state = ["--posture", "17,-69,92,-57,69,11", "--rates", "3,-2,4,1,-5,2", "--attitude-rpy", "10,-20,30"]
    momentum = "0.4,-0.2,0.1,0.3,0.05,-0.2"
    assert _run(UR5, CLIENT, out, *state, "--momentum", momentum, "--joints", joints, "--no-html") == 0
    printed = capsys.readouterr().out
    assert {p.name for p in out.iterdir()} == {"capture.json", "manifest.json"}
    robot = sa.load_robot(UR5)
    q = np.radians([17.0, -69.0, 92.0, -57.0, 69.0, 11.0])
    qd = np.radians([3.0, -2.0, 4.0, 1.0, -5.0, 2.0])
    R = rpy_matrix(np.radians([10.0, -20.0, 30.0]))
    m = np.array([0.4, -0.2, 0.1, 0.3, 0.05, -0.2])
    expected = sa.capture(robot, q, qd, _client(), base_rotation=R, momentum=m, joints=joints)
    data = json.loads((out / "capture.json").read_text())
    after = data["after"]
    for name, value in zip(("qd_after", "base_after", "impulse"), expected, strict=True):
        np.testing.assert_allclose(after[name], value, rtol=1e-12, atol=1e-15)
    if joints == "locked":
        np.testing.assert_array_equal(after["qd_after"], qd)
    np.testing.assert_allclose(_printed(printed, "joint rates    "), expected[0], rtol=1e-5)
    np.testing.assert_allclose(_printed(printed, "impulse        "), expected[2][:3], rtol=1e-5)
    _check_rigid_grasp(robot, q, R, after, _client())
    _check_replay_start(robot, q, R, m, data, _client())
    assert data["inputs"]["joints"] == joints and data["inputs"]["target"]["mass"] == 50.0
    np.testing.assert_allclose(data["inputs"]["base_rotation"], R, rtol=0, atol=1e-15)
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["kind"] == "capture" and set(manifest["files"]) == {"capture.json", "manifest.json"}
    assert len(manifest["config"]["target"]["sha256"]) == 64


def test_planar_robot_and_no_replay_off_the_link_line(tmp_path, capsys):
    """The paper's planar system: a scalar moment, a 2-D offset. At this grasp the target's centroid
    is off the last link's line, where a planar link cannot hold it: no replay, one printed reason."""
    target = _target(tmp_path / "t.yaml", PLANAR_TARGET)
    out = tmp_path / "run"
    assert _run(PLANAR, target, out, "--posture=10,-60,120", "--rates", "5,-3", "--seconds", "0.2", "--dt", "0.02") == 0
    printed = capsys.readouterr().out
    robot = sa.umetani1990()
    phi, qd = np.radians([10.0, -60.0, 120.0]), np.radians([5.0, -3.0])
    spec = dict(mass=80.0, inertia=12.5, offset=np.array([0.4, -0.1]), velocity=np.array([0.05, -0.02, 0.03]))
    expected = sa.capture(robot, phi, qd, spec)
    after = json.loads((out / "capture.json").read_text())["after"]
    for name, value in zip(("qd_after", "base_after", "impulse"), expected, strict=True):
        np.testing.assert_allclose(after[name], value, rtol=1e-12, atol=1e-15)
    _check_rigid_grasp(robot, phi, None, after, spec)
    assert {p.name for p in out.iterdir()} == {"capture.json", "manifest.json"}
    skipped = [line for line in printed.splitlines() if line.startswith("replay ")]
    assert len(skipped) == 1 and "not written" in skipped[0] and "across the last link" in skipped[0]
    data = json.loads((out / "capture.json").read_text())
    assert "across the last link" in data["inputs"]["replay"]["payload"]["skipped"]
    assert "momentum_with_target" not in data["after"]


def test_planar_replay_holds_a_target_on_the_link_line(tmp_path, capsys):
    """The target's centroid on the last link's line at the grasp (beyond the tip): welded to the
    link, the replay is written and starts from the momentum before the grasp."""
    theta = np.radians(10.0 - 60.0 + 120.0)
    offset = 0.9 * np.array([np.cos(theta), np.sin(theta)])
    text = PLANAR_TARGET.replace("offset: [0.4, -0.1]", f"offset: [{float(offset[0])!r}, {float(offset[1])!r}]")
    target = _target(tmp_path / "t.yaml", text.replace("mass: 80.0", "mass: 200.0"))
    out = tmp_path / "run"
    state = ["--posture=10,-60,120", "--rates", "5,-3", "--momentum", "2,-1,0.5"]
    assert _run(PLANAR, target, out, *state, "--seconds", "0.2", "--dt", "0.02") == 0
    printed = capsys.readouterr().out
    files = {"capture.json", "manifest.json"} | ({"capture.html"} if view_extra_available() else set())
    assert {p.name for p in out.iterdir()} == files
    if view_extra_available():
        assert "replay         0.2 s of the robot holding the target" in printed
    robot = sa.umetani1990()
    phi = np.radians([10.0, -60.0, 120.0])
    spec = dict(mass=200.0, inertia=12.5, offset=offset, velocity=np.array([0.05, -0.02, 0.03]))
    data = json.loads((out / "capture.json").read_text())
    _check_replay_start(robot, phi, None, np.array([2.0, -1.0, 0.5]), data, spec)


def test_a_tree_grasps_with_the_tip_it_is_given(tmp_path, capsys):
    """Two UR5 on one bus: --tip by name and by index give sa.capture(tip=1)'s numbers."""
    robot = sa.load_robot(DUAL)
    rng = np.random.default_rng(3)
    q, qd = rng.uniform(-1.5, 1.5, 12), rng.uniform(-0.1, 0.1, 12)
    posture, rates = (",".join(repr(float(v)) for v in x) for x in (q, qd))
    state = ["--radians", f"--posture={posture}", f"--rates={rates}"]
    by_name, by_index = tmp_path / "name", tmp_path / "index"
    assert _run(DUAL, CLIENT, by_name, *state, "--tip", "right/tool0", "--no-html") == 0
    assert _run(DUAL, CLIENT, by_index, *state, "--tip", "1", "--no-html") == 0
    assert "tip 1 (right/tool0)" in capsys.readouterr().out
    expected = sa.capture(robot, q, qd, _client(), tip=1)
    for out in (by_name, by_index):
        data = json.loads((out / "capture.json").read_text())
        assert data["inputs"]["tip"] == {"index": 1, "name": "right/tool0"}
        for name, value in zip(("qd_after", "base_after", "impulse"), expected, strict=True):
            np.testing.assert_allclose(data["after"][name], value, rtol=1e-12, atol=1e-15)
    _check_rigid_grasp(robot, q, np.eye(3), data["after"], _client(), tip=1)
    _check_replay_start(robot, q, np.eye(3), np.zeros(6), data, _client(), tip=1)
    assert _run(DUAL, CLIENT, tmp_path / "bad", *state, "--tip", "middle/tool0") == 2
    assert "--tip" in capsys.readouterr().err and not (tmp_path / "bad").exists()


_GOOD = "mass: 50.0\ninertia: [[2, 0, 0], [0, 2, 0], [0, 0, 2]]\noffset: [0.2, 0, 0]\nvelocity: [0, 0, 0, 0, 0, 0.1]\n"


@pytest.mark.parametrize(
    "text, field",
    [
        (_GOOD.replace("mass: 50.0", "mass: -5"), "target.mass: must be positive"),
        (_GOOD.replace("mass: 50.0", "mass: heavy"), "target.mass"),
        (_GOOD.replace("mass: 50.0\n", ""), "target.mass: missing"),
        (_GOOD.replace("[0, 2, 0]", "[0.5, 2, 0]"), "target.inertia: must be symmetric"),
        (_GOOD.replace("[[2, 0, 0]", "[[-2, 0, 0]"), "target.inertia: must be positive definite"),
        (_GOOD.replace("inertia: [[2, 0, 0], [0, 2, 0], [0, 0, 2]]", "inertia: 2.0"), "target.inertia: must be a 3x3"),
        (_GOOD.replace("[0, 0, 2]]", "[0, 0]]"), "target.inertia[2]"),
        (_GOOD.replace("offset: [0.2, 0, 0]", "offset: [0.2, 0]"), "target.offset"),
        (_GOOD.replace("velocity: [0, 0, 0, 0, 0, 0.1]", "velocity: [0, 0, 0.1]"), "target.velocity"),
        (_GOOD.replace("velocity: [0, 0, 0, 0, 0, 0.1]", "velocity: [0, 0, 0, 0, .nan, 0.1]"), "target.velocity[4]"),
        (_GOOD + "spin: 3\n", "unknown key 'spin'"),
        ("[50, 2]\n", "target: must be a mapping"),
    ],
)
def test_refuses_a_bad_target_file(tmp_path, capsys, text, field):
    """One line naming the file and the field, exit 2, nothing written."""
    target = _target(tmp_path / "target.yaml", text)
    out = tmp_path / "out"
    assert _run(UR5, target, out) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and field in err and target in err
    assert not out.exists()


@pytest.mark.parametrize(
    "robot, text, more, field",
    [
        (PLANAR, PLANAR_TARGET.replace("inertia: 12.5", "inertia: -1"), (), "target.inertia"),
        (PLANAR, PLANAR_TARGET.replace("[0.05, -0.02, 0.03]", "[0.05, -0.02, 0.03, 0, 0, 0]"), (), "target.velocity"),
        (PLANAR, PLANAR_TARGET, ("--tip", "0"), "--tip"),
        (PLANAR, PLANAR_TARGET, ("--attitude-rpy", "0,0,10"), "--attitude-rpy"),
        (PLANAR, PLANAR_TARGET, ("--seconds", "0"), "--seconds"),
        (PLANAR, PLANAR_TARGET, ("--dt", "nan"), "--dt"),
        (PLANAR, PLANAR_TARGET, ("--posture", "1,2"), "--posture"),
    ],
)
def test_refuses_bad_options(tmp_path, capsys, robot, text, more, field):
    target = _target(tmp_path / "target.yaml", text)
    out = tmp_path / "out"
    assert _run(robot, target, out, *more) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and field in err
    assert not out.exists()


def test_never_replaces_another_commands_results(tmp_path, capsys):
    """A folder holding a simulate run is refused (exit 2) and left as it was."""
    out = tmp_path / "run"
    out.mkdir()
    (out / "manifest.json").write_text(json.dumps({"kind": "simulate"}))
    target = _target(tmp_path / "t.yaml", PLANAR_TARGET)
    assert _run(PLANAR, target, out, "--no-html") == 2
    assert "spacearm simulate" in capsys.readouterr().err
    assert [p.name for p in out.iterdir()] == ["manifest.json"]


def test_offset_and_velocity_default_to_zero(tmp_path):
    """A target file with mass and inertia only: grasped at its centroid, at rest (as a sweep's
    reference target)."""
    target = _target(tmp_path / "t.yaml", "mass: 20.0\ninertia: [[1, 0, 0], [0, 2, 0], [0, 0, 2.5]]\n")
    out = tmp_path / "run"
    assert _run(UR5, target, out, "--posture", "17,-69,92,-57,69,11", "--rates", "3,-2,4,1,-5,2", "--no-html") == 0
    spec = dict(mass=20.0, inertia=np.diag([1.0, 2.0, 2.5]), offset=np.zeros(3), velocity=np.zeros(6))
    q, qd = np.radians([17.0, -69.0, 92.0, -57.0, 69.0, 11.0]), np.radians([3.0, -2.0, 4.0, 1.0, -5.0, 2.0])
    expected = sa.capture(sa.load_robot(UR5), q, qd, spec)
    data = json.loads((out / "capture.json").read_text())
    assert data["inputs"]["target"]["offset"] == [0.0, 0.0, 0.0] and data["inputs"]["target"]["velocity"] == [0.0] * 6
    for name, value in zip(("qd_after", "base_after", "impulse"), expected, strict=True):
        np.testing.assert_allclose(data["after"][name], value, rtol=1e-12, atol=1e-15)
