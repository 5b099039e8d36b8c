"""The hybrid design search, the optimize command's output, and the spatial design fields
and objectives it searches over (``links.<name>.length``, ``low_total_mass``)."""

import csv
import dataclasses
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import yaml
from scipy.spatial import Delaunay

import spacearm as sa
from spacearm import design
from spacearm._core.errors import ConfigError
from spacearm.cli import main as cli_main
from spacearm.design.fronts import hypervolume, nondominated_mask, reference_from_population
from spacearm.design.hybrid import (
    END_LENGTHS,
    HybridSettings,
    _end_designs,
    _neighbour_designs,
    _newton_designs,
    _newton_probes,
    _simplex_designs,
    hybrid_search,
    nondominated_ranks,
    parse_hybrid,
)
from spacearm.design.problem import load_problem as load_design_problem
from spacearm.models import load_robot
from spacearm.models.spatial import fields

from .conftest import count_compiles
from .test_design import CHEAP_WBAR, reference_config

UR5 = "configs/ur5-smallsat.yaml"


@pytest.fixture(scope="module")
def ur5():
    return load_robot(UR5)


# Fields --------------------------------------------------------------------------------


def test_length_factor_one_is_the_identity(ur5):
    for name in ("base_link", "upper_arm_link", "wrist_3_link"):
        scaled = fields.set_field(ur5, f"links.{name}.length", 1.0)
        for key in (
            "joint_translation",
            "tip_translation",
            "root_com",
            "link_com",
            "root_inertia",
            "link_inertia",
            "link_mass",
            "root_mass",
        ):
            np.testing.assert_array_equal(np.asarray(getattr(scaled, key)), np.asarray(getattr(ur5, key)), key)


def test_length_factor_scales_one_body(ur5):
    """upper_arm_link is body 2: the elbow (joint 3) placement, its centroid times s, its
    inertia times s^2, its mass kept; every other body untouched. The last body carries the tip."""
    s = 1.3
    scaled = fields.set_field(ur5, "links.upper_arm_link.length", s)
    expected = np.array(ur5.joint_translation)
    expected[2] *= s
    np.testing.assert_allclose(np.asarray(scaled.joint_translation), expected, rtol=1e-15)
    com, inertia = np.array(ur5.link_com), np.array(ur5.link_inertia)
    com[1] *= s
    inertia[1] *= s * s
    np.testing.assert_allclose(np.asarray(scaled.link_com), com, rtol=1e-15)
    np.testing.assert_allclose(np.asarray(scaled.link_inertia), inertia, rtol=1e-15)
    np.testing.assert_array_equal(np.asarray(scaled.link_mass), np.asarray(ur5.link_mass))
    np.testing.assert_array_equal(np.asarray(scaled.tip_translation), np.asarray(ur5.tip_translation))
    tip = fields.set_field(ur5, "links.wrist_3_link.length", s)
    np.testing.assert_allclose(np.asarray(tip.tip_translation), s * np.asarray(ur5.tip_translation), rtol=1e-15)
    np.testing.assert_array_equal(np.asarray(tip.joint_translation), np.asarray(ur5.joint_translation))
    # The whole arm: every body's length factor together is arm.length (no prismatic joints here).
    each = ur5
    for name in fields._body_names(ur5):
        each = fields.set_field(each, f"links.{name}.length", s)
    whole = fields.set_field(ur5, "arm.length", s)
    for key in ("joint_translation", "tip_translation", "root_com", "link_com", "root_inertia", "link_inertia"):
        np.testing.assert_allclose(np.asarray(getattr(each, key)), np.asarray(getattr(whole, key)), rtol=1e-14)


def test_link_field_errors_name_the_field(ur5):
    with pytest.raises(ConfigError, match="'mass' or 'length'"):
        fields.check_field("axis", "links.upper_arm_link.width", ur5)
    with pytest.raises(ConfigError, match=r"did you mean .upper_arm_link."):
        fields.check_field("axis", "links.upper_arm_lnk.length", ur5)


