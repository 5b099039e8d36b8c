"""Tests run in float64 (the package itself never flips the global flag on import).

Compiled programs are shared across the session: fixtures that build robots are
session-scoped (their pytrees have the same shapes, so every test hits the same jitted
entry points). They are also shared across sessions: a persistent compilation cache,
kept between runs, lets programs traced again from new closures (each DesignProblem's
objective), in a new process (each command-line subprocess) or in the next run load
instead of compiling (``SPACEARM_TEST_IN_PROCESS_CACHE=0`` leaves the test processes
themselves out: only subprocesses use it then). The folder is ``$SPACEARM_TEST_CACHE``, else
``$XDG_CACHE_HOME/spacearm-tests`` (``~/.cache/spacearm-tests``); ``--fresh-cache`` or
``SPACEARM_FRESH_CACHE=1`` uses a new empty folder instead, deleted at the end (what a
first run on a clean machine costs). The command-line tests call spacearm.cli.main,
which enables the cache at ``$SPACEARM_CACHE_DIR``: it is set to the same folder, so they
never write into the user's ``~/.cache/spacearm``.

A warm cache cannot hide a recompilation bug: the no-recompilation tests count
compilations in memory (``_cache_size``, and :func:`count_compiles`, which also counts a
program loaded from disk, since it missed its jitted function's in-memory cache), and
neither depends on the persistent cache. JAX keys each entry by the program, its
compile options and the JAX version, so an edited kernel never loads a stale program.

The same kept folder records each test's CPU seconds in its last run
(``test-cpu-seconds.json``); ``--fast`` leaves out the tests marked ``slow`` and those
that took more than ``--fast-limit`` (5 s) there, for the edit-test loop. CI runs all.
It also keeps the documentation site tests/test_docs.py last built, under a digest of
the sources it was built from.
"""

import collections
import contextlib
import glob
import json
import os
import shutil
import tempfile

import jax
import jax.monitoring
import numpy as np
import pytest

jax.config.update("jax_enable_x64", True)

import spacearm as sa
import spacearm.cli

_FRESH_DIR_VARIABLE = "SPACEARM_TEST_FRESH_CACHE_DIR"  # set by the controller for pytest-xdist workers
_fresh_dir: str | None = None
_record_folder = ""  # the kept (or fresh) cache folder; workers compile into subfolders of it
_CPU_RECORD = "test-cpu-seconds.json"  # in the kept cache folder: each test's CPU seconds in its last run
_cpu_seconds: dict[str, float] = {}


def pytest_addoption(parser):
    parser.addoption(
        "--fresh-cache",
        action="store_true",
        default=False,
        help="compile into a new, empty JAX cache folder (deleted at the end) instead of the kept one "
        "(also SPACEARM_FRESH_CACHE=1)",
    )
    parser.addoption(
        "--fast",
        action="store_true",
        default=False,
        help="the edit-test loop: leave out tests marked slow and those that took more than --fast-limit "
        "CPU seconds when they last ran (recorded in the kept cache folder)",
    )
    parser.addoption("--fast-limit", type=float, default=5.0, help="CPU seconds for --fast (default 5)")


def suite_cache_dir(fresh: bool) -> str:
    """The test suite's compilation cache folder (module docstring); a new temporary one when ``fresh``."""
    global _fresh_dir
    if fresh:
        inherited = os.environ.get(_FRESH_DIR_VARIABLE)
        if inherited:  # a pytest-xdist worker shares its controller's fresh folder
            return inherited
        _fresh_dir = tempfile.mkdtemp(prefix="spacearm-test-jax-cache-")
        os.environ[_FRESH_DIR_VARIABLE] = _fresh_dir
        return _fresh_dir
    folder = os.environ.get("SPACEARM_TEST_CACHE")
    if not folder:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        folder = os.path.join(base, "spacearm-tests")
    return os.path.abspath(folder)  # tests that change directory must not move it


def pytest_configure(config):
    """Before any test compiles: one cache folder for the session, its subprocesses and its CLI runs."""
    fresh = config.getoption("--fresh-cache") or os.environ.get("SPACEARM_FRESH_CACHE", "") not in ("", "0")
    global _record_folder
    _record_folder = suite_cache_dir(fresh)
    folder = _record_folder
    os.makedirs(folder, exist_ok=True)
    os.environ["SPACEARM_CACHE_DIR"] = folder  # subprocesses and CLI runs share the cache
    # SPACEARM_TEST_IN_PROCESS_CACHE=0: the test processes compile everything themselves
    # (short-lived subprocesses still use the cache), to tell a cache problem from others.
    if os.environ.get("SPACEARM_TEST_IN_PROCESS_CACHE", "1") == "0":
        # The command line enables the cache when it starts; called in-process by the
        # tests, it must not turn it on for the rest of the worker's life.
        spacearm.cli.enable_compilation_cache = lambda *args, **kwargs: None
        return
    if sa.enable_compilation_cache(folder) is None:
        raise pytest.UsageError(f"cannot create the test compilation cache folder {folder}")


def pytest_report_header(config):
    return f"spacearm: JAX compilation cache {os.environ.get('SPACEARM_CACHE_DIR')}"


def _record_path(config) -> str | None:
    """Where each test's CPU seconds are kept; None for a fresh cache (cold numbers, not kept)."""
    if config.getoption("--fresh-cache") or os.environ.get(_FRESH_DIR_VARIABLE):
        return None
    return os.path.join(_record_folder, _CPU_RECORD)


