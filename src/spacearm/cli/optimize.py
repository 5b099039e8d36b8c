"""``spacearm optimize FILE``: the Pareto search of a design problem, its baselines and figures."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "optimize",
        help="gradient-based Pareto search over designs (w-bar vs S_G), with grid and NSGA-II baselines",
        description=(
            "Search the Pareto front of the objectives declared in FILE (e.g. sweeps/pareto-attachment.yaml) "
            "and write pareto.csv, summary.json and figures into results/<name>/ or --out."),
    )
    parser.add_argument("file", help="problem YAML, e.g. sweeps/pareto-attachment.yaml")
    parser.add_argument("--out", help="output folder (default results/<name>/)")
    parser.add_argument("--no-baselines", action="store_true", help="skip the grid and NSGA-II baselines")
    parser.add_argument(
        "--cost-ratio", action="store_true",
        help="time a value-and-gradient against a value on one batch apart (compiles one more program); "
             "by default the ratio is read off the search's own timed calls")


def run(args: argparse.Namespace) -> int:
    from .._core.schema import read_yaml
    from ..design import load_problem, run_problem
    from ..figures.design import plot_results

    config = read_yaml(args.file, what="design problem file")
    problem = load_problem(config, name=os.fspath(args.file), base_dir=os.path.dirname(os.path.abspath(args.file)))
    out_dir = Path(args.out) if args.out else Path("results") / problem.name
    run_problem(problem, out_dir, baselines=not args.no_baselines, config=config, outputs=(plot_results,),
                command=sys.argv, cost_ratio="measured" if args.cost_ratio else "search")
    return 0
