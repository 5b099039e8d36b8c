"""Ctrl-C while ``spacearm`` itself is being imported (JAX loads for seconds) ends the
console script with one line and exit status 130, not a traceback."""

import os
import signal
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ENV = dict(os.environ, PYTHONPATH=str(ROOT / "src") + os.pathsep + os.environ.get("PYTHONPATH", ""))

# Holds the import of jax (the slow part of `import spacearm`) until the test interrupts it:
# the interrupt then lands inside the package's import, every time.
_SLOW_IMPORT = """
import signal, sys, time
# Ctrl-C as from a terminal: a runner started with a shell's & ignores SIGINT, and its
# children inherit that.
signal.signal(signal.SIGINT, signal.default_int_handler)
class HoldJax:
    def find_spec(self, name, path=None, target=None):
        if name == "jax":
            print("importing jax", flush=True)
            for _ in range(600):  # short sleeps: a signal that lands between two is handled at the next
                time.sleep(0.1)
        return None
sys.meta_path.insert(0, HoldJax())
sys.argv = ["spacearm", "info"]
{entry}
sys.exit(console_main())
"""


def interrupt_during_import(entry: str) -> subprocess.CompletedProcess:
    process = subprocess.Popen(
        [sys.executable, "-c", _SLOW_IMPORT.format(entry=entry)],
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stdout.readline().strip() == "importing jax"
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=30)
    finally:
        process.kill()
        process.wait()
    return subprocess.CompletedProcess(process.args, process.returncode, out, err)


def test_ctrl_c_while_spacearm_is_imported_is_one_line_and_exit_130():
    done = interrupt_during_import("from _spacearm_entry import console_main")
    assert done.returncode == 130, done.stderr
    assert done.stderr == "spacearm: interrupted\n"
    # The entry point inside the package cannot catch it: its own import is what runs.
    inside = interrupt_during_import("from spacearm.cli import console_main")
    assert inside.returncode != 130 and "Traceback" in inside.stderr and "KeyboardInterrupt" in inside.stderr


def test_the_console_script_is_the_entry_module_and_runs_commands():
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts == {"spacearm": "_spacearm_entry:console_main"}
    done = subprocess.run(
        [sys.executable, "-c", "import sys, _spacearm_entry; sys.exit(_spacearm_entry.console_main())", "--help"],
        env=ENV,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("usage: spacearm")


@pytest.mark.parametrize("argv", [["validate", "no/such/file.yaml"]])
def test_errors_after_the_import_keep_their_exit_status(argv):
    done = subprocess.run(
        [sys.executable, "-c", "import sys, _spacearm_entry; sys.exit(_spacearm_entry.console_main())", *argv],
        env=ENV,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "no/such/file.yaml" in done.stderr
