"""Numeric settings. Nothing here runs at import time (jaxsim#322)."""

from __future__ import annotations

import os

import jax


def enable_x64(enabled: bool = True) -> None:
    """Turn JAX's float64 mode on (or off). The command line calls this; library users call it once."""
    jax.config.update("jax_enable_x64", bool(enabled))


def x64_enabled() -> bool:
    """Whether JAX currently creates float64 arrays by default."""
    return bool(jax.config.jax_enable_x64)


def enable_compilation_cache(path: str | None = None) -> str | None:
    """Keep compiled XLA programs on disk so a second command-line run skips compilation.

    The folder is ``$SPACEARM_CACHE_DIR``, else ``$XDG_CACHE_HOME/spacearm/jax`` (or
    ``~/.cache/spacearm/jax``); ``SPACEARM_CACHE_DIR=off`` disables it. Returns the folder.
    """
    path = path or os.environ.get("SPACEARM_CACHE_DIR")
    if path == "off":
        return None
    if not path:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        path = os.path.join(base, "spacearm", "jax")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:
        return None
    jax.config.update("jax_compilation_cache_dir", path)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.5)
    return path
