"""``spacearm info``: versions, devices and the float64 flag."""

from __future__ import annotations

import argparse
import platform
import sys


def register(subparsers) -> None:
    subparsers.add_parser(
        "info",
        help="versions, devices and the float64 flag",
        description="Print versions, devices and the float64 flag.",
    )


def run(args: argparse.Namespace) -> int:
    import jax
    import numpy

    from .. import __version__
    from .._core.numeric import x64_enabled

    print(f"spacearm {__version__}")
    print(f"python   {platform.python_version()} ({sys.executable})")
    print(f"jax      {jax.__version__}   numpy {numpy.__version__}")
    print(f"float64  {'on' if x64_enabled() else 'off'}")
    print(f"backend  {jax.default_backend()}   device_count {jax.device_count()}")
    for device in jax.devices():
        print(f"  - {device}")
    return 0
