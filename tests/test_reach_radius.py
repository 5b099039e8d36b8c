"""The ``reach_radius`` design objective: the path-independent workspace radius and its
envelope-theorem gradient, checked against the radius kernels, central differences of the
radius recomputed from scratch, and a short hybrid search."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from spacearm import design
from spacearm._core.errors import ConfigError
from spacearm.analysis.workspace_search import singular_radius
from spacearm.design.hybrid import HybridSettings, hybrid_search
from spacearm.design.objectives import RADIUS_OPTIONS
from spacearm.design.problem import load_problem as load_design_problem
from spacearm.models.planar import singularities

from .test_design import CHEAP_WBAR, reference_config

UR5 = "configs/ur5-smallsat.yaml"

# Mounts (x, y, pitch) where the closest singular tip is a unique constrained minimum off the
# joint limits. Without the Newton polish of the minimizer (the descent leaves it ~1e-5 rad
# off) the gradient was 4e-4 to 3e-3 (relative) off the differences here.
UR5_DESIGNS = np.array([[0.1, 0.0, 0.0], [-0.3, -0.2, -0.5], [0.3, 0.1, 0.3]])


def _ur5_mount_problem(**changes):
    config = dict(
        name="ur5-mount-radius",
        robot=UR5,
        variables={"mount.xyz[0]": [-0.4, 0.6], "mount.xyz[1]": [-0.4, 0.4], "mount.rpy[1]": [-0.8, 0.8]},
        objectives=["reach_radius", "low_disturbance"],
        average={"samples": 64, "randomizations": 4, "seed": 0},
    )
    config.update(changes)
    return config


@pytest.fixture(scope="module")
def ur5_radius():
    """The UR5 mount problem with reach_radius alone beside low_total_mass (no joint-box
    average, so the program holds the radius search only)."""
    problem = load_design_problem(_ur5_mount_problem(objectives=["reach_radius", "low_total_mass"]), base_dir=".")
    return problem, problem.batch_function()


@pytest.mark.slow
def test_reach_radius_equals_the_radius_kernel_spatial(ur5_radius):
    """(a) The objective is the polished singular_radius with the problem's options (the same
    search, here batched and compiled inside the problem's program; two compiles of the
    radius search, ~25 s of CPU)."""
    problem, batch = ur5_radius
    values = np.asarray(batch(jnp.asarray(UR5_DESIGNS)))[:, 0]
    for x, value in zip(UR5_DESIGNS, values, strict=True):
        kernel = float(singular_radius(problem.robot(jnp.asarray(x)), **RADIUS_OPTIONS, polish=True)[0])
        # Batched vs single: the same search in two programs. The polished minimum over the
        # singular set moves by ~1e-12 m (2e-9 relative at the 2 mm radius) with the
        # rounding of J*, as the references below do at 1e-8.
        np.testing.assert_allclose(value, kernel, rtol=1e-8, atol=1e-12)
    # The radii of the analysis defaults (2^14 samples) at these designs: the same minima.
    np.testing.assert_allclose(values, [0.0109377753, 0.0022230301, 0.0689811532], rtol=1e-8)


@pytest.mark.slow
def test_reach_radius_gradient_matches_central_differences(ur5_radius):
    """(b) The envelope-theorem gradient (posture held fixed, the singular set's motion through
    its Lagrange multipliers) against central differences of the radius recomputed from
    scratch: the whole search, at x +- h e_j. Compiles the reverse program (~15 s CPU)."""
    problem, batch = ur5_radius
    gradient = jax.jit(jax.vmap(jax.grad(lambda x: problem.objective_function()(x)[0])))
    g = np.asarray(gradient(jnp.asarray(UR5_DESIGNS)))
    h = 1e-4
    d = UR5_DESIGNS.shape[1]
    # The shifted designs go through the batch program of three designs the fixture's first
    # test built (a batch of 18 would be one more radius program to trace, load or compile).
    values = np.stack(
        [
            np.asarray(batch(jnp.asarray(UR5_DESIGNS + s * h * np.eye(d)[j])))[:, 0]
            for s in (1.0, -1.0)
            for j in range(d)
        ],
        axis=1,
    )  # (designs, 2 d): +h e_0 .. +h e_{d-1}, then -h e_0 ..
    differences = (values[:, :d] - values[:, d:]) / (2 * h)
    np.testing.assert_allclose(g, differences, rtol=1e-6, atol=1e-7)


def test_reach_radius_planar_matches_the_root_tracing_and_differences():
    """(a, b) Planar two-link arms: the objective equals the root tracing of det J*
    (`singularities.path_independent_radius`), and its gradient central differences
    (~20 s: compiles the planar radius search for values and for the gradient)."""
    problem = design.problem_from_mapping(reference_config(wbar=CHEAP_WBAR, objectives=["wbar", "reach_radius"]))
    xs = np.array([[1.4, 0.5], [0.7, 0.4], [2.2, 0.65]])
    batch = problem.batch_function()
    values = np.asarray(batch(jnp.asarray(xs)))[:, 1]
    for x, value in zip(xs, values, strict=True):
        traced = float(singularities.path_independent_radius(problem.robot(jnp.asarray(x))))
        np.testing.assert_allclose(value, traced, rtol=1e-8)
    gradient = np.asarray(jax.jit(jax.vmap(jax.grad(lambda x: problem.objective_function()(x)[1])))(xs))
    h = 1e-5
    for j in range(2):
        step = h * np.eye(2)[j]
        difference = np.asarray(batch(jnp.asarray(xs + step)))[:, 1] - np.asarray(batch(jnp.asarray(xs - step)))[:, 1]
        np.testing.assert_allclose(gradient[:, j], difference / (2 * h), rtol=1e-6, atol=1e-9)


def test_reach_radius_problem_file_errors():
    with pytest.raises(ConfigError, match=r"p: radius: options of the reach_radius objective, which objectives"):
        load_design_problem(
            _ur5_mount_problem(objectives=["w_avg", "low_disturbance"], radius={"samples": 512}), name="p"
        )
    with pytest.raises(ConfigError, match=r"p: radius: unknown key 'sample'.*samples"):
        load_design_problem(_ur5_mount_problem(radius={"sample": 512}), name="p")
    with pytest.raises(ConfigError, match=r"p: radius.keep: at most radius.samples \(256\)"):
        load_design_problem(_ur5_mount_problem(radius={"samples": 256}), name="p")
    with pytest.raises(ConfigError, match=r"p: radius.descent_steps"):
        load_design_problem(_ur5_mount_problem(radius={"descent_steps": 0}), name="p")
    with pytest.raises(ConfigError, match=r"objectives\[0\]: reach_radius: single-arm robots only"):
        design.problem_from_mapping(
            {
                "name": "dual",
                "robot": "configs/dual-ur5-servicer.yaml",
                "variables": {"base.mass": [300.0, 600.0]},
                "objectives": ["reach_radius", "low_total_mass"],
            },
            source="dual.yaml",
            base_dir=".",
        )
    problem = load_design_problem(_ur5_mount_problem(radius={"samples": 1024, "keep": 128}), base_dir=".")
    assert problem.reference_point is None
    assert problem.fixed_summary()["radius"] == {**RADIUS_OPTIONS, "samples": 1024, "keep": 128}


@pytest.mark.slow
def test_hybrid_search_with_reach_radius():
    """(c) A short hybrid search on the UR5 mount problem with reach_radius beside
    low_disturbance (compiles the value and the reverse programs of a small radius search
    and a joint-box average: ~20 s of CPU, most of it compiling). Its archive is the batch
    function at its designs, the reference comes from the first population, the
    hypervolume does not fall. The search's machinery is under test, not the radius's
    accuracy (the tests above), so the radius search is a small one."""
    small = {"samples": 256, "keep": 64, "candidates": 8, "descent_steps": 10}
    problem = load_design_problem(_ur5_mount_problem(radius=small), base_dir=".")
    result = hybrid_search(problem, HybridSettings(population=8, generations=2, seed=0, jacobian="reverse"))
    assert result.objectives.shape[1] == 2 and np.all(np.isfinite(result.objectives))
    assert np.all(result.objectives[:, 0] > 0)
    again = np.asarray(problem.batch_function()(jnp.asarray(result.designs[:8])))
    np.testing.assert_allclose(result.objectives[:8], again, rtol=1e-9)
    hypervolumes = [c["hypervolume"] for c in result.checkpoints]
    assert hypervolumes[-1] >= hypervolumes[0] > 0
