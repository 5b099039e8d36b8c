"""The robot description: YAML loading, validation messages, the CLI's validate."""

import copy
import subprocess
import sys

import jax
import numpy as np
import pytest
import yaml

import spacearm as sa
from spacearm.cli import main

TABLE1 = {
    "name": "umetani1990",
    "base": {"mass": 1000.0, "inertia": 635.3, "attach": 1.4},
    "links": [
        {"mass": 100.0, "inertia": 33.3, "a": 1.0, "b": 1.0},
        {"mass": 100.0, "inertia": 33.3, "a": 1.0, "b": 1.0},
    ],
}


def test_config_file_is_table1():
    robot = sa.load_robot("configs/umetani1990.yaml")
    assert robot.name == "umetani1990"
    assert robot.n_links == 2
    np.testing.assert_array_equal(robot.link_length, [2.0, 2.0])
    assert float(robot.base_mass) == 1000.0 and float(robot.base_inertia) == 635.3
    assert float(robot.base_attach) == 1.4 and float(robot.reach) == 4.0
    assert np.all(np.isinf(robot.joint_lower)) and np.all(np.isinf(robot.joint_upper))


def test_mapping_and_path_agree(tmp_path):
    path = tmp_path / "r.yaml"
    path.write_text(yaml.safe_dump(TABLE1))
    a, b = sa.load_robot(path), sa.load_robot(TABLE1)
    for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=False):
        np.testing.assert_array_equal(x, y)


def _broken(edit):
    config = copy.deepcopy(TABLE1)
    edit(config)
    return config


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda c: c["links"][1].update(mass=-3.0), r"links\[1\]\.mass: must be positive"),
        (lambda c: c["links"][0].update(inertia=0.0), r"links\[0\]\.inertia: must be positive"),
        (lambda c: c["links"][0].update(a=-1.0), r"links\[0\]\.a: must not be negative"),
        (lambda c: c["links"][1].update(b=-0.5), r"links\[1\]\.b: must not be negative"),
        (lambda c: c["base"].update(mass=float("nan")), r"base\.mass: must be a finite number"),
        (lambda c: c["base"].update(attach=float("inf")), r"base\.attach: must be a finite number"),
        (lambda c: c["base"].update(attach=-1.0), r"base\.attach: must not be negative"),
        (lambda c: c["links"].pop(), r"links: 2 to 16 links are supported, got 1"),
        (lambda c: c["links"][0].update(mas=1.0), r"links\[0\]: unknown key 'mas' \(did you mean 'mass'\?\)"),
        (lambda c: c.update(bsae={}), r"unknown key 'bsae' \(did you mean 'base'\?\)"),
        (lambda c: c["links"][0].pop("b"), r"links\[0\]\.b: missing required key"),
        (lambda c: c.pop("base"), r"base: missing required key"),
        (lambda c: c["links"][0].update(mass="heavy"), r"links\[0\]\.mass: must be a number, got str"),
        (lambda c: c["links"][0].update(mass=True), r"links\[0\]\.mass: must be a number, got bool"),
        (lambda c: c.update(links={"a": 1}), r"links: must be a list"),
        (lambda c: c["links"][0].update(a=0.0, b=0.0), r"links\[0\]: the length a \+ b must be positive"),
        (lambda c: c["links"][0].update(limit_deg=[90, -90]), r"links\[0\]\.limit_deg: the lower limit"),
        (lambda c: c["links"][0].update(limit_deg=[1]), r"links\[0\]\.limit_deg: must be a list"),
    ],
)
def test_invalid_mapping_names_field(edit, message):
    with pytest.raises(sa.ConfigError, match=message):
        sa.load_robot(_broken(edit))


def test_constructor_validates():
    robot = sa.umetani1990()
    with pytest.raises(sa.ConfigError, match=r"links\[1\]\.mass: must be positive"):
        robot.replace(link_mass=np.array([100.0, -1.0]))


