"""Deprecated path (one release): use :mod:`spacearm.studies.table2`."""

from .studies.table2 import (
    PAPER_TABLE2 as PAPER_TABLE2,
    REPORT_CHECKS as REPORT_CHECKS,
    REPORTS as REPORTS,
    table2_report as table2_report,
    wbar_readings as wbar_readings,
)
