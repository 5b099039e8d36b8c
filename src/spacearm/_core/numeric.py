"""Numeric settings, applied only when called: importing spacearm changes no JAX setting."""

from __future__ import annotations

import contextlib
import importlib.metadata
import math
import os
import sys
import threading
import time

import jax

from .errors import RunError, Stalled


def enable_x64(enabled: bool = True) -> None:
    """Turn JAX's float64 mode on (or off). The command line calls this; library users call it once."""
    jax.config.update("jax_enable_x64", bool(enabled))


def x64_enabled() -> bool:
    """Whether JAX currently creates float64 arrays by default."""
    return bool(jax.config.jax_enable_x64)


def compilation_cache_dir(path: str | os.PathLike | None = None) -> str | None:
    """The folder `enable_compilation_cache` would use, or None when the cache is off.

    ``SPACEARM_CACHE_DIR=off`` turns it off whatever the caller asks; otherwise ``path``,
    else ``$SPACEARM_CACHE_DIR``, else ``$XDG_CACHE_HOME/spacearm/jax`` (``~/.cache/spacearm/jax``).
    """
    env = os.environ.get("SPACEARM_CACHE_DIR")
    if env == "off" or (path is not None and os.fspath(path) == "off"):
        return None
    if path is not None:
        return os.fspath(path)
    if env:
        return env
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "spacearm", "jax")


def enable_compilation_cache(path: str | os.PathLike | None = None, *, min_compile_seconds: float = 0.0) -> str | None:
    """Keep compiled XLA programs on disk, so the next process loads them instead of compiling.

    Importing spacearm changes no JAX setting; this call does (the command line makes it
    for every command): it sets JAX's persistent compilation cache folder and its
    threshold (``jax_compilation_cache_dir``, ``jax_persistent_cache_min_compile_time_secs``).
    Call it once, before the first computation: programs compiled earlier are not kept,
    and JAX keeps the first folder it opened.

    Args:
        path: the folder; default ``$SPACEARM_CACHE_DIR``, else
            ``$XDG_CACHE_HOME/spacearm/jax`` (or ``~/.cache/spacearm/jax``).
            ``SPACEARM_CACHE_DIR=off`` (or ``path="off"``) leaves the cache off.
        min_compile_seconds: programs that compile faster are not written. By default
            every program is kept: loading even a tiny program (an eager operation, a
            few kB on disk) is much cheaper than compiling it.

    Empty program files in the folder (left by a full disk) are removed.

    Returns:
        The folder, or None when the cache stays off (``off``, or a folder that cannot
        be created).
    """
    folder = compilation_cache_dir(path)
    if folder is None:
        return None
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError:
        return None
    _drop_empty_entries(folder)
    jax.config.update("jax_compilation_cache_dir", folder)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", float(min_compile_seconds))
    return folder


def _drop_empty_entries(folder: str) -> None:
    """Remove empty program files that a full disk left in the cache: JAX would warn about
    each on every later run and compile the program again without replacing it."""
    with contextlib.suppress(OSError), os.scandir(folder) as entries:
        for entry in entries:
            with contextlib.suppress(OSError):
                if entry.name.endswith("-cache") and entry.is_file(follow_symlinks=False) and not entry.stat().st_size:
                    os.unlink(entry.path)


PEER_TIMEOUT_S = 60.0  # how long a process of a distributed job waits for its peers


