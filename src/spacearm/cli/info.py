"""``spacearm info [ROBOT]``: versions, devices and the float64 flag; with a robot file,
its mass budget (the bus, each root body and what was merged into it, the moving links
of each arm, the total)."""

from __future__ import annotations

import argparse
import platform
import sys


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "info",
        help="versions, devices and the float64 flag; a robot's mass budget",
        description=(
            "Print versions, devices and the float64 flag. With ROBOT, print its mass budget instead: the bus, "
            "each rigid root body and the URDF links merged into it, the moving links of each arm, and the total."
        ),
    )
    parser.add_argument("robot", nargs="?", help="a robot YAML file, e.g. configs/dual-ur5-servicer.yaml")


def run(args: argparse.Namespace) -> int:
    import jax
    import numpy

    from .. import __version__
    from .._core.numeric import x64_enabled
    from ..models import load_robot
    from ..models.budget import format_mass_budget

    if args.robot is not None:
        print(format_mass_budget(load_robot(args.robot)))
        return 0

    print(f"spacearm {__version__}")
    print(f"python   {platform.python_version()} ({sys.executable})")
    print(f"jax      {jax.__version__}   numpy {numpy.__version__}")
    print(f"float64  {'on' if x64_enabled() else 'off'}")
    print(f"backend  {jax.default_backend()}   device_count {jax.device_count()}")
    for device in jax.devices():
        print(f"  - {device}")
    return 0
