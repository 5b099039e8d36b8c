"""Studies over several arms: the design fields of a tree, per-tip and whole-system
averages and objectives, and sweeps and design problems on a two-arm robot.

References: the spatial fields (an established single-arm implementation) on the same
URDF chain, a tree built from a URDF chain scaled by hand, direct means of
``sa.manipulability`` over the same QMC points, and finite differences.
"""

import csv
import dataclasses
import functools
import json
import shutil
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import yaml

import spacearm as sa
from spacearm._core.errors import ConfigError
from spacearm.analysis.joint_box import box_postures, digital_shifts, sobol_direction_numbers, sobol_points
from spacearm.cli import main
from spacearm.cli.validate import validate_file
from spacearm.io import read_csv
from spacearm.models.spatial import fields as spatial_fields
from spacearm.models.spatial.robot import robot_from_chain
from spacearm.models.spatial.schema import locate_package_file
from spacearm.models.spatial.urdf import parse_urdf
from spacearm.models.tree import fields as tree_fields
from spacearm.models.tree.robot import tree_from_chains
from spacearm.studies.designs import build_designs
from spacearm.studies.metrics import design_function, metric_columns
from spacearm.studies.spec import load_sweep

MOUNT_XYZ = [[0.3, 0.5526, 0.08], [0.3, -0.5526, 0.08]]
MOUNT_RPY = [[-1.5708, 0.0, 0.0], [1.5708, 0.0, 0.0]]
BUS = {"base_mass": 400.0, "base_com": [0.01, -0.02, 0.03], "base_inertia": np.diag([60.0, 62.0, 64.0])}


@pytest.fixture(scope="module")
def ur5_chain():
    path = locate_package_file("test", "example-robot-data", "robots/ur_description/urdf/ur5_robot.urdf")
    with open(path) as file:
        return parse_urdf(file.read(), source=path, root_link="base_link", tip="tool0")


def _dual(chains):
    return tree_from_chains(list(chains), arm_names=["left", "right"], mount_xyz=MOUNT_XYZ, mount_rpy=MOUNT_RPY, **BUS)


@pytest.fixture(scope="module")
def dual(ur5_chain):
    return _dual([ur5_chain, ur5_chain])


def _leaves(robot):
    return {key.name: np.asarray(value) for key, value in jax.tree_util.tree_leaves_with_path(robot) for key in key}


def _changed(before, after):
    """The leaves that differ between two designs."""
    a, b = _leaves(before), _leaves(after)
    return {name for name in a if not np.array_equal(a[name], b[name])}


# Fields -------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("field", "value", "leaf", "index"),
    [
        ("arms.right.mount.xyz[0]", 0.45, "mount_xyz", (1, 0)),
        ("arms.right.mount.xyz[2]", -0.1, "mount_xyz", (1, 2)),
        ("arms.left.mount.rpy[1]", 0.3, "mount_rpy", (0, 1)),
        ("base.mass", 250.0, "base_mass", ()),
        ("base.com[1]", 0.07, "base_com", (1,)),
        ("links.right/forearm_link.mass", 3.0, "link_mass", (8,)),
        ("links.left/upper_arm_link.mass", 9.0, "link_mass", (1,)),
    ],
)
def test_absolute_fields_round_trip(dual, field, value, leaf, index):
    """set_field writes exactly that number (and what follows from it), field_columns reads it back."""
    robot = tree_fields.set_field(dual, field, value)
    assert np.asarray(getattr(robot, leaf))[index] == pytest.approx(value, abs=0, rel=1e-15)
    column = next(iter(tree_fields.field_columns(robot, [field]).values()))
    assert float(column) == pytest.approx(value, rel=1e-15)
    expected = {leaf} | ({"link_inertia"} if leaf == "link_mass" else set())
    assert _changed(dual, robot) == expected
    changed = np.argwhere(np.asarray(getattr(robot, leaf)) != np.asarray(getattr(dual, leaf)))
    assert [tuple(i) for i in changed] in ([index], [])  # only that entry
    robot.replace()  # a valid design


