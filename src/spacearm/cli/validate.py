"""``spacearm validate FILE``: check a robot, sweep or design-problem file as a run would.

Each kind is checked by the loader its run uses (the robot families' schema,
`spacearm.studies.spec.load_sweep`, `spacearm.design.problem.load_problem`),
so a file that validates is one a run accepts.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Mapping

from .._core.errors import ConfigError
from .._core.schema import read_yaml


def validate_file(path: str | os.PathLike) -> tuple[str, str]:
    """Validate a robot, sweep or design-problem file; return (kind, one-line summary) or raise ConfigError."""
    from ..design.spatial_problem import load_design_problem
    from ..models import is_robot_mapping, robot_from_file_mapping
    from ..studies.runner import check_sweep_memory
    from ..studies.spec import load_sweep

    path = os.fspath(path)
    config = read_yaml(path, what="YAML file")
    if is_robot_mapping(config):
        robot = robot_from_file_mapping(config, source=path, base_dir=os.path.dirname(os.path.abspath(path)))
        return "robot", f"{robot.name}, {robot.n_links} links, L = {float(robot.reach):g} m"
    if isinstance(config, Mapping) and ("variables" in config or "objectives" in config):
        problem = load_design_problem(path)
        return "design problem", f"{problem.name}: variables {', '.join(problem.variable_names)}"
    if isinstance(config, Mapping) and ("axes" in config or "robot" in config):
        spec = load_sweep(path)
        check_sweep_memory(spec)  # as run_sweep does before it allocates anything
        return "sweep", spec.summary()
    raise ConfigError(
        f"{path}: neither a robot file (needs 'base' and 'links'), a sweep file (needs 'robot' and 'axes') "
        "nor a design problem (needs 'variables' and 'objectives')"
    )


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "validate",
        help="check a robot, sweep or design-problem YAML file",
        description=(
            "Check a robot, sweep or design-problem YAML file with the checks a run makes. "
            "Exit 0 when valid, 2 with the reason when not."
        ),
    )
    parser.add_argument("file", help="path to the YAML file, e.g. configs/umetani1990.yaml")


def run(args: argparse.Namespace) -> int:
    kind, summary = validate_file(args.file)
    print(f"{args.file}: valid {kind} ({summary})")
    return 0