def _tiny_arm_problem(**changes):
    config = dict(
        name="tiny-ur5-arm",
        robot=UR5,
        variables={
            "links.upper_arm_link.length": [0.7, 1.3],
            "links.forearm_link.mass": [1.0, 4.0],
            "base.mass": [200.0, 600.0],
        },
        objectives=["w_avg", "low_disturbance", "low_total_mass"],
        average={"samples": 64, "randomizations": 4, "seed": 0},
    )
    config.update(changes)
    return config


@pytest.fixture(scope="module")
def tiny_arm():
    return load_design_problem(_tiny_arm_problem(), base_dir=".")


def test_low_total_mass_and_gradients_match_finite_differences(tiny_arm, ur5):
    """low_total_mass = -(bus + every arm mass); every objective's gradient against central
    differences (the QMC rule is fixed, so each objective is a smooth function of the design)."""
    assert tiny_arm.reference_point is None
    objective = jax.jit(tiny_arm.objective_function())
    x = np.array([1.1, 2.0, 420.0])
    f = np.asarray(objective(x))
    arm = float(ur5.root_mass) + float(np.sum(ur5.link_mass)) - float(ur5.link_mass[2]) + 2.0
    assert f[2] == pytest.approx(-(420.0 + arm), rel=1e-15)
    jacobian = np.asarray(jax.jit(jax.jacrev(tiny_arm.objective_function()))(x))
    steps = np.array([1e-5, 1e-5, 1e-3])
    for j in range(3):
        up, down = x.copy(), x.copy()
        up[j] += steps[j]
        down[j] -= steps[j]
        difference = (np.asarray(objective(up)) - np.asarray(objective(down))) / (2 * steps[j])
        np.testing.assert_allclose(jacobian[:, j], difference, rtol=1e-6, atol=1e-9 * np.abs(f).max())
    assert jacobian[0, 0] > 0  # a longer upper arm reaches further: more w_avg
    assert jacobian[2, 1] == pytest.approx(-1.0) and jacobian[2, 2] == pytest.approx(-1.0)


# The search ----------------------------------------------------------------------------


def test_nondominated_ranks_peel_layers():
    f = np.array([[3.0, 1.0], [1.0, 3.0], [2.0, 0.5], [0.5, 2.0], [0.2, 0.2], [3.0, 1.0]])
    np.testing.assert_array_equal(nondominated_ranks(f), [0, 0, 1, 1, 2, 0])


def test_reference_from_population_lies_below_the_front_nadir():
    f = np.array([[1.0, 4.0], [3.0, 2.0], [0.5, 0.5]])
    np.testing.assert_allclose(reference_from_population(f, 0.1), [1.0 - 0.2, 2.0 - 0.2])


