"""The planar family's building blocks that the paper's studies assemble themselves.

The Table 2 readings (`spacearm.studies.table2_readings`) rebuild w* from the coefficients of
eq. 1 and the columns of J* under several readings of the paper, the Table 2 report scales
the Table 1 arm over b0, the planar design problems start from the paper's uniform-rod arm
and its first-generation field names, and the figures draw the links' centroids. This module
names those parts of the planar closed forms (`spacearm.models.planar.closed_forms`) for
them, so that only `spacearm.paper` reaches into the planar family.
"""

from ..models.planar import stack_robots as stack_robots
from ..models.planar.closed_forms import (
    DesignCoefficients as DesignCoefficients,
    _manipulability_from_columns as manipulability_from_columns,
    _momentum_rows as momentum_rows,
    _momentum_terms as momentum_terms,
    _tip_columns as tip_columns,
    centroid_positions as centroid_positions,
    grid_angle_tables as grid_angle_tables,
)
from ..models.planar.fields import alias_names as design_field_aliases

__all__ = [
    "DesignCoefficients",
    "centroid_positions",
    "design_field_aliases",
    "grid_angle_tables",
    "manipulability_from_columns",
    "momentum_rows",
    "momentum_terms",
    "stack_robots",
    "tip_columns",
]
