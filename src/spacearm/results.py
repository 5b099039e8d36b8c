"""Results on disk: atomic writes, tables, labelled grids and the run manifest.

Every file is written to a temporary name in its destination folder and renamed into
place, so an interrupted run never leaves a half-written file.
"""

from __future__ import annotations

import contextlib
import csv
import hashlib
import io
import json
import os
import platform
import subprocess
import tempfile
import time
from collections.abc import Iterator, Mapping, Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

_UMASK = os.umask(0)
os.umask(_UMASK)

_PACKAGES = ("spacearm", "jax", "jaxlib", "numpy", "optax", "matplotlib", "pyyaml", "scipy")


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` only on success."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(handle)
    try:
        yield Path(temporary)
        os.chmod(temporary, 0o666 & ~_UMASK)  # mkstemp creates 0600; give the usual mode
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.remove(temporary)
        raise


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write a text file atomically."""
    with atomic_path(path) as temporary:
        temporary.write_text(text, encoding="utf-8")
    return Path(path)


def write_json(path: str | os.PathLike, data: Any) -> Path:
    """Write JSON atomically (keys in the order given: a sweep's axis order is meaning, not
    presentation; indented, NumPy scalars converted)."""
    return write_text(path, json.dumps(data, indent=2, default=_json_default) + "\n")


def write_npz(path: str | os.PathLike, **arrays: np.ndarray) -> Path:
    """Write an uncompressed ``.npz`` atomically."""
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    with atomic_path(path) as temporary:
        temporary.write_bytes(buffer.getvalue())
    return Path(path)


def write_csv(path: str | os.PathLike, columns: Mapping[str, Sequence]) -> Path:
    """Write a table (column name -> values, equal lengths) as CSV atomically.

    Floats are written with 17 significant digits so the file round-trips exactly.
    """
    names = list(columns)
    rows = zip(*(columns[name] for name in names))
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(names)
    for row in rows:
        writer.writerow([_format_cell(value) for value in row])
    return write_text(path, buffer.getvalue())


def read_csv(path: str | os.PathLike) -> dict[str, list]:
    """Read a CSV written by :func:`write_csv`; numeric cells become floats."""
    with open(path, encoding="utf-8", newline="") as handle:
        reader = csv.reader(handle)
        names = next(reader)
        columns: dict[str, list] = {name: [] for name in names}
        for row in reader:
            for name, cell in zip(names, row):
                columns[name].append(_parse_cell(cell))
    return columns


def save_figure(fig, path: str | os.PathLike, **kwargs) -> Path:
    """Save a matplotlib figure atomically (format from the suffix)."""
    path = Path(path)
    with atomic_path(path) as temporary:
        fig.savefig(temporary, format=path.suffix.lstrip(".") or "png", **kwargs)
    return path


def _format_cell(value) -> str:
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if isinstance(value, (np.integer,)):
        return str(int(value))
    return str(value)


def _parse_cell(cell: str):
    try:
        return float(cell)
    except ValueError:
        return cell


def _json_default(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"not JSON serializable: {type(value).__name__}")


def config_hash(config: Any) -> str:
    """SHA-256 of the compact JSON of a resolved config (built in a fixed key order by the loaders)."""
    # Key order is kept: in a sweep the order of the axes decides which design is which row.
    text = json.dumps(config, separators=(",", ":"), default=_json_default)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def package_versions() -> dict[str, str | None]:
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
    import jax

    return {
        "backend": jax.default_backend(),
        "device_count": jax.device_count(),
        "process_count": jax.process_count(),
        "devices": [str(device) for device in jax.devices()],
    }


def manifest(config: Any, *, command: Sequence[str] | None = None, timings: Mapping[str, float] | None = None,
             extra: Mapping[str, Any] | None = None, git: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Everything needed to rerun a result: the resolved config and its hash, versions,
    git state, float64 flag, devices and timings.

    ``git``: the state taken before the run wrote anything (default: now). Regenerating
    results that are committed changes tracked files, which must not mark the code dirty.
    """
    import jax

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
