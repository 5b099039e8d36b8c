"""Spatial workspace shells and w* maps on joint slices.

- ``spatial_shells``: for the example spatial robots, tips of joint-box postures (bus
  attitude fixed) in the meridian half-plane (rho = sqrt(x^2 + y^2), z) about the system
  centroid, the dynamic singular tips, and the shells: inner and outer reachable
  radii, the path-independent radius (Papadopoulos & Dubowsky) and the eq.-(8) analogue
  (kinematic singular set). Every workspace is a spherical shell because a cyclic joint
  motion turns the bus by any rotation about the centroid.
- ``spatial_wstar_slices``: w* (m^3) over a slice of two joints (the others at 0), with
  the dynamic singular curves (det J*_v = 0, or the smallest |s| cells for redundant arms).

Both compute in the precision the caller chose (``spacearm figures`` turns float64 on
unless ``--float32``): a figure changes no global JAX setting.
"""

from __future__ import annotations

from pathlib import Path

import jax.numpy as jnp
import numpy as np
from matplotlib.figure import Figure

from ..analysis.joint_box import joint_box
from ..analysis.workspace_search import guaranteed_workspace, singular_postures, singularity_measure
from ..io import save_figure
from ..kinematics import manipulability, tip_position
from ..models import load_robot
from . import figure

# (config file, label, slice joints) for the example robots.
ROBOTS = (
    ("configs/arm3dof-100kg.yaml", "3-DOF arm, 100 kg bus", (1, 2)),
    ("configs/ur5-smallsat.yaml", "UR5 on a 500 kg smallsat", (1, 2)),
)


def _config_path(name: str) -> Path:
    # Relative to the repository (the figures command runs from it), else to this file's checkout.
    here = Path(name)
    return here if here.exists() else Path(__file__).resolve().parents[3] / name


def _save(fig, path: Path) -> Path:
    return save_figure(fig, Path(path), dpi=130, bbox_inches="tight")


def _shell(ax, radius, **style):
    angle = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 181)
    ax.plot(radius * np.cos(angle), radius * np.sin(angle), **style)


@figure("spatial_shells")
def spatial_shells(out_dir: Path) -> list[Path]:
    fig = Figure(figsize=(11, 5), layout="constrained")
    axes = fig.subplots(1, len(ROBOTS))
    for ax, (config, label, _) in zip(np.atleast_1d(axes), ROBOTS, strict=False):
        robot = load_robot(_config_path(config))
        lower, upper = (np.asarray(x) for x in joint_box(robot))
        q = lower + (upper - lower) * np.random.default_rng(0).random((20000, robot.n_joints))
        tips = np.asarray(tip_position(robot, jnp.asarray(q)))
        rho = np.hypot(tips[:, 0], tips[:, 1])
        ax.scatter(rho, tips[:, 2], s=0.5, color="0.75", rasterized=True, label="tips over the joint box")
        singular = singular_postures(robot)
        on = np.asarray(singular.on_set)
        st = np.asarray(singular.tip)[on]
        ax.scatter(np.hypot(st[:, 0], st[:, 1]), st[:, 2], s=1.5, color="tab:red", label="dynamic singular tips")
        shells = guaranteed_workspace(robot)
        _shell(ax, float(shells.outer), color="k", lw=1.2, label=f"outer reach {float(shells.outer):.3f} m")
        _shell(ax, float(shells.inner), color="k", lw=1.0, ls=":", label=f"inner reach {float(shells.inner):.3f} m")
        empty = " (empty: equals the hole)" if bool(shells.empty) else ""
        _shell(ax, float(shells.path_independent), color="tab:blue", lw=1.5,
               label=f"path-independent {float(shells.path_independent):.3f} m{empty}")  # fmt: skip
        _shell(ax, float(shells.kinematic), color="tab:green", lw=1.2, ls="--",
               label=f"eq. (8) analogue {float(shells.kinematic):.3f} m")  # fmt: skip
        ax.set_aspect("equal")
        ax.set_xlabel("rho = sqrt(x^2 + y^2) about the system centroid [m]")
        ax.set_ylabel("z [m]")
        ax.set_title(label)
        ax.legend(fontsize=7, loc="lower left", markerscale=4)
    fig.suptitle("Workspace shells about the system centroid (bus attitude fixed for the tip cloud)")
    return [_save(fig, Path(out_dir) / "spatial_shells.png")]


@figure("spatial_wstar_slices")
def spatial_wstar_slices(out_dir: Path) -> list[Path]:
    fig = Figure(figsize=(12, 4.5), layout="constrained")
    axes = fig.subplots(1, len(ROBOTS))
    for ax, (config, label, (i, j)) in zip(np.atleast_1d(axes), ROBOTS, strict=False):
        robot = load_robot(_config_path(config))
        lower, upper = (np.asarray(x) for x in joint_box(robot))
        a = np.linspace(lower[i], upper[i], 241)
        b = np.linspace(lower[j], upper[j], 241)
        A, B = np.meshgrid(a, b, indexing="ij")
        q = np.zeros(A.shape + (robot.n_joints,))
        q[..., i], q[..., j] = A, B
        w = np.asarray(manipulability(robot, jnp.asarray(q)))
        image = ax.pcolormesh(np.degrees(a), np.degrees(b), w.T, shading="auto", cmap="viridis")
        fig.colorbar(image, ax=ax, label="w* [m^3]")
        s = np.asarray(singularity_measure(robot, jnp.asarray(q)))
        if robot.n_joints == 3:  # det J*_v changes sign across the dynamic singular set
            ax.contour(np.degrees(a), np.degrees(b), s.T, levels=[0.0], colors="tab:red", linewidths=1.0)
        names = robot.joint_names
        ax.set_xlabel(f"joint {i + 1} ({names[i] if i < len(names) else ''}) [deg]")
        ax.set_ylabel(f"joint {j + 1} ({names[j] if j < len(names) else ''}) [deg]")
        ax.set_title(f"{label}: other joints at 0")
    fig.suptitle("Translational w* on joint slices (red: dynamic singularities, det J*_v = 0)")
    return [_save(fig, Path(out_dir) / "spatial_wstar_slices.png")]
