"""``spacearm figures``: regenerate the paper's figures (and ours) as PNG files."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .._core.errors import ConfigError


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "figures",
        help="regenerate every paper figure into results/figures/",
        description="Regenerate the paper's figures (and ours) as PNG files.",
    )
    parser.add_argument(
        "--out", default="results/figures", metavar="DIR", help="output folder (default results/figures)"
    )
    parser.add_argument("--only", metavar="NAMES", help="comma-separated figure names, e.g. fig2,fig7")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def run(args: argparse.Namespace) -> int:
    from tqdm.auto import tqdm

    from ..figures import all_figures

    figures = all_figures()
    if args.only is not None and not args.only.strip(","):
        raise ConfigError(f"--only: no figure named; known: {', '.join(figures)}")
    wanted = [name for name in args.only.split(",") if name] if args.only is not None else list(figures)
    unknown = [name for name in wanted if name not in figures]
    if unknown:
        raise ConfigError(f"--only: unknown figure(s) {', '.join(unknown)}; known: {', '.join(figures)}")
    out_dir = Path(args.out)
    written: list[Path] = []
    for name in tqdm(wanted, desc="figures", unit="figure", file=sys.stderr, disable=args.quiet):
        written.extend(figures[name](out_dir))
    for path in written:
        print(path)
    return 0
