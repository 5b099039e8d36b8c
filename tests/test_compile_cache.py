"""The persistent compilation cache: off on import, on by one explicit call, at $SPACEARM_CACHE_DIR."""

import os
import subprocess
import sys

from spacearm._core.numeric import compilation_cache_dir


def test_cache_folder_precedence(monkeypatch, tmp_path):
    monkeypatch.delenv("SPACEARM_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert compilation_cache_dir() == os.path.join(str(tmp_path / "xdg"), "spacearm", "jax")
    monkeypatch.setenv("SPACEARM_CACHE_DIR", str(tmp_path / "env"))
    assert compilation_cache_dir() == str(tmp_path / "env")
    assert compilation_cache_dir(tmp_path / "arg") == str(tmp_path / "arg")  # an explicit folder wins
    assert compilation_cache_dir("off") is None
    monkeypatch.setenv("SPACEARM_CACHE_DIR", "off")  # the user's opt-out wins over a program's folder
    assert compilation_cache_dir(tmp_path / "arg") is None


def test_import_changes_nothing_and_enabling_honours_the_environment(tmp_path):
    """`import spacearm` leaves JAX's cache off; `sa.enable_compilation_cache()` opens
    $SPACEARM_CACHE_DIR, and a compiled program lands there as a file."""
    folder = tmp_path / "cache"
    code = (
        "import jax, jax.numpy as jnp, os, spacearm as sa\n"
        "assert jax.config.jax_compilation_cache_dir is None, jax.config.jax_compilation_cache_dir\n"
        "path = sa.enable_compilation_cache(min_compile_seconds=0.0)\n"
        "assert path == os.environ['SPACEARM_CACHE_DIR'] == jax.config.jax_compilation_cache_dir, path\n"
        "jax.jit(lambda x: jnp.sin(x) * 3.0)(jnp.arange(5.0)).block_until_ready()\n"
    )
    env = dict(os.environ, SPACEARM_CACHE_DIR=str(folder))
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert any(name.startswith("jit__lambda-") for name in os.listdir(folder)), os.listdir(folder)


def test_empty_entries_a_full_disk_left_are_removed_so_the_program_is_cached_again(tmp_path):
    """Before: each empty entry made every later run warn and compile again, never replaced."""
    folder = tmp_path / "cache"
    code = (
        "import jax, jax.numpy as jnp, spacearm as sa\n"
        "sa.enable_compilation_cache(min_compile_seconds=0.0)\n"
        "jax.jit(lambda x: jnp.cos(x) * 2.0)(jnp.arange(5.0)).block_until_ready()\n"
    )
    env = dict(os.environ, SPACEARM_CACHE_DIR=str(folder))
    first = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert first.returncode == 0, first.stderr
    (entry,) = [name for name in os.listdir(folder) if name.startswith("jit__lambda-") and name.endswith("-cache")]
    (folder / entry).write_bytes(b"")  # what a write onto a full disk leaves
    (folder / "notes-cache.txt").write_bytes(b"")  # not an entry: kept
    again = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    assert "Traceback" not in again.stderr and "WARNING" not in again.stderr, again.stderr
    assert (folder / entry).stat().st_size > 0  # compiled once more and written whole
    assert (folder / "notes-cache.txt").exists()
