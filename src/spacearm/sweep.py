"""Deprecated path (one release): use :mod:`spacearm.studies`."""

from .studies import (
    FIELD_HELP as FIELD_HELP,
    METRICS as METRICS,
    Axis as Axis,
    MetricSpec as MetricSpec,
    SweepResult as SweepResult,
    SweepSpec as SweepSpec,
    axis_points as axis_points,
    build_designs as build_designs,
    design_function as design_function,
    load_sweep as load_sweep,
    run_sweep as run_sweep,
)
