"""Several arms on one bus, drawn: the tree body frames against Pinocchio, and the 3-D figure
(it renders, each arm has its own colour, the links end at the kernels' body origins)."""

from __future__ import annotations

import json
import os
import re
import types

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest

import spacearm as sa
from spacearm._core.groups import rpy_matrix
from spacearm.figures import spatial
from spacearm.models.tree import primitives
from spacearm.planning.spatial_reach import PHASE_STRAIGHT

from .test_tree_files import CONFIGS, UR5, erd, pinocchio_tip_poses

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def dual_ur5():
    erd(UR5)
    sa.enable_x64()
    return sa.load_robot(os.path.join(CONFIGS, "dual-ur5-servicer.yaml"))


@pytest.fixture(scope="module")
def three_arm():
    sa.enable_x64()
    return sa.load_robot(os.path.join(CONFIGS, "three-arm-servicer.yaml"))


def test_body_frames_agree_with_pinocchio_on_two_ur5(dual_ur5):
    robot = dual_ur5
    q = np.random.default_rng(3).uniform(-2.0, 2.0, robot.n_joints)
    axes, origins = (np.asarray(x) for x in primitives.body_frames(robot, q))
    for r in range(2):
        joints = [j for j in range(robot.n_joints) if robot.labels.joint_roots[j] == r]
        values = {robot.joint_names[j].split("/")[-1]: q[j] for j in joints}
        links = [robot.labels.body_links[j][0].split("/")[-1] for j in joints]
        poses, _ = pinocchio_tip_poses(erd(UR5), "base_link", links, values)
        mount = rpy_matrix(np.asarray(robot.mount_rpy[r])), np.asarray(robot.mount_xyz[r])
        for j, (rotation, origin) in zip(joints, poses, strict=True):
            np.testing.assert_allclose(axes[j], mount[0] @ rotation, atol=1e-12)
            np.testing.assert_allclose(origins[j], mount[1] + mount[0] @ origin, atol=1e-12)


def test_body_frames_agree_with_pinocchio_on_a_tree_with_prismatic_joints(three_arm):
    robot = three_arm
    assert "prismatic" in robot.joint_kinds
    q = spatial.THREE_ARM_POSTURE
    axes, origins = (np.asarray(x) for x in primitives.body_frames(robot, q))
    path = os.path.join(CONFIGS, "urdf", "three_arm_servicer.urdf")
    links = [robot.labels.body_links[j][0] for j in range(robot.n_joints)]
    poses, _ = pinocchio_tip_poses(path, "Servicer_Bus", links, dict(zip(robot.joint_names, q, strict=True)))
    for j, (rotation, origin) in enumerate(poses):
        np.testing.assert_allclose(axes[j], rotation, atol=1e-12)
        np.testing.assert_allclose(origins[j], origin, atol=1e-12)


