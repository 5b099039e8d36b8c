"""The one error type a user sees for bad input."""

from __future__ import annotations

__all__ = ["ConfigError"]


class ConfigError(ValueError):
    """A robot, sweep or design-problem description is invalid.

    The message names the file, the field (or the link or joint) and the reason; the
    command line prints it on one line and exits with status 2.
    """
