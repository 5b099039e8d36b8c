"""Result folders that change as a whole or not at all, with one writer at a time.

A run takes `lock_folder` on its output folder (an advisory ``fcntl`` lock on the file
``.<name>.lock`` beside the folder; a second writer is refused with the holder's PID),
builds its results in a staging folder beside the target (`stage_folder`: the files it
keeps from the old folder are hard links, its own files are new) and swaps the staging
folder in at the end. On Linux the swap is one ``renameat2(RENAME_EXCHANGE)`` call, so a
reader sees the old folder or the new one, never files of two runs; where that call is
missing, two renames leave at worst no folder for an instant, and the next writer puts
the old folder back (`lock_folder` recovers it). A run killed before the swap leaves the
old folder untouched; the next writer removes its staging folder.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import errno
import fcntl
import os
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path

from .._core.errors import ConfigError

__all__ = ["FolderLocked", "check_output_folder", "lock_folder", "lock_path", "stage_folder", "swap_in"]

_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


class FolderLocked(ConfigError):
    """Another process holds the output folder's lock (exit status 2 on the command line)."""


def check_output_folder(out_dir: str | os.PathLike, *, label: str | None = None) -> None:
    """ConfigError unless ``out_dir`` is, or can become, a writable folder of its own
    (nothing is created). The results replace the folder as a whole, so it is never the
    folder this process works in or one above it, nor a mount point."""
    out_dir = Path(out_dir)
    label = label or f"--out {out_dir}"
    target = out_dir.absolute()
    existing = target
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise ConfigError(f"{label}: {existing} is a file, not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise ConfigError(f"{label}: cannot write into {existing} (permission denied)")
    real, here = Path(os.path.realpath(target)), Path(os.path.realpath(os.getcwd()))
    if real == here or real in here.parents or (real.exists() and os.path.ismount(real)):
        raise ConfigError(
            f"{label}: results replace their folder as a whole, so they need a folder of "
            f"their own, not the current folder, one above it or a mount point (e.g. --out results/{real.name or 'run'})"
        )


def lock_path(folder: str | os.PathLike) -> Path:
    """The lock file of a result folder: ``.<name>.lock`` beside it (beside the real folder
    when ``folder`` is a symbolic link, so every name of one folder shares one lock)."""
    folder = Path(os.path.realpath(folder))
    return folder.parent / f".{folder.name}.lock"


def _holder(path: Path) -> str:
    try:
        text = path.read_text().strip()
    except OSError:
        return "unknown"
    return text if text.isdigit() else "unknown"


@contextlib.contextmanager
def lock_folder(folder: str | os.PathLike, *, label: str | None = None) -> Iterator[Path]:
    """Hold the advisory write lock of ``folder`` for the ``with`` block.

    The lock is ``flock`` on ``.<name>.lock`` beside the folder (created if needed; its
    text is the holder's PID). The kernel drops it when the holder exits, however it
    ends, so a killed run never leaves a stale lock. On entry, leftovers of an earlier
    writer that was killed are cleaned: its staging folders are removed, and a folder
    it had moved aside during a non-atomic swap is put back.

    Raises:
        FolderLocked: another process holds the lock; the message names its PID.
    """
    folder = Path(os.path.realpath(folder))
    label = label or str(folder)
    folder.parent.mkdir(parents=True, exist_ok=True)
    path = lock_path(folder)
    handle = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as error:
            if error.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise
            raise FolderLocked(
                f"{label}: another spacearm run (PID {_holder(path)}) is writing this folder; "
                f"wait for it to finish or choose another output folder (lock: {path})"
            ) from None
        os.ftruncate(handle, 0)
        os.write(handle, f"{os.getpid()}\n".encode())
        _recover(folder)
        yield folder
    finally:
        os.close(handle)  # closing the descriptor releases the lock


def _recover(folder: Path) -> None:
    """Undo what a killed writer left beside ``folder`` (the caller holds the lock)."""
    aside = sorted(folder.parent.glob(f".{folder.name}.old-*"))
    if aside and not folder.exists():
        os.rename(aside.pop(), folder)
    for leftover in aside + list(folder.parent.glob(f".{folder.name}.staging-*")):
        shutil.rmtree(leftover, ignore_errors=True)


def stage_folder(folder: str | os.PathLike, keep: Callable[[str], bool]) -> Path:
    """A fresh staging folder beside ``folder`` holding the entries of ``folder`` that ``keep``
    accepts (by name, top level only), as hard links (copies where links fail).

    Write the new results into the returned folder, then call `swap_in`.
    """
    folder = Path(os.path.realpath(folder))
    staging = folder.parent / f".{folder.name}.staging-{os.getpid()}"
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir(parents=True)
    if folder.is_dir():
        for entry in folder.iterdir():
            if not keep(entry.name):
                continue
            target = staging / entry.name
            if entry.is_symlink():
                os.symlink(os.readlink(entry), target)
            elif entry.is_dir():
                shutil.copytree(entry, target, symlinks=True, copy_function=_link_or_copy)
            else:
                _link_or_copy(entry, target)
    return staging


def _link_or_copy(source, target) -> None:
    try:
        os.link(source, target)
    except OSError:
        shutil.copy2(source, target)


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths in one step (Linux ``renameat2``); False where the system cannot."""
    libc_name = ctypes.util.find_library("c")
    if not libc_name:
        return False
    try:
        libc = ctypes.CDLL(libc_name, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    renameat2.restype = ctypes.c_int
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False
    raise OSError(code, os.strerror(code), str(b))


def swap_in(staging: str | os.PathLike, folder: str | os.PathLike) -> None:
    """Make ``staging`` the folder ``folder`` in one step, then remove the old folder."""
    staging, folder = Path(staging), Path(os.path.realpath(folder))
    if not folder.exists():
        os.rename(staging, folder)
        return
    if _exchange(staging, folder):
        shutil.rmtree(staging, ignore_errors=True)  # now the old folder
        return
    aside = folder.parent / f".{folder.name}.old-{os.getpid()}"
    os.rename(folder, aside)
    os.rename(staging, folder)
    shutil.rmtree(aside, ignore_errors=True)