def test_parse_hybrid_checks_its_section():
    assert parse_hybrid("f.yaml", {"population": 12}).population == 12
    with pytest.raises(ConfigError, match=r"f.yaml: hybrid.population"):
        parse_hybrid("f.yaml", {"population": 2})
    with pytest.raises(ConfigError, match="populaton"):
        parse_hybrid("f.yaml", {"populaton": 12})
    assert parse_hybrid("f.yaml", {"jacobian": "reverse", "gradient_share": 0}).jacobian == "reverse"
    assert parse_hybrid("f.yaml", {"gradient_share": None}).gradient_share is None
    with pytest.raises(ConfigError, match=r"f.yaml: hybrid.jacobian: must be one of auto, reverse, differences"):
        parse_hybrid("f.yaml", {"jacobian": "forward"})
    with pytest.raises(ConfigError, match=r"f.yaml: hybrid.gradient_share: must lie in \[0, 1\]"):
        parse_hybrid("f.yaml", {"gradient_share": 1.5})
    assert parse_hybrid("f.yaml", {"step_rule": "armijo"}).step_rule == "armijo"
    with pytest.raises(ConfigError, match=r"f.yaml: hybrid.step_rule: must be one of auto, per_variable, armijo"):
        parse_hybrid("f.yaml", {"step_rule": "newton"})
    assert parse_hybrid("f.yaml", {"settled_fill": 0}).settled_fill == 0
    assert parse_hybrid("f.yaml", {"bound_refresh": 0, "common_ascent": False}).common_ascent is False
    with pytest.raises(ConfigError, match=r"f.yaml: hybrid.common_ascent: must be true or false"):
        parse_hybrid("f.yaml", {"common_ascent": 1})
    assert parse_hybrid("f.yaml", {"newton": False}).newton is False and HybridSettings().newton is True
    with pytest.raises(ConfigError, match=r"f.yaml: hybrid.newton: must be true or false"):
        parse_hybrid("f.yaml", {"newton": "yes"})
    with pytest.raises(ConfigError, match=r"f.yaml: hybrid.bound_refresh"):
        parse_hybrid("f.yaml", {"bound_refresh": -1})
    with pytest.raises(ConfigError, match=r"f.yaml: hybrid.settled_fill"):
        parse_hybrid("f.yaml", {"settled_fill": -1})


def test_neighbour_designs_lie_on_chords_between_near_front_designs_and_fill_gaps():
    """Three-objective densification: every new design lies on the chord between a front
    design and one of its 4 nearest front neighbours (in range-scaled objectives), and an
    isolated front point (the largest gap) is drawn far more often than a crowded one."""
    rng = np.random.default_rng(0)
    u = np.concatenate([rng.uniform(0.0, 0.3, size=(40, 2)), [[0.9, 0.05]]])  # one isolated design
    z = np.column_stack([u, np.full(u.shape[0], 0.3)])
    f = np.column_stack([u, 1.0 - u.sum(axis=1)])  # a linear front: f is the design's (u, v)
    new = _neighbour_designs(np.random.default_rng(1), f, z, 4000)
    assert new.shape == (4000, 3) and np.all(new[:, 2] == 0.3)
    scaled = (f - f.min(axis=0)) / np.ptp(f, axis=0)
    near = np.argsort(np.linalg.norm(scaled[:, None] - scaled[None], axis=2), axis=1)[:, 1:5]
    pairs = [(i, j) for i in range(f.shape[0]) for j in near[i]]
    a, b = z[[p[0] for p in pairs]], z[[p[1] for p in pairs]]
    # Distance of each new design to the nearest chord a-b.
    t = np.clip(np.einsum("nk,pk->np", new, b - a) - np.sum(a * (b - a), axis=1), 0, None)
    t = np.minimum(t / np.sum((b - a) ** 2, axis=1), 1.0)
    off = np.linalg.norm(new[:, None, :] - (a[None] + t[:, :, None] * (b - a)[None]), axis=2).min(axis=1)
    assert off.max() < 1e-12
    # The isolated design is drawn most of the time
    # (its gap^2 outweighs the 40 crowded ones together), and its chords reach far;
    # drawn uniformly it would be 1 in 41.
    far = np.sum(new[:, 0] > 0.5)
    assert far > 0.3 * new.shape[0]


def test_end_designs_extend_a_two_objective_front_along_its_curve():
    """Past each end of a front whose designs lie on a line, the extrapolations stay on
    that line at the set lengths beyond the end (the shortest first, the ends
    alternating), and are clipped to the box."""
    t = np.linspace(0.2, 0.6, 50)
    direction = np.array([3.0, 1.0, 0.0]) / np.sqrt(10.0)
    z = np.array([0.1, 0.3, 1.0]) + t[:, None] * direction
    ends = _end_designs(z)
    assert ends.shape == (2 * len(END_LENGTHS), 3)
    for k, length in enumerate(END_LENGTHS):
        high, low = ends[2 * k], ends[2 * k + 1]
        np.testing.assert_allclose(high, np.clip(z[-1] + length * direction, 0.0, 1.0), atol=1e-12)
        np.testing.assert_allclose(low, np.clip(z[0] - length * direction, 0.0, 1.0), atol=1e-12)
    assert np.all(ends[:, 2] == 1.0)


