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
from .._core.memory import check_working_memory, working_numbers
from .._core.schema import read_yaml


def check_problem_memory(where: str, problem) -> float:
    """Refuse a design problem whose search would not fit in memory: its directions x starts
    runs evaluate the objectives (and their gradients) side by side. Returns the estimate."""
    runs = problem.search.directions * problem.search.starts
    if hasattr(problem, "wbar_options"):  # planar: the w-bar quadrature dominates
        n = problem.n_links
        numbers, option = (
            working_numbers("wbar", problem.wbar_options, n) if "wbar" in problem.objectives else (4096.0 * (n + 1), "")
        )
        option = f"wbar.{option.split(' or ')[0]}" if option else ""
    else:  # spatial: the joint-box samples of each objective
        numbers, option = working_numbers("objectives", {"samples": problem.samples}, problem.base.n_joints)
        option = "average.samples"
    advice = "lower search.directions or search.starts" + (f", or {option}" if option else "")
    return check_working_memory(
        f"{where}: search",
        runs,
        3 * numbers,  # value and gradient
        f"{runs:,} search runs (directions x starts)",
        advice,
    )


def validate_file(path: str | os.PathLike) -> tuple[str, str]:
    """Validate a robot, sweep or design-problem file; return (kind, one-line summary) or raise ConfigError."""
    from ..design.hybrid import parse_hybrid
    from ..design.problem import load_problem as load_design_problem
    from ..models import family_of, is_robot_mapping, robot_from_file_mapping
    from ..studies.runner import check_sweep_memory
    from ..studies.spec import load_sweep

    path = os.fspath(path)
    config = read_yaml(path, what="YAML file")
    if is_robot_mapping(config):
        robot = robot_from_file_mapping(config, source=path, base_dir=os.path.dirname(os.path.abspath(path)))
        if family_of(robot).tip_count(robot) is not None:  # several arms on one bus (a tip axis)
            return "robot", f"{robot.name}, {robot.n_joints} joints, tips {', '.join(robot.tip_names)}"
        return "robot", f"{robot.name}, {robot.n_links} links, L = {float(robot.reach):g} m"
    if isinstance(config, Mapping) and ("variables" in config or "objectives" in config):
        problem = load_design_problem(path)
        check_problem_memory(path, problem)
        parse_hybrid(path, config.get("hybrid"))  # as spacearm optimize reads it
        return "design problem", f"{problem.name}: variables {', '.join(problem.variable_names)}"
    if isinstance(config, Mapping) and ("axes" in config or "robot" in config):
        spec = load_sweep(path)
        check_sweep_memory(spec)  # as run_sweep does before it allocates anything
        return "sweep", spec.summary()
    raise ConfigError(
        f"{path}: neither a robot file (needs 'base' and 'links', 'arm', 'arms' or 'system'), a sweep file (needs 'robot' and 'axes') "
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
    from ..models import load_robot
    from ..models.budget import format_mass_budget

    kind, summary = validate_file(args.file)
    print(f"{args.file}: valid {kind} ({summary})")
    if kind == "robot":
        print(format_mass_budget(load_robot(args.file)))
    return 0
