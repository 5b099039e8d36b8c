"""Argument parsing shared by the commands."""

from __future__ import annotations

import numpy as np

from .._core.errors import ConfigError

__all__ = ["check_limits", "comma_numbers"]


def comma_numbers(text: str, count: int, what: str) -> np.ndarray:
    """``count`` finite numbers from ``"a,b,c"`` (an option's value); ConfigError naming ``what``."""
    try:
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise ConfigError(f"{what}: expected {count} comma-separated numbers, got {text!r}") from None
    if values.size != count or not np.all(np.isfinite(values)):
        raise ConfigError(f"{what}: expected {count} finite comma-separated numbers, got {text!r}")
    return values


def check_limits(what: str, values, lower, upper, *, degrees, prismatic=False, names=None) -> None:
    """ConfigError naming the first of ``values`` (rad, or m where ``prismatic``) outside
    ``[lower, upper]``, in the units the user typed: degrees for a revolute joint when
    ``degrees`` (flags per joint, or one for all)."""
    values, lower, upper = (np.asarray(a, dtype=float) for a in (values, lower, upper))
    outside = (values < lower) | (values > upper)
    if not np.any(outside):
        return
    j = int(np.argmax(outside))
    if np.broadcast_to(prismatic, values.shape)[j]:
        scale, unit = 1.0, "m"
    else:
        scale, unit = (180.0 / np.pi, "deg") if np.broadcast_to(degrees, values.shape)[j] else (1.0, "rad")
    name = f" ({names[j]})" if names is not None else ""
    raise ConfigError(
        f"{what}: joint {j + 1}{name} = {values[j] * scale:.6g} {unit} is outside its limits "
        f"[{lower[j] * scale:.6g}, {upper[j] * scale:.6g}] {unit}"
    )
