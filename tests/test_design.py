"""Design optimization (issue 7): parametrization, objectives and their gradients, fronts,
exact hypervolume, the gradient Pareto search, the baselines and the optimize command.

Costly compilations are kept few: the search tests share one module-scoped run, and the
w-bar quadrature uses the metrics module's own cheap options ("product" rule on a small
grid) wherever the test is about the search machinery rather than the quadrature; every
method uses the same objective code, so that choice does not favour any of them.
"""

import copy
import csv
import dataclasses
import itertools
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import yaml

import spacearm as sa
from spacearm import design
from spacearm.cli import main as cli_main

from .conftest import count_compiles

ROOT = Path(__file__).resolve().parents[1]
CHEAP_WBAR = {"rule": "product", "phi1_panels": 4, "phi2_panels": 2, "order": 4}
TINY_SEARCH = {"directions": 8, "starts": 2, "steps": 12, "chunk": 4, "initial_samples": 16, "learning_rate": 0.05}


def reference_config(**changes):
    config = yaml.safe_load((ROOT / "sweeps" / "pareto-attachment.yaml").read_text())
    config.update(copy.deepcopy(changes))
    return config


# Brute-force references ---------------------------------------------------------------


def brute_nondominated(f):
    keep = []
    for i, p in enumerate(f):
        dominated = np.any(np.all(f >= p, axis=1) & np.any(f > p, axis=1))
        duplicate_before = np.any(np.all(f[:i] == p, axis=1))
        keep.append(not dominated and not duplicate_before)
    return np.array(keep)


def brute_hypervolume(f, reference):
    """Area of the union of boxes [r, p] by coordinate compression (independent of the sweep)."""
    f = f[np.all(f > reference, axis=1)]
    xs = np.unique(np.concatenate([[reference[0]], f[:, 0]]))
    total = 0.0
    for left, right in itertools.pairwise(xs):
        cover = f[f[:, 0] >= right]
        if cover.size:
            total += (right - left) * (cover[:, 1].max() - reference[1])
    return total


# Fronts and hypervolume ---------------------------------------------------------------


def test_nondominated_matches_brute_force_with_ties_and_duplicates():
    rng = np.random.default_rng(0)
    for _ in range(20):
        f = rng.integers(0, 6, size=(40, 2)).astype(float)  # many ties and duplicates
        np.testing.assert_array_equal(design.nondominated_mask(f), brute_nondominated(f))
    f = rng.integers(0, 4, size=(30, 3)).astype(float)
    np.testing.assert_array_equal(design.nondominated_mask(f), brute_nondominated(f))


def test_hypervolume_is_exact():
    # Two boxes [0,2]x[0,1] and [0,1]x[0,3] overlap in [0,1]x[0,1]: 2 + 3 - 1 = 4.
    assert design.hypervolume_2d(np.array([[2.0, 1.0], [1.0, 3.0]])) == 4.0
    assert design.hypervolume_2d(np.array([[2.0, 1.0], [1.0, 3.0], [0.5, 0.5]])) == 4.0
    assert design.hypervolume_2d(np.array([[-1.0, 5.0]])) == 0.0
    rng = np.random.default_rng(1)
    for _ in range(10):
        f = rng.uniform(-0.2, 1.0, size=(200, 2))
        reference = rng.uniform(-0.1, 0.1, size=2)
        np.testing.assert_allclose(design.hypervolume_2d(f, reference), brute_hypervolume(f, reference), rtol=1e-13)


# Parametrization and objectives -------------------------------------------------------


def test_reference_problem_at_table1_point_is_the_table1_robot():
    problem = design.problem_from_mapping(reference_config())
    robot = problem.robot(jnp.array([1.4, 0.5]))
    table1 = sa.umetani1990()
    for field in ("base_mass", "base_inertia", "base_attach", "link_mass", "link_a", "link_b"):
        np.testing.assert_allclose(getattr(robot, field), getattr(table1, field), rtol=1e-15)
    # Uniform rods: I = m l^2 / 12 = 33.33 kg m^2 (Table 1 prints 33.3).
    np.testing.assert_allclose(robot.link_inertia, [100.0 * 4.0 / 12.0] * 2, rtol=1e-15)