def test_simplex_designs_fill_the_largest_triangles_of_the_front_once():
    """The settled fill: centroids of the front's triangles (triangulated in the scaled
    objectives along (1, 1, 1)), the largest first, each triangle once; on a front whose
    designs lie in one face of the box the centroids stay on that face exactly."""
    rng = np.random.default_rng(0)
    u = np.concatenate([rng.uniform(0.0, 0.3, size=(40, 2)), [[0.9, 0.05]]])  # one isolated design
    z = np.column_stack([u, np.ones(u.shape[0])])  # on the face z3 = 1
    f = np.column_stack([u, 1.0 - u.sum(axis=1)])  # a linear front: f is the design's (u, v)
    tried = set()
    first = _simplex_designs(f, z, 5, tried)
    assert first.shape == (5, 3) and np.all(first[:, 2] == 1.0) and len(tried) == 5
    # The largest triangle reaches the isolated design and is drawn first.
    assert first[0, 0] > 0.3
    spread = np.ptp(f, axis=0)
    scaled = (f - f.min(axis=0)) / spread
    basis = np.linalg.svd(np.ones((1, 3)))[2][1:]
    simplices = Delaunay(scaled @ basis.T).simplices
    area = 0.5 * np.linalg.norm(
        np.cross(*(scaled[simplices[:, 1:]] - scaled[simplices[:, :1]]).transpose(1, 0, 2)), axis=1
    )
    np.testing.assert_allclose(first[0], z[simplices[np.argmax(area)]].mean(axis=0), atol=1e-15)
    # A second call skips the triangles already filled; all of them: nothing left.
    second = _simplex_designs(f, z, 5, tried)
    assert not np.any(np.all(np.isclose(second[:, None], first[None]), axis=2))
    rest = _simplex_designs(f, z, 10**6, tried)
    assert rest.shape[0] == simplices.shape[0] - 10 and _simplex_designs(f, z, 5, tried).shape == (0, 3)


class _FaceFront:
    """Three closed-form objectives of three unit-box variables whose Pareto set is the
    face z3 = 1: f = (z1 + z3, z2 + z3, z3 - z1 - z2), a linear front there."""

    variables = ("z1", "z2", "z3")
    objectives = ("a", "b", "c")
    lower, upper = np.zeros(3), np.ones(3)
    closed_form = True
    reference_point = (-0.1, -0.1, -2.1)

    def batch_function(self):
        return jax.jit(lambda x: jnp.stack([x[:, 0] + x[:, 2], x[:, 1] + x[:, 2], x[:, 2] - x[:, 0] - x[:, 1]], axis=1))


def test_hybrid_settles_into_filling_the_front():
    """Once the population's hypervolume stalls and the fill gains more per evaluation than
    the rest, the steps stop and each generation evaluates ``settled_fill`` populations of
    simplex centroids beside half a population of offspring; with ``settled_fill: 0`` the
    search never switches (steps and chords to the end)."""
    generations = 30
    settings = HybridSettings(population=8, generations=generations, seed=1, tolerance=0.0)
    result = hybrid_search(_FaceFront(), settings)
    settled = result.extra["settled_at_generation"]
    assert settled is not None and settled < generations
    by_source = result.extra["evaluations_by_source"]
    assert by_source["newton_probes"] == by_source["newton"] == by_source["common_ascent"] == 0  # two objectives only
    after = generations - settled
    assert by_source["densified"] == 8 * settled + 3 * 8 * after
    assert by_source["offspring"] >= 4 * after
    never = hybrid_search(
        _FaceFront(), HybridSettings(population=8, generations=generations, seed=1, tolerance=0.0, settled_fill=0)
    )
    assert never.extra["settled_at_generation"] is None
    assert never.extra["evaluations_by_source"]["densified"] == 8 * generations
    # Filling pays here: a higher hypervolume from fewer evaluations (11.37 from 1,264
    # against 11.15 from 1,456 when written).
    assert result.evaluations < never.evaluations
    assert result.checkpoints[-1]["hypervolume"] > never.checkpoints[-1]["hypervolume"]