def join_processes(coordinator: str, num_processes: int, process_id: int, *, timeout_s: float = PEER_TIMEOUT_S) -> None:
    """Join ``num_processes`` processes into one JAX job (``jax.distributed``), CPU
    collectives over gloo, so ``jax.devices()`` spans every process and a sharded
    ``jit`` runs across them. Call before anything starts JAX's backend.

    Args:
        coordinator: ``HOST:PORT`` of process 0 (every process gives the same address).
        num_processes: how many processes join.
        process_id: this process's rank, 0 .. num_processes - 1.
        timeout_s: how long to wait for every peer to join; a silent peer is declared dead
            by the coordination service after twice that (its heartbeat timeout).

    Raises:
        RunError: the peers did not all join within ``timeout_s``.
    """
    jax.config.update("jax_cpu_collectives_implementation", "gloo")
    seconds = max(1, int(math.ceil(timeout_s)))
    message = (
        f"process {process_id} of {num_processes}: the processes did not all join at {coordinator} within "
        f"{seconds} s (start every process, or wait longer with --peer-timeout)"
    )
    # jaxlib's own connect timeout ends the process with a C++ stack (a fatal log), so this
    # process keeps its own clock, a little shorter, and leaves with one line instead.
    joined = threading.Event()

    def give_up() -> None:
        if not joined.wait(seconds):
            print(f"spacearm: error: {message}", file=sys.stderr, flush=True)
            os._exit(1)

    threading.Thread(target=give_up, name="spacearm-join-timeout", daemon=True).start()
    try:
        jax.distributed.initialize(
            coordinator_address=coordinator,
            num_processes=num_processes,
            process_id=process_id,
            initialization_timeout=seconds + 30,
            # twice the wait: a peer that is gone is reported by spacearm's own
            # waits (one line) before the service's heartbeat check aborts the process
            heartbeat_timeout_seconds=2 * seconds,
            shutdown_timeout_seconds=seconds,
        )
    except Exception as error:  # jaxlib's runtime error (UNAVAILABLE, ...)
        reason = (str(error).strip().splitlines() or [type(error).__name__])[0][:200]
        raise RunError(f"{message}; {reason}") from None
    finally:
        joined.set()


# jaxlib releases whose batched LAPACK kernels wait for their chunks on XLA's intra-op
# thread pool: with as many CPU devices as pool threads, each device blocks one thread and
# none is left to run the chunks (see pyproject.toml, which excludes them).
_POOL_DEADLOCK_JAXLIB = frozenset({"0.10.0", "0.10.1", "0.10.2"})

STALL_S = 120.0  # how long a wait for the devices may go without this process using CPU


def devices_share_a_deadlock() -> bool:
    """Whether the installed jaxlib deadlocks several CPU devices of one process."""
    try:
        return importlib.metadata.version("jaxlib") in _POOL_DEADLOCK_JAXLIB
    except importlib.metadata.PackageNotFoundError:
        return False


def wait_until_ready(tree, what: str, *, stall_s: float = STALL_S) -> None:
    """Block until every JAX array in ``tree`` is computed.

    A computation in progress uses CPU; one whose threads all sleep never ends. The wait
    watches this process's CPU time and raises `Stalled` naming ``what`` once ``stall_s``
    seconds pass without any.

    Raises:
        Stalled: no CPU used for ``stall_s`` seconds before the arrays were ready.
    """
    arrays = [leaf for leaf in jax.tree_util.tree_leaves(tree) if hasattr(leaf, "is_ready")]
    cpu, since = time.process_time(), time.monotonic()
    pause = 1e-3
    while not all(array.is_ready() for array in arrays):
        time.sleep(pause)
        pause = min(2 * pause, 0.25)
        now = time.process_time()
        if now - cpu > 0.05:  # the polling itself costs microseconds
            cpu, since = now, time.monotonic()
        elif time.monotonic() - since > stall_s:
            raise Stalled(
                f"{what}: no progress in {stall_s:g} s (every thread asleep: the devices deadlocked); "
                "finished work is kept; rerun with one device (XLA_FLAGS=--xla_force_host_platform_device_count=1)"
            )


def use_every_cpu_core() -> int:
    """Expose each CPU core as a JAX device, so sweeps shard their designs over all cores.

    XLA runs most of a CPU program on one thread; with one host device per core the
    sweep's sharded chunks run side by side (docs/guide/performance.md). Only effective
    before JAX starts its backend, and only when ``XLA_FLAGS`` does not already set the
    count (so an explicit setting always wins) and the installed jaxlib does not deadlock
    several CPU devices (`devices_share_a_deadlock`). Returns the number of cores asked for.
    """
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_force_host_platform_device_count" in flags or devices_share_a_deadlock():
        return 0
    count = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    count = min(count, _cgroup_cpu_limit() or count)
    if count > 1:
        os.environ["XLA_FLAGS"] = f"{flags} --xla_force_host_platform_device_count={count}".strip()
    return count


def _cgroup_cpu_limit() -> int | None:
    """The CPU quota of this container (cgroup v2 ``cpu.max``), rounded up; None when unlimited."""
    try:
        with open("/sys/fs/cgroup/cpu.max") as limits:
            quota, period = limits.read().split()[:2]
    except (OSError, ValueError):
        return None
    if quota == "max":
        return None
    return max(1, -(-int(quota) // int(period)))