@pytest.mark.parametrize("name", ["dual_ur5", "three_arm"])
def test_links_end_at_the_kernels_body_origins_and_tips(name, request):
    robot = request.getfixturevalue(name)
    q = spatial.DUAL_UR5_POSTURE if name == "dual_ur5" else spatial.THREE_ARM_POSTURE
    R = rpy_matrix(np.array([0.3, -0.2, 0.5]))
    drawing = spatial.robot_drawing(robot, q, R)
    # the same points from the public kernels: tips about the centroid (inertial axes) fix the centroid
    tips = np.asarray(sa.tip_position(robot, q, base_rotation=R))
    _, tips_bus = (np.asarray(x) for x in primitives.tip_pose(robot, q))
    centroid = tips_bus[0] - R.T @ tips[0]
    expected = (np.asarray(primitives.body_frames(robot, q)[1]) - centroid) @ R.T
    np.testing.assert_allclose(drawing.body_origins, expected, atol=1e-12)
    np.testing.assert_allclose(drawing.tips, tips, atol=1e-12)
    ends = drawing.segments[:, 1]
    for j in range(robot.n_joints):  # every body origin ends a segment, and starts its children's
        assert np.min(np.linalg.norm(ends - expected[j], axis=-1)) < 1e-12
    for parent in set(robot.parents) - {p for p in robot.parents if p < 0}:
        assert np.min(np.linalg.norm(drawing.segments[:, 0] - expected[parent], axis=-1)) < 1e-12
    for t, body in enumerate(robot.tip_bodies):  # body to tip, in that tip's arm
        row = np.flatnonzero(np.linalg.norm(ends - tips[t], axis=-1) < 1e-12)
        assert row.size == 1 and drawing.segment_arm[row[0]] == t
        np.testing.assert_allclose(drawing.segments[row[0], 0], expected[body], atol=1e-12)
    mounts = (np.asarray(robot.mount_xyz) - centroid) @ R.T
    np.testing.assert_allclose(drawing.mounts, mounts, atol=1e-12)
    # the bus box: centred on the bus centroid, 12 edges of the equivalent box
    np.testing.assert_allclose(drawing.bus_corners.mean(axis=0), drawing.bus, atol=1e-12)


def test_each_arm_has_its_own_colour(dual_ur5, three_arm):
    fig = plt.figure()
    for i, (robot, q) in enumerate(((dual_ur5, spatial.DUAL_UR5_POSTURE), (three_arm, spatial.THREE_ARM_POSTURE))):
        ax = fig.add_subplot(1, 2, i + 1, projection="3d")
        drawing = spatial.draw_robot(ax, robot, q)
        lines = {line.get_label(): line.get_color() for line in ax.lines if not line.get_label().startswith("_")}
        arms = [lines[name] for name in drawing.arm_names]
        assert len(set(arms)) == robot.n_tips  # one colour per arm
        assert ("shared joints" in lines) == (robot is three_arm)  # the turret moves two tips
        if "shared joints" in lines:
            assert lines["shared joints"] not in arms
    assert drawing.arm_names == ("Left_EE", "Right_EE", "Boom_EE")
    assert spatial.robot_drawing(dual_ur5, spatial.DUAL_UR5_POSTURE).arm_names == ("left", "right")
    plt.close(fig)


def test_tree_figure_renders(tmp_path):
    erd(UR5)
    [path] = spatial.fig_tree_arms(tmp_path)
    assert path.name == "tree_arms.png" and path.read_bytes()[:4] == b"\x89PNG"
    image = plt.imread(path)
    assert image.shape[0] > 500 and image.shape[1] > 1000


# The interactive view (spacearm view) of a tree ---------------------------------------------------


def _view_helpers():
    """tests/test_views.py's node and Chromium helpers (that module skips without plotly)."""
    pytest.importorskip("plotly", reason="the 'view' extra (plotly) is not installed")
    from . import test_views

    return test_views


@pytest.mark.parametrize("name", ["dual_ur5", "three_arm"])
def test_view_kinematics_match_the_kernels(name, request, tmp_path):
    """fk.js on a tree page's model = spacearm.tip_position (every tip) and the drawing's body
    origins and segments, to 1e-9 m, at random postures and bus attitudes."""
    helpers = _view_helpers()
    if helpers.NODE is None:
        pytest.skip("node is not installed")
    from spacearm.figures.views import write_arm_view

    robot = request.getfixturevalue(name)
    page = write_arm_view(robot, tmp_path / "view.html")
    rng = np.random.default_rng(11)
    low, high = np.maximum(robot.joint_lower, -np.pi), np.minimum(robot.joint_upper, np.pi)
    q = rng.uniform(low, high, size=(6, robot.n_joints))
    R = np.stack([rpy_matrix(r) for r in rng.uniform(-np.pi, np.pi, size=(6, 3))])
    program = (
        helpers._page_scripts(page)
        + """
    const d = JSON.parse(require("fs").readFileSync(0, "utf8"));
    const M = window.SPACEARM.model;
    console.log(JSON.stringify(d.q.map((q, i) => spacearmPose(M, q, d.R[i]))));"""
    )
    poses = helpers._node(program, json.dumps(dict(q=q.tolist(), R=R.tolist())))
    tips = np.asarray(sa.tip_position(robot, q, base_rotation=R))
    np.testing.assert_allclose([p["tips"] for p in poses], tips, rtol=0, atol=1e-9)
    for i in range(2):  # eager drawing: two postures
        drawing = spatial.robot_drawing(robot, q[i], R[i])
        np.testing.assert_allclose(poses[i]["bodies"], drawing.body_origins, rtol=0, atol=1e-9)
        np.testing.assert_allclose(poses[i]["segments"], drawing.segments, rtol=0, atol=1e-9)
        assert poses[i]["owner"] == drawing.segment_arm.tolist()
        np.testing.assert_allclose(poses[i]["corners"], drawing.bus_corners, rtol=0, atol=1e-9)
    assert np.ptp(tips, axis=0).max() > 0.1


