"""The run manifest: everything needed to rerun a result (config and its hash, versions,
git state, float64 flag, devices, timings)."""

from __future__ import annotations

import hashlib
import json
import os
import platform
import subprocess
import time
from collections.abc import Mapping, Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

import jax

from .files import json_default

__all__ = ["config_hash", "package_versions", "git_state", "device_info", "build_manifest"]

_PACKAGES = ("spacearm", "jax", "jaxlib", "numpy", "optax", "matplotlib", "pyyaml", "scipy")


def config_hash(config: Any) -> str:
    """SHA-256 of the compact JSON of a resolved config (built in a fixed key order by the loaders)."""
    # Key order is kept: in a sweep the order of the axes decides which design is which row.
    text = json.dumps(config, separators=(",", ":"), default=json_default)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def package_versions() -> dict[str, str | None]:
    """Installed versions of spacearm and the packages a result depends on (None if absent)."""
    versions: dict[str, str | None] = {}
    for name in _PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return versions


def git_state(start: str | os.PathLike | None = None) -> dict[str, Any]:
    """The git revision and dirty flag of the checkout holding ``start`` (None outside git)."""
    where = Path(start) if start else Path(__file__).resolve().parent
    try:
        revision = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=where, capture_output=True, text=True, timeout=10, check=True
        ).stdout.strip()
        status = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=where, capture_output=True, text=True, timeout=10, check=True,
        ).stdout
        return {"revision": revision, "dirty": bool(status.strip())}
    except (OSError, subprocess.SubprocessError):
        return {"revision": None, "dirty": None}


def device_info() -> dict[str, Any]:
    """The JAX backend, device and process counts, and the devices."""
    return {
        "backend": jax.default_backend(),
        "device_count": jax.device_count(),
        "process_count": jax.process_count(),
        "devices": [str(device) for device in jax.devices()],
    }


def build_manifest(config: Any, *, command: Sequence[str] | None = None, timings: Mapping[str, float] | None = None,
             extra: Mapping[str, Any] | None = None, git: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Everything needed to rerun a result: the resolved config and its hash, versions,
    git state, float64 flag, devices and timings.

    ``git``: the state taken before the run wrote anything (default: now). Regenerating
    results that are committed changes tracked files, which must not mark the code dirty.
    """
    data = {
        "config": config,
        "config_sha256": config_hash(config),
        "command": list(command) if command is not None else None,
        "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "packages": package_versions(),
        "git": dict(git) if git is not None else git_state(),
        "float64": bool(jax.config.jax_enable_x64),
        **device_info(),
        "timings_s": dict(timings or {}),
    }
    if extra:
        data.update(extra)
    return data