def test_rpy_deg_and_relative(dual):
    degrees = tree_fields.set_field(dual, "arms.right.mount.rpy_deg[2]", 30.0)
    assert degrees.mount_rpy[1, 2] == pytest.approx(np.pi / 6, rel=1e-15)
    doubled = tree_fields.set_field(dual, "arms.left.mount.xyz[1]", 2.0, relative=True)
    assert doubled.mount_xyz[0, 1] == pytest.approx(2 * MOUNT_XYZ[0][1], rel=1e-15)
    assert np.array_equal(doubled.mount_xyz[1], dual.mount_xyz[1])


def test_batched_numpy_and_traced_fields_agree(dual):
    """A numpy batch (sweeps) and a traced single design (problems) give the same numbers."""
    values = np.array([0.8, 1.0, 1.3])
    batch = jax.tree_util.tree_map(lambda x: np.repeat(np.asarray(x)[None], 3, axis=0), dual)
    batched = tree_fields.set_field(batch, "arms.right.length", values)
    traced = jax.jit(lambda s: tree_fields.set_field(dual, "arms.right.length", s))(1.3)
    for name, leaf in _leaves(traced).items():
        np.testing.assert_array_equal(leaf, _leaves(batched)[name][2], err_msg=name)


def _scaled_chain(chain, s: float, mass: float = 1.0):
    """The URDF chain scaled by hand: lengths times s, masses times ``mass``, inertias times mass s^2."""
    prismatic = np.array([kind == "prismatic" for kind in chain.joint_kinds])
    return dataclasses.replace(
        chain,
        joint_translation=chain.joint_translation * s,
        body_com=chain.body_com * s,
        body_mass=chain.body_mass * mass,
        body_inertia=chain.body_inertia * mass * s * s,
        tip_translation=chain.tip_translation * s,
        joint_lower=np.where(prismatic, chain.joint_lower * s, chain.joint_lower),
        joint_upper=np.where(prismatic, chain.joint_upper * s, chain.joint_upper),
    )


def test_arm_length_and_mass_equal_a_tree_of_a_scaled_urdf(dual, ur5_chain):
    """arms.right.length = 1.3 and arms.right.mass = 0.7 give the tree of a URDF scaled by hand
    (the left arm and both mounts untouched)."""
    robot = tree_fields.set_field(dual, "arms.right.length", 1.3)
    robot = tree_fields.set_field(robot, "arms.right.mass", 0.7)
    reference = _dual([ur5_chain, _scaled_chain(ur5_chain, 1.3, 0.7)])
    for name, leaf in _leaves(reference).items():
        np.testing.assert_allclose(_leaves(robot)[name], leaf, rtol=1e-14, atol=0, err_msg=name)
    columns = tree_fields.field_columns(robot, ["arms.right.mass", "arms.right.length"])
    arm_mass = float(np.sum(ur5_chain.body_mass))
    assert columns["right_mass_kg"] == pytest.approx(0.7 * arm_mass, rel=1e-14)
    assert float(tree_fields.arm_mass(robot)) == pytest.approx(1.7 * arm_mass, rel=1e-14)