def test_parametrization_holds_reach_total_mass_and_base_gyration():
    config = yaml.safe_load((ROOT / "sweeps" / "pareto-6var.yaml").read_text())
    problem = design.problem_from_mapping(config)
    rng = np.random.default_rng(2)
    for _ in range(5):
        x = problem.lower + (problem.upper - problem.lower) * rng.uniform(size=6)
        robot = problem.robot(jnp.asarray(x))
        np.testing.assert_allclose(robot.reach, 4.0, rtol=1e-14)
        np.testing.assert_allclose(robot.total_mass, 1200.0, rtol=1e-14)
        np.testing.assert_allclose(robot.base_inertia / robot.base_mass, 635.3 / 1000.0, rtol=1e-14)
        b0, l1_over_l, m1_over_arm, a1, a2, ratio = x
        np.testing.assert_allclose(robot.base_attach, b0)
        np.testing.assert_allclose(robot.link_length[0] / 4.0, l1_over_l, rtol=1e-14)
        np.testing.assert_allclose(jnp.sum(robot.link_mass) / robot.base_mass, ratio, rtol=1e-14)
        np.testing.assert_allclose(robot.link_mass[0] / jnp.sum(robot.link_mass), m1_over_arm, rtol=1e-14)
        np.testing.assert_allclose(robot.link_a / robot.link_length, [a1, a2], rtol=1e-14)


