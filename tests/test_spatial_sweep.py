"""Sweeps and design problems over spatial robots: design fields, validation, a run."""

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import yaml

import spacearm as sa
from spacearm._core.errors import ConfigError
from spacearm.cli.validate import validate_file
from spacearm.design.problem import load_problem as load_design_problem
from spacearm.models.spatial import fields
from spacearm.studies import build_designs, load_sweep, run_sweep
from spacearm.studies.designs import design_columns

UR5 = str(Path("configs/ur5-smallsat.yaml").resolve())
ARM3 = str(Path("configs/arm3dof-100kg.yaml").resolve())


@pytest.fixture(scope="module")
def ur5():
    return sa.load_robot(UR5)


def sweep(axes, metrics=("posture",), robot=UR5, **changes):
    return {"name": "spatial", "robot": robot, "axes": axes, "metrics": list(metrics), **changes}


def test_arm_length_scales_geometry_and_inertias_consistently(ur5):
    spec = load_sweep(sweep({"s": {"field": "arm.length", "values": [0.5, 2.0]}}))
    robot, _ = build_designs(spec)
    s = np.array([0.5, 2.0])
    np.testing.assert_allclose(robot.joint_translation, s[:, None, None] * ur5.joint_translation, rtol=1e-15)
    np.testing.assert_allclose(robot.link_com, s[:, None, None] * ur5.link_com, rtol=1e-15)
    np.testing.assert_allclose(robot.tip_translation, s[:, None] * ur5.tip_translation, rtol=1e-15)
    np.testing.assert_allclose(robot.link_inertia, s[:, None, None, None] ** 2 * ur5.link_inertia, rtol=1e-15)
    np.testing.assert_allclose(robot.root_inertia, s[:, None, None] ** 2 * ur5.root_inertia, rtol=1e-15)
    np.testing.assert_allclose(robot.link_mass, np.broadcast_to(ur5.link_mass, (2, 6)), rtol=0)  # masses kept
    np.testing.assert_allclose(robot.mount_xyz, np.broadcast_to(ur5.mount_xyz, (2, 3)), rtol=0)  # the bus's
    np.testing.assert_allclose(fields.path_length(robot), s * fields.path_length(ur5), rtol=1e-14)


def test_masses_mount_and_bus_fields(ur5):
    spec = load_sweep(
        sweep(
            {
                "ratio": {"field": "arm.mass_ratio", "values": [0.02, 0.1]},
                "x": {"field": "mount.xyz[0]", "values": [-0.3]},
                "pitch": {"field": "mount.rpy_deg[1]", "values": [30.0]},
                "m0": {"field": "base.mass", "values": [800.0]},
                "I0": {"field": "base.inertia", "values": [2.0]},
            }
        )
    )
    robot, points = build_designs(spec)
    np.testing.assert_allclose(fields.arm_mass(robot) / robot.base_mass, points["ratio"], rtol=1e-14)
    np.testing.assert_allclose(robot.mount_xyz[:, 0], -0.3, rtol=0)
    np.testing.assert_allclose(robot.mount_rpy[:, 1], np.radians(30.0), rtol=1e-15)
    np.testing.assert_allclose(robot.mount_rpy[:, [0, 2]], np.broadcast_to(ur5.mount_rpy[[0, 2]], (2, 2)), rtol=0)
    np.testing.assert_allclose(robot.base_inertia, 2.0 * np.broadcast_to(ur5.base_inertia, (2, 3, 3)), rtol=0)
    factor = fields.arm_mass(robot) / fields.arm_mass(ur5)  # every mass and inertia scaled alike
    np.testing.assert_allclose(robot.link_inertia, factor[:, None, None, None] * ur5.link_inertia, rtol=1e-14)
    columns = design_columns(robot, spec.axes)
    assert {
        "arm_mass_kg",
        "arm_over_base",
        "mount_x_m",
        "mount_pitch_rad",
        "base_mass_kg",
        "base_inertia_trace_kg_m2",
    } <= set(columns)

    spec = load_sweep(
        sweep(
            {
                "wrist": {"field": "links.wrist_3_link.mass", "values": [1.0, 2.0]},
                "root": {"field": "links.base_link.mass", "relative": True, "values": [3.0]},
            }
        )
    )
    robot, _ = build_designs(spec)
    np.testing.assert_allclose(robot.link_mass[:, 5], [1.0, 2.0], rtol=0)
    np.testing.assert_allclose(
        robot.link_inertia[:, 5],
        np.array([1.0, 2.0])[:, None, None] * ur5.link_inertia[5] / ur5.link_mass[5],
        rtol=1e-14,
    )  # radius of gyration kept
    np.testing.assert_allclose(robot.root_mass, 3.0 * ur5.root_mass, rtol=1e-15)
    assert "wrist_3_link_mass_kg" in design_columns(robot, spec.axes)


