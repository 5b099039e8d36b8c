"""``spacearm view ROBOT [--posture ...] [--out DIR]``: the robot on its bus as an interactive HTML page.

Writes ``<robot name>.html`` into ``--out``: one self-contained file (plotly.js inlined,
no server, no network) with a slider per joint that re-poses the arm in the browser.
Needs the optional ``view`` extra (Plotly); without it, exit 2 with a message naming it.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from .._core.errors import ConfigError
from .._core.schema import check_name
from ..io.folders import check_output_folder
from ._args import comma_numbers


def register(subparsers) -> None:
    """Register ``spacearm view ROBOT.yaml [--posture ...] [--out DIR]``."""
    parser = subparsers.add_parser(
        "view",
        help="the robot on its bus as an interactive offline HTML page (a slider per joint)",
        description=(
            "Write ROBOT's interactive 3-D view: the arm (or every arm, each in its colour) drawn from its kinematic model on the bus "
            "(the uniform box of its mass and inertia), about the system centroid, with a slider per joint "
            "(and the bus attitude) that re-poses it in the browser. One self-contained HTML file, no "
            "server and no network. Needs the 'view' extra: pip install -e \".[view]\"."
        ),
    )
    parser.add_argument(
        "robot",
        help="robot YAML file, e.g. configs/ur5-smallsat.yaml, configs/dual-ur5-servicer.yaml or configs/umetani1990.yaml",
    )
    parser.add_argument(
        "--posture",
        default=None,
        metavar="Q1,Q2,..",
        help="first posture shown, DEGREES (radians with --radians; m for prismatic joints): spatial and tree "
        "robots the joints (a tree's in its joint order, all arms), planar robots the base attitude then the joints; default all zero "
        "(write --posture=-10,20 when the first value is negative)",
    )
    parser.add_argument(
        "--attitude-rpy",
        dest="attitude",
        default=None,
        metavar="R,P,Y",
        help="the first bus attitude as roll, pitch, yaw (URDF convention), degrees, for robots whose posture "
        "does not hold it (a planar posture starts with its base attitude)",
    )
    parser.add_argument("--radians", action="store_true", help="read --posture and --attitude-rpy in radians")
    parser.add_argument("--out", default="results/view", help="output folder (default results/view)")


def run(args: argparse.Namespace) -> int:
    from ..figures.views import write_arm_view
    from ..figures.views.model import posture_prismatic, view_model
    from ..figures.views.page import plotly_bundle
    from ..models import load_robot

    plotly_bundle()  # the extra is checked before any work (MissingViewExtra: exit 2)
    robot = load_robot(args.robot)
    model = view_model(robot)
    posture = None
    if args.posture is not None:
        posture = comma_numbers(args.posture, model["posture"]["size"], "--posture")
        if not args.radians:
            posture = np.where(posture_prismatic(model), posture, np.radians(posture))
    attitude = None
    if args.attitude is not None:
        if model["posture"]["base_turn"] is not None:
            raise ConfigError(
                "--attitude-rpy: this robot's posture holds its bus attitude; give it as the first --posture value"
            )
        attitude = comma_numbers(args.attitude, 3, "--attitude-rpy")
        if not args.radians:
            attitude = np.radians(attitude)
    name = check_name(f"{args.robot}: name", robot.name)  # the page's file name
    check_output_folder(args.out, label=f"--out {args.out}", whole=False)
    path = write_arm_view(robot, Path(args.out) / f"{name}.html", posture, attitude_rpy=attitude)
    print(f"view   {path} ({os.path.getsize(path) / 1e6:.2f} MB, self-contained; open it in any browser)")
    return 0