class _UnitBoxTrade:
    """Two closed-form objectives ("a", "b") of three variables on the unit box."""

    variables = ("z1", "z2", "z3")
    objectives = ("a", "b")
    lower, upper = np.zeros(3), np.ones(3)
    closed_form = True


class _BoundedTrade(_UnitBoxTrade):
    """A Pareto set that is the segment z2 = 0.5, z3 = 0 (the lower bound, where moving
    inward lowers both): f = (z1 - q - z3, 1 - z1^2 - q - z3) with q = (z2 - 0.5)^2."""

    reference_point = (-1.0, -1.0)

    def batch_function(self):
        def f(x):
            q = (x[:, 1] - 0.5) ** 2
            return jnp.stack([x[:, 0] - q - x[:, 2], 1.0 - x[:, 0] ** 2 - q - x[:, 2]], axis=1)

        return jax.jit(f)


def test_hybrid_skips_blocked_bound_differences_and_tries_common_ascent():
    """Two objectives: a variable at a bound where moving inward lowered both objectives
    is not differenced between refreshes, and front members that are not Pareto-critical
    try designs along their common ascent direction; deterministic for a seed; both off:
    neither."""
    settings = HybridSettings(population=8, generations=12, seed=2, tolerance=0.0, common_ascent=True)
    result = hybrid_search(_BoundedTrade(), settings)
    again = hybrid_search(_BoundedTrade(), settings)
    np.testing.assert_array_equal(result.designs, again.designs)
    assert result.extra["skipped_differences"] > 0
    assert result.extra["evaluations_by_source"]["common_ascent"] > 0
    off = hybrid_search(_BoundedTrade(), dataclasses.replace(settings, bound_refresh=0, common_ascent=False))
    assert off.extra["skipped_differences"] == 0 and off.extra["evaluations_by_source"]["common_ascent"] == 0


# Two concave quadratics of (z1, z2) with different metrics, both lowered by z3: the
# Pareto set is the curve z(w) = (w A + (1 - w) B)^-1 (w A a + (1 - w) B b), z3 = 0.
_METRICS = (np.array([[2.0, 0.5], [0.5, 1.0]]), np.array([[1.0, -0.3], [-0.3, 3.0]]))
_CENTRES = (np.array([0.2, 0.3]), np.array([0.8, 0.6]))


def _curved_objectives(z, xp=np):
    u, v = z[:, :2] - _CENTRES[0], z[:, :2] - _CENTRES[1]
    first = -xp.sum(u * (u @ _METRICS[0]), axis=1) - z[:, 2]
    second = -xp.sum(v * (v @ _METRICS[1]), axis=1) - z[:, 2]
    return xp.stack([first, second], axis=1)


class _CurvedTrade(_UnitBoxTrade):
    """`_curved_objectives` as a closed-form design problem on the unit box."""

    reference_point = (-2.0, -2.0)

    def batch_function(self):
        return jax.jit(lambda x: _curved_objectives(x, jnp))


