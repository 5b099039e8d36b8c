"""The ``spacearm`` console script's entry point, a module outside the ``spacearm`` package.

Importing ``spacearm`` loads JAX, which takes seconds; a Ctrl-C meanwhile must end like
one during a command (one line, exit status 130), not in a traceback. Any import of
``spacearm.cli`` runs ``spacearm/__init__.py`` first, so only a module outside the
package can catch it.
"""

import importlib
import importlib.metadata
import os
import sys

__all__ = ["console_main"]


def _quiet_cache_loads() -> None:
    """jaxlib before 0.10 logs two error lines for each program it loads from the
    compilation cache on CPUs whose LLVM tuning features it does not list as host
    features (``+prefer-no-gather``): noise on every warm run, harmless. Its C++ log lines
    below FATAL are hidden then, unless ``TF_CPP_MIN_LOG_LEVEL`` is set. Before jaxlib loads."""
    try:
        major, minor = (int(part) for part in importlib.metadata.version("jaxlib").split(".")[:2])
    except (importlib.metadata.PackageNotFoundError, ValueError):
        return
    if (major, minor) < (0, 10):
        os.environ.setdefault("TF_CPP_MIN_LOG_LEVEL", "3")


def console_main() -> int:
    """Import the command line (`spacearm.cli`), then run it; Ctrl-C during the import is
    one line on stderr and exit status 130."""
    _quiet_cache_loads()
    try:
        cli = importlib.import_module("spacearm.cli")
    except KeyboardInterrupt:
        print("spacearm: interrupted", file=sys.stderr)
        return 130
    return cli.console_main()


if __name__ == "__main__":
    sys.exit(console_main())