def _read_record(path: str) -> dict[str, float]:
    try:
        with open(path) as file:
            return {str(k): float(v) for k, v in json.load(file).items()}
    except (OSError, ValueError, AttributeError):
        return {}


def _write_record(path: str, record: dict[str, float]) -> None:
    scratch = f"{path}.{os.getpid()}.tmp"
    with open(scratch, "w") as file:
        json.dump(record, file, indent=0, sort_keys=True)
    os.replace(scratch, path)


def pytest_collection_modifyitems(config, items):
    """``--fast``: deselect the slow-marked tests and those over ``--fast-limit`` CPU seconds last time."""
    if not config.getoption("--fast"):
        return
    path = _record_path(config)
    record = _read_record(path) if path else {}
    limit = config.getoption("--fast-limit")
    keep, drop = [], []
    for item in items:
        slow = item.get_closest_marker("slow") is not None or record.get(item.nodeid, 0.0) > limit
        (drop if slow else keep).append(item)
    if drop:
        config.hook.pytest_deselected(items=drop)
        items[:] = keep


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """Each test's CPU seconds (set-up, call and tear-down; this process, its threads and the
    subprocesses it waited for)."""
    start = _cpu_now()
    yield
    _cpu_seconds[item.nodeid] = _cpu_now() - start
    if nextitem is None or nextitem.path != item.path or _cpu_seconds[item.nodeid] > 5.0:
        _release_programs_near_map_limit()


# Every compiled XLA:CPU program holds about three memory mappings until it is dropped, and
# a long-lived test process keeps thousands (one pytest-xdist worker held 64,264 when it
# aborted inside XLA's compiler: Linux refuses mappings past vm.max_map_count, 65,530 by
# default, and XLA then aborts or segfaults). Between files, and after a test that took
# more than 5 s, the compiled programs are dropped once the count passes a third of the
# limit; the next test compiles what it needs again.


def _memory_map_count() -> int:
    try:
        with open("/proc/self/maps", "rb") as maps:
            return sum(chunk.count(b"\n") for chunk in iter(lambda: maps.read(1 << 20), b""))
    except OSError:  # not Linux
        return 0


def _map_limit() -> int:
    try:
        with open("/proc/sys/vm/max_map_count") as limit:
            return int(limit.read())
    except (OSError, ValueError):
        return 65530


_MAP_LIMIT = _map_limit()


def _release_programs_near_map_limit() -> None:
    if _memory_map_count() > _MAP_LIMIT // 3:
        jax.clear_caches()


def _cpu_now() -> float:
    times = os.times()
    return times.user + times.system + times.children_user + times.children_system


def pytest_sessionfinish(session, exitstatus):
    path = _record_path(session.config)
    if path and _cpu_seconds:
        worker = os.environ.get("PYTEST_XDIST_WORKER")
        if worker:  # the controller merges the workers' parts
            _write_record(f"{path}.{worker}", _cpu_seconds)
        else:
            _write_record(path, {**_read_record(path), **_cpu_seconds})
    if path and not os.environ.get("PYTEST_XDIST_WORKER"):
        parts = glob.glob(f"{glob.escape(path)}.gw*")
        if parts:
            record = _read_record(path)
            for part in parts:
                record.update(_read_record(part))
                os.remove(part)
            _write_record(path, record)
    if _fresh_dir is not None:  # only the process that created it (the controller under xdist)
        shutil.rmtree(_fresh_dir, ignore_errors=True)


_BACKEND_COMPILE = "/jax/core/compile/backend_compile_duration"


@contextlib.contextmanager
def count_compiles():
    """Count the XLA programs built inside the block, by function name.

    Yields a ``collections.Counter``; a program loaded from the persistent cache counts
    too (it missed the in-memory cache of its jitted function, i.e. it was traced again).
    """
    counts = collections.Counter()

    def listen(event, seconds, **kwargs):
        if event == _BACKEND_COMPILE:
            counts[kwargs.get("fun_name", "?")] += 1

    jax.monitoring.register_event_duration_secs_listener(listen)
    try:
        yield counts
    finally:
        jax.monitoring.unregister_event_duration_listener(listen)


@pytest.fixture(scope="session")
def table1():
    """The Table 1 robot of Umetani & Yoshida 1990 (one pytree for the whole session)."""
    return sa.umetani1990()


def random_robot(rng: np.random.Generator, n: int, name: str = "random") -> sa.PlanarRobot:
    """A random valid design with n links (masses 10-1000 kg, lengths 0.3-3 m)."""
    a = rng.uniform(0.1, 1.5, n)
    b = rng.uniform(0.1, 1.5, n)
    m = rng.uniform(10.0, 200.0, n)
    inertia = m * (a + b) ** 2 / 12.0 * rng.uniform(0.5, 2.0, n)
    m0 = rng.uniform(100.0, 2000.0)
    return sa.PlanarRobot(
        base_mass=np.float64(m0),
        base_inertia=np.float64(m0 * rng.uniform(0.2, 2.0)),
        base_attach=np.float64(rng.uniform(0.0, 2.5)),
        link_mass=m,
        link_inertia=inertia,
        link_a=a,
        link_b=b,
        name=name,
    )