@pytest.mark.parametrize(
    ("tree_field", "spatial_field", "value"),
    [
        ("arms.only.mount.xyz[1]", "mount.xyz[1]", 0.2),
        ("arms.only.mount.rpy_deg[0]", "mount.rpy_deg[0]", 12.0),
        ("arms.only.mass", "arm.mass", 1.4),
        ("arms.only.length", "arm.length", 0.8),
        ("base.inertia", "base.inertia", 1.5),
        ("links.upper_arm_link.mass", "links.upper_arm_link.mass", 10.0),
        ("links.upper_arm_link.length", "links.upper_arm_link.length", 1.25),
        ("links.wrist_3_link.length", "links.wrist_3_link.length", 2.0),
        ("links.shoulder_link.length", "links.shoulder_link.length", 0.9),
    ],
)
def test_one_arm_tree_fields_equal_the_spatial_fields(ur5_chain, tree_field, spatial_field, value):
    """On a tree of one arm every field sets what the spatial field sets on the same arm."""
    bus = {**BUS, "mount_xyz": MOUNT_XYZ[0], "mount_rpy": MOUNT_RPY[0]}
    spatial = spatial_fields.set_field(robot_from_chain(ur5_chain, **bus), spatial_field, value)
    tree = tree_from_chains(
        [ur5_chain], arm_names=["only"], **{k: [v] if k.startswith("mount") else v for k, v in bus.items()}
    )
    tree = tree_fields.set_field(tree, tree_field, value)
    for name, leaf in _leaves(spatial).items():
        np.testing.assert_array_equal(np.reshape(_leaves(tree)[name], np.shape(leaf)), leaf, err_msg=name)


@pytest.mark.parametrize(
    ("field", "message"),
    [
        ("arms.rigth.mass", "unknown arm 'rigth' (did you mean 'right'?)"),
        ("arms.right.mount.xyz[3]", "index 3 out of range"),
        ("links.upper_arm_link.mass", "several arms have a link 'upper_arm_link'"),
        ("links.left/forearm.length", "did you mean 'left/forearm_link'?"),
        ("links.right/tool0.mass", "merged into body 'right/wrist_3_link'"),
        ("links.left/forearm_link.size", "a link field is 'mass' or 'length'"),
        ("mount.xyz[0]", "arms.<arm>.mount.xyz"),
        ("arms.left.colour", "an arm field is"),
    ],
)
def test_bad_fields_name_the_field(dual, field, message):
    with pytest.raises(ConfigError) as error:
        tree_fields.check_field("sweep.yaml: axes.x", field, dual)
    assert message in str(error.value)
    assert str(error.value).startswith("sweep.yaml: axes.x.field")


def test_conflicts_stages_and_units(dual):
    conflict = tree_fields.conflicting_number
    assert conflict("arms.right.mass", "links.right/forearm_link.mass", dual) == "links.right/forearm_link.mass"
    assert conflict("arms.left.mass", "links.right/forearm_link.mass", dual) is None
    assert conflict("arms.right.mount.rpy[1]", "arms.right.mount.rpy_deg[1]", dual)
    assert conflict("arms.right.length", "links.right/forearm_link.length", dual) is None
    assert conflict("arms.right.length", "arms.right.mass", dual) is None
    stage = tree_fields.field_stage
    assert stage("arms.right.mount.xyz[0]") < stage("arms.right.length") < stage("arms.right.mass")
    unit = tree_fields.field_unit
    assert [unit(f) for f in ("arms.a.mount.xyz[0]", "arms.a.mount.rpy[0]", "arms.a.mount.rpy_deg[0]")] == [
        "m",
        "rad",
        "deg",
    ]
    assert unit("arms.a.mass") == unit("arms.a.length") == unit("links.x.length") == "1"
    assert unit("links.x.mass") == unit("base.mass") == "kg"
    assert "arms.a.mass" in tree_fields.FACTOR_FIELDS and "links.x.mass" not in tree_fields.FACTOR_FIELDS


def test_fields_are_differentiable(dual):
    """d(arm mass)/d(arms.right.mass) is the right arm's mass; a mount field moves one number."""
    mass = lambda s: tree_fields.arm_mass(tree_fields.set_field(dual, "arms.right.mass", s))
    assert float(jax.grad(mass)(1.0)) == pytest.approx(
        float(np.sum(np.asarray(dual.root_mass)[1]) + np.sum(np.asarray(dual.link_mass)[6:])), rel=1e-14
    )
    mount = jax.grad(lambda x: jnp.sum(tree_fields.set_field(dual, "arms.right.mount.xyz[2]", x).mount_xyz))(0.2)
    assert float(mount) == 1.0


