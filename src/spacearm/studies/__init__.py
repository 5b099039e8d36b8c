"""Design studies: YAML sweep files -> one batched design pytree -> tables and grids.

Modules: ``spec`` (the sweep file schema, ``--set`` overrides, `SweepSpec`),
``designs`` (design fields and the batched designs), ``metrics`` (the metric registry),
``runner`` (chunked, sharded, resumable execution and the files), ``table2`` (the
Table 2 report). Figures of a sweep live in `spacearm.figures.sweep`.
"""

from .designs import (
    FIELD_HELP as FIELD_HELP,
    Axis as Axis,
    axis_points as axis_points,
    build_designs as build_designs,
)
from .metrics import METRICS as METRICS, Metric as Metric, MetricSpec as MetricSpec, design_function as design_function
from .runner import SweepResult as SweepResult, run_sweep as run_sweep
from .spec import SweepSpec as SweepSpec, apply_overrides as apply_overrides, load_sweep as load_sweep
from .table2 import (
    PAPER_TABLE2 as PAPER_TABLE2,
    REPORTS as REPORTS,
    table2_report as table2_report,
    wbar_readings as wbar_readings,
)

__all__ = [
    "FIELD_HELP",
    "METRICS",
    "PAPER_TABLE2",
    "REPORTS",
    "Axis",
    "Metric",
    "MetricSpec",
    "SweepResult",
    "SweepSpec",
    "apply_overrides",
    "axis_points",
    "build_designs",
    "design_function",
    "load_sweep",
    "run_sweep",
    "table2_report",
    "wbar_readings",
]
