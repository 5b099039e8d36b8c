"""The paper's figures and ours, one module per family, gathered by a registry.

A figure function takes the output folder and returns the paths it wrote. Modules
register their figures with `figure`; ``spacearm figures`` imports every module
in `FIGURE_MODULES` and runs them all.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from pathlib import Path

# Modules under spacearm.figures that define figures (imported on demand).
FIGURE_MODULES: list[str] = ["planning", "motion", "workspace", "maps", "spatial", "spatial_analysis"]

FigureFunction = Callable[[Path], list[Path]]
_REGISTRY: dict[str, FigureFunction] = {}


def figure(name: str) -> Callable[[FigureFunction], FigureFunction]:
    """Register ``fn(out_dir) -> [paths]`` under ``name`` (e.g. ``"fig2"``)."""

    def register(fn: FigureFunction) -> FigureFunction:
        _REGISTRY[name] = fn
        return fn

    return register


def all_figures() -> dict[str, FigureFunction]:
    """Every registered figure, after importing the figure modules."""
    for module in FIGURE_MODULES:
        importlib.import_module(f"spacearm.figures.{module}")
    return dict(sorted(_REGISTRY.items()))
