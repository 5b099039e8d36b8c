"""Deprecated path (one release): use `spacearm.analysis` (``normalized_areas`` of the
workspaces is now `spacearm.analysis.normalized_workspace_areas`)."""

from .analysis import *  # noqa: F403
from .analysis import __all__ as __all__  # noqa: F401
