"""Numeric settings. Nothing here runs at import time (jaxsim#322)."""

from __future__ import annotations

import jax


def enable_x64(enabled: bool = True) -> None:
    """Turn JAX's float64 mode on (or off). The command line calls this; library users call it once."""
    jax.config.update("jax_enable_x64", bool(enabled))


def x64_enabled() -> bool:
    """Whether JAX currently creates float64 arrays by default."""
    return bool(jax.config.jax_enable_x64)
