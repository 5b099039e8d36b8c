"""Tests run in float64 (the package itself never flips the global flag on import).

Compiled programs are shared across the session: fixtures that build robots are
session-scoped (their pytrees have the same shapes, so every test hits the same jitted
entry points), and a persistent compilation cache in a temporary folder lets programs
that are traced again from new closures (e.g. each DesignProblem's objective, each
command-line run) load instead of compiling. The folder is new per session, so a
recompilation bug cannot hide behind a cache filled by an earlier run; the
no-recompilation tests count compilations in memory (``_cache_size`` and
:func:`count_compiles`), which the persistent cache does not change.
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

# Before any test compiles: the command-line tests call spacearm.cli.main, which enables
# the cache at $SPACEARM_CACHE_DIR, so they share this folder too (and never write into
# the user's ~/.cache).
_CACHE_DIR = tempfile.mkdtemp(prefix="spacearm-test-jax-cache-")
os.environ["SPACEARM_CACHE_DIR"] = _CACHE_DIR
jax.config.update("jax_compilation_cache_dir", _CACHE_DIR)
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.2)

import spacearm as sa  # noqa: E402

_BACKEND_COMPILE = "/jax/core/compile/backend_compile_duration"


def pytest_sessionfinish(session, exitstatus):
    shutil.rmtree(_CACHE_DIR, ignore_errors=True)


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