def test_fields_are_differentiable(ur5):
    single = jax.tree_util.tree_map(jnp.asarray, ur5)
    mass = jax.grad(lambda v: fields.arm_mass(fields.set_field(single, "arm.mass", v)))(2.0)
    np.testing.assert_allclose(mass, float(fields.arm_mass(ur5)), rtol=1e-14)
    slope = jax.grad(lambda v: fields.set_field(single, "mount.rpy_deg[2]", v).mount_rpy[2])(10.0)
    np.testing.assert_allclose(slope, np.pi / 180.0, rtol=1e-15)


@pytest.mark.parametrize(
    "axes, metrics, message",
    [
        ({"a": {"field": "links.wrist3_link.mass", "values": [1.0]}}, ["posture"], "did you mean 'wrist_3_link'"),
        ({"a": {"field": "links.tool0.mass", "values": [1.0]}}, ["posture"], "merged into body 'wrist_3_link'"),
        ({"a": {"field": "mount.xyz[3]", "values": [1.0]}}, ["posture"], "index 3 of mount.xyz out of range"),
        ({"a": {"field": "mount.xzy[0]", "values": [1.0]}}, ["posture"], "did you mean 'mount.xyz[0]'"),
        ({"a": {"field": "base.attach", "values": [1.0]}}, ["posture"], "unknown design field 'base.attach'"),
        (
            {"a": {"field": "arm.mass", "values": [1.0]}, "b": {"field": "links.base_link.mass", "values": [2.0]}},
            ["posture"],
            "both set",
        ),
        ({"a": {"field": "arm.mass", "values": [1.0]}}, ["wbar"], "'wbar' is a metric of planar robots"),
        ({"a": {"field": "arm.mass", "values": [1.0]}}, [{"name": "w_avg", "block": 100}], "power of two"),
        ({"a": {"field": "arm.mass", "values": [1.0]}}, [{"name": "posture", "q_deg": [0, 0]}], "needs 6 joint"),
        ({"a": {"field": "base.mass", "values": [-1.0]}}, ["posture"], "sweep point 0"),
        ({"a": {"field": "arm.mass", "values": [1.0]}}, [{"name": "reach_radii", "starts": 0}], "starts"),
        (
            {"a": {"field": "arm.mass", "values": [1.0]}},
            [{"name": "path_independent_radius", "sample": 64}],
            "did you mean 'samples'",
        ),
    ],
)
def test_bad_spatial_sweeps_are_refused(tmp_path, axes, metrics, message):
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(sweep(axes, metrics)))
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]").replace("(", r"\(")):
        validate_file(path)


def test_example_files_validate():
    assert validate_file("sweeps/ets7-mount.yaml")[0] == "sweep"
    assert validate_file("sweeps/ur5-mass-ratio.yaml")[0] == "sweep"
    kind, summary = validate_file("sweeps/pareto-mount-ur5.yaml")
    assert kind == "design problem" and "mount.rpy[1]" in summary
    problem = load_design_problem("sweeps/pareto-mount-ur5.yaml")
    assert problem.objectives == ("w_avg", "gci", "low_disturbance")


def test_spatial_sweep_runs_in_chunks(tmp_path):
    spec = load_sweep(
        sweep(
            {
                "x": {"field": "mount.xyz[0]", "values": [0.0, 0.2, 0.4]},
                "s": {"field": "arm.length", "values": [1.0, 1.5]},
            },
            robot=ARM3,
            chunk_size=4,
        )
    )
    result = run_sweep(spec, tmp_path / "out", progress=False)
    table = result.table
    assert list(table["mount_x_m"]) == [0.0, 0.0, 0.2, 0.2, 0.4, 0.4]
    assert np.all(np.isfinite(table["w_star_m3"])) and np.all(table["w_star_m3"] > 0)
    # the row of (x = 0.2, s = 1) is the robot file's design with its mount moved, evaluated directly
    moved = sa.load_robot(ARM3)
    moved = moved.replace(mount_xyz=np.array([0.2, *np.asarray(moved.mount_xyz)[1:]]))
    direct = sa.manipulability(moved, jnp.radians(jnp.full(3, 30.0)))
    np.testing.assert_allclose(table["w_star_m3"][2], direct, rtol=1e-12)
    assert not np.allclose(table["w_star_m3"][3], table["w_star_m3"][2], rtol=1e-3)  # arm.length changes w*
    manifest = result.manifest
    assert manifest["n_designs"] == 6 and manifest["config"]["robot"]["arm"]["urdf"].endswith("arm3dof.urdf")
