"""``shells.html``: a sweep's workspace shells about the system centroid, design by design.

Written for sweeps whose table holds a shell radius (``R_max_m`` and ``R_inner_m`` of the
``reach_radii`` metric, ``R_path_independent_m`` of ``path_independent_radius``): a slider
picks a design, the page draws its robot (joints at zero) and each radius as a sphere
about the system centroid. Every spatial workspace is such a shell, because a cyclic joint
motion turns the bus by any rotation about the centroid (Umetani & Yoshida 1990, sec. 3,
in 3-D; Papadopoulos & Dubowsky 1993 for the path-independent radius).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import jax
import numpy as np

from ...studies.designs import build_designs
from .model import view_model
from .page import view_extra_available, write_page

__all__ = ["MAX_DESIGNS", "SHELL_COLUMNS", "shells_view", "write_shells_view"]

MAX_DESIGNS = 200
# Table column -> (label, colour) of the sphere drawn for it.
SHELL_COLUMNS = {
    "R_max_m": ("Maximum Reachable (outer)", "#1f77b4"),
    "R_inner_m": ("Maximum Reachable (inner)", "#ff7f0e"),
    "R_path_independent_m": ("path-independent (closest dynamic singular tip)", "#2ca02c"),
}


def write_shells_view(path: str | Path, robots, radii: Mapping[str, np.ndarray], labels, *, title: str) -> Path:
    """Write the shells page.

    Args:
        path: the HTML file to write.
        robots: one robot per design (robots that move in 3-D: the shells are spheres).
        radii: column name of `SHELL_COLUMNS` -> ``(designs,)`` radius, m (inf or NaN: none drawn).
        labels: one line per design (its axis values).
        title: the page title.
    """
    designs, extents = [], []
    for k, robot in enumerate(robots):
        model = view_model(robot)
        extents.append(model["extent"])
        shells = []
        for column, values in radii.items():
            value = float(np.asarray(values)[k])
            name, colour = SHELL_COLUMNS[column]
            shells.append(
                dict(name=f"{name}: {value:.4g} m", radius=value if np.isfinite(value) else None, color=colour)
            )
        designs.append(
            dict(model=model, posture=np.zeros(model["posture"]["size"]), label=str(labels[k]), shells=shells)
        )
    extent = max(
        extents
        + [1.1 * float(np.nanmax(np.where(np.isfinite(v), v, np.nan))) for v in radii.values() if np.isfinite(v).any()]
    )
    note = (
        "Drag the design slider; each sphere is a workspace radius about the system centroid (the origin), "
        "the arm drawn with its joints at zero."
    )
    return write_page(
        path, title=title, note=note, data=dict(mode="shells", designs=designs, extent=extent, title=title)
    )


def shells_view(spec, out_dir: Path, table: Mapping[str, np.ndarray]) -> list[Path]:
    """``shells.html`` for a sweep with a shell column (a `spacearm.studies.runner.SweepOutput`)
    of a robot that moves in 3-D (its view model has no ``plane``: a planar arm's radii are disks,
    drawn in its own figures); nothing otherwise, or without the ``view`` extra. At most
    `MAX_DESIGNS` designs, evenly spaced."""
    columns = [c for c in SHELL_COLUMNS if c in table]
    if not columns or view_model(spec.robot)["plane"] is not None or not view_extra_available():
        return []
    robot, points = build_designs(spec)
    count = spec.n_designs
    picked = np.unique(np.linspace(0, count - 1, min(count, MAX_DESIGNS)).round().astype(int))
    robots = [jax.tree_util.tree_map(lambda leaf, k=k: np.asarray(leaf)[k], robot) for k in picked]
    labels = [", ".join(f"{name} = {values[k]:.4g}" for name, values in points.items()) for k in picked]
    radii = {c: np.asarray(table[c], float)[picked] for c in columns}
    return [
        write_shells_view(Path(out_dir) / "shells.html", robots, radii, labels, title=f"{spec.name}: workspace shells")
    ]
