"""The ``spacearm`` command line: one console script, one subcommand per job.

Every subcommand runs in float64. Invalid input ends with exit status 2 and a one-line
message naming the field and the reason, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Callable, Sequence

from .robot import ConfigError

EXIT_INVALID = 2

# Subcommands living in other modules: (module, function adding the subparser).
# Each adder receives the subparsers object and sets ``func`` on its parser.
_EXTERNAL_COMMANDS: list[tuple[str, str]] = [
    ("sweep", "add_sweep_command"),
    ("sweep", "add_figures_command"),
    ("planning", "add_reach_command"),
    ("design", "add_optimize_command"),
]


def _cmd_validate(args: argparse.Namespace) -> int:
    from .validate import validate_file

    kind, summary = validate_file(args.file)
    print(f"{args.file}: valid {kind} ({summary})")
    return 0


def _cmd_info(args: argparse.Namespace) -> int:
    import platform

    import jax
    import numpy

    from . import __version__
    from .config import x64_enabled

    print(f"spacearm {__version__}")
    print(f"python   {platform.python_version()} ({sys.executable})")
    print(f"jax      {jax.__version__}   numpy {numpy.__version__}")
    print(f"float64  {'on' if x64_enabled() else 'off'}")
    print(f"backend  {jax.default_backend()}   device_count {jax.device_count()}")
    for device in jax.devices():
        print(f"  - {device}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="spacearm",
        description=(
            "Workspace and manipulability of manipulators on free-floating spacecraft "
            "(Umetani & Yoshida 1990, generalized to n links)."
        ),
    )
    parser.add_argument("--float32", action="store_true", help="compute in float32 (faster, less exact); default float64")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    validate = sub.add_parser(
        "validate",
        help="check a robot, sweep or design-problem YAML file",
        description="Check a robot, sweep or design-problem YAML file. Exit 0 when valid, 2 with the reason when not.",
    )
    validate.add_argument("file", help="path to the YAML file, e.g. configs/umetani1990.yaml")
    validate.set_defaults(func=_cmd_validate)

    info = sub.add_parser("info", help="versions, devices and the float64 flag", description="Print versions, devices and the float64 flag.")
    info.set_defaults(func=_cmd_info)

    for module_name, adder_name in _EXTERNAL_COMMANDS:
        module = importlib.import_module(f"spacearm.{module_name}")
        adder: Callable = getattr(module, adder_name)
        adder(sub)
    for command in sub.choices.values():  # also accepted after the subcommand
        command.add_argument("--float32", action="store_true", default=argparse.SUPPRESS,
                             help="compute in float32 (faster, less exact); default float64")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    from .config import enable_compilation_cache, enable_x64

    enable_x64(not args.float32)
    enable_compilation_cache()
    try:
        return int(args.func(args) or 0)
    except ConfigError as error:
        print(f"spacearm {args.command}: error: {error}", file=sys.stderr)
        return EXIT_INVALID
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


def console_main() -> int:
    """The ``spacearm`` console script: :func:`main` with one JAX device per CPU core."""
    from .config import use_every_cpu_core

    use_every_cpu_core()
    return main()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(console_main())