def test_guaranteed_area_table2_and_the_honest_clamp():
    table1 = sa.umetani1990()
    # Table 2: S_G = 0.39 at b0 = B0 (closed form (K1 + K2 - K0)^2 / L^2 = 0.390625).
    np.testing.assert_allclose(jax.jit(design.guaranteed_area)(table1), 0.390625, rtol=1e-14)
    np.testing.assert_allclose(design.maximum_reachable_area(table1), (1.75 + 23 / 12 + 7 / 6) ** 2 / 16, rtol=1e-14)
    # K0 = b0 m0 / w crosses K1 + K2 = 11/3 m at b0 = 4.4 m: past it the paper's formula
    # grows again, while no point inside the circle is reachable; the clamp gives 0.
    b0 = jnp.linspace(3.0, 6.0, 61)
    robots = table1.replace(
        base_attach=b0,
        base_mass=jnp.full(61, 1000.0),
        base_inertia=jnp.full(61, 635.3),
        link_mass=jnp.tile(table1.link_mass, (61, 1)),
        link_inertia=jnp.tile(table1.link_inertia, (61, 1)),
        link_a=jnp.tile(table1.link_a, (61, 1)),
        link_b=jnp.tile(table1.link_b, (61, 1)),
        joint_lower=jnp.tile(table1.joint_lower, (61, 1)),
        joint_upper=jnp.tile(table1.joint_upper, (61, 1)),
    )
    clamped = np.asarray(jax.jit(design.guaranteed_area)(robots))
    paper = np.asarray(jax.jit(lambda r: design.guaranteed_area(r, clamp=False))(robots))
    margin = 11.0 / 3.0 - np.asarray(b0) / 1.2
    np.testing.assert_allclose(paper, margin**2 / 16.0, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(clamped, np.maximum(margin, 0.0) ** 2 / 16.0, rtol=1e-13, atol=1e-16)
    # Continuously differentiable at the crossing: the slope goes to 0 from both sides.
    slope = jax.jit(jax.grad(lambda b: design.guaranteed_area(table1.replace(base_attach=b))))
    assert abs(float(slope(jnp.float64(4.4 - 1e-7)))) < 1e-7
    assert float(slope(jnp.float64(4.4 + 1e-7))) == 0.0
    # Agrees with the table-2 helper's closed form where the disc exists.
    np.testing.assert_allclose(sa.paper.normalized_areas(table1)[1], design.guaranteed_area(table1), rtol=1e-14)


def test_objective_gradients_match_finite_differences():
    """Both objectives, all six variables, the adaptive quadrature rule of eq. 12.

    One compiled JVP gives the directional derivatives and, at shifted points, the
    values for central differences (one compile keeps the test fast).
    """
    config = yaml.safe_load((ROOT / "sweeps" / "pareto-6var.yaml").read_text())
    config["wbar"] = {"phi1_panels": 4, "phi2_panels": 2, "order": 6, "newton_steps": 3}
    problem = design.problem_from_mapping(config)
    value_and_derivative = jax.jit(lambda x, v: jax.jvp(problem.objective_function(), (x,), (v,)))
    x = jnp.array([1.1, 0.45, 0.55, 0.45, 0.6, 0.25])
    step = 1e-5 * (problem.upper - problem.lower)
    for j in range(6):
        e = jnp.zeros(6).at[j].set(1.0)
        _, derivative = value_and_derivative(x, e)
        plus, _ = value_and_derivative(x + step[j] * e, e)
        minus, _ = value_and_derivative(x - step[j] * e, e)
        numeric = (np.asarray(plus) - np.asarray(minus)) / (2 * step[j])
        assert np.all(np.isfinite(derivative))
        np.testing.assert_allclose(derivative, numeric, rtol=2e-6, atol=1e-9)


def test_problem_yaml_errors_name_the_field():
    with pytest.raises(sa.ConfigError, match=r"variables\.b_0.*unknown design field 'b_0'.*did you mean 'b0'"):
        design.problem_from_mapping(reference_config(variables={"b_0": [0.0, 3.0]}))
    with pytest.raises(sa.ConfigError, match=r"variables.b0: the lower bound must be below"):
        design.problem_from_mapping(reference_config(variables={"b0": [3.0, 0.0]}))
    with pytest.raises(sa.ConfigError, match=r"l1_over_L.*sum below 1"):
        design.problem_from_mapping(reference_config(variables={"b0": [0.0, 3.0], "l1_over_L": [0.5, 1.0]}))
    with pytest.raises(
        sa.ConfigError,
        match=r"objectives\[1\]: must be one of wbar, S_G, S_M, low_virtual_mass, low_bus_rate_jump, "
        r"low_capture_bus_rate, reach_radius, got 'area'",
    ):
        design.problem_from_mapping(reference_config(objectives=["wbar", "area"]))
    with pytest.raises(sa.ConfigError, match=r"search.steps: must be an integer >= 1"):
        design.problem_from_mapping(reference_config(search={"steps": 0}))
    # The w-bar options are checked when the problem loads, not when the objective first runs.
    with pytest.raises(sa.ConfigError, match=r"wbar: unknown key 'n_phi'"):
        design.problem_from_mapping(reference_config(wbar={"n_phi": 3}))
    with pytest.raises(sa.ConfigError, match=r"wbar: unknown key 'ordr' \(did you mean 'order'\?\)"):
        design.problem_from_mapping(reference_config(wbar={"ordr": 4}))
    with pytest.raises(sa.ConfigError, match=r"wbar\.order: must be an integer >= 1, got 0"):
        design.problem_from_mapping(reference_config(wbar={"order": 0}))


def test_load_problem_loads_both_families():
    planar = sa.load_problem(ROOT / "sweeps" / "pareto-attachment.yaml")
    spatial = sa.load_problem(ROOT / "sweeps" / "pareto-mount-ur5.yaml")
    assert planar.family.name == "planar" and spatial.family.name == "spatial"
    assert [v.field for v in planar.variables] == ["base.attach", "links[0].length_share"]
    assert planar.variable_names == ("b0", "l1_over_L")  # table columns keep the names of the file
    assert spatial.variable_names == ("mount.xyz[0]", "mount.xyz[1]", "mount.rpy[1]")
    assert spatial.objectives == ("w_avg", "gci", "low_disturbance")
    robot = spatial.robot(jnp.array([0.1, -0.2, 0.3]))
    np.testing.assert_allclose(robot.mount_xyz[:2], [0.1, -0.2], rtol=1e-15)
    np.testing.assert_allclose(robot.mount_rpy[1], 0.3, rtol=1e-15)


def test_closed_form_problems_are_those_without_averages_or_radius():
    """The hybrid search steps every member and takes differences only for closed forms;
    a per-tip average (``w_avg[left/tool0]``) is a joint-box average like ``w_avg``."""
    planar = sa.load_problem(ROOT / "sweeps" / "pareto-attachment.yaml")
    spatial = sa.load_problem(ROOT / "sweeps" / "pareto-mount-ur5.yaml")
    tree = sa.load_problem(ROOT / "sweeps" / "pareto-dual-ur5.yaml")
    assert planar.closed_form and not spatial.closed_form and not tree.closed_form
    per_tip_and_mass = dataclasses.replace(tree, objectives=("w_avg[left/tool0]", "low_total_mass"))
    assert not per_tip_and_mass.closed_form
    assert dataclasses.replace(tree, objectives=("low_total_mass", "low_total_mass")).closed_form
    assert not dataclasses.replace(planar, objectives=("reach_radius", "wbar")).closed_form


def test_old_planar_names_are_aliases_of_the_design_fields():
    """pareto-6var.yaml written with the sweep's field names: the same problem, the same numbers."""
    config = yaml.safe_load((ROOT / "sweeps" / "pareto-6var.yaml").read_text())
    renamed = dict(config)
    fields = sa.family_of(sa.paper.umetani1990()).fields  # the planar design fields
    renamed["variables"] = {fields.canonical_name(k): v for k, v in config["variables"].items()}
    assert list(renamed["variables"]) == [
        "base.attach",
        "links[0].length_share",
        "links[0].mass_share",
        "links[0].centroid",
        "links[1].centroid",
        "arm.mass_ratio_fixed_total",
    ]
    old, new = design.problem_from_mapping(config), design.problem_from_mapping(renamed)
    x = jnp.array([1.1, 0.45, 0.55, 0.45, 0.6, 0.25])
    a, b = old.robot(x), new.robot(x)
    for leaf_a, leaf_b in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=False):
        np.testing.assert_array_equal(leaf_a, leaf_b)
    # The fields agree with the parametrization written out: l1 = 0.45 L, m1 = 0.55 m_arm,
    # a_i = ratio l_i, m_arm / m0 = 0.25 at w = 1200 kg, rods I = m l^2 / 12.
    masses = np.array([0.55, 0.45]) * 1200.0 * 0.25 / 1.25
    lengths = np.array([0.45, 0.55]) * 4.0
    np.testing.assert_allclose(b.link_mass, masses, rtol=1e-14)
    np.testing.assert_allclose(b.link_a, [0.45 * lengths[0], 0.6 * lengths[1]], rtol=1e-14)
    np.testing.assert_allclose(b.link_inertia, masses * lengths**2 / 12.0, rtol=1e-14)
    np.testing.assert_allclose(b.base_mass, 1200.0 / 1.25, rtol=1e-14)
    # A field and its alias together set the same number: refused.
    config["variables"]["base.attach"] = [0.0, 1.0]
    with pytest.raises(sa.ConfigError, match=r"b0 and base.attach set the same design number"):
        design.problem_from_mapping(config)


