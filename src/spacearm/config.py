"""Deprecated path (one release): use :mod:`spacearm._core.numeric` (and :func:`spacearm.enable_x64`)."""

from ._core.numeric import (
    enable_compilation_cache as enable_compilation_cache,
    enable_x64 as enable_x64,
    use_every_cpu_core as use_every_cpu_core,
    x64_enabled as x64_enabled,
)
