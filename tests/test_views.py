"""Interactive HTML views (spacearm.figures.views): the browser's forward kinematics against
the library, and the pages themselves in headless Chromium.

- The JavaScript forward kinematics of every page (fk.js, run with node on the scripts and
  data a written page holds) gives the tip and the joint origins that `spacearm.tip_position`
  and the matplotlib figures' outlines give, to 1e-9 m, at random postures and attitudes.
- Each page opens in headless Chromium with every host name unresolvable (one browser per
  test process, a tab per page: tests/browser.py): its screenshot shows the arm's (or the
  front's) colours, and the tab's network events hold no request from the page to anything
  but the file itself. A control page with an external image proves that check can fail.
- Without Plotly (the ``view`` extra) the command exits 2 with a message naming the extra.

node and chromium are system programs: the tests that need one skip, saying so, without it.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import jax
import matplotlib.image
import numpy as np
import pytest
import yaml

import spacearm as sa
from spacearm.cli import main
from spacearm.figures.robot import robot_outline
from spacearm.figures.spatial import arm_points
from spacearm.figures.views import replay_from_npz, write_arm_view, write_replay_view
from spacearm.models.planar import PlanarRobot
from spacearm.models.spatial.urdf import rpy_matrix

from . import browser

pytest.importorskip("plotly", reason="the 'view' extra (plotly) is not installed")

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ["ur5-smallsat.yaml", "ets7.yaml", "arm3dof-100kg.yaml", "umetani1990.yaml"]
NODE = shutil.which("node") or shutil.which("nodejs")
CHROMIUM = next(
    (shutil.which(name) for name in ("chromium", "chromium-browser", "google-chrome") if shutil.which(name)), None
)
needs_node = pytest.mark.skipif(NODE is None, reason="node is not installed (apt-get install nodejs)")
needs_chromium = pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (apt-get install chromium)")


@pytest.fixture(scope="session")
def robots():
    return {name: sa.load_robot(ROOT / "configs" / name) for name in CONFIGS}


@pytest.fixture(scope="session")
def pages(robots, tmp_path_factory):
    """One page of each kind: the UR5 and the planar arm (view), a UR5 joint-loop replay."""
    out = tmp_path_factory.mktemp("views")
    ur5, planar = robots["ur5-smallsat.yaml"], robots["umetani1990.yaml"]
    written = {
        "ur5": write_arm_view(ur5, out / "ur5.html", [0.3, -1.2, 1.6, -0.9, 1.2, 0.2]),
        "planar": write_arm_view(planar, out / "planar.html", np.radians([10.0, 40.0, 60.0])),
    }
    q, R, tip = _ur5_loop(ur5)
    written["replay"] = write_replay_view(ur5, out / "replay.html", joints=q, base_rotation=R, tip=tip, target=tip[-1])
    return written


def _ur5_loop(robot):
    """A closed joint loop of the UR5 (figures.spatial's demo loop): joints, bus attitudes, tips."""
    from spacearm.figures.spatial import loop_history

    R, q = loop_history(robot, samples_per_segment=2)
    return q, R, np.asarray(sa.tip_position(robot, q, base_rotation=R))


def _page_scripts(path: Path) -> str:
    """The page's own scripts (fk.js and the data), without plotly.js, as one node program."""
    scripts = re.findall(r"<script>(.*?)</script>", path.read_text(), flags=re.S)
    ours = [s for s in scripts if "spacearmPose" in s[:2000] or s.startswith("window.SPACEARM")]
    assert len(ours) == 2, "the page holds fk.js and its data"
    return "const window = globalThis;\n" + "\n".join(ours)


def _node(program: str, stdin: str = "") -> object:
    done = subprocess.run([NODE, "-e", program], input=stdin, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@needs_node
@pytest.mark.parametrize("name", CONFIGS)
def test_page_kinematics_match_the_library(robots, tmp_path, name):
    """fk.js on the model a page holds = spatial.tip_position and the drawn joint origins, to 1e-9 m."""
    robot = robots[name]
    page = write_arm_view(robot, tmp_path / "view.html")
    planar = isinstance(robot, PlanarRobot)
    rng = np.random.default_rng(7)
    count = robot.n_links + 1 if planar else robot.n_joints
    q = rng.uniform(-np.pi, np.pi, size=(8, count))
    R = np.stack([rpy_matrix(r) for r in rng.uniform(-np.pi, np.pi, size=(8, 3))])
    program = (
        _page_scripts(page)
        + """
    const d = JSON.parse(require("fs").readFileSync(0, "utf8"));
    const M = window.SPACEARM.model;
    console.log(JSON.stringify(d.q.map((q, i) => { const p = spacearmPose(M, q, d.R[i]); return p.joints.concat(p.tips); })));"""
    )
    joints = np.array(_node(program, json.dumps(dict(q=q.tolist(), R=R.tolist()))))
    if planar:
        tips = np.asarray(sa.tip_position(robot, q))
        outlines = np.stack([robot_outline(robot, p)[1] for p in q])
        np.testing.assert_allclose(joints[:, :, :2], outlines, rtol=0, atol=1e-9)
        np.testing.assert_allclose(joints[:, :, 2], 0.0, atol=0)
    else:
        tips = np.asarray(sa.tip_position(robot, q, base_rotation=R))
        outlines = np.stack(
            [arm_points(robot, qk, Rk)[0] for qk, Rk in zip(q[:3], R[:3], strict=False)]
        )  # eager: 3 postures
        np.testing.assert_allclose(joints[:3], outlines, rtol=0, atol=1e-9)
    np.testing.assert_allclose(joints[:, -1, : tips.shape[-1]], tips, rtol=0, atol=1e-9)
    assert np.ptp(tips, axis=0).max() > 0.1  # the postures differ: the comparison has teeth


@needs_node
def test_replay_frames_reproduce_the_recorded_tip(robots, pages):
    """(~10 s: the UR5 loop history compiles once.) Every frame of the replay drawn from its joints and bus attitude puts the tip on the recorded tip."""
    program = (
        _page_scripts(pages["replay"])
        + """
    const D = window.SPACEARM, F = D.frames;
    console.log(JSON.stringify(F.q.map((q, k) => spacearmPose(D.model, q, F.R[k]).tips[0])));"""
    )
    drawn = np.array(_node(program))
    _q, R, tip = _ur5_loop(robots["ur5-smallsat.yaml"])
    assert drawn.shape == tip.shape and len(tip) > 10
    np.testing.assert_allclose(drawn, tip, rtol=0, atol=1e-9)
    angle = np.degrees(np.arccos((np.trace(R[0].T @ R[-1]) - 1) / 2))
    assert angle > 0.5  # the loop turns the bus: the attitude is part of what is checked


@pytest.mark.parametrize("name", CONFIGS)
def test_view_model_is_one_tree_for_every_family(robots, name):
    """The model a page holds names no family: the same keys for every robot, and its NumPy
    walk (`view_pose`, the twin of fk.js) puts the tip where `spacearm.tip_position` does."""
    from spacearm.models.view_model import view_model, view_pose

    robot = robots[name]
    model = view_model(robot)
    assert "family" not in model and set(model) == set(view_model(robots["ur5-smallsat.yaml"]))
    rng = np.random.default_rng(5)
    q = rng.uniform(-np.pi, np.pi, size=(4, model["posture"]["size"]))
    R = np.stack([rpy_matrix(r) for r in rng.uniform(-np.pi, np.pi, size=(4, 3))])
    if model["posture"]["base_turn"] is None:
        expected = np.asarray(sa.tip_position(robot, q, base_rotation=R))
    else:  # the posture holds the bus attitude
        expected, R = np.asarray(sa.tip_position(robot, q)), [None] * len(q)
    drawn = np.stack([view_pose(model, qk, Rk)["tips"][0] for qk, Rk in zip(q, R, strict=True)])
    np.testing.assert_allclose(drawn[:, : expected.shape[-1]], expected, rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="one design"):
        view_model(jax.tree_util.tree_map(lambda leaf: np.stack([leaf, leaf]), robot))


def test_replay_from_npz_reads_both_layouts(robots, tmp_path):
    """Planar reach.npz (postures_rad, tips_m) and the spatial history keys (joints, base_rotation, tip)."""
    planar, ur5 = robots["umetani1990.yaml"], robots["ur5-smallsat.yaml"]
    phi = np.radians([[0.0, 30.0, 60.0], [5.0, 40.0, 50.0]])
    np.savez(tmp_path / "planar.npz", postures_rad=phi, tips_m=np.asarray(sa.tip_position(planar, phi)))
    assert replay_from_npz(planar, tmp_path / "planar.npz", tmp_path / "planar.html").stat().st_size > 4e6
    q, R, tip = _ur5_loop(ur5)
    np.savez(tmp_path / "spatial.npz", joints=q, base_rotation=R, tip=tip)
    assert replay_from_npz(ur5, tmp_path / "spatial.npz", tmp_path / "spatial.html").stat().st_size > 4e6
    np.savez(tmp_path / "empty.npz", end_joints=q[-1])
    with pytest.raises(sa.ConfigError, match="no history to replay"):
        replay_from_npz(ur5, tmp_path / "empty.npz", tmp_path / "none.html")
    assert not (tmp_path / "none.html").exists()


def test_view_command_writes_one_page(tmp_path, capsys):
    assert (
        main(["view", str(ROOT / "configs" / "ets7.yaml"), "--posture", "10,20,30,40,50,60", "--out", str(tmp_path)])
        == 0
    )
    page = tmp_path / "ets7.html"
    assert 4.5e6 < page.stat().st_size < 5.5e6  # plotly.js (4.8 MB) + the model (a few kB)
    assert "MB, self-contained" in capsys.readouterr().out
    data = json.loads(re.search(r"window\.SPACEARM = (\{.*?\});</script>", page.read_text()).group(1))
    np.testing.assert_allclose(data["posture"], np.radians([10, 20, 30, 40, 50, 60]), rtol=1e-15)


def test_view_command_refuses_bad_input(tmp_path, capsys):
    assert main(["view", str(ROOT / "configs" / "ets7.yaml"), "--posture", "1,2", "--out", str(tmp_path)]) == 2
    assert "--posture: expected 6" in capsys.readouterr().err
    assert (
        main(["view", str(ROOT / "configs" / "umetani1990.yaml"), "--attitude-rpy", "1,2,3", "--out", str(tmp_path)])
        == 2
    )
    assert not list(tmp_path.iterdir())


def test_view_without_plotly_names_the_extra(tmp_path, capsys, monkeypatch):
    """With plotly unimportable: exit 2, one line naming the 'view' extra, nothing written."""
    for module in [m for m in sys.modules if m == "plotly" or m.startswith("plotly.")]:
        monkeypatch.delitem(sys.modules, module)
    monkeypatch.setitem(sys.modules, "plotly", None)
    monkeypatch.setitem(sys.modules, "plotly.offline", None)
    assert main(["view", str(ROOT / "configs" / "ur5-smallsat.yaml"), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "'view' extra" in err and ".[view]" in err
    assert not tmp_path.exists() or not list(tmp_path.iterdir())
    assert (
        main(
            [
                "reach",
                str(ROOT / "configs" / "umetani1990.yaml"),
                "--from",
                "0,-60,120",
                "--to",
                "2,1",
                "--out",
                str(tmp_path / "reach"),
                "--html",
            ]
        )
        == 2
    )  # checked before planning: nothing written
    assert "'view' extra" in capsys.readouterr().err and not (tmp_path / "reach").exists()


# Headless Chromium ------------------------------------------------------------------------


def _render(page: Path, tmp_path: Path) -> tuple[np.ndarray, list[str]]:
    """Screenshot ``page`` (RGB array) and the URLs the page itself requested, other than its
    own files (the tab's network events)."""
    shot = tmp_path / f"{page.stem}.png"
    requested = browser.screenshot(CHROMIUM, page, shot)
    assert shot.exists(), f"chromium wrote no screenshot of {page}"
    image = (matplotlib.image.imread(shot)[..., :3] * 255).round().astype(int)
    return image, [url for url in requested if not url.startswith(("file:", "data:", "blob:"))]


def _pixels_near(image: np.ndarray, rgb, tolerance: int = 40) -> int:
    return int((np.abs(image - np.asarray(rgb)).max(axis=-1) <= tolerance).sum())


@needs_chromium
@pytest.mark.slow
@pytest.mark.parametrize("kind", ["ur5", "planar", "replay", "front", "front3", "shells"])
def test_pages_render_offline_in_chromium(pages, front_pages, shells_page, tmp_path, kind):
    """A few seconds each: the page draws the links (their blue) or the front's markers, and requests
    nothing from the network."""
    page = {**pages, "front": front_pages["spatial"], "front3": front_pages["three"], "shells": shells_page["page"]}[
        kind
    ]
    image, requested = _render(page, tmp_path)
    plot = image[:, : image.shape[1] - 340]  # left of the control panel
    background = int((plot.min(axis=-1) >= 250).sum())
    assert plot.shape[0] * plot.shape[1] - background > 0.01 * plot.size / 3  # not blank
    colour = {"front": (214, 39, 40), "front3": (31, 119, 180)}.get(kind, (31, 119, 180))  # markers; links #1f77b4
    assert _pixels_near(plot, colour) > 200, "nothing of the scene drawn"
    assert requested == []
    size = page.stat().st_size
    assert 4.5e6 < size < 5.5e6, f"{page.name}: {size} bytes"


@needs_chromium
def test_network_check_sees_an_external_request(tmp_path):
    """The control: a page that asks for anything outside is caught by the same check, from
    the page itself (an image), a sandboxed iframe, a worker and a WebSocket."""
    page = tmp_path / "external.html"
    page.write_text(
        '<html><body><img src="https://example.com/x.png">'
        "<iframe sandbox srcdoc='<img src=\"https://example.org/frame.png\">'></iframe><script>"
        "new Worker(URL.createObjectURL(new Blob(['fetch(\"https://example.net/worker.json\").catch(function () {})'],"
        ' {type: "text/javascript"})));'
        'try { new WebSocket("wss://example.com/socket"); } catch (e) {}'
        "</script><p>x</p></body></html>"
    )
    _, requested = _render(page, tmp_path)
    assert sorted(requested) == [
        "https://example.com/x.png",
        "https://example.net/worker.json",
        "https://example.org/frame.png",
        "wss://example.com/socket",
    ]


@needs_node
def test_reach_html_replays_the_planar_plan(tmp_path, capsys):
    """``spacearm reach --html``: reach.html beside reach.npz; its frames put the tip on the planned tips."""
    out = tmp_path / "reach"
    assert (
        main(
            [
                "reach",
                str(ROOT / "configs" / "umetani1990.yaml"),
                "--from",
                "0,-60,120",
                "--to",
                "2,1",
                "--out",
                str(out),
                "--html",
            ]
        )
        == 0
    )
    assert "reach.html" in capsys.readouterr().out
    program = (
        _page_scripts(out / "reach.html")
        + """
    const D = window.SPACEARM, F = D.frames;
    console.log(JSON.stringify(F.q.map((q) => spacearmPose(D.model, q).tips[0])));"""
    )
    drawn = np.array(_node(program))
    with np.load(out / "reach.npz") as history:
        tips = history["tips_m"]
    assert len(tips) > 10 and np.linalg.norm(tips[-1] - [2.0, 1.0]) < 1e-9
    np.testing.assert_allclose(drawn[:, :2], tips, rtol=0, atol=1e-9)


@pytest.fixture(scope="session")
def front_pages(tmp_path_factory):
    """front.html of a spatial problem (UR5 mount) from a made-up search result, and a 3-objective front."""
    from spacearm.design import SearchResult
    from spacearm.design.problem import load_problem as load_design_problem
    from spacearm.figures.views import front_view, write_front_view

    out = tmp_path_factory.mktemp("fronts")
    problem = load_design_problem(str(ROOT / "sweeps" / "pareto-mount-ur5.yaml"), base_dir=str(ROOT / "sweeps"))
    rng = np.random.default_rng(3)
    designs = problem.lower + rng.uniform(size=(12, len(problem.lower))) * (problem.upper - problem.lower)
    first = np.sort(rng.uniform(size=12))
    objectives = np.stack([first, 1.0 - first**2] + [rng.uniform(size=12)] * (len(problem.objectives) - 2), axis=1)
    result = SearchResult(
        method="gradient",
        designs=designs,
        objectives=objectives,
        checkpoints=[],
        evaluations=12,
        compile_seconds=0.0,
        run_seconds=0.0,
    )
    (spatial,) = front_view(problem, {"gradient": result}, {}, out)
    three = write_front_view(
        out / "front3.html",
        objective_names=["f1", "f2", "f3"],
        variable_names=["a", "b"],
        fronts={"nsga2": (rng.uniform(size=(30, 2)), rng.uniform(size=(30, 3)))},
    )
    return dict(problem=problem, designs=designs, objectives=objectives, spatial=spatial, three=three)


@needs_node
def test_front_robots_are_the_picked_designs(front_pages):
    """The robot a click on the front draws is that point's design (tip at zero joints, to 1e-9 m)."""
    program = (
        _page_scripts(front_pages["spatial"])
        + """
    const D = window.SPACEARM, T = D.traces[0];
    console.log(JSON.stringify(T.x.map((x, j) => [x, spacearmPose(D.robots[T.customdata[j]].model,
        D.robots[T.customdata[j]].posture, null).tips[0]])));"""
    )
    drawn = _node(program)
    problem, designs, objectives = front_pages["problem"], front_pages["designs"], front_pages["objectives"]
    assert len(drawn) == len(designs)
    for x, tip in drawn:
        row = int(np.argmin(np.abs(objectives[:, 0] - x)))
        robot = jax.tree_util.tree_map(np.asarray, problem.robot(designs[row]))
        expected = np.asarray(sa.tip_position(robot, np.zeros(robot.n_joints)))
        np.testing.assert_allclose(tip, expected, rtol=0, atol=1e-9)


def _drive(page: Path, tmp_path: Path, script: str) -> dict:
    """Open a copy of ``page`` with ``script`` run after the page's own, in headless Chromium;
    return the ``data-*`` attributes it left on <body> (``result``: JSON the script wrote)."""
    driven = tmp_path / f"driven-{page.name}"
    driven.write_text(page.read_text().replace("</body>", f"<script>{script}</script></body>"))
    return browser.body_data(CHROMIUM, driven)


_READ_ARM = """
document.body.dataset.result = JSON.stringify((function () {
  var d = document.getElementById("plot").data[3]; return d.x.map(function (x, i) { return [x, d.y[i], d.z[i]]; }); })());"""


@needs_chromium
@pytest.mark.slow
def test_sliders_repose_the_arm_in_chromium(robots, pages, tmp_path):
    """Moving the joint and bus-attitude sliders redraws the links where the library puts them (1e-9 m)."""
    degrees = [20.0, -75.5, 100.0, -40.0, 65.0, 10.0, 15.0, -30.0, 45.0]  # six joints, then roll, pitch, yaw
    script = (
        f"""
    var inputs = document.querySelectorAll("#controls input[type=range]");
    {json.dumps(degrees)}.forEach(function (v, i) {{ inputs[i].value = v; inputs[i].dispatchEvent(new Event("input")); }});
    """
        + _READ_ARM
    )
    state = _drive(pages["ur5"], tmp_path, script)
    assert state.get("spacearm") == "ready" and "error" not in state
    drawn = np.array(json.loads(state["result"]))
    robot = robots["ur5-smallsat.yaml"]
    q, R = np.radians(degrees[:6]), rpy_matrix(np.radians(degrees[6:]))
    np.testing.assert_allclose(drawn, arm_points(robot, q, R)[0], rtol=0, atol=1e-9)


@needs_chromium
@pytest.mark.slow
def test_replay_frame_slider_in_chromium(robots, pages, tmp_path):
    """Dragging the replay's frame slider to frame k puts the drawn tip on the recorded tip k."""
    _q, _R, tip = _ur5_loop(robots["ur5-smallsat.yaml"])
    k = len(tip) // 2
    script = (
        f"""
    var frame = document.querySelectorAll("#controls input[type=range]")[0];
    frame.value = {k}; frame.dispatchEvent(new Event("input"));"""
        + _READ_ARM
    )
    state = _drive(pages["replay"], tmp_path, script)
    assert state.get("spacearm") == "ready" and "error" not in state
    np.testing.assert_allclose(json.loads(state["result"])[-1], tip[k], rtol=0, atol=1e-9)
    assert np.linalg.norm(tip[k] - tip[0]) > 0.05  # frame k is elsewhere: the slider moved the arm


@pytest.fixture(scope="session")
def shells_page(tmp_path_factory):
    """shells.html of a 3-design bus-mass sweep of the 3-DOF arm, with made-up radii (the metrics
    themselves are tested in tests/test_workspace_search.py; here only the page)."""
    from spacearm.figures.views import shells_view
    from spacearm.studies import load_sweep

    spec = load_sweep(
        dict(
            name="shells",
            robot=str(ROOT / "configs" / "arm3dof-100kg.yaml"),
            axes={"mass": {"field": "base.mass", "values": [50.0, 100.0, 400.0]}},
            metrics=[{"name": "reach_radii"}, {"name": "path_independent_radius"}],
        )
    )
    table = {
        "R_max_m": np.array([1.34, 1.47, 1.61]),
        "R_inner_m": np.array([0.02, 0.07, 0.12]),
        "R_path_independent_m": np.array([0.03, np.inf, 0.18]),
    }
    out = tmp_path_factory.mktemp("shells")
    assert shells_view(spec, out, {"w_avg_m3": np.ones(3)}) == []  # no shell column: no page
    (page,) = shells_view(spec, out, table)
    return dict(spec=spec, page=page)


@needs_node
def test_shells_page_holds_each_designs_robot(shells_page):
    """Design k of the page is sweep point k (the bus mass moves the centroid, so the tip differs)."""
    from spacearm.studies.designs import build_designs

    program = (
        _page_scripts(shells_page["page"])
        + """
    const D = window.SPACEARM;
    console.log(JSON.stringify(D.designs.map((d) => [spacearmPose(d.model, d.posture, null).tips[0],
        d.shells.map((s) => s.radius)])));"""
    )
    drawn = _node(program)
    robot, _ = build_designs(shells_page["spec"])
    expected = np.stack(
        [
            np.asarray(
                sa.tip_position(jax.tree_util.tree_map(lambda leaf, k=k: leaf[k], robot), np.zeros(robot.n_joints))
            )
            for k in range(3)
        ]
    )
    np.testing.assert_allclose([tip for tip, _ in drawn], expected, rtol=0, atol=1e-9)
    assert np.ptp(expected, axis=0).max() > 1e-3
    assert [radii for _, radii in drawn][1] == [1.47, 0.07, None]  # an infinite radius draws no sphere


def test_replay_names_the_planar_phases(robots, tmp_path):
    planar = robots["umetani1990.yaml"]
    phi = np.radians([[0.0, 30.0, 60.0], [5.0, 40.0, 50.0], [6.0, 41.0, 49.0]])
    page = write_replay_view(
        planar, tmp_path / "r.html", phi=phi, tip=np.asarray(sa.tip_position(planar, phi)), phase=np.array([0, 1, 2])
    )
    data = json.loads(re.search(r"window\.SPACEARM = (\{.*?\});</script>", page.read_text()).group(1))
    assert data["frames"]["phase"] == ["repositioning move", "reorientation loop", "straight tip path"]


@needs_chromium
@pytest.mark.slow
def test_clicking_the_front_draws_that_design(front_pages, tmp_path):
    """A click on a gradient-front point draws that design's robot beside the front (tip to 1e-9 m)."""
    script = """
    var T = window.SPACEARM.traces[0], j = 5;
    document.getElementById("plot").emit("plotly_click", {points: [{customdata: T.customdata[j], text: T.text[j]}]});
    var d = document.querySelector("#controls div").data[3];
    document.body.dataset.result = JSON.stringify({x: T.x[j], tip: [d.x[d.x.length - 1], d.y[d.y.length - 1],
        d.z[d.z.length - 1]], readout: document.getElementById("readout").textContent});"""
    state = _drive(front_pages["spatial"], tmp_path, script)
    assert state.get("spacearm") == "ready" and "error" not in state
    result = json.loads(state["result"])
    problem, designs, objectives = front_pages["problem"], front_pages["designs"], front_pages["objectives"]
    row = int(np.argmin(np.abs(objectives[:, 0] - result["x"])))
    robot = jax.tree_util.tree_map(np.asarray, problem.robot(designs[row]))
    np.testing.assert_allclose(result["tip"], sa.tip_position(robot, np.zeros(robot.n_joints)), rtol=0, atol=1e-9)
    assert f"{problem.variable_names[0]} = {designs[row, 0]:.6g}" in result["readout"]


def test_a_name_with_markup_stays_inside_its_script_block(tmp_path):
    """Before: a robot named '<!--<script>' broke the page (the data block never closed)."""
    robot = yaml.safe_load((ROOT / "configs" / "umetani1990.yaml").read_text())
    robot["name"] = "<!--<script>x&"
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(robot))
    assert main(["view", str(path), "--out", str(tmp_path / "out")]) == 0
    page = next((tmp_path / "out").glob("*.html")).read_text()
    block = re.search(r"<script>window\.SPACEARM = (.*?);</script>", page, flags=re.S).group(1)
    assert "<" not in block and ">" not in block and "&" not in block
    assert "<!--<script>x&" in json.dumps(json.loads(block), ensure_ascii=False)
    assert "&lt;!--&lt;script&gt;x&amp;</title>" in page
