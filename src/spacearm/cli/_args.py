"""Argument parsing shared by the commands."""

from __future__ import annotations

import numpy as np

from .._core.errors import ConfigError

__all__ = ["comma_numbers"]


def comma_numbers(text: str, count: int, what: str) -> np.ndarray:
    """``count`` finite numbers from ``"a,b,c"`` (an option's value); ConfigError naming ``what``."""
    try:
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise ConfigError(f"{what}: expected {count} comma-separated numbers, got {text!r}") from None
    if values.size != count or not np.all(np.isfinite(values)):
        raise ConfigError(f"{what}: expected {count} finite comma-separated numbers, got {text!r}")
    return values
