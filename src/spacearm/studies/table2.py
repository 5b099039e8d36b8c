"""The Table 2 report of a sweep (``report: table2`` in the sweep YAML): the paper beside ours.

``REPORTS["table2"](out_dir, rows, spec)`` writes ``table.md`` (Table 2 of Umetani &
Yoshida 1990 with our values and the relative differences, then the readings of the
w-bar column we tried, from `spacearm.studies.table2_readings`). ``spacearm sweep``
adds Fig. 10 beside it (`spacearm.figures.sweep.report_figures`).
``REPORT_CHECKS["table2"](spec)`` refuses, when the sweep is loaded, a sweep the report
cannot compare with the paper.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .._core.errors import ConfigError
from ..io import write_text
from ..paper import PlanarRobot, umetani1990
from ..paper.planar_parts import stack_robots
from .table2_readings import (
    AVERAGES,
    DEPARTURES,
    FAITHFUL,
    chance_level,
    grid_averages,
    relative_errors,
    shape_error,
    wbar_readings as model_readings,
)

__all__ = [
    "B0",
    "FIG10_RATIOS",
    "PAPER_TABLE2",
    "REPORTS",
    "REPORT_CHECKS",
    "check_table2",
    "table2_report",
    "wbar_readings",
]

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
# The derivation variants and averaging rules live in table2_readings; here they become rows.


def wbar_readings(base: PlanarRobot | None = None, ratios=tuple(PAPER_TABLE2)) -> list[dict]:
    """Every reading of the w-bar column tried against the printed values.

    Each model variant of `spacearm.studies.table2_readings.model_variants` (the faithful
    derivation, every single departure and every pair) by each averaging rule of
    `spacearm.studies.AVERAGES`, then three readings outside that grid
    (B0 read as the base length; the ground robot's closed forms). Each entry: ``name``,
    ``note``, ``departures`` (how many choices differ from eq. 1-12 as written) and
    ``values`` (w-bar x 1e-2 at ``ratios``; NaN where the variant's I_S vanishes on the
    strip). Computed on a 512 x 256 midpoint grid (under 1e-5 relative; the faithful
    area row is also computed by the adaptive quadrature in the main table).
    """
    base = umetani1990() if base is None else base
    readings = []
    for reading in model_readings(base, tuple(ratios)):
        model = " + ".join(reading["model"]) or "faithful"
        extra = 0 if reading["average"] == "area" else 1
        readings.append(
            {
                "name": f"{model} / {reading['average']}",
                "model": model,
                "rule": reading["average"],
                "note": AVERAGES[reading["average"]]
                if not reading["model"]
                else "; ".join(DEPARTURES[n][1] for n in reading["model"]),
                "departures": len(reading["model"]) + extra,
                "values": np.asarray(reading["values"], float),
            }
        )
    l1, l2 = np.asarray(base.link_length)
    reach = l1 + l2
    scaled = stack_robots([base.replace(base_attach=np.float64(2.6 * r)) for r in ratios])
    readings += [
        {
            "name": "faithful, B0 = l0 = 2.6 m / area",
            "note": "b0/B0 scaled by the base length (then S_M, S_G no longer match)",
            "departures": 1,
            "values": 100 * grid_averages([FAITHFUL], scaled)["area"][0],
        },
        {
            "name": "ground robot / area",
            "note": "(l1 l2 / L^2) pi/4, no base motion",
            "departures": 1,
            "values": np.full(len(ratios), 100 * l1 * l2 / reach**2 * math.pi / 4),
        },
        {
            "name": "ground robot / joint",
            "note": "(l1 l2 / L^2) 2/pi",
            "departures": 2,
            "values": np.full(len(ratios), 100 * l1 * l2 / reach**2 * 2 / math.pi),
        },
    ]
    return readings


def _rms_relative(values, printed) -> float:
    return float(np.sqrt(np.mean((np.asarray(values) / np.asarray(printed) - 1.0) ** 2)))


def _readings_lines(base: PlanarRobot, ratios: list[float], printed: list[float]) -> list[str]:
    """The readings section of table.md: the variants, the rules, the verdict, every reading."""
    readings = wbar_readings(base, tuple(ratios))
    for r in readings:
        r["max"], r["rms"] = relative_errors(r["values"], printed)
        r["shape"] = shape_error(r["values"], printed)
    return [
        *_variants_lines(),
        *_verdict_lines(readings, printed),
        *_rms_grid_lines(readings),
        *_every_reading_lines(readings, ratios, printed),
    ]


def _variants_lines() -> list[str]:
    """What a reading is: the departures from the faithful derivation and the averaging rules."""
    return [
        "## Readings of the w-bar column (x1e-2; no parameter, none tuned to the printed numbers)",
        "",
        "A reading = a derivation of I_S, I_M and J_S, J_M (eq. 2, 5; the faithful one or departures",
        "from it that a hand derivation could make) and a rule for averaging w* (eq. 12 or a",
        "misreading of it). Derivations: src/spacearm/studies/table2_readings.py; the reasoning:",
        "docs/explanation/table2-wbar.md. Every value comes from a 512 x 256 midpoint grid of the",
        "elbow-down strip (under 1e-5 relative; the faithful area row differs from the main table by 6e-6).",
        "",
        "### Departures from the faithful derivation (each alone, and every pair changing two different things)",
        "",
        "| departure | why a 1990 derivation could make it |",
        "|---|---|",
        *[f"| {name} | {note} |" for name, (_, note) in DEPARTURES.items()],
        "",
        "### Averaging rules (each with every model variant)",
        "",
        "| rule | what it changes |",
        "|---|---|",
        *[f"| {name} | {note} |" for name, note in AVERAGES.items()],
        "",
    ]


def _reading_line(r: dict) -> str:
    return f"{r['name']} (rms {r['rms']:.1%}, max {r['max']:.1%}: " + ", ".join(f"{v:.2f}" for v in r["values"]) + ")"


def _verdict_lines(readings: list[dict], printed: list[float]) -> list[str]:
    """The closest readings by each measure, and how they compare with chance."""
    finite = [r for r in readings if np.all(np.isfinite(r["values"]))]
    growth = printed[-1] / printed[0]
    best = min(finite, key=lambda r: r["rms"])
    best_single = min(
        (r for r in finite if r["departures"] <= 1 and r["name"] != "faithful / area"), key=lambda r: r["rms"]
    )
    best_area = min(
        (r for r in finite if r["name"].endswith("/ area") and r["name"] != "faithful / area"), key=lambda r: r["rms"]
    )
    by_max = min(finite, key=lambda r: r["max"])
    faithful = next(r for r in readings if r["name"] == "faithful / area")["values"]
    fraction, median = chance_level(np.array([r["values"] for r in readings]), printed)
    shaped = [r for r in finite if np.isfinite(r["shape"])]
    # Rules that scale every row alike (area, square, area / joint volume) tie in shape: prefer fewer departures.
    by_shape = min(shaped, key=lambda r: (round(r["shape"], 9), r["departures"]))
    by_shape_single = min(
        (r for r in shaped if len(r.get("model", "").split(" + ")) == 1 and r.get("model") != "faithful"),
        key=lambda r: (round(r["shape"], 9), r["departures"]),
    )
    shape_fraction, shape_median = chance_level(np.array([r["values"] for r in readings]), printed, statistic="shape")
    return [
        "### Verdict",
        "",
        f"{len(readings)} readings, {len(finite)} finite (the others put I_S = 0 somewhere on the strip, where w* has a pole).",
        f"Growth from the first row to the last: x{growth:.3f} printed, x{faithful[-1] / faithful[0]:.3f} faithful.",
        "",
        f"- Closest by rms: {_reading_line(best)}, {best['departures']} departures.",
        f"- Closest by maximum error: {_reading_line(by_max)}.",
        f"- Closest with at most one departure: {_reading_line(best_single)}.",
        f"- Closest keeping eq. 12's area average: {_reading_line(best_area)}.",
        (
            "- Closest in shape (each column divided by its first row, so blind to any constant factor of the"
            f" averaging or the normalization): {by_shape['name']} (shape error {by_shape['shape']:.1%});"
            f" with one model departure: {by_shape_single['name']} (shape error {by_shape_single['shape']:.1%},"
            f" growth x{by_shape_single['values'][-1] / by_shape_single['values'][0]:.3f})."
        ),
        (
            f"- No reading reproduces the column: the printed values are rounded to 0.005 (at most "
            f"{0.005 / min(printed):.2%} relative); every reading misses some row by {by_max['max']:.1%} or more."
        ),
        (
            f"- Against chance: over 1000 random increasing columns with the printed first and last values, the"
            f" best of these readings has a median rms of {median:.1%}; {fraction:.1%} of the random columns are"
            " fitted at least as well as the printed one. In shape: median best shape error"
            f" {shape_median:.1%}, {shape_fraction:.1%} of the random columns fitted at least as well."
        ),
        "- The faithful definition stays the default everywhere.",
        "",
    ]


def _rms_grid_lines(readings: list[dict]) -> list[str]:
    """The rms error of every reading, model variants by averaging rules."""
    lines = [
        "### rms relative error of every reading (rows: model variant; columns: averaging rule; - = diverges)",
        "",
        "| model variant | " + " | ".join(AVERAGES) + " |",
        "|---|" + "---|" * len(AVERAGES),
    ]
    grid = {}
    for r in readings:
        if "model" in r:
            grid.setdefault(r["model"], {})[r["rule"]] = r
    for model, cells in grid.items():
        lines.append(
            f"| {model} | "
            + " | ".join("-" if not np.isfinite(cells[k]["rms"]) else f"{cells[k]['rms']:.1%}" for k in AVERAGES)
            + " |"
        )
    return lines


def _every_reading_lines(readings: list[dict], ratios: list[float], printed: list[float]) -> list[str]:
    """Every reading's column beside the printed one, closest first (diverging ones last)."""
    growth = printed[-1] / printed[0]
    header = " | ".join(f"b0/B0={r:g}" for r in ratios)
    lines = [
        "",
        "### Every reading, closest first",
        "",
        "departures = how many choices differ from eq. 1-12 as written (model departures, plus one for a rule",
        f"other than the area average). growth = last row / first (paper: {growth:.3f}). shape err = max over the",
        "rows of |(ours_i / ours_0) / (paper_i / paper_0) - 1|, blind to a constant factor.",
        "",
        f"| reading (model / rule) | departures | {header} | max rel. err | rms rel. err | growth | shape err |",
        "|---|---|" + "---|" * len(ratios) + "---|---|---|---|",
        "| **paper (printed)** | | " + " | ".join(f"{p:.2f}" for p in printed) + f" | 0 | 0 | {growth:.3f} | 0 |",
    ]
    finite = [r for r in readings if np.all(np.isfinite(r["values"]))]
    for r in sorted(finite, key=lambda r: r["rms"]) + [r for r in readings if r not in finite]:
        if np.all(np.isfinite(r["values"])):
            cells = " | ".join(f"{v:.2f}" for v in r["values"])
            ratio = f"{r['values'][-1] / r['values'][0]:.3f}" if r["values"][0] else "-"
            shape = f"{r['shape']:.1%}" if np.isfinite(r["shape"]) else "-"
            tail = f"{r['max']:.1%} | {r['rms']:.1%} | {ratio} | {shape}"
        else:
            cells = " | ".join("-" if not np.isfinite(v) else f"{v:.2f}" for v in r["values"])
            tail = "diverges | | | "
        lines.append(f"| {r['name']} | {r['departures']} | {cells} | {tail} |")
    return lines


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
        lines += _readings_lines(base, ratios, printed)
    return [write_text(out_dir / "table.md", "\n".join(lines) + "\n")]


def _table2_summary(rows: list[dict]) -> list[str]:
    """What the comparison shows, in words, from the numbers themselves."""
    matched = [
        (r, PAPER_TABLE2[round(float(r["b0_over_B0"]), 6)])
        for r in rows
        if round(float(r["b0_over_B0"]), 6) in PAPER_TABLE2
    ]
    if not matched:
        return ["None of these b0/B0 values is printed in Table 2; nothing to compare."]
    areas_agree = sum(
        abs(float(r[key]) - p[k]) <= 0.005 + 1e-9 for r, p in matched for k, key in ((1, "S_M"), (2, "S_G"))
    )
    ours = [100 * float(r["wbar"]) for r, _ in matched]
    printed = [p[0] for _, p in matched]
    lines = [
        f"S_M and S_G agree with the printed values to their two decimals in {areas_agree} of {2 * len(matched)} cells.",
        f"w-bar: ours {min(ours):.2f} to {max(ours):.2f} (x1e-2) where the paper prints {min(printed):.2f} to "
        f"{max(printed):.2f}; rms relative difference {_rms_relative(ours, printed):.2f}.",
    ]
    if len(matched) > 1:
        first, last = float(matched[0][0]["b0_over_B0"]), float(matched[-1][0]["b0_over_B0"])
        lines.append(
            f"Growth from b0/B0 = {first:g} to {last:g}: x{ours[-1] / ours[0]:.2f} here, x{printed[-1] / printed[0]:.2f} in the paper."
        )
    return lines


def check_table2(spec) -> None:
    """ConfigError unless the sweep is one the Table 2 report can compare with the paper:
    one axis ``b0_over_B0`` on base.attach relative to Table 1's B0, the metrics wbar,
    S_M and S_G, and the Table 1 robot."""
    where = f"{spec.source}: report: table2"
    axes = spec.axes
    if len(axes) != 1 or axes[0].name != "b0_over_B0" or axes[0].field != "base.attach" or not axes[0].relative:
        raise ConfigError(
            f"{where} needs exactly one axis, b0_over_B0: {{field: base.attach, relative: true, values: [...]}}"
        )
    missing = {"wbar", "S_M", "S_G"} - {m.name for m in spec.metrics}
    if missing:
        raise ConfigError(f"{where} needs the metrics wbar, S_M and S_G (missing: {', '.join(sorted(missing))})")
    wbar = next(m for m in spec.metrics if m.name == "wbar")
    if wbar.options.get("measure", "area") != "area":
        raise ConfigError(
            f"{where} compares the area average of eq. 12; drop wbar's measure: {wbar.options['measure']}"
        )
    ours, paper = dataclasses.asdict(spec.robot), dataclasses.asdict(umetani1990())
    for field in ("base_mass", "base_inertia", "base_attach", "link_mass", "link_inertia", "link_a", "link_b"):
        if np.shape(ours[field]) != np.shape(paper[field]) or not np.allclose(
            ours[field], paper[field], rtol=1e-12, atol=0.0
        ):
            raise ConfigError(f"{where} compares with the paper's Table 1 robot; this robot's {field} differs")


REPORTS: dict[str, Callable[[Path, list[dict], object], list[Path]]] = {"table2": table2_report}
# Checks run by load_sweep, so that `spacearm validate` refuses what a report cannot do.
REPORT_CHECKS: dict[str, Callable[[object], None]] = {"table2": check_table2}