# Averages, objectives and the command line on a tree ---------------------------------------

ARM3DOF = Path(__file__).resolve().parents[1] / "configs" / "urdf" / "arm3dof.urdf"


def _small_tree_file(folder: Path) -> Path:
    """Two 3-DOF arms (configs/urdf/arm3dof.urdf, two copies beside the file) on a 100 kg bus: 6 joints, 2 tips."""
    shutil.copy(ARM3DOF, folder / "arm3dof.urdf")
    arm = {"urdf": "arm3dof.urdf", "root_link": "arm_base", "tip": "tool"}
    config = {
        "name": "two-small",
        "base": {"mass": 100.0, "com": [0.0, 0.0, 0.0], "inertia": [[9.3, 0, 0], [0, 9.3, 0], [0, 0, 9.3]]},
        "arms": [
            {"name": "left", "mount": {"xyz": [0.0, 0.4, 0.3], "rpy": [-1.2, 0.0, 0.0]}, **arm},
            {"name": "right", "mount": {"xyz": [0.1, -0.4, 0.3], "rpy": [1.2, 0.0, 0.3]}, **arm},
        ],
    }
    path = folder / "two-small.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


@pytest.fixture(scope="module")
def small_tree_file(tmp_path_factory):
    return _small_tree_file(tmp_path_factory.mktemp("tree"))


def _problem_config(robot_file: Path, **changes) -> dict:
    config = {
        "name": "two-small-mount",
        "robot": str(robot_file),
        "variables": {"arms.right.mount.xyz[0]": [-0.2, 0.3], "arms.right.mount.rpy[1]": [-0.5, 0.5]},
        "objectives": [{"name": "w_avg", "tip": "left/tool"}, "w_avg[right/tool]", "low_disturbance", "low_total_mass"],
        "average": {"samples": 256, "randomizations": 8, "seed": 3},
        "hybrid": {"population": 4, "generations": 1},
    }
    config.update(changes)
    return config


def _rule_postures(robot, shifts, points: int):
    """The fixed QMC rule's postures ``(R points, n)``: digitally shifted Sobol points mapped
    onto the joint box (inside the caller's program, not op by op)."""
    n = robot.n_joints
    unit = sobol_points(jnp.asarray(sobol_direction_numbers(n)), 0, points, shifts)
    return box_postures(robot, unit).reshape(-1, n)


@functools.partial(jax.jit, static_argnames=("points",))
def _rule_means_kernels(robot, shifts, points: int):
    """w* per tip and C at the rule's postures, from the public kernels (one program)."""
    q = _rule_postures(robot, shifts, points)
    return sa.manipulability(robot, q), sa.base_rate_matrix(robot, q)


@functools.partial(jax.jit, static_argnames=("points",))
def _rule_jacobians_and_inertias(robot, shifts, points: int):
    """J* per tip and H* at the rule's postures, from the public kernels (one program)."""
    q = _rule_postures(robot, shifts, points)
    return sa.generalized_jacobian(robot, q), sa.arm_inertia(robot, q)


