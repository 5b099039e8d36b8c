"""Files on disk, written atomically: text, JSON, NPZ, CSV tables and figures.

Every file is written to a temporary name in its destination folder and renamed into
place, so an interrupted run never leaves a half-written file.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import tempfile
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "atomic_path",
    "json_default",
    "read_csv",
    "save_figure",
    "write_csv",
    "write_json",
    "write_npz",
    "write_text",
]

_UMASK = os.umask(0)
os.umask(_UMASK)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, keep_suffix: bool = False) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` only on success.

    ``keep_suffix``: end the temporary name with ``path``'s suffix too (``.x.gif.abc.tmp.gif``),
    for writers that choose the format from the file name (Pillow's GIF writer).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    suffix = ".tmp" + (path.suffix if keep_suffix else "")
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix, dir=path.parent)
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
    return write_text(path, json.dumps(data, indent=2, default=json_default) + "\n")


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
    rows = zip(*(columns[name] for name in names), strict=False)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(names)
    for row in rows:
        writer.writerow([_format_cell(value) for value in row])
    return write_text(path, buffer.getvalue())


def read_csv(path: str | os.PathLike) -> dict[str, list]:
    """Read a CSV written by `write_csv`; numeric cells become floats."""
    with open(path, encoding="utf-8", newline="") as handle:
        reader = csv.reader(handle)
        names = next(reader)
        columns: dict[str, list] = {name: [] for name in names}
        for row in reader:
            for name, cell in zip(names, row, strict=False):
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


def json_default(value):
    """``json.dumps(default=...)`` for NumPy arrays and scalars and paths."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"not JSON serializable: {type(value).__name__}")
