"""``spacearm optimize FILE``: the Pareto search of a design problem, its baselines and figures."""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "optimize",
        help="Pareto search over designs (hybrid evolution + hypervolume gradients), with grid and NSGA-II baselines",
        description=(
            "Search the Pareto front of the objectives declared in FILE (e.g. sweeps/pareto-ur5-arm.yaml) "
            "and write pareto.csv, summary.json and figures into results/<name>/ or --out; print a summary "
            "table. NSGA-II, when the file declares it, runs 3x the search's wall time (compile included)."
        ),
    )
    parser.add_argument("file", help="problem YAML, e.g. sweeps/pareto-attachment.yaml")
    parser.add_argument("--out", help="output folder (default results/<name>/)")
    parser.add_argument("--no-baselines", action="store_true", help="skip the grid and NSGA-II baselines")
    parser.add_argument(
        "--method",
        choices=("hybrid", "scalarized"),
        default="hybrid",
        help="hybrid: evolution + set-based hypervolume-gradient steps (default); scalarized: "
        "the Chebyshev gradient search of the file's search: section",
    )
    parser.add_argument(
        "--max-seconds",
        type=float,
        default=None,
        help="stop the hybrid search after this run time (s); overrides hybrid.max_seconds",
    )
    parser.add_argument(
        "--nsga2-factor",
        type=float,
        default=3.0,
        help="NSGA-II's wall time as a multiple of the search's, compile included (default 3)",
    )
    parser.add_argument(
        "--cost-ratio",
        action="store_true",
        help="time a value-and-gradient against a value on one batch apart (compiles one more program); "
        "by default the ratio is read off the search's own timed calls",
    )


def run(args: argparse.Namespace) -> int:
    import dataclasses

    from .._core.errors import ConfigError
    from .._core.schema import read_yaml
    from ..design import load_problem, run_problem
    from ..design.hybrid import parse_hybrid
    from ..figures.design import plot_results
    from .validate import check_problem_memory

    for option, value in (("--max-seconds", args.max_seconds), ("--nsga2-factor", args.nsga2_factor)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise ConfigError(f"{option} {value:g}: must be a positive number")
    config = read_yaml(args.file, what="design problem file")
    problem = load_problem(config, name=os.fspath(args.file), base_dir=os.path.dirname(os.path.abspath(args.file)))
    check_problem_memory(os.fspath(args.file), problem)  # before the search allocates anything
    hybrid = parse_hybrid(os.fspath(args.file), config.get("hybrid"))
    if args.max_seconds is not None:
        hybrid = dataclasses.replace(hybrid, max_seconds=args.max_seconds)
    out_dir = Path(args.out) if args.out else Path("results") / problem.name
    outputs = (plot_results, *_html_outputs())
    run_problem(
        problem,
        out_dir,
        method=args.method,
        hybrid=hybrid,
        baselines=not args.no_baselines,
        config=config,
        outputs=outputs,
        command=sys.argv,
        cost_ratio="measured" if args.cost_ratio else "search",
        nsga2_time_factor=args.nsga2_factor,
    )
    return 0


def _html_outputs() -> tuple:
    """front.html (figures.views) with the 'view' extra; without it, a note and no page."""
    from ..figures.views import VIEW_EXTRA_MESSAGE, front_view, view_extra_available

    if view_extra_available():
        return (front_view,)
    print(f"front.html skipped: {VIEW_EXTRA_MESSAGE}", file=sys.stderr)
    return ()
