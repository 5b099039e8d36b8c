"""A sweep's grids as one labelled xarray Dataset (xarray is the optional extra ``xarray``).

A sweep writes ``grids.npz`` (``axis/<name>``: the axis values, ``metric/<column>``: one
array per metric column, shaped like the grid, ``dims``: the axis names of a product
sweep or ``["design"]`` for a zipped one), ``table.csv`` (one row per design) and
``manifest.json``; :func:`open_results` reads them back as a Dataset whose dimensions
are the sweep axes.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from .._core.errors import ConfigError
from .files import read_csv

__all__ = ["open_results"]


def open_results(folder: str | os.PathLike) -> Any:
    """Open a sweep's results folder as an ``xarray.Dataset``.

    Product sweeps: one dimension per axis, with the axis values as coordinates. Zipped
    sweeps: one dimension ``design``, each axis a coordinate along it. Every metric
    column is a data variable; the design numbers of ``table.csv`` that are not axes
    (``base_attach_m``, ``l1_m``, ...) are coordinates on the same dimensions. The
    attributes hold the sweep name, the config hash and each axis's field and whether
    it is relative to the base design.

    Raises:
        ConfigError: when ``folder`` holds no ``grids.npz``.
        ModuleNotFoundError: without xarray (``pip install 'spacearm[xarray]'``).
    """
    try:  # the optional extra "xarray": imported when a folder is opened
        import xarray as xr  # noqa: PLC0415
    except ModuleNotFoundError as error:
        raise ModuleNotFoundError(
            "open_results needs xarray: pip install 'spacearm[xarray]'", name=error.name
        ) from None
    folder = Path(folder)
    grids_path = folder / "grids.npz"
    if not grids_path.is_file():
        raise ConfigError(f"{folder}: no grids.npz here; is it the output folder of a sweep?")
    with np.load(grids_path) as grids:
        arrays = {key: grids[key] for key in grids.files}
    dims = tuple(str(d) for d in arrays.pop("dims"))
    axes = {key.split("/", 1)[1]: value for key, value in arrays.items() if key.startswith("axis/")}
    metrics = {key.split("/", 1)[1]: value for key, value in arrays.items() if key.startswith("metric/")}
    shape = next(iter(metrics.values())).shape if metrics else tuple(len(axes[d]) for d in dims)

    if dims == ("design",):
        coords: dict[str, Any] = {"design": np.arange(shape[0])}
        coords.update({name: ("design", values) for name, values in axes.items()})
    else:
        coords = {name: axes[name] for name in dims}
    data = {name: (dims, values) for name, values in metrics.items()}

    table_path = folder / "table.csv"
    if table_path.is_file():
        table = read_csv(table_path)
        for name, column in table.items():
            if name == "design" or name in axes or name in metrics:
                continue
            values = np.asarray(column)
            if values.size == int(np.prod(shape)):
                coords[name] = (dims, values.reshape(shape))

    attrs: dict[str, Any] = {}
    manifest_path = folder / "manifest.json"
    if manifest_path.is_file():
        try:
            manifest = json.loads(manifest_path.read_text(encoding="utf-8"))
        except ValueError:
            manifest = {}
        config = manifest.get("config") if isinstance(manifest, dict) else None
        if isinstance(config, dict):
            attrs["name"] = config.get("name", folder.name)
            attrs["config_sha256"] = manifest.get("config_sha256", "")
        dataset_axes = config.get("axes", {}) if isinstance(config, dict) else {}
    else:
        dataset_axes = {}
    dataset = xr.Dataset(data, coords=coords, attrs=attrs)
    for name in axes:
        entry = dataset_axes.get(name) if isinstance(dataset_axes, dict) else None
        if isinstance(entry, dict):
            dataset[name].attrs.update(field=str(entry.get("field", "")), relative=int(bool(entry.get("relative"))))
    return dataset
