"""Result folders that change as a whole or not at all, with one writer at a time.

A run takes `lock_folder` on its output folder (an advisory ``fcntl`` lock on the file
``.<name>.lock`` beside the folder; a second writer is refused with the holder's PID),
refuses a folder that holds another command's results (`claim_folder`),
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
import json
import os
import shutil
import stat
from collections.abc import Callable, Iterator
from pathlib import Path

from .._core.errors import ConfigError

__all__ = [
    "RESULT_KINDS",
    "FolderLocked",
    "check_output_folder",
    "claim_folder",
    "claimed_folder",
    "folder_owner",
    "lock_folder",
    "lock_path",
    "replacing_folder",
    "stage_folder",
    "swap_in",
]

# The commands that write result folders (a manifest's ``kind``).
RESULT_KINDS = ("sweep", "optimize", "reach", "simulate", "capture")

_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


class FolderLocked(ConfigError):
    """Another process holds the output folder's lock (exit status 2 on the command line)."""


def check_output_folder(out_dir: str | os.PathLike, *, label: str | None = None, whole: bool = True) -> None:
    """ConfigError unless ``out_dir`` is, or can become, a writable folder (nothing is
    created). With ``whole`` (results that replace the folder as a whole) it must be a
    folder of its own: never the folder this process works in or one above it, nor a
    mount point."""
    label = label or f"--out {os.fspath(out_dir)!r}"
    if "\0" in os.fspath(out_dir):
        raise ConfigError(f"{label}: a folder name cannot hold a NUL byte")
    target = Path(out_dir).absolute()
    existing = target
    while True:
        try:
            mode = os.stat(existing).st_mode
        except FileNotFoundError:
            existing = existing.parent
            continue
        except OSError as error:  # a loop of symbolic links, a name too long, a path under a file
            raise ConfigError(f"{label}: {error.strerror or error}") from None
        if not stat.S_ISDIR(mode):
            raise ConfigError(f"{label}: {existing} is a file, not a folder")
        break
    if not os.access(existing, os.W_OK | os.X_OK):
        raise ConfigError(f"{label}: cannot write into {existing} (permission denied)")
    if not whole:
        return
    real, here = Path(os.path.realpath(target)), Path(os.path.realpath(os.getcwd()))
    if real == here or real in here.parents or (real.exists() and os.path.ismount(real)):
        raise ConfigError(
            f"{label}: results replace their folder as a whole, so they need a folder of "
            f"their own, not the current folder, one above it or a mount point (e.g. --out results/{real.name or 'run'})"
        )


def folder_owner(folder: str | os.PathLike) -> str | None:
    """Which command's results ``folder`` holds: ``"sweep"``, ``"optimize"``, ``"reach"``, ``"simulate"``,
    ``"capture"``, or None (no folder, or no spacearm results in it).

    Read from the ``kind`` of its ``manifest.json`` (older manifests: a sweep's lists its
    ``n_designs``, an optimization's its ``summary.json``), else from a reach run's ``reach.npz``.
    """
    folder = Path(folder)
    manifest = _small_json(folder / "manifest.json")
    if isinstance(manifest, dict):
        kind = manifest.get("kind")
        if kind in RESULT_KINDS:
            return kind
        if "n_designs" in manifest:
            return "sweep"
        if "summary.json" in (manifest.get("files") or []):
            return "optimize"
    return "reach" if (folder / "reach.npz").is_file() else None


def claim_folder(folder: str | os.PathLike, kind: str, *, label: str | None = None) -> None:
    """ConfigError when ``folder`` holds the results of another command than ``kind``: a
    run replaces its own earlier results, never another command's."""
    owner = folder_owner(folder)
    if owner not in (None, kind):
        raise ConfigError(
            f"{label or folder}: holds the results of 'spacearm {owner}', which 'spacearm {kind}' would "
            "replace; choose another output folder"
        )


def _small_json(path: Path, limit: int = 1 << 24):
    """The JSON in a regular file of at most ``limit`` bytes, or None."""
    try:
        with open(
            path, "rb", opener=lambda name, flags: os.open(name, flags | os.O_NOFOLLOW | os.O_NONBLOCK)
        ) as handle:
            if not stat.S_ISREG(os.fstat(handle.fileno()).st_mode):
                return None
            text = handle.read(limit + 1)
        return json.loads(text) if len(text) <= limit else None
    except (OSError, ValueError):
        return None


def lock_path(folder: str | os.PathLike) -> Path:
    """The lock file of a result folder: ``.<name>.lock`` beside it (beside the real folder
    when ``folder`` is a symbolic link, so every name of one folder shares one lock)."""
    folder = Path(os.path.realpath(folder))
    return folder.parent / f".{folder.name}.lock"