def test_newton_steps_put_designs_on_a_curved_pareto_set():
    """From designs 3e-3 off a curved Pareto set (Jacobians by forward differences, as in
    the search), one Newton step lands near it: the sine of the angle between the two
    gradients (zero on the set) falls from 4e-3-0.06 to 2e-6-6e-4, each by at least 10
    times; z3, 1e-5 above the bound where both objectives fall, goes to the bound; a
    design on the set takes no step."""
    weights = np.linspace(0.1, 0.9, 9)[:, None, None]
    metric = weights * _METRICS[0] + (1 - weights) * _METRICS[1]
    pull = weights[:, :, 0] * (_CENTRES[0] @ _METRICS[0]) + (1 - weights[:, :, 0]) * (_CENTRES[1] @ _METRICS[1])
    on = np.linalg.solve(metric, pull[:, :, None])[:, :, 0]  # (9, 2): on the Pareto set
    rng = np.random.default_rng(0)
    off = rng.normal(size=on.shape)
    z = np.concatenate([on + 3e-3 * off / np.linalg.norm(off, axis=1, keepdims=True), np.full((9, 1), 1e-5)], axis=1)
    z = np.concatenate([z, [[*on[4], 0.0]]])  # the last one on the set
    f = _curved_objectives(z)

    def jacobians(z):
        h = np.where(z > 0.5, -1e-6, 1e-6)
        shifted = z[:, None, :] + h[:, :, None] * np.eye(3)
        return (_curved_objectives(shifted.reshape(-1, 3)).reshape(-1, 3, 2) - _curved_objectives(z)[:, None]) / h[
            :, :, None
        ]

    def sine(z):
        g = jacobians(z)[:, :2]  # (n, 2 free, 2)
        return np.abs(np.linalg.det(g)) / np.prod(np.linalg.norm(g, axis=1), axis=1)

    probes = _newton_probes(z, jacobians(z))
    np.testing.assert_array_equal(probes["members"], np.arange(9))  # not the one on the set
    assert probes["free"][:, :2].all() and probes["lower"][:, 2].all()
    assert probes["taken"].sum() == 9 * 3  # (z1, z1), (z1, z2), (z2, z2)
    values = _curved_objectives(probes["probes"].reshape(-1, 3)).reshape(9, -1, 2)
    stepped = _newton_designs(z[:9], f[:9], jacobians(z)[:9], probes, values)
    assert stepped.shape == (9, 3) and np.all(stepped[:, 2] == 0.0)
    assert np.all(sine(z[:9]) > 4e-3) and np.all(sine(stepped) < 0.1 * sine(z[:9]))
    assert np.median(sine(stepped)) < 2e-5
    assert np.all(np.linalg.norm(stepped[:, :2] - z[:9, :2], axis=1) < 1e-2)


def test_hybrid_newton_steps_two_objectives_only():
    """Two objectives: the search spends values on the probes and the Newton steps (the
    steps in the densified batch: every batch a multiple of the population), the same
    for a seed; ``newton: false`` spends none."""
    settings = HybridSettings(population=8, generations=10, seed=0, tolerance=0.0)
    result = hybrid_search(_CurvedTrade(), settings)
    again = hybrid_search(_CurvedTrade(), settings)
    np.testing.assert_array_equal(result.designs, again.designs)
    by_source = result.extra["evaluations_by_source"]
    assert by_source["newton_probes"] > 0 and by_source["newton"] > 0
    assert result.extra["value_evaluations"] == sum(by_source.values()) and result.evaluations % 8 == 0
    assert by_source["newton"] + by_source["densified"] >= 10 * 8
    without = hybrid_search(_CurvedTrade(), dataclasses.replace(settings, newton=False))
    assert without.extra["evaluations_by_source"]["newton_probes"] == 0
    assert without.extra["evaluations_by_source"]["newton"] == 0


@pytest.fixture(scope="module")
def planar_hybrid():
    problem = design.problem_from_mapping(reference_config(wbar=CHEAP_WBAR))
    jax.clear_caches()  # count this run's compilations, not whether another file already ran the same problem
    with count_compiles() as compiles:
        result = hybrid_search(problem, HybridSettings(population=16, generations=6, seed=3))
    return problem, result, dict(compiles)


