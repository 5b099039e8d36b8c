"""The ``spacearm`` console script's entry point, a module outside the ``spacearm`` package.

Importing ``spacearm`` loads JAX, which takes seconds; a Ctrl-C meanwhile must end like
one during a command (one line, exit status 130), not in a traceback. Any import of
``spacearm.cli`` runs ``spacearm/__init__.py`` first, so only a module outside the
package can catch it.
"""

import importlib
import sys

__all__ = ["console_main"]


def console_main() -> int:
    """Import the command line (`spacearm.cli`), then run it; Ctrl-C during the import is
    one line on stderr and exit status 130."""
    try:
        cli = importlib.import_module("spacearm.cli")
    except KeyboardInterrupt:
        print("spacearm: interrupted", file=sys.stderr)
        return 130
    return cli.console_main()


if __name__ == "__main__":
    sys.exit(console_main())
