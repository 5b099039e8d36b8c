"""Help text that needs a library layer, built only when ``--help`` asks for it."""

from __future__ import annotations

import argparse
from collections.abc import Callable


class LazyEpilogHelp(argparse.Action):
    """``-h/--help`` that fills the parser's epilog from ``epilog()`` first.

    A command whose help lists names from a heavy layer (the sweep's fields and metrics)
    registers with ``add_help=False`` and this action, so building the parser stays light.
    """

    def __init__(
        self,
        option_strings,
        dest=argparse.SUPPRESS,
        default=argparse.SUPPRESS,
        help="show this help message and exit",
        epilog: Callable[[], str] | None = None,
    ):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)
        self.epilog = epilog

    def __call__(self, parser, namespace, values, option_string=None):
        if self.epilog is not None:
            parser.epilog = self.epilog()
        parser.print_help()
        parser.exit()
