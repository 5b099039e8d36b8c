"""Tests run in float64 (the package itself never flips the global flag on import).

Compiled programs are shared across the session: fixtures that build robots are
session-scoped (their pytrees have the same shapes, so every test hits the same jitted
entry points). They are also shared across sessions: a persistent compilation cache,
kept between runs, lets programs traced again from new closures (each DesignProblem's
objective), in a new process (each command-line subprocess) or in the next run load
instead of compiling. The folder is ``$SPACEARM_TEST_CACHE``, else
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
"""

import collections
import contextlib
import os
import shutil
import tempfile

import jax
import jax.monitoring
import numpy as np
import pytest

jax.config.update("jax_enable_x64", True)

import spacearm as sa  # noqa: E402

_FRESH_DIR_VARIABLE = "SPACEARM_TEST_FRESH_CACHE_DIR"  # set by the controller for pytest-xdist workers
_fresh_dir: str | None = None


def pytest_addoption(parser):
    parser.addoption(
        "--fresh-cache", action="store_true", default=False,
        help="compile into a new, empty JAX cache folder (deleted at the end) instead of the kept one "
             "(also SPACEARM_FRESH_CACHE=1)",
    )


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
    return folder


def pytest_configure(config):
    """Before any test compiles: one cache folder for the session, its subprocesses and its CLI runs."""
    fresh = config.getoption("--fresh-cache") or os.environ.get("SPACEARM_FRESH_CACHE", "") not in ("", "0")
    folder = suite_cache_dir(fresh)
    os.environ["SPACEARM_CACHE_DIR"] = folder
    if sa.enable_compilation_cache(folder) is None:
        raise pytest.UsageError(f"cannot create the test compilation cache folder {folder}")


def pytest_report_header(config):
    return f"spacearm: JAX compilation cache {os.environ.get('SPACEARM_CACHE_DIR')}"


def pytest_sessionfinish(session, exitstatus):
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