# The search ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def b0_only():
    """With b0 the only variable (l1 = l2 = 2 m): the search and the curve traced by b0."""
    config = reference_config(variables={"b0": [0.0, 3.0]}, wbar=CHEAP_WBAR, search=TINY_SEARCH, baselines={})
    problem = design.problem_from_mapping(config)
    return problem, design.pareto_search(problem)


def independent_curve(b0):
    """(wbar, S_G) along b0 for the Table 1 robot, built without the design module
    (with uniform-rod inertias m l^2 / 12 = 33.33 kg m^2 as the problem declares)."""
    table1 = sa.umetani1990().replace(link_inertia=np.full(2, 100.0 * 4.0 / 12.0))
    robots = sa.stack_robots([table1.replace(base_attach=np.float64(b)) for b in b0])
    wbar = jax.jit(lambda r: sa.paper.normalized_wbar(r, **CHEAP_WBAR))(robots)
    K = np.asarray(sa.tip_coefficients(robots))
    s_g = np.maximum(K[:, 1] + K[:, 2] - K[:, 0], 0.0) ** 2 / 16.0
    return np.stack([np.asarray(wbar), s_g], axis=1)


def test_b0_only_front_is_the_analytic_curve(b0_only):
    _problem, result = b0_only
    front = result.front()
    designs, values = result.designs[front, 0], result.objectives[front]
    # Every front design lies on the curve: the closed-form S_G (K0 = b0 m0 / w) and
    # w-bar of the Table 1 robot with that b0, built without the parametrization.
    np.testing.assert_allclose(values[:, 1], (11.0 / 3.0 - designs / 1.2) ** 2 / 16.0, rtol=1e-12)
    sweep = np.linspace(0.0, 3.0, 301)
    both = independent_curve(np.concatenate([designs, sweep]))  # one batch, one compile
    np.testing.assert_allclose(values, both[: designs.size], rtol=1e-12)
    # The curve's own front (a dense b0 sweep, its non-dominated part) is what the search
    # covers: from the S_G anchor at b0 = 0 to the w-bar maximum, with the same hypervolume.
    curve = both[designs.size :]
    curve_front = design.nondominated(curve)
    assert designs.min() == 0.0  # the bound is reached exactly (projection, no sigmoid)
    assert abs(designs.max() - sweep[curve_front].max()) < 0.02
    hv_curve = design.hypervolume_2d(curve)
    hv_search = design.hypervolume_2d(values)
    # A tiny search (16 runs, 12 steps): within 0.1% of the dense curve's hypervolume,
    # the gap being the spacing of its front points, and never above it.
    assert (1 - 1e-3) * hv_curve < hv_search < (1 + 1e-9) * hv_curve
    # Front points are Pareto-optimal up to the tiny search's convergence: no point of the
    # dense curve improves both objectives of a front point by more than 1e-4 (relative).
    improvement = np.min((curve[:, None, :] - values[None, :, :]) / values[None, :, :], axis=2)
    assert improvement.max() < 1e-4


