"""Results that cannot be trusted are never written: a non-finite metric is an error naming
the metric and the design (exit 1), and a disk that fills up while writing leaves the old
results folder whole (exit 1, one line)."""

import errno
import json
from pathlib import Path

import jax.numpy as jnp
import yaml

from spacearm.cli import main
from spacearm.studies import runner

ROBOT = str(Path("configs/umetani1990.yaml").resolve())


def write_sweep(tmp_path, metrics=("radii",)):
    path = tmp_path / "sweep.yaml"
    path.write_text(
        yaml.safe_dump(
            {
                "name": "results",
                "robot": ROBOT,
                "axes": {"b0": {"field": "base.attach", "values": [0.0, 1.0, 2.0]}},
                "metrics": list(metrics),
                "chunk_size": 4,
            }
        )
    )
    return path


def test_a_non_finite_metric_is_an_error_naming_metric_and_design(tmp_path, monkeypatch, capsys, request):
    """Before: NaN columns written with exit 0 (--float32 with a 1e300 kg bus; such numbers
    are now refused when read, so the NaN is injected into one design here)."""
    # The chunk programs are cached per process: build this one from the patched metrics,
    # and keep it from the tests that follow.
    runner._evaluator.cache_clear()
    request.addfinalizer(runner._evaluator.cache_clear)
    real = runner.design_function

    def with_a_nan(metrics):
        evaluate = real(metrics)

        def patched(robot):
            values = evaluate(robot)
            values["R_max_m"] = jnp.where(robot.base_attach > 1.5, jnp.nan, values["R_max_m"])
            return values

        return patched

    # The runner memoizes its compiled evaluator by metrics: start and end with an empty
    # memo, so the injected NaN reaches this run and no later test.
    runner._evaluator.cache_clear()
    monkeypatch.setattr(runner, "design_function", with_a_nan)
    out = tmp_path / "out"
    try:
        code = main(["sweep", str(write_sweep(tmp_path)), "--out", str(out), "--quiet"])
    finally:
        runner._evaluator.cache_clear()
    err = capsys.readouterr().err
    assert code == 1, err
    line = err.strip().splitlines()[-1]
    assert "metric column 'R_max_m' is nan for design 2 (b0 = 2)" in line and "nothing was written" in line
    assert "Traceback" not in err
    assert not (out / "table.csv").exists()


def test_a_full_disk_while_writing_keeps_the_old_folder(tmp_path, monkeypatch, capsys):
    sweep = write_sweep(tmp_path)
    out = tmp_path / "out"
    assert main(["sweep", str(sweep), "--out", str(out), "--quiet"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    capsys.readouterr()

    real = runner.write_npz

    def full(path, **arrays):  # the chunks fit; the disk fills up while the results are staged
        if ".staging-" in str(path):
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return real(path, **arrays)

    monkeypatch.setattr(runner, "write_npz", full)
    sweep.write_text(sweep.read_text().replace("2.0", "3.0"))
    code = main(["sweep", str(sweep), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2, err  # the sweep command reports it as a problem with --out
    assert err.strip().splitlines()[-1].endswith("cannot write the results (No space left on device)")
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before
    assert json.loads((out / "manifest.json").read_text())["config"]["axes"]["b0"]["values"][-1] == 2.0
    assert not list(tmp_path.glob(".out.staging-*"))