def test_view_command_draws_the_dual_ur5(tmp_path, capsys):
    helpers = _view_helpers()
    assert helpers.main(["view", os.path.join(CONFIGS, "dual-ur5-servicer.yaml"), "--out", str(tmp_path)]) == 0
    page = tmp_path / "dual-ur5-servicer.html"
    assert "MB, self-contained" in capsys.readouterr().out
    data = json.loads(re.search(r"window\.SPACEARM = (\{.*?\});</script>", page.read_text()).group(1))
    assert data["model"]["tip_names"] == ["left", "right"]
    assert data["title"] == "dual-ur5-servicer: 12 joints, 2 arms on a 400 kg bus"
    # the extent holds every tip: the arms stretched straight out of the faces
    robot = sa.load_robot(os.path.join(CONFIGS, "dual-ur5-servicer.yaml"))
    reach = np.abs(np.asarray(sa.tip_position(robot, np.zeros(12)))).max()
    assert reach < data["extent"] < 4 * reach
    assert helpers.main(["view", os.path.join(CONFIGS, "dual-ur5-servicer.yaml"), "--posture", "1,2"]) == 2
    assert "--posture: expected 12" in capsys.readouterr().err


@pytest.mark.slow
def test_tree_view_renders_offline_in_chromium(tmp_path, dual_ur5):
    """A few seconds: the page draws both arms in their colours and requests nothing from the network."""
    helpers = _view_helpers()
    if helpers.CHROMIUM is None:
        pytest.skip("chromium is not installed")
    from spacearm.figures.views import write_arm_view

    page = write_arm_view(dual_ur5, tmp_path / "dual.html", spatial.DUAL_UR5_POSTURE)
    image, requested = helpers._render(page, tmp_path)
    plot = image[:, : image.shape[1] - 340]
    assert helpers._pixels_near(plot, (31, 119, 180)) > 200  # left arm, #1f77b4
    assert helpers._pixels_near(plot, (255, 127, 14)) > 200  # right arm, #ff7f0e
    assert requested == []


_READ_TIPS = """
document.body.dataset.result = JSON.stringify((function () {
  var d = document.getElementById("plot").data.filter(function (t) { return t.name === "tips"; })[0];
  return d.x.map(function (x, i) { return [x, d.y[i], d.z[i]]; }); })());"""