@pytest.fixture(scope="module")
def two_variable_search():
    config = reference_config(wbar=CHEAP_WBAR, search=TINY_SEARCH)
    problem = design.problem_from_mapping(config)
    return problem, design.pareto_search(problem)


def test_front_is_nondominated_and_covers_the_archive(two_variable_search):
    problem, result = two_variable_search
    f = result.objectives
    front = f[result.front()]
    assert front.shape[0] > 10
    for point in front:  # no evaluated design dominates a front design
        assert not np.any(np.all(f >= point, axis=1) & np.any(f > point, axis=1))
    for point in f:  # every evaluated design is dominated by, or equal to, a front design
        assert np.any(np.all(front >= point, axis=1))
    # Every design stayed inside the box, and the archive hypervolume never decreases.
    assert np.all(result.designs >= problem.lower) and np.all(result.designs <= problem.upper)
    hv = [c["hypervolume"] for c in result.checkpoints]
    assert np.all(np.diff(hv) >= 0)
    assert result.evaluations == f.shape[0] == result.checkpoints[-1]["evaluations"]


def test_a_run_compiles_each_program_once_and_times_nothing_apart(tmp_path):
    """The value program serves every batch of the search (densified batches are padded),
    the gradient program compiles once, and the default cost ratio is read off the
    search's own calls: no gradient program is compiled only to time it."""
    problem = design.problem_from_mapping(reference_config(wbar=CHEAP_WBAR, search=dict(TINY_SEARCH, seed=5)))
    with count_compiles() as compiles:
        summary = design.run_problem(problem, tmp_path, method="scalarized", baselines=False, log=lambda line: None)
    heavy = {name: count for name, count in compiles.items() if "evaluate" in name or "run_chunk" in name}
    assert heavy and max(heavy.values()) == 1, dict(compiles)
    assert not [name for name in compiles if "summed" in name], dict(compiles)
    gradient = summary["methods"]["gradient"]
    assert gradient["value_and_gradient_cost_ratio"] > 0
    assert gradient["value_and_gradient_cost_ratio_from"] == "search"


