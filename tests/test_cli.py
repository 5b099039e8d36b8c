"""The command line's shape: one module per command, a light --help, the removed module paths."""

import importlib
import subprocess
import sys

import pytest

import spacearm.cli
from spacearm.cli import COMMANDS, build_parser, main


def test_help_loads_no_heavy_layer():
    """`spacearm --help` and building the parser import neither optax nor the design, studies
    or figures layers (nor matplotlib); each command loads those when it runs."""
    code = (
        "import sys\n"
        "from spacearm.cli import build_parser\n"
        "build_parser()\n"
        "heavy = [m for m in sys.modules if m.split('.')[0] in ('optax', 'matplotlib', 'pymoo') "
        "or m.startswith(('spacearm.design', 'spacearm.studies', 'spacearm.figures', 'spacearm.analysis', "
        "'spacearm.planning'))]\n"
        "print(heavy)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"
    help_text = subprocess.run([sys.executable, "-m", "spacearm.cli", "--help"], capture_output=True, text=True).stdout
    for name, _ in COMMANDS:
        assert f"    {name} " in help_text


@pytest.mark.parametrize("name", [name for name, _ in COMMANDS])
def test_every_command_prints_its_help(name, capsys):
    with pytest.raises(SystemExit) as stop:
        main([name, "--help"])
    assert stop.value.code == 0
    out = capsys.readouterr().out
    assert f"usage: spacearm {name}" in out and "--float32" in out


def test_sweep_help_lists_fields_and_metrics(capsys):
    with pytest.raises(SystemExit):
        main(["sweep", "--help"])
    out = capsys.readouterr().out
    assert "design fields for axes" in out and "base.mass" in out and "workspace_areas" in out


def test_each_command_module_has_register_and_run():
    parser = build_parser()
    assert parser.prog == "spacearm"
    for _, module in COMMANDS:
        loaded = importlib.import_module(module)
        assert callable(loaded.register) and callable(loaded.run)


@pytest.mark.parametrize("old", ["robot", "metrics", "workspace", "sweep", "results", "reports", "validate", "config"])
def test_removed_module_paths_are_gone(old):
    """The one-release re-export modules are deleted: an old import fails loudly instead of
    silently serving a renamed function (``workspace.normalized_areas`` did)."""
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module(f"spacearm.{old}")


def test_an_interrupt_inside_an_import_is_one_line_and_exit_130(monkeypatch, capsys):
    """Ctrl-C while an extension module initializes reaches the command as the ImportError it
    caused (seen from matplotlib's Agg renderer: "initialization failed"): still exit 130 and
    one line. An ImportError with no interrupt behind it is not swallowed."""

    def interrupted_import():
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as interrupt:
            raise ImportError("initialization failed") from interrupt

    monkeypatch.setattr(spacearm.cli, "_draw_into_files", interrupted_import)
    assert main(["validate", "configs/umetani1990.yaml"]) == 130
    err = capsys.readouterr().err
    assert err == "spacearm validate: interrupted\n"

    def broken_import():
        raise ImportError("initialization failed")

    monkeypatch.setattr(spacearm.cli, "_draw_into_files", broken_import)
    with pytest.raises(ImportError, match="initialization failed"):
        main(["validate", "configs/umetani1990.yaml"])