def _direct_means(robot, samples: int, randomizations: int, seed: int):
    """The means of w* per tip and of ||C_w||_F over the fixed QMC rule, from the public kernels."""
    shifts = digital_shifts(seed, randomizations, robot.n_joints)
    w, C = (np.asarray(x) for x in _rule_means_kernels(robot, shifts, samples // randomizations))  # (P, k), (P, 6, n)
    return w.mean(axis=0), np.linalg.norm(C[:, 3:, :], axis=(-2, -1)).mean()


def _direct_gci_and_wd(robot, samples: int, randomizations: int, seed: int):
    """The means of 1/kappa of each tip's J*_v (NumPy singular values) and of its
    w_d = sqrt det(J*_v H*^-1 H*^-T J*_v^T) (NumPy solve and determinant) over the fixed QMC rule."""
    shifts = digital_shifts(seed, randomizations, robot.n_joints)
    J, H = (np.asarray(x) for x in _rule_jacobians_and_inertias(robot, shifts, samples // randomizations))
    J = J[..., :3, :]  # (P, k, 3, n); H: (P, n, n)
    singular = np.linalg.svd(J, compute_uv=False)
    K = np.swapaxes(np.linalg.solve(H[:, None], np.swapaxes(J, -1, -2)), -1, -2)  # J H^-1 (H symmetric)
    w_d = np.sqrt(np.linalg.det(K @ np.swapaxes(K, -1, -2)))
    return (singular[..., -1] / singular[..., 0]).mean(axis=0), w_d.mean(axis=0)  # (k,), (k,)


def test_per_tip_objectives_equal_direct_means_of_manipulability(small_tree_file):
    """w_avg of tip i is the mean of sa.manipulability(robot, q)[..., i] over the problem's
    fixed QMC points; low_disturbance the mean ||C_w||_F over every joint; low_total_mass
    minus the bus and both arms."""
    problem = sa.load_problem(_problem_config(small_tree_file))
    assert problem.objectives == ("w_avg[left/tool]", "w_avg[right/tool]", "low_disturbance", "low_total_mass")
    x = np.array([0.25, 0.3])
    values = np.asarray(jax.jit(problem.objective_function())(x))
    robot = problem.robot(jnp.asarray(x))
    w, disturbance = _direct_means(robot, 256, 8, 3)
    assert w.shape == (2,) and abs(w[0] - w[1]) > 1e-3 * w[0]  # two different tips
    np.testing.assert_allclose(values[:3], [w[0], w[1], -disturbance], rtol=1e-12)
    total = 100.0 + float(np.sum(robot.root_mass) + np.sum(robot.link_mass))
    assert values[3] == pytest.approx(-total, rel=1e-15)
    # The tips by index give the same objectives (another program: XLA may fuse it
    # differently, 7e-18 apart on jaxlib 0.9.2; the two tips differ by over 1e-3).
    by_index = _problem_config(small_tree_file, objectives=[{"name": "w_avg", "tip": 0}, "w_avg[1]"])
    np.testing.assert_allclose(jax.jit(sa.load_problem(by_index).objective_function())(x), values[:2], rtol=1e-13)


def test_per_tip_objective_gradient_matches_finite_differences(small_tree_file):
    """The reverse-mode Jacobian of the per-tip and whole-system objectives against central
    differences (about 10 s: a reverse-mode program and eager objective calls)."""
    problem = sa.load_problem(_problem_config(small_tree_file))
    f = problem.objective_function()
    x = np.array([0.1, -0.2])
    jacobian = np.asarray(jax.jit(jax.jacrev(f))(x))
    step = 1e-6
    for j in range(2):
        e = np.eye(2)[j] * step
        central = (np.asarray(f(x + e)) - np.asarray(f(x - e))) / (2 * step)
        np.testing.assert_allclose(jacobian[:, j], central, rtol=1e-5, atol=1e-10)
    assert np.all(jacobian[:2] != 0)  # the right arm's mount moves both tips' w*


def test_per_tip_sweep_metrics_share_one_pass_and_name_their_tips(small_tree_file):
    """A sweep's per-tip columns equal the direct means on a fixed rule (min = max samples)."""
    options = {"randomizations": 8, "block": 32, "min_samples": 256, "max_samples": 256, "seed": 3}
    spec = load_sweep(
        {
            "name": "t",
            "robot": str(small_tree_file),
            "axes": {"x": {"field": "arms.right.mount.xyz[0]", "values": [0.25]}},
            "metrics": [
                {"name": "w_avg", "tip": 1, **options},
                {"name": "w_avg", "tip": "left/tool", **options},
                {"name": "base_disturbance", **options},
                {"name": "gci", "tip": "right/tool", **options},
                {"name": "dynamic_manipulability", "tip": "left/tool", **options},
            ],
        }
    )
    columns = ["w_avg_m3[right/tool]", "w_avg_m3[left/tool]", "C_w_avg", "gci[right/tool]", "w_d_avg[left/tool]"]
    assert metric_columns(spec.metrics)[::3] == columns  # each: value, error, samples
    robot, _ = build_designs(spec)
    single = jax.tree_util.tree_map(lambda leaf: leaf[0], robot)
    values = jax.jit(design_function(spec.metrics))(single)
    w, disturbance = _direct_means(single, 256, 8, 3)
    gci, w_d = _direct_gci_and_wd(single, 256, 8, 3)
    expected = [w[1], w[0], disturbance, gci[1], w_d[0]]
    np.testing.assert_allclose([values[c] for c in columns], expected, rtol=1e-12)


def test_posture_metric_of_one_tip(small_tree_file):
    """The posture metric of a tip: w* of that tip, 1/kappa of its J*_v rows over every joint
    (NumPy singular values) and the whole system's ||C_w||_F at q_deg."""
    q_deg = [10.0, -40.0, 70.0, 25.0, 50.0, -30.0]
    spec = load_sweep(
        {
            "name": "t",
            "robot": str(small_tree_file),
            "axes": {"x": {"field": "base.mass", "values": [100.0]}},
            "metrics": [{"name": "posture", "tip": 1, "q_deg": q_deg}, {"name": "posture", "tip": 0, "q_deg": q_deg}],
        }
    )
    columns = ["w_star_m3[right/tool]", "inverse_condition[right/tool]", "C_w_fro", "w_star_m3[left/tool]"]
    assert metric_columns(spec.metrics)[:4] == columns
    robot = jax.tree_util.tree_map(lambda leaf: leaf[0], build_designs(spec)[0])
    values = jax.jit(design_function(spec.metrics))(robot)
    q = np.radians(q_deg)
    J = np.asarray(sa.generalized_jacobian(robot, q))[:, :3, :]
    singular = np.linalg.svd(J, compute_uv=False)
    expected = [
        np.sqrt(np.linalg.det(J[1] @ J[1].T)),
        singular[1, -1] / singular[1, 0],
        np.linalg.norm(np.asarray(sa.base_rate_matrix(robot, q))[3:]),
        np.sqrt(np.linalg.det(J[0] @ J[0].T)),
    ]
    np.testing.assert_allclose([values[c] for c in columns], expected, rtol=1e-11)
    assert values["inverse_condition[left/tool]"] == pytest.approx(singular[0, -1] / singular[0, 0], rel=1e-11)


@pytest.mark.parametrize(
    ("metrics", "message"),
    [
        (["w_avg"], "w_avg is per tip and the robot has 2 (left/tool, right/tool)"),
        ([{"name": "w_avg", "tip": "left/tol"}], "unknown tip 'left/tol' (did you mean 'left/tool'?)"),
        ([{"name": "w_avg", "tip": 2}], "index 2 out of range"),
        ([{"name": "base_disturbance", "tip": 0}], "takes no tip"),
        (["posture"], "posture is per tip and the robot has 2"),
        ([{"name": "w_avg", "tip": 0}, {"name": "w_avg", "tip": "left/tool"}], "listed twice for tip left/tool"),
    ],
)
def test_bad_tips_are_refused(small_tree_file, metrics, message):
    with pytest.raises(ConfigError) as error:
        load_sweep(
            {
                "name": "t",
                "robot": str(small_tree_file),
                "axes": {"x": {"field": "base.mass", "values": [100.0]}},
                "metrics": metrics,
            }
        )
    assert message in str(error.value)


def test_cli_sweep_optimize_and_bad_fields_on_a_tree(tmp_path, small_tree_file, capsys, monkeypatch):
    """The command line, from the files' folder: a 2-design sweep and a 2-variable optimize
    (population 4, one generation) of a two-arm tree, and a bad field in each file (exit 2,
    the file and the field named, nothing written). About 30 s cold: a sweep program and the
    search's value and value-and-gradient programs."""
    sweep = {
        "name": "two-small-sweep",
        "robot": str(small_tree_file),
        "axes": {"z": {"field": "arms.right.mount.xyz[2]", "values": [0.2, 0.4]}},
        "metrics": [
            {"name": "w_avg", "tip": "right/tool", "min_samples": 256, "max_samples": 256, "block": 32},
            {"name": "base_disturbance", "min_samples": 256, "max_samples": 256, "block": 32},
        ],
    }
    (tmp_path / "sweep.yaml").write_text(yaml.safe_dump(sweep))
    (tmp_path / "problem.yaml").write_text(yaml.safe_dump(_problem_config(small_tree_file), sort_keys=False))
    bad_sweep = {**sweep, "axes": {"z": {"field": "arms.rigth.mount.xyz[2]", "values": [0.2]}}}
    (tmp_path / "bad-sweep.yaml").write_text(yaml.safe_dump(bad_sweep))
    bad_problem = _problem_config(small_tree_file, variables={"links.left/forarm.mass": [1.0, 2.0]})
    (tmp_path / "bad-problem.yaml").write_text(yaml.safe_dump(bad_problem))
    monkeypatch.chdir(tmp_path)
    codes = [
        main(["sweep", "sweep.yaml", "--out", "sweep-out"]),
        main(["optimize", "problem.yaml", "--out", "opt-out", "--no-baselines"]),
        main(["sweep", "bad-sweep.yaml", "--out", "bad1"]),
        main(["optimize", "bad-problem.yaml", "--out", "bad2"]),
    ]
    run = capsys.readouterr()
    assert codes == [0, 0, 2, 2], run.out + run.err
    assert (
        "bad-sweep.yaml: axes.z.field: arms.rigth.mount.xyz[2]: unknown arm 'rigth' (did you mean 'right'?)" in run.err
    )
    assert (
        "bad-problem.yaml: variables.links.left/forarm.mass.field: links.left/forarm.mass: unknown link 'left/forarm' "
        "(did you mean 'left/forearm'?)" in run.err
    )
    assert not (tmp_path / "bad1").exists() and not (tmp_path / "bad2").exists()
    table = read_csv(tmp_path / "sweep-out" / "table.csv")
    assert list(table) == [
        "design",
        "z",
        "right_mount_z_m",
        "w_avg_m3[right/tool]",
        "w_avg_m3[right/tool]_error",
        "w_avg_m3[right/tool]_samples",
        "C_w_avg",
        "C_w_avg_error",
        "C_w_avg_samples",
    ]
    assert np.all(np.asarray(table["w_avg_m3[right/tool]"]) > 0)
    # The resolved config is itself a sweep file: the arms' URDF paths work from here too.
    config = json.loads((tmp_path / "sweep-out" / "manifest.json").read_text())["config"]
    assert config["metrics"][0]["tip"] == "right/tool"
    assert load_sweep(config).robot.tip_names == ("left/tool", "right/tool")
    with open(tmp_path / "opt-out" / "pareto.csv") as handle:
        header, *rows = list(csv.reader(handle))
    front = np.array(rows, dtype=float)
    problem = sa.load_problem(tmp_path / "problem.yaml")
    np.testing.assert_allclose(problem.batch_function()(front[:, :2]), front[:, 2:], rtol=1e-12)
    assert header == [
        "arms.right.mount.xyz[0]",
        "arms.right.mount.rpy[1]",
        "w_avg[left/tool]",
        "w_avg[right/tool]",
        "low_disturbance",
        "low_total_mass",
    ]


def test_shipped_tree_examples_validate():
    """The two-UR5 servicer's sweep and Pareto problem (needs example-robot-data)."""
    assert validate_file("sweeps/dual-ur5-mount.yaml")[0] == "sweep"
    spec = load_sweep("sweeps/dual-ur5-mount.yaml")
    assert metric_columns(spec.metrics)[::3] == ["w_avg_m3[left/tool0]", "w_avg_m3[right/tool0]", "C_w_avg"]
    problem = sa.load_problem("sweeps/pareto-dual-ur5.yaml")
    assert problem.objectives == ("w_avg[left/tool0]", "w_avg[right/tool0]", "low_disturbance")
    assert problem.variable_names == ("arms.right.mount.xyz[0]", "arms.right.mount.xyz[2]", "arms.right.mount.rpy[1]")
    assert problem.reference_point is None
    config = yaml.safe_load(Path("sweeps/pareto-dual-ur5.yaml").read_text())
    del config["objectives"]  # the default on several arms: each tip's w_avg and the disturbance
    default = sa.load_problem(config, base_dir="sweeps")
    assert default.objectives == problem.objectives


def test_fields_of_a_whole_system_urdf():
    """configs/three-arm-servicer.yaml (one root, a turret carrying two arms, prismatic joints):
    the system's length factor scales the prismatic limits only; the turret's length factor
    scales both joints hanging from it and nothing else; a link mass keeps the radius of gyration."""
    robot = sa.load_robot("configs/three-arm-servicer.yaml")
    assert tree_fields.arm_names(robot) == ("Servicer_Bus",)
    scaled = tree_fields.set_field(robot, "arms.Servicer_Bus.length", 1.5)
    prismatic = np.array([kind == "prismatic" for kind in robot.joint_kinds])
    np.testing.assert_array_equal(scaled.joint_upper[prismatic], 1.5 * robot.joint_upper[prismatic])
    np.testing.assert_array_equal(scaled.joint_upper[~prismatic], robot.joint_upper[~prismatic])
    np.testing.assert_array_equal(scaled.joint_translation, 1.5 * robot.joint_translation)
    np.testing.assert_array_equal(scaled.mount_xyz, robot.mount_xyz)
    turret = tree_fields.set_field(robot, "links.Turret.length", 2.0)
    moved = np.flatnonzero(np.any(turret.joint_translation != robot.joint_translation, axis=-1))
    assert [robot.joint_names[j] for j in moved] == ["Right_Shoulder", "Boom_Deploy"]
    np.testing.assert_array_equal(turret.joint_translation[moved], 2.0 * robot.joint_translation[moved])
    assert _changed(robot, turret) == {"joint_translation", "link_com", "link_inertia"}
    heavy = tree_fields.set_field(robot, "links.Boom_Arm.mass", 2 * float(robot.link_mass[8]))
    np.testing.assert_allclose(heavy.link_inertia[8], 2 * robot.link_inertia[8], rtol=1e-15)
    with pytest.raises(ConfigError, match="link 'Boom_EE' is merged into body 'Boom_Tool'"):
        tree_fields.check_field("f.yaml: axes.a", "links.Boom_EE.mass", robot)


def test_whole_system_problem_with_a_shared_turret_and_prismatic_joints():
    """configs/three-arm-servicer.yaml: two tips share the turret joint, two joints are
    prismatic, three continuous; the per-tip objectives are still the direct means.
    About 20 s cold: it compiles the objective program of a 10-joint tree."""
    config = {
        "name": "three-arm",
        "robot": "../configs/three-arm-servicer.yaml",
        "variables": {"links.Turret.length": [0.8, 1.2], "base.mass": [400.0, 900.0]},
        "objectives": ["w_avg[Right_EE]", {"name": "w_avg", "tip": "Boom_EE"}, "low_disturbance"],
        "average": {"samples": 128, "randomizations": 8, "seed": 1},
    }
    problem = sa.load_problem(config, base_dir="sweeps")
    x = np.array([1.1, 500.0])
    values = np.asarray(jax.jit(problem.objective_function())(x))
    robot = problem.robot(jnp.asarray(x))
    w, disturbance = _direct_means(robot, 128, 8, 1)
    np.testing.assert_allclose(values, [w[1], w[2], -disturbance], rtol=1e-12)