def test_baselines_use_the_same_objective_code(two_variable_search):
    problem, result = two_variable_search
    grid = design.grid_search(problem, points=(7, 5), chunk=16)
    assert grid.designs.shape == (35, 2)
    np.testing.assert_allclose(grid.designs[[0, -1]], [problem.lower, problem.upper])
    runs = [grid, result]
    pymoo = pytest.importorskip("pymoo")
    if pymoo:
        nsga = design.nsga2_search(problem, population=16, evaluations=48, seed=1)
        assert nsga.evaluations >= 48
        assert np.all(nsga.designs >= problem.lower) and np.all(nsga.designs <= problem.upper)
        runs.append(nsga)
    # Re-evaluate every archived design with a fresh trace of the objective (one batch).
    designs = np.concatenate([run.designs[:64] for run in runs])
    values = np.concatenate([run.objectives[:64] for run in runs])
    objective = jax.jit(jax.vmap(problem.objective_function()))
    np.testing.assert_allclose(values, objective(jnp.asarray(designs)), rtol=1e-13)


def test_optimize_command_writes_front_summary_and_figures(tmp_path):
    pytest.importorskip("pymoo")
    config = reference_config(
        wbar=CHEAP_WBAR,
        search={**TINY_SEARCH, "steps": 8},
        baselines={"grid": {"points": [9, 5], "chunk": 16}, "nsga2": {"population": 16, "evaluations": 32}},
        hybrid={"population": 8, "generations": 3},
    )
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(config))
    out = tmp_path / "out"
    assert cli_main(["optimize", str(path), "--out", str(out), "--nsga2-factor", "0.5"]) == 0
    with open(out / "pareto.csv") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == ["b0", "l1_over_L", "wbar", "S_G"]
    front = np.array(rows[1:], dtype=float)
    assert np.all(design.nondominated_mask(front[:, 2:]))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["reference_point"] == [0.0, 0.0]
    np.testing.assert_allclose(summary["hypervolume"], design.hypervolume_2d(front[:, 2:]), rtol=1e-12)
    assert set(summary["methods"]) == {"hybrid", "grid", "nsga2"}  # the hybrid search is the default
    assert summary["methods"]["grid"]["evaluations"] == 45
    hybrid = summary["methods"]["hybrid"]  # closed forms: every member steps, by differences
    assert hybrid["jacobian"] == "differences" and hybrid["gradient_steps_per_generation"] == 8
    assert hybrid["accepted_gradient_steps"] > 0 and hybrid["value_and_gradient_evaluations"] == 0
    assert "value-and-gradient" in summary["evaluation_counting"]
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["config"] == config and manifest["float64"] is True
    for key in ("config_sha256", "packages", "git", "device_count", "command", "timings_s"):
        assert key in manifest
    for name in ("front.png", "designs.png", "convergence.png", "pareto_grid.csv", "pareto_nsga2.csv"):
        assert (out / name).stat().st_size > 0
    assert not list(out.glob(".*tmp"))  # atomic writes leave no temporaries
    # Invalid input: exit 2 with the field named, no traceback.
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(reference_config(variables={"b0": [0.0, -1.0]})))
    assert cli_main(["optimize", str(bad)]) == 2
