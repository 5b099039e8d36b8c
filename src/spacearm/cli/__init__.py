"""The ``spacearm`` command line: one console script, one module per command.

Every command is a module here with ``register(subparsers)`` (its arguments and help,
importing nothing heavy) and ``run(args)`` (which imports the library layers it needs),
named in `COMMANDS`. Building the parser imports only these light modules, so
``spacearm --help`` loads neither optax nor the design or studies layers; a command's
library layers are imported when it runs.

Every command runs in float64 unless ``--float32``. Invalid input ends with exit
status 2 and a one-line message naming the field and the reason; a run that cannot
finish correctly (a non-finite result, a full disk, a peer process gone) with exit
status 1 and one line; Ctrl-C with 130. Never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from .._core.errors import ConfigError, RunError
from .._core.numeric import enable_compilation_cache, enable_x64, use_every_cpu_core

__all__ = ["COMMANDS", "EXIT_FAILED", "EXIT_INVALID", "build_parser", "console_main", "main"]

EXIT_INVALID = 2
EXIT_FAILED = 1

# Every command: (name, module with register(subparsers) and run(args)), in help order.
COMMANDS: tuple[tuple[str, str], ...] = (
    ("validate", "spacearm.cli.validate"),
    ("info", "spacearm.cli.info"),
    ("sweep", "spacearm.cli.sweep"),
    ("figures", "spacearm.cli.figures"),
    ("reach", "spacearm.cli.reach"),
    ("optimize", "spacearm.cli.optimize"),
    ("view", "spacearm.cli.view"),
    ("simulate", "spacearm.cli.simulate"),
    ("capture", "spacearm.cli.capture"),
)

_FLOAT32_HELP = "compute in float32 (faster, less exact); default float64"


def build_parser() -> argparse.ArgumentParser:
    """The parser of every command (imports only the light command modules)."""
    parser = argparse.ArgumentParser(
        prog="spacearm",
        description=(
            "Workspace and manipulability of manipulators on free-floating spacecraft "
            "(Umetani & Yoshida 1990, generalized to n links)."
        ),
    )
    parser.add_argument("--float32", action="store_true", help=_FLOAT32_HELP)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for _name, module in COMMANDS:
        importlib.import_module(module).register(sub)
    for command in sub.choices.values():  # also accepted after the command
        command.add_argument("--float32", action="store_true", default=argparse.SUPPRESS, help=_FLOAT32_HELP)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; return its exit status (2 for invalid input, 1 when a run fails,
    130 when interrupted). Every error is one line on stderr, never a traceback."""
    name = "spacearm"
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        name = f"spacearm {args.command}"
        enable_x64(not args.float32)
        enable_compilation_cache()
        _draw_into_files()
        command = importlib.import_module(dict(COMMANDS)[args.command])
        return int(command.run(args) or 0)
    except ConfigError as error:
        print(f"{name}: error: {_one_line(error)}", file=sys.stderr)
        return EXIT_INVALID
    except RunError as error:
        print(f"{name}: error: {_one_line(error)}", file=sys.stderr)
        return EXIT_FAILED
    except KeyboardInterrupt:  # also during start-up (imports, parsing)
        print(f"{name}: interrupted", file=sys.stderr)
        return 130
    except RecursionError:
        print(f"{name}: error: the input nests too deeply", file=sys.stderr)
        return EXIT_INVALID
    except MemoryError:
        print(
            f"{name}: error: out of memory; make the run smaller (fewer designs, a smaller chunk_size)", file=sys.stderr
        )
        return EXIT_FAILED
    except OSError as error:  # a read-only or full disk under --out, a vanished file
        where = f"{error.filename}: " if error.filename else ""
        print(f"{name}: error: {where}{error.strerror or error}", file=sys.stderr)
        return EXIT_FAILED
    except Exception as error:
        if not _caused_by_interrupt(error):
            raise
        # Ctrl-C inside an extension module's import surfaces as the ImportError it caused
        # (matplotlib's Agg renderer: "initialization failed"): still an interrupt.
        print(f"{name}: interrupted", file=sys.stderr)
        return 130


def _caused_by_interrupt(error: BaseException) -> bool:
    """Whether a KeyboardInterrupt is in the chain of causes and contexts of ``error``."""
    seen = set()
    while error is not None and id(error) not in seen:
        if isinstance(error, KeyboardInterrupt):
            return True
        seen.add(id(error))
        error = error.__cause__ or error.__context__
    return False


def _one_line(error: BaseException, limit: int = 2000) -> str:
    """The message on one line, at most ``limit`` characters."""
    text = " ".join(str(error).split("\n"))
    return text if len(text) <= limit else text[: limit - 15] + " ... (shortened)"


def _draw_into_files() -> None:
    """Figures are written to files: matplotlib's Agg backend, chosen before pyplot loads
    (the figures layer leaves the backend to its caller, as it leaves the precision)."""
    import matplotlib

    matplotlib.use("Agg")


def console_main() -> int:
    """The ``spacearm`` console script: `main` with one JAX device per CPU core."""
    use_every_cpu_core()
    return main()
