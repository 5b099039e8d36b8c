"""The Table 2 report of a sweep (``report: table2`` in the sweep YAML): the paper beside ours.

``REPORTS["table2"](out_dir, rows, spec)`` writes ``table.md`` (Table 2 of Umetani &
Yoshida 1990 with our values and the relative differences, then the readings of the
w-bar column we tried). ``spacearm sweep`` adds Fig. 10 beside it
(:func:`spacearm.figures.sweep.report_figures`). ``REPORT_CHECKS["table2"](spec)``
refuses, when the sweep is loaded, a sweep the report cannot compare with the paper.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from ..io import write_text
from ..models.planar import PlanarRobot, stack_robots, umetani1990
from ..models.planar.closed_forms import manipulability_on_grid

__all__ = ["REPORTS", "REPORT_CHECKS", "PAPER_TABLE2", "B0", "FIG10_RATIOS", "table2_report", "check_table2",
           "wbar_readings"]

B0 = 1.4  # m, Table 1's b0
# Table 2 as printed: b0/B0 -> (w-bar x 1e-2, S_M, S_G).
PAPER_TABLE2 = {
    0.0: (5.59, 0.84, 0.84),
    0.5: (5.93, 1.13, 0.59),
    1.0: (6.70, 1.46, 0.39),
    1.5: (7.52, 1.83, 0.23),
    2.0: (8.08, 2.25, 0.11),
}
# The b0/B0 values Fig. 10 shows beside the table (spacearm.figures.sweep draws it).
FIG10_RATIOS = (0.0, 1.0, 2.0)

# Readings of the w-bar column -------------------------------------------------------------

_GRID_PHI1, _GRID_PHI2 = 512, 256  # midpoint grid for the readings (second order: ~1e-6 relative)


@jax.jit
def _grid_statistics(robots: PlanarRobot) -> dict[str, jax.Array]:
    """Several averages of w*/L^2 per design on one midpoint grid of the elbow-down strip."""

    def single(robot):
        phi1 = -jnp.pi + 2 * jnp.pi * (jnp.arange(_GRID_PHI1) + 0.5) / _GRID_PHI1
        phi2 = jnp.pi * (jnp.arange(_GRID_PHI2) + 0.5) / _GRID_PHI2
        w = manipulability_on_grid(robot, [phi1, phi2]) / robot.reach**2
        area = jnp.broadcast_to(jnp.sin(phi2), w.shape)  # l1 l2 cancels in the ratios
        return {
            "area": jnp.sum(w * area) / jnp.sum(area),
            "joint": jnp.mean(w),
            "area_squared": jnp.sum(w * w * area) / jnp.sum(area),
            "inertial_area": jnp.sum(w * w) / jnp.sum(w),
        }

    return jax.lax.map(single, robots)


def _model(base: PlanarRobot, ratio: float, variant: str) -> PlanarRobot:
    robot = base.replace(base_attach=np.float64(B0 * ratio))
    if variant == "I0 about joint 1":
        return robot.replace(base_inertia=np.float64(robot.base_inertia + robot.base_mass * robot.base_attach**2))
    if variant == "I_i about joint i":
        return robot.replace(link_inertia=robot.link_inertia + robot.link_mass * robot.link_a**2)
    if variant == "point-mass links":
        return robot.replace(link_inertia=np.full_like(robot.link_inertia, 1e-9))
    if variant == "B0 = l0 = 2.6 m":
        return base.replace(base_attach=np.float64(2.6 * ratio))
    return robot


def wbar_readings(base: PlanarRobot | None = None, ratios=tuple(PAPER_TABLE2)) -> list[dict]:
    """The plausible readings of the w-bar column tried against the printed values.

    Each entry: ``name``, ``note`` and ``values`` (w-bar x 1e-2 at ``ratios``). The
    numbers come from a 512 x 256 midpoint grid (about 1e-6 relative; the faithful
    row is also computed by the adaptive quadrature in the main table).
    """
    base = umetani1990() if base is None else base
    variants = ("Table 1", "I0 about joint 1", "I_i about joint i", "point-mass links", "B0 = l0 = 2.6 m")
    robots = stack_robots([_model(base, r, v) for v in variants for r in ratios])
    stats = {k: np.asarray(v).reshape(len(variants), len(ratios)) * 100 for k, v in _grid_statistics(robots).items()}
    l1, l2 = np.asarray(base.link_length)
    reach = l1 + l2
    b0 = B0 * np.asarray(ratios)
    readings = [
        ("faithful: area average, elbow-down, w*/L^2 (default)", "eq. 12 as written; elbow-up and both sheets give the same number (mirror symmetry)", stats["area"][0]),
        ("joint-space average (uniform dphi1 dphi2)", "ds read as dphi instead of the area element", stats["joint"][0]),
        ("area average of (w*/L^2)^2", "det(J* J*^T)/L^4 instead of its square root", stats["area_squared"][0]),
        ("inertial-area weighting ds = w* dphi", "average over the area the tip sweeps in the inertial frame", stats["inertial_area"][0]),
        ("normalized by (b0 + L)^2", "L read as the reach from the base centroid", stats["area"][0] * reach**2 / (b0 + reach) ** 2),
        ("model: I0 about joint 1 (I0 + m0 b0^2)", "base inertia taken about the attachment point", stats["area"][1]),
        ("model: I_i about joint i (I_i + m_i a_i^2)", "link inertias about the joints", stats["area"][2]),
        ("model: point-mass links (I_i = 0)", "no link rotational inertia", stats["area"][3]),
        ("model: B0 = l0 = 2.6 m", "b0/B0 scaled by the base length (then S_M, S_G no longer match)", stats["area"][4]),
        ("joint-space average + I_i about joint i", "the two nearest single readings combined", stats["joint"][2]),
        ("ground robot, area average", "(l1 l2 / L^2) pi/4, no base motion", np.full(len(ratios), 100 * l1 * l2 / reach**2 * math.pi / 4)),
        ("ground robot, joint-space average", "(l1 l2 / L^2) 2/pi", np.full(len(ratios), 100 * l1 * l2 / reach**2 * 2 / math.pi)),
    ]
    return [{"name": n, "note": note, "values": np.asarray(v, float)} for n, note, v in readings]


def _rms_relative(values, printed) -> float:
    return float(np.sqrt(np.mean((np.asarray(values) / np.asarray(printed) - 1.0) ** 2)))


# Table 2 ------------------------------------------------------------------------------------


def table2_report(out_dir: Path, rows: list[dict], spec) -> list[Path]:
    """Write ``table.md`` (paper vs ours, readings of w-bar).

    Args:
        out_dir: the sweep's output folder.
        rows: one dict per design with at least ``b0_over_B0``, ``wbar``, ``S_M``, ``S_G``.
        spec: the sweep spec (its ``robot`` is the base design; Table 1 when absent).
    """
    out_dir = Path(out_dir)
    base = getattr(spec, "robot", None) or umetani1990()
    rows = sorted(rows, key=lambda r: float(r["b0_over_B0"]))
    lines = [
        "# Table 2 of Umetani & Yoshida (1990), reproduced",
        "",
        "w-bar: eq. 12, w*/L^2 (eq. 11) averaged over the elbow-down reachable area of the robot",
        "frame, ds = l1 l2 |sin phi2| dphi1 dphi2, by Gauss-Legendre quadrature split at the",
        "zeros of det J* (converged to ~1e-14). S_M = (K0+K1+K2)^2/L^2, S_G = (K0-K1-K2)^2/L^2.",
        "Relative difference = ours / paper - 1.",
        "",
        "| b0/B0 | w-bar paper [x1e-2] | w-bar ours [x1e-2] | rel. diff | S_M paper | S_M ours | rel. diff | S_G paper | S_G ours | rel. diff |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    ratios, ours = [], []
    for row in rows:
        ratio = float(row["b0_over_B0"])
        wbar, s_m, s_g = float(row["wbar"]), float(row["S_M"]), float(row["S_G"])
        paper = PAPER_TABLE2.get(round(ratio, 6))
        if paper is None:
            lines.append(f"| {ratio:g} | - | {100 * wbar:.2f} | - | - | {s_m:.3f} | - | - | {s_g:.3f} | - |")
            continue
        ratios.append(ratio)
        ours.append(100 * wbar)
        cells = [f"{ratio:g}"]
        for printed, value, digits in ((paper[0], 100 * wbar, 2), (paper[1], s_m, 3), (paper[2], s_g, 3)):
            cells += [f"{printed:.2f}", f"{value:.{digits}f}", f"{value / printed - 1:+.1%}"]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", *_table2_summary(rows), ""]
    if ratios:
        printed = [PAPER_TABLE2[round(r, 6)][0] for r in ratios]
        readings = wbar_readings(base, tuple(ratios))
        header = " | ".join(f"b0/B0={r:g}" for r in ratios)
        lines += [
            "## Readings of the w-bar column tried (x1e-2; none tuned to the printed numbers)",
            "",
            "Computed on a 512 x 256 midpoint grid of the elbow-down strip (about 1e-6 relative).",
            "rms rel. = root mean square of ours / paper - 1 over the five rows; growth = value at",
            "the last row / value at the first (paper: %.3f)." % (printed[-1] / printed[0]),
            "",
            f"| reading | {header} | rms rel. | growth | what it changes |",
            "|---|" + "---|" * len(ratios) + "---|---|---|",
            "| **paper (printed)** | " + " | ".join(f"{p:.2f}" for p in printed) + " | 0 | %.3f | |" % (printed[-1] / printed[0]),
        ]
        for reading in readings:
            values = reading["values"]
            lines.append(
                f"| {reading['name']} | "
                + " | ".join(f"{v:.2f}" for v in values)
                + f" | {_rms_relative(values, printed):.3f} | {values[-1] / values[0]:.3f} | {reading['note']} |"
            )
        best = min(readings[1:], key=lambda r: _rms_relative(r["values"], printed))
        lines += [
            "",
            f"Closest: {best['name']} (rms rel. {_rms_relative(best['values'], printed):.3f}). No single",
            "reading reproduces the column; the faithful definition stays the default.",
        ]
    return [write_text(out_dir / "table.md", "\n".join(lines) + "\n")]


def _table2_summary(rows: list[dict]) -> list[str]:
    """What the comparison shows, in words, from the numbers themselves."""
    matched = [(r, PAPER_TABLE2[round(float(r["b0_over_B0"]), 6)]) for r in rows
               if round(float(r["b0_over_B0"]), 6) in PAPER_TABLE2]
    if not matched:
        return ["None of these b0/B0 values is printed in Table 2; nothing to compare."]
    areas_agree = sum(abs(float(r[key]) - p[k]) <= 0.005 + 1e-9 for r, p in matched for k, key in ((1, "S_M"), (2, "S_G")))
    ours = [100 * float(r["wbar"]) for r, _ in matched]
    printed = [p[0] for _, p in matched]
    lines = [
        f"S_M and S_G agree with the printed values to their two decimals in {areas_agree} of {2 * len(matched)} cells.",
        f"w-bar: ours {min(ours):.2f} to {max(ours):.2f} (x1e-2) where the paper prints {min(printed):.2f} to "
        f"{max(printed):.2f}; rms relative difference {_rms_relative(ours, printed):.2f}.",
    ]
    if len(matched) > 1:
        first, last = float(matched[0][0]["b0_over_B0"]), float(matched[-1][0]["b0_over_B0"])
        lines.append(f"Growth from b0/B0 = {first:g} to {last:g}: x{ours[-1] / ours[0]:.2f} here, x{printed[-1] / printed[0]:.2f} in the paper.")
    return lines


def check_table2(spec) -> None:
    """ConfigError unless the sweep is one the Table 2 report can compare with the paper:
    one axis ``b0_over_B0`` on base.attach relative to Table 1's B0, the metrics wbar,
    S_M and S_G, and the Table 1 robot."""
    where = f"{spec.source}: report: table2"
    axes = spec.axes
    if len(axes) != 1 or axes[0].name != "b0_over_B0" or axes[0].field != "base.attach" or not axes[0].relative:
        raise ConfigError(f"{where} needs exactly one axis, b0_over_B0: {{field: base.attach, relative: true, values: [...]}}")
    missing = {"wbar", "S_M", "S_G"} - {m.name for m in spec.metrics}
    if missing:
        raise ConfigError(f"{where} needs the metrics wbar, S_M and S_G (missing: {', '.join(sorted(missing))})")
    wbar = next(m for m in spec.metrics if m.name == "wbar")
    if wbar.options.get("measure", "area") != "area":
        raise ConfigError(f"{where} compares the area average of eq. 12; drop wbar's measure: {wbar.options['measure']}")
    paper = umetani1990()
    for field in ("base_mass", "base_inertia", "base_attach", "link_mass", "link_inertia", "link_a", "link_b"):
        if np.shape(getattr(spec.robot, field)) != np.shape(getattr(paper, field)) or not np.allclose(
            getattr(spec.robot, field), getattr(paper, field), rtol=1e-12, atol=0.0
        ):
            raise ConfigError(f"{where} compares with the paper's Table 1 robot; this robot's {field} differs")


REPORTS: dict[str, Callable[[Path, list[dict], object], list[Path]]] = {"table2": table2_report}
# Checks run by load_sweep, so that `spacearm validate` refuses what a report cannot do.
REPORT_CHECKS: dict[str, Callable[[object], None]] = {"table2": check_table2}