def test_hybrid_archive_front_and_hypervolume(planar_hybrid):
    problem, result, compiles = planar_hybrid
    f = result.objectives
    # Every evaluated design is in the box and archived, with the values batch_function gives.
    assert np.all(result.designs >= problem.lower) and np.all(result.designs <= problem.upper)
    by_source = result.extra["evaluations_by_source"]
    assert result.extra["value_evaluations"] == f.shape[0] == sum(by_source.values())
    # Start, then per generation every member's step, and the Newton steps with densified
    # designs filling their batch (at least 16 of them); offspring fill the batches of the
    # differences and of the steps with the Newton probes.
    assert by_source["start"] == 2 * 16 and by_source["steps"] == 6 * 16
    assert by_source["densified"] >= 6 * 16 and (by_source["densified"] + by_source["newton"]) % 16 == 0
    assert f.shape[0] % 16 == 0 and by_source["offspring"] >= 6 * 8
    np.testing.assert_allclose(f, np.asarray(problem.batch_function()(jnp.asarray(result.designs))), rtol=1e-12)
    hv = [c["hypervolume"] for c in result.checkpoints]
    assert np.all(np.diff(hv) >= 0)
    assert hv[-1] == pytest.approx(hypervolume(f, problem.reference_point), rel=1e-14)
    assert result.extra["accepted_gradient_steps"] > 0
    # Each heavy program compiled once: the value program and the gradient (VJP) program.
    heavy = {name: count for name, count in compiles.items() if "evaluate" in name or "pull" in name}
    assert heavy and max(heavy.values()) == 1, compiles


def test_hybrid_reverse_jacobian_steps_like_the_differences():
    """The vector-Jacobian product (one more program) and the forward differences through
    the value program give the same design-space gradients, so the same run to a few
    digits; the population rule stops a run without densification once the population's
    own hypervolume rose no higher for ``population_patience`` generations and the
    archive's gained less than ``population_tolerance``."""
    problem = design.problem_from_mapping(reference_config(wbar=CHEAP_WBAR))
    runs = {}
    for jacobian in ("reverse", "differences"):
        settings = HybridSettings(
            population=16,
            generations=40,
            seed=3,
            jacobian=jacobian,
            densify=False,
            population_patience=3,
            population_tolerance=1e-2,
            bound_refresh=0,  # the gradients alone: what only the differences add is off
            common_ascent=False,
            newton=False,
        )
        with count_compiles() as compiles:
            runs[jacobian] = hybrid_search(problem, settings)
        pulls = [count for name, count in compiles.items() if "pull" in name]
        assert pulls == ([1] if jacobian == "reverse" else []), dict(compiles)
    reverse, differences = runs["reverse"], runs["differences"]
    assert reverse.extra["jacobian"] == "reverse" and differences.extra["jacobian"] == "differences"
    first = len(reverse.checkpoints[1:3])  # the first two generations, before paths can part
    for a, b in zip(reverse.checkpoints[1 : 1 + first], differences.checkpoints[1 : 1 + first], strict=True):
        assert a["population_hypervolume"] == pytest.approx(b["population_hypervolume"], rel=1e-6)
    for run in runs.values():
        assert run.extra["stop_reason"].startswith("converged: the population") and run.extra["generations"] < 40
        population_hv = [c["population_hypervolume"] for c in run.checkpoints]
        assert max(population_hv[-3:]) <= max(population_hv[:-3]) * (1 + 1e-9)
        archive_hv = [c["hypervolume"] for c in run.checkpoints]
        assert archive_hv[-1] - archive_hv[-4] <= 1e-2 * archive_hv[-1]


def test_hybrid_gradient_steps_raise_the_hypervolume_of_a_population(planar_hybrid):
    """More generations of the same seed never end lower, and the hybrid beats its own
    space-filling start."""
    _problem, result, _ = planar_hybrid
    assert result.checkpoints[-1]["hypervolume"] > result.checkpoints[0]["hypervolume"]