def test_joint_limits_in_degrees():
    config = _broken(lambda c: c["links"][1].update(limit_deg=[-150, 150]))
    robot = sa.load_robot(config)
    np.testing.assert_allclose(robot.joint_lower, [-np.inf, -150 * np.pi / 180])
    np.testing.assert_allclose(robot.joint_upper, [np.inf, 150 * np.pi / 180])


def test_malformed_and_missing_files(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("base: [1, 2\n")
    with pytest.raises(sa.ConfigError, match="malformed YAML"):
        sa.load_robot(bad)
    with pytest.raises(sa.ConfigError, match="no such robot file"):
        sa.load_robot(tmp_path / "missing.yaml")


def test_batched_designs_are_the_same_pytree(table1):
    batch = sa.stack_robots([table1, table1.replace(base_attach=np.float64(0.0))])
    assert batch.batch_shape == (2,)
    assert batch.n_links == 2
    K = jax.vmap(sa.tip_coefficients)(batch)
    np.testing.assert_allclose(K[1, 0], 0.0)


def test_cli_validate_ok_and_invalid(tmp_path, capsys):
    assert main(["validate", "configs/umetani1990.yaml"]) == 0
    assert "valid robot" in capsys.readouterr().out
    bad = tmp_path / "neg.yaml"
    bad.write_text(yaml.safe_dump(_broken(lambda c: c["links"][1].update(mass=-3.0))))
    assert main(["validate", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "links[1].mass: must be positive" in err and "Traceback" not in err


def test_console_script_exit_status(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("links: [1, 2\n")
    proc = subprocess.run([sys.executable, "-m", "spacearm.cli", "validate", str(bad)], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "malformed YAML" in proc.stderr and "Traceback" not in proc.stderr


def test_fast_validity_check_agrees_with_the_detailed_one(table1):
    """robot._looks_valid (one vectorized pass) accepts exactly the designs the named checks accept."""
    from spacearm.models.planar.robot import _check_fields, _looks_valid

    rng = np.random.default_rng(3)
    fields = [
        "base_mass",
        "base_inertia",
        "base_attach",
        "link_mass",
        "link_inertia",
        "link_a",
        "link_b",
        "joint_lower",
        "joint_upper",
    ]
    bad_values = [0.0, -1.0, np.nan, np.inf, -np.inf, 1e-300, 5.0]
    seen = {True: 0, False: 0}
    for _ in range(400):
        leaves = {f: np.array(getattr(table1, f), dtype=float) for f in fields}
        for _ in range(rng.integers(1, 3)):
            field = rng.choice(fields)
            value = leaves[field]
            index = () if value.ndim == 0 else (rng.integers(value.size),)
            value[index] = rng.choice(bad_values)
        robot = object.__new__(sa.PlanarRobot)  # unvalidated, as _unflatten builds them
        for f in fields:
            object.__setattr__(robot, f, leaves[f])
        object.__setattr__(robot, "name", "corrupted")
        try:
            _check_fields(robot)
            valid = True
        except sa.ConfigError:
            valid = False
        assert _looks_valid(robot) == valid, leaves
        seen[valid] += 1
    assert min(seen.values()) > 20  # both outcomes exercised


def test_console_script_uses_every_cpu_core_unless_told_otherwise(monkeypatch):
    from spacearm._core.numeric import use_every_cpu_core

    monkeypatch.setenv("XLA_FLAGS", "--xla_cpu_use_thunk_runtime=true")
    count = use_every_cpu_core()
    import os

    if count > 1:
        assert (
            os.environ["XLA_FLAGS"]
            == f"--xla_cpu_use_thunk_runtime=true --xla_force_host_platform_device_count={count}"
        )
    monkeypatch.setenv("XLA_FLAGS", "--xla_force_host_platform_device_count=3")
    assert use_every_cpu_core() == 0 and os.environ["XLA_FLAGS"] == "--xla_force_host_platform_device_count=3"
    code = (
        "import jax; from spacearm.cli import console_main; import sys; sys.argv = ['spacearm', 'info']; console_main()"
    )
    monkeypatch.delenv("XLA_FLAGS")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout
    assert f"device_count {max(1, len(os.sched_getaffinity(0)))}" in out