@pytest.mark.slow
def test_tree_sliders_and_replay_in_chromium(tmp_path, three_arm):
    """A few seconds: the sliders of a tree page (ten joints, then the bus roll, pitch, yaw) put the
    drawn tips where spacearm.tip_position puts them; a replay of a tree joint path, dragged to
    frame k, draws the tips of frame k (1e-9 m)."""
    helpers = _view_helpers()
    if helpers.CHROMIUM is None:
        pytest.skip("chromium is not installed")
    from spacearm.figures.views import write_arm_view, write_replay_view

    robot = three_arm
    values = [20.0, -35.0, 50.0, 15.0, 30.0, 0.3, -25.0, 0.6, 40.0, 70.0, 10.0, -20.0, 30.0]  # deg; m for prismatic
    script = (
        f"""
    var inputs = document.querySelectorAll("#controls input[type=range]");
    {json.dumps(values)}.forEach(function (v, i) {{ inputs[i].value = v; inputs[i].dispatchEvent(new Event("input")); }});
    document.body.dataset.values = JSON.stringify(Array.from(inputs).map(function (x) {{ return Number(x.value); }}));
    """
        + _READ_TIPS
    )
    state = helpers._drive(write_arm_view(robot, tmp_path / "three.html"), tmp_path, script)
    assert state.get("spacearm") == "ready" and "error" not in state
    taken = json.loads(state["values"])  # a slider snaps to its steps from its lower limit
    np.testing.assert_allclose(taken, values, atol=0.3)
    values = taken
    prismatic = np.array([k == "prismatic" for k in robot.joint_kinds])
    q = np.where(prismatic, values[:10], np.radians(values[:10]))
    R = rpy_matrix(np.radians(values[10:]))
    expected = np.asarray(sa.tip_position(robot, q, base_rotation=R))
    np.testing.assert_allclose(json.loads(state["result"]), expected, rtol=0, atol=1e-9)

    path = np.linspace(np.zeros(robot.n_joints), spatial.THREE_ARM_POSTURE, 9)
    turns = np.stack([rpy_matrix(np.array([0.0, 0.0, 0.05 * k])) for k in range(9)])
    tips = np.asarray(sa.tip_position(robot, path, base_rotation=turns))
    page = write_replay_view(robot, tmp_path / "replay.html", joints=path, base_rotation=turns, tip=tips[:, 1])
    script = (
        """
    var frame = document.querySelectorAll("#controls input[type=range]")[0];
    frame.value = 6; frame.dispatchEvent(new Event("input"));"""
        + _READ_TIPS
    )
    state = helpers._drive(page, tmp_path, script)
    assert state.get("spacearm") == "ready" and "error" not in state
    np.testing.assert_allclose(json.loads(state["result"]), tips[6], rtol=0, atol=1e-9)


def test_reach_figure_draws_every_arm_of_a_tree(tmp_path, dual_ur5):
    """``spacearm reach`` on a tree writes reach.png: draw_spatial_reach takes a focused tree
    (the plan's history of the chosen tip) and draws every arm at the start and the end."""
    robot = dual_ur5.focus(tip="right/tool0", moving=("right",))
    joints = np.linspace(spatial.DUAL_UR5_POSTURE, spatial.DUAL_UR5_POSTURE + np.r_[np.zeros(6), 0.1 * np.ones(6)], 5)
    rotations = np.broadcast_to(np.eye(3), (5, 3, 3))
    tips = np.asarray(sa.tip_position(dual_ur5, joints))[:, 1]
    plan = types.SimpleNamespace(
        joints=joints,
        base_rotation=rotations,
        tips=tips,
        phase=np.full(5, PHASE_STRAIGHT),
        loops=0,
        target=tips[-1],
        mode="straight",
        bus_turn=0.0,
        error=0.0,
    )
    path = spatial.draw_spatial_reach(robot, plan, tmp_path / "reach.png")
    assert path.read_bytes()[:4] == b"\x89PNG"
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    spatial._draw(ax, robot, joints[-1], rotations[-1], "C3")
    drawn = np.concatenate([np.stack(line.get_data_3d(), axis=-1) for line in ax.lines])
    for tip in np.asarray(sa.tip_position(dual_ur5, joints[-1])):  # both arms drawn, in one colour
        assert np.nanmin(np.linalg.norm(drawn - tip, axis=-1)) < 1e-12  # NaN: breaks between segments
    assert {line.get_color() for line in ax.lines} == {"C3"}
    plt.close(fig)
