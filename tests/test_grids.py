"""A sweep's grids as one labelled xarray Dataset (spacearm.open_results)."""

from pathlib import Path

import numpy as np
import pytest

import spacearm as sa
from spacearm.io import read_csv
from spacearm.studies import load_sweep, run_sweep

xr = pytest.importorskip("xarray")

ROBOT = str(Path("configs/umetani1990.yaml").resolve())


def run(tmp_path, **changes):
    config = {"name": "grid", "robot": ROBOT, "metrics": ["S_M", "S_G"], "chunk_size": 4}
    config.update(changes)
    out = tmp_path / "out"
    run_sweep(load_sweep(config), out, progress=False)
    return out


def test_product_sweep_opens_with_one_dimension_per_axis(tmp_path):
    axes = {
        "b0": {"field": "base.attach", "values": [0.0, 0.7, 1.4]},
        "m0": {"field": "base.mass", "values": [500.0, 1000.0]},
    }
    out = run(tmp_path, axes=axes)
    data = sa.open_results(out)
    assert isinstance(data, xr.Dataset)
    assert data["S_M"].dims == ("b0", "m0") and data["S_M"].shape == (3, 2)
    np.testing.assert_array_equal(data["b0"], [0.0, 0.7, 1.4])
    np.testing.assert_array_equal(data["m0"], [500.0, 1000.0])
    # Values are those of the table, row i = C-order index over (b0, m0).
    table = read_csv(out / "table.csv")
    np.testing.assert_array_equal(data["S_G"].values.ravel(), table["S_G"])
    point = data["S_M"].sel(b0=1.4, m0=500.0).item()
    robot = sa.umetani1990().replace(base_attach=np.float64(1.4), base_mass=np.float64(500.0))
    np.testing.assert_allclose(point, float(sa.normalized_areas(robot)[0]), rtol=1e-14)
    # Design numbers from the table ride along as coordinates; the axis fields as attributes.
    np.testing.assert_array_equal(data["base_attach_m"].values.ravel(), table["base_attach_m"])
    assert data["b0"].attrs["field"] == "base.attach" and data["b0"].attrs["relative"] == 0
    assert data.attrs["name"] == "grid" and len(data.attrs["config_sha256"]) == 64


def test_zipped_sweep_opens_along_design(tmp_path):
    axes = {
        "m0": {"field": "base.mass", "values": [500.0, 900.0]},
        "b0": {"field": "base.attach", "relative": True, "values": [0.5, 1.5]},
    }
    data = sa.open_results(run(tmp_path, axes=axes, combine="zip"))
    assert data["S_M"].dims == ("design",)
    np.testing.assert_array_equal(data["m0"], [500.0, 900.0])
    assert data["b0"].dims == ("design",) and data["b0"].attrs["relative"] == 1


def test_a_folder_without_grids_is_refused(tmp_path):
    with pytest.raises(sa.ConfigError, match=r"no grids.npz"):
        sa.open_results(tmp_path)