@pytest.mark.slow
def test_spatial_optimize_without_reference_writes_a_front_that_batch_function_reproduces(tmp_path):
    """A 3-objective spatial problem with no reference point (compiles two spatial programs:
    about a minute on a loaded machine): the reference is chosen and written, pareto.csv holds
    variables then objectives, and its objectives are batch_function() at its designs to 1e-9."""
    config = _tiny_arm_problem(hybrid={"population": 8, "generations": 2}, baselines={"nsga2": {"population": 8}})
    config["robot"] = str(Path(UR5).resolve())
    path = tmp_path / "arm.yaml"
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    out = tmp_path / "out"
    assert cli_main(["optimize", str(path), "--out", str(out), "--nsga2-factor", "0.2"]) == 0
    with open(out / "pareto.csv") as handle:
        rows = list(csv.reader(handle))
    variables = list(config["variables"])
    assert rows[0] == variables + config["objectives"]
    table = np.array(rows[1:], dtype=float)
    problem = sa.load_problem(str(path))  # the public entry point reads spatial problem files too
    again = np.asarray(problem.batch_function()(jnp.asarray(table[:, :3])))
    np.testing.assert_allclose(table[:, 3:], again, rtol=1e-9, atol=0)
    assert np.all(nondominated_mask(table[:, 3:]))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["reference_point_from"].startswith("nadir")
    assert len(summary["reference_point"]) == 3 and summary["against_nsga2"]["nsga2_final_hypervolume"] > 0
    for name in ("front.png", "designs.png", "convergence.png"):
        assert (out / name).stat().st_size > 0


HIDDEN_FIELDS = {  # the fields of the unseen 9-variable arm problem, with bounds of our own
    "mount.xyz[0]": [-0.3, 0.5],
    "mount.xyz[1]": [-0.3, 0.3],
    "mount.rpy[0]": [-0.6, 0.6],
    "mount.rpy[1]": [-0.6, 0.6],
    "links.upper_arm_link.length": [0.7, 1.4],
    "links.forearm_link.length": [0.7, 1.4],
    "links.upper_arm_link.mass": [5.0, 10.0],
    "links.forearm_link.mass": [1.5, 3.5],
    "base.mass": [200.0, 500.0],
}


@pytest.mark.slow
def test_nine_variable_arm_without_reference_writes_the_batch_function_front(tmp_path):
    """The unseen 9-variable problem's shape at a cheap joint-box rule (compiles the spatial
    value program: tens of seconds on a loaded machine): no reference point in the file, so
    the one taken below the first population's nadir is written to the summary, with the
    front's hypervolume above it; pareto.csv holds the 9 variables then the 3 objectives, and
    its objectives are ``sa.load_problem(file).batch_function()`` at its designs to 1e-9."""
    config = _tiny_arm_problem(
        variables=HIDDEN_FIELDS,
        average={"samples": 32, "randomizations": 2, "seed": 1},
        hybrid={"population": 8, "generations": 3},
    )
    config["robot"] = str(Path(UR5).resolve())
    path = tmp_path / "hidden.yaml"
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    out = tmp_path / "out"
    assert cli_main(["optimize", str(path), "--out", str(out), "--no-baselines"]) == 0
    with open(out / "pareto.csv") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == list(HIDDEN_FIELDS) + config["objectives"]
    table = np.array(rows[1:], dtype=float)
    designs, front = table[:, :9], table[:, 9:]
    bounds = np.array(list(HIDDEN_FIELDS.values()))
    assert np.all(designs >= bounds[:, 0]) and np.all(designs <= bounds[:, 1])
    problem = sa.load_problem(str(path))
    assert problem.reference_point is None
    again = np.asarray(problem.batch_function()(jnp.asarray(designs)))
    np.testing.assert_allclose(front, again, rtol=1e-9, atol=0)
    assert front.shape[0] >= 2 and np.all(nondominated_mask(front))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["reference_point_from"].startswith("nadir")
    reference = np.array(summary["reference_point"])
    assert np.sum(np.all(front > reference, axis=1)) >= 2
    assert summary["methods"]["hybrid"]["hypervolume"] == pytest.approx(hypervolume(front, reference), rel=1e-12)