def _holder(handle: int) -> str:
    try:
        text = os.pread(handle, 32, 0).decode("ascii").strip()
    except (OSError, UnicodeDecodeError):
        return "unknown"
    return text if text.isdigit() else "unknown"


@contextlib.contextmanager
def lock_folder(folder: str | os.PathLike, *, label: str | None = None) -> Iterator[Path]:
    """Hold the advisory write lock of ``folder`` for the ``with`` block.

    The lock is ``flock`` on ``.<name>.lock`` beside the folder: a regular file of ours
    holding the holder's PID, created if needed and removed on release. The kernel drops
    the lock when the holder exits, however it ends, so a killed run never leaves a stale
    lock. A symbolic link, a hard link, another user's file or a file with other contents
    at that name is refused, never followed or overwritten. On entry, leftovers of an
    earlier writer that was killed are cleaned: its staging folders are removed, and a
    folder it had moved aside during a non-atomic swap is put back.

    Raises:
        FolderLocked: another process holds the lock; the message names its PID.
        ConfigError: the lock's name holds something that is not a spacearm lock.
    """
    folder = Path(os.path.realpath(folder))
    label = label or str(folder)
    folder.parent.mkdir(parents=True, exist_ok=True)
    path = lock_path(folder)
    handle = _take_lock(path, label)
    try:
        os.ftruncate(handle, 0)  # ours: a regular file of one link holding at most a PID
        os.write(handle, f"{os.getpid()}\n".encode())
        _recover(folder)
        yield folder
    finally:
        # Removed while still held: a process that opened the old file finds it gone
        # (its inode check below fails) and opens the new one.
        with contextlib.suppress(OSError):
            if _same_file(os.fstat(handle), os.lstat(path)):
                os.unlink(path)
        os.close(handle)  # closing the descriptor releases the lock


def _take_lock(path: Path, label: str) -> int:
    """An open descriptor of the lock file ``path``, locked (`lock_folder`)."""
    while True:
        try:
            handle = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC, 0o644)
        except OSError as error:
            why = "a symbolic link" if error.errno == errno.ELOOP else (error.strerror or str(error))
            raise ConfigError(f"{label}: cannot use the lock file {path}: {why}; remove it") from None
        try:
            _check_lock_file(handle, path, label)
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as error:
                if error.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    raise
                raise FolderLocked(
                    f"{label}: another spacearm run (PID {_holder(handle)}) is writing this folder; "
                    f"wait for it to finish or choose another output folder (lock: {path})"
                ) from None
            try:
                current = os.lstat(path)
            except FileNotFoundError:
                current = None
            if current is not None and _same_file(os.fstat(handle), current):
                return handle
        except BaseException:
            os.close(handle)
            raise
        os.close(handle)  # the holder removed it as we opened it: take the new one


def _check_lock_file(handle: int, path: Path, label: str) -> None:
    info = os.fstat(handle)
    text = os.pread(handle, 64, 0) if stat.S_ISREG(info.st_mode) else b""
    if (
        not stat.S_ISREG(info.st_mode)
        or info.st_nlink > 1
        or info.st_uid != os.geteuid()
        or info.st_size > 32
        or (not text.strip().isdigit() and text.strip())
    ):
        raise ConfigError(f"{label}: {path} is not a spacearm lock file (a lock holds only a PID); remove it")


def _same_file(a: os.stat_result, b: os.stat_result) -> bool:
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


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
        os.chmod(staging, stat.S_IMODE(folder.stat().st_mode))  # the swap keeps the folder's mode
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


@contextlib.contextmanager
def claimed_folder(folder: str | os.PathLike, kind: str, *, label: str | None = None) -> Iterator[Path]:
    """Hold ``folder``'s write lock (`lock_folder`) for the ``with`` block, once `claim_folder`
    finds no other command's results in it: how every command that writes a results
    folder starts, before it computes anything, so a refused run costs nothing.

    Raises:
        FolderLocked: another process holds the lock.
        ConfigError: ``folder`` holds another command's results.
    """
    with lock_folder(folder, label=label):
        claim_folder(folder, kind, label=label)
        yield Path(folder)


@contextlib.contextmanager
def replacing_folder(
    folder: str | os.PathLike, *, keep: Callable[[str], bool], before_swap: Callable[[Path], None] | None = None
) -> Iterator[Path]:
    """A staging folder beside ``folder`` (`stage_folder`, with the entries ``keep``
    accepts) that replaces ``folder`` in one step (`swap_in`) when the ``with`` block ends
    without an error, and is removed when it fails: a reader never sees files of two runs,
    and a run that dies first leaves the old folder as it was. The caller holds the lock
    (`claimed_folder`).

    Args:
        before_swap: called with the staging folder right before the swap (a test hook:
            the fault-injection tests kill the run there).
    """
    staging = stage_folder(folder, keep)
    try:
        yield staging
        if before_swap is not None:
            before_swap(staging)
        swap_in(staging, folder)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
