"""``spacearm sweep FILE``: run a design sweep, its report and its figures."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .._core.errors import ConfigError
from ._help import LazyEpilogHelp


def _epilog() -> str:
    from ..studies.designs import FIELD_HELP
    from ..studies.metrics import METRICS, WBAR_OPTIONS

    return (
        "examples:\n"
        "  spacearm sweep sweeps/table2.yaml\n"
        "  spacearm sweep sweeps/masses.yaml --set chunk_size=64 --out /tmp/quick\n"
        f"design fields for axes: {FIELD_HELP}\n"
        f"metrics: {', '.join(sorted(METRICS))}\n"
        f"wbar options ({{name: wbar, ...}}): {', '.join(WBAR_OPTIONS)}; rule: product trades the\n"
        "  default's ~1e-13 for ~1e-4 and a fixed node grid that is many times faster for big sweeps"
    )


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "sweep",
        help="run a YAML design sweep (e.g. sweeps/table2.yaml)",
        description=(
            "Evaluate every design of a sweep file in compiled, batched chunks and write table.csv,\n"
            "grids.npz, manifest.json and figures into results/<name>/ (or --out). An interrupted\n"
            "sweep resumes from the finished chunks when run again."
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
        add_help=False,
    )
    parser.add_argument("-h", "--help", action=LazyEpilogHelp, epilog=_epilog)
    parser.add_argument("file", help="the sweep YAML file")
    parser.add_argument("--out", metavar="DIR", help="output folder (default: the file's 'output', or results/<name>)")
    parser.add_argument("--set", metavar="KEY=VALUE", action="append",
                        help="override a key of the sweep file (dotted path, YAML value); repeatable")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def run(args: argparse.Namespace) -> int:
    from ..figures.sweep import write_figures
    from ..studies import load_sweep, run_sweep

    spec = load_sweep(args.file, overrides=args.set or [])
    out_dir = Path(args.out) if args.out else Path(spec.output)
    print(spec.summary(), file=sys.stderr)
    try:
        # The table, the grids and the report, then the figures (listed in the manifest).
        result = run_sweep(spec, out_dir, progress=not args.quiet, command=sys.argv, outputs=(write_figures,))
    except OSError as error:  # e.g. a read-only file system under --out
        raise ConfigError(f"--out {out_dir}: cannot write the results ({error.strerror or error})") from None
    timings = result.manifest["timings_s"]
    print(f"wrote {out_dir}/ ({len(result.files)} files; compile {timings['compile']:.1f} s, "
          f"run {timings['run']:.1f} s, wall {timings['wall']:.1f} s)")
    return 0
