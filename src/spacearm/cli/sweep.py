"""``spacearm sweep FILE``: run a design sweep, its report and its figures."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from .._core.errors import ConfigError, RunError, Stalled
from ._help import LazyEpilogHelp

ROWS_SHOWN = 20  # a longer table prints its first rows and a summary of every column


def _epilog() -> str:
    from ..models.family import known_families
    from ..studies.metrics import AVERAGE_OPTIONS, METRICS, WBAR_OPTIONS

    families = known_families()
    return (
        "examples:\n"
        "  spacearm sweep sweeps/table2.yaml\n"
        "  spacearm sweep sweeps/masses.yaml --set chunk_size=64 --out /tmp/quick\n"
        "  SPACEARM_COORDINATOR=127.0.0.1:8476 SPACEARM_NUM_PROCESSES=2 SPACEARM_PROCESS_ID=0 spacearm sweep FILE &\n"
        "  SPACEARM_COORDINATOR=127.0.0.1:8476 SPACEARM_NUM_PROCESSES=2 SPACEARM_PROCESS_ID=1 spacearm sweep FILE\n"
        "    (two processes, one sweep: jax.distributed over gloo; process 0 writes the results)\n"
        "design fields for axes, by robot family:\n"
        + "".join(f"  {family.name}: {family.fields.FIELD_HELP}\n" for family in families)
        + "".join(
            f"metrics ({family.name}): "
            f"{', '.join(sorted(n for n, m in METRICS.items() if m.offered(family.capabilities)))}\n"
            for family in families
        )
        + f"the joint-box averages take {', '.join(AVERAGE_OPTIONS)}\n"
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
    parser.add_argument(
        "--set",
        metavar="KEY=VALUE",
        action="append",
        help="override a key of the sweep file (dotted path, YAML value); repeatable",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    group = parser.add_argument_group(
        "many processes (jax.distributed; each defaults to its SPACEARM_* environment variable)"
    )
    group.add_argument(
        "--coordinator",
        metavar="HOST:PORT",
        default=os.environ.get("SPACEARM_COORDINATOR") or None,
        help="process 0's address; every process gives the same (SPACEARM_COORDINATOR)",
    )
    group.add_argument(
        "--num-processes",
        metavar="N",
        type=int,
        default=os.environ.get("SPACEARM_NUM_PROCESSES") or None,
        help="how many processes run the sweep together (SPACEARM_NUM_PROCESSES)",
    )
    group.add_argument(
        "--process-id",
        metavar="I",
        type=int,
        default=os.environ.get("SPACEARM_PROCESS_ID") or None,
        help="this process's rank, 0..N-1; process 0 writes the results (SPACEARM_PROCESS_ID)",
    )
    group.add_argument(
        "--peer-timeout",
        metavar="SECONDS",
        type=float,
        default=float(os.environ.get("SPACEARM_PEER_TIMEOUT") or 60.0),
        help="how long to wait for the other processes before giving up with one line "
        "(SPACEARM_PEER_TIMEOUT; default 60)",
    )
    parser.add_argument(
        "--stall-timeout",
        metavar="SECONDS",
        type=float,
        default=float(os.environ.get("SPACEARM_STALL_TIMEOUT") or 120.0),
        help="end with one line when a chunk goes this long without using any CPU, a deadlock "
        "(SPACEARM_STALL_TIMEOUT; default 120)",
    )


def _join(args: argparse.Namespace) -> bool:
    """Join the other processes of a distributed sweep, when asked (before JAX starts).

    Returns whether this process joined; bad options raise before anything starts."""
    given = [args.coordinator is not None, args.num_processes is not None, args.process_id is not None]
    if not any(given):
        return False
    if not all(given):
        raise ConfigError(
            "a distributed sweep needs all three of --coordinator (SPACEARM_COORDINATOR), "
            "--num-processes (SPACEARM_NUM_PROCESSES) and --process-id (SPACEARM_PROCESS_ID)"
        )
    if args.num_processes < 1 or not 0 <= args.process_id < args.num_processes:
        raise ConfigError(
            f"--process-id {args.process_id}: must be in 0..{args.num_processes - 1} "
            f"(--num-processes {args.num_processes})"
        )
    host, _, port = args.coordinator.rpartition(":")
    if not host or not port.isdigit():
        raise ConfigError(f"--coordinator {args.coordinator}: must be HOST:PORT, e.g. 127.0.0.1:8476")
    from .._core.numeric import join_processes

    if not args.peer_timeout > 0:
        raise ConfigError(f"--peer-timeout {args.peer_timeout:g}: must be a positive number of seconds")
    join_processes(args.coordinator, args.num_processes, args.process_id, timeout_s=args.peer_timeout)
    return True


def run(args: argparse.Namespace) -> int:
    # First: jax.distributed must start before JAX's backend. Bad options raise here, as
    # any bad input does (in-process callers such as the tests keep their process).
    joined = _join(args)
    if not args.stall_timeout > 0:
        raise ConfigError(f"--stall-timeout {args.stall_timeout:g}: must be a positive number of seconds")
    try:
        return _run(args)
    except (ConfigError, RunError) as error:
        if not joined and not isinstance(error, Stalled):
            raise
        # One of several processes, or threads that are stuck: say why in one line and
        # leave at once. A normal exit would wait in jax.distributed's shutdown for peers
        # that may be gone (then abort with a C++ stack), or for the stuck threads.
        status = 2 if isinstance(error, ConfigError) else 1
        message = " ".join(str(error).splitlines())
        print(f"spacearm sweep: error: {message}", file=sys.stderr, flush=True)
        sys.stdout.flush()
        os._exit(status)


def _run(args: argparse.Namespace) -> int:
    from ..figures.sweep import write_figures
    from ..studies import load_sweep, run_sweep

    spec = load_sweep(args.file, overrides=args.set or [])
    out_dir = Path(args.out) if args.out else Path(spec.output)
    print(spec.summary(), file=sys.stderr)
    try:
        # The table, the grids and the report, then the figures (listed in the manifest).
        result = run_sweep(
            spec,
            out_dir,
            progress=not args.quiet,
            command=sys.argv,
            outputs=(write_figures, _shells_view),
            peer_timeout_s=args.peer_timeout,
            stall_s=args.stall_timeout,
        )
    except OSError as error:  # e.g. a read-only file system under --out
        raise ConfigError(f"--out {out_dir}: cannot write the results ({error.strerror or error})") from None
    if not result.manifest:  # a distributed sweep's other processes: process 0 wrote the results
        print(f"process {args.process_id} of {args.num_processes}: done; process 0 wrote {out_dir}/")
        return 0
    print(format_table(result.table))
    timings = result.manifest["timings_s"]
    print(
        f"wrote {out_dir}/ ({len(result.files)} files; compile {timings['compile']:.1f} s, "
        f"run {timings['run']:.1f} s, wall {timings['wall']:.1f} s)"
    )
    return 0


def _shells_view(spec, out_dir: Path, table) -> list[Path]:
    """shells.html (figures.views) where the sweep computes shell radii; needs the 'view' extra."""
    from ..figures.views.shells import shells_view

    return shells_view(spec, out_dir, table)


def _cell(value: float) -> str:
    return f"{value:.6g}" if np.isfinite(value) else str(value)


def format_table(table: dict[str, np.ndarray], max_rows: int = ROWS_SHOWN) -> str:
    """The sweep's table as aligned text: a value and its ``_error`` column as ``v ± e``.

    A table longer than ``max_rows`` shows its first rows, then the minimum, median and
    maximum of every column over all rows, so a large sweep still ends on one screen.
    """
    names = [n for n in table if not (n.endswith("_error") and n[: -len("_error")] in table)]
    rows = len(table["design"]) if "design" in table else len(next(iter(table.values())))

    def cell(name: str, value: float, error: float | None) -> str:
        return _cell(value) if error is None else f"{_cell(value)} ± {error:.2g}"

    def line(i: int) -> list[str]:
        out = []
        for name in names:
            error = table.get(name + "_error")
            out.append(cell(name, float(table[name][i]), None if error is None else float(error[i])))
        return out

    body = [line(i) for i in range(min(rows, max_rows))]
    if rows > max_rows:
        body.append(["..."] * len(names))
        for label, reduce in (("min", np.nanmin), ("median", np.nanmedian), ("max", np.nanmax)):
            body.append(
                [label if name == "design" else _cell(float(reduce(np.asarray(table[name], float)))) for name in names]
            )
    widths = [max(len(name), *(len(row[j]) for row in body)) for j, name in enumerate(names)]
    text = ["  ".join(name.rjust(w) for name, w in zip(names, widths, strict=True))]
    text += ["  ".join(c.rjust(w) for c, w in zip(row, widths, strict=True)) for row in body]
    if rows > max_rows:
        text.append(f"({rows} rows; the first {max_rows} shown, then min, median and max over all rows)")
    return "\n".join(text)
