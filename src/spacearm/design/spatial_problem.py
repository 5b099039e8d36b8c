"""Aliases for the spatial design problem: one `DesignProblem` serves every family.

Names: `SpatialDesignProblem` (the same class), `spatial_problem_from_mapping`,
`load_design_problem` and `SPATIAL_OBJECTIVES` (see `spacearm.design.problem` and
`spacearm.design.objectives`).
"""

from __future__ import annotations

from .objectives import SPATIAL_OBJECTIVES as SPATIAL_OBJECTIVES
from .problem import DesignProblem, load_problem, problem_from_mapping

__all__ = ["SPATIAL_OBJECTIVES", "SpatialDesignProblem", "load_design_problem", "spatial_problem_from_mapping"]

SpatialDesignProblem = DesignProblem
spatial_problem_from_mapping = problem_from_mapping
load_design_problem = load_problem
