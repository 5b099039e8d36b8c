"""Time to first result: each command in a fresh process, cold (empty compile cache) and warm.

Run: python benchmarks/bench_startup.py [--repeat 1] [--only reach,optimize] [--programs]

Every command runs as the console script does (``spacearm.cli.console_main``: one JAX
device per core, float64, the persistent compilation cache) in a new Python process.
"cold" points ``SPACEARM_CACHE_DIR`` at a fresh empty folder; "warm" runs the same
command again with the folder the cold run filled (programs that compile in under
``jax_persistent_cache_min_compile_time_secs`` are not stored, so a warm run still
compiles those). Each run reports its wall time, its CPU time (user + sys of the child,
which does not depend on how busy the machine is as much as wall time does), and from
``jax.monitoring`` the number of XLA compilations, the seconds spent tracing, lowering
and compiling, and the compile share (those seconds over the wall time).
``--programs`` lists, per command, how often each program was compiled: a program
compiled twice in one job is a recompilation bug (DESIGN.md, "Scale").
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# (label, argv after "spacearm"); TMP is replaced by a fresh output folder per run.
COMMANDS: tuple[tuple[str, list[str]], ...] = (
    ("--help", ["--help"]),
    ("sweep table2", ["sweep", "sweeps/table2.yaml", "--out", "TMP"]),
    ("reach (point C)", ["reach", "configs/umetani1990.yaml", "--from", "0,-60,120", "--to=-2.5,-3", "--out", "TMP"]),
    ("optimize --no-baselines", ["optimize", "sweeps/pareto-attachment.yaml", "--no-baselines", "--out", "TMP"]),
    ("figures", ["figures", "--out", "TMP"]),
)

# Runs in the child: count compile events, then run the console script with argv.
_CHILD = r"""
import atexit, json, sys, time
start = time.perf_counter()
import jax.monitoring as monitoring
stats = {"compiles": 0, "compile_s": 0.0, "trace_s": 0.0, "lower_s": 0.0, "cache_hits": 0,
         "programs": {}}
EVENTS = {"/jax/core/compile/backend_compile_duration": "compile_s",
          "/jax/core/compile/jaxpr_trace_duration": "trace_s",
          "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower_s"}
def on_duration(event, seconds, **kwargs):
    key = EVENTS.get(event)
    if key is None:
        return
    stats[key] += seconds
    if key == "compile_s":
        stats["compiles"] += 1
        count, total = stats["programs"].get(kwargs.get("fun_name", "?"), (0, 0.0))
        stats["programs"][kwargs.get("fun_name", "?")] = (count + 1, total + seconds)
def on_event(event, **kwargs):
    if event == "/jax/compilation_cache/cache_hits":
        stats["cache_hits"] += 1
monitoring.register_event_duration_secs_listener(on_duration)
monitoring.register_event_listener(on_event)
def report():
    stats["wall_s"] = time.perf_counter() - start
    with open(REPORT, "w") as file:
        json.dump(stats, file)
atexit.register(report)
sys.argv = ["spacearm", *ARGV]
from spacearm.cli import console_main
try:
    code = console_main()
except SystemExit as exit:
    code = exit.code
sys.exit(code or 0)
"""


def run_once(argv: list[str], cache_dir: str) -> dict:
    """One fresh process: wall, CPU (user + sys) and the child's compile statistics."""
    with tempfile.TemporaryDirectory() as out, tempfile.NamedTemporaryFile(suffix=".json") as report:
        args = [out if word == "TMP" else word for word in argv]
        code = _CHILD.replace("REPORT", repr(report.name)).replace("ARGV", repr(args))
        env = dict(os.environ, SPACEARM_CACHE_DIR=cache_dir, PYTHONPATH=str(ROOT / "src"))
        env.pop("JAX_LOG_COMPILES", None)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if done.returncode != 0:
            raise SystemExit(f"spacearm {' '.join(args)} failed ({done.returncode}):\n{done.stderr[-2000:]}")
        stats = json.loads(Path(report.name).read_text())
    stats["wall_s"] = wall
    stats["cpu_s"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    stats["jax_s"] = stats["compile_s"] + stats["trace_s"] + stats["lower_s"]
    return stats


def measure(argv: list[str], repeat: int) -> tuple[dict, dict]:
    """The best cold and warm runs of a command out of ``repeat`` (each cold run in a new cache)."""
    colds, warms = [], []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory(prefix="spacearm-cache-") as cache:
            colds.append(run_once(argv, cache))
            warms.append(run_once(argv, cache))
    best = lambda runs: min(runs, key=lambda stats: stats["wall_s"])  # noqa: E731
    return best(colds), best(warms)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1, help="runs per command; the fastest is shown")
    parser.add_argument("--only", default="", help="comma-separated words picking commands (e.g. reach,optimize)")
    parser.add_argument("--programs", action="store_true", help="list each command's compiled programs")
    parser.add_argument("--json", help="also write the numbers to this file")
    args = parser.parse_args()
    picks = [word for word in args.only.split(",") if word]
    commands = [(label, argv) for label, argv in COMMANDS if not picks or any(p in label for p in picks)]

    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    header = (
        "| command | compiles | cold wall s | cold CPU s | compile share | warm wall s | warm CPU s "
        "| warm compiles |"
    )
    print(header)
    print("|" + "---|" * header.count(" | ") + "---|")
    results = {}
    for label, argv in commands:
        cold, warm = measure(argv, args.repeat)
        results[label] = {"cold": cold, "warm": warm}
        share = cold["jax_s"] / cold["wall_s"]
        print(
            f"| `{label}` | {cold['compiles']} | {cold['wall_s']:.1f} | {cold['cpu_s']:.1f} | {share:.0%} "
            f"| {warm['wall_s']:.1f} | {warm['cpu_s']:.1f} | {warm['compiles'] - warm['cache_hits']} |",
            flush=True,
        )
    if args.programs:
        for label, result in results.items():
            programs = sorted(result["cold"]["programs"].items(), key=lambda item: -item[1][1])
            listed = ", ".join(f"{name} x{count} {seconds:.2f}s" for name, (count, seconds) in programs)
            print(f"\n{label} (XLA compile seconds, slowest first): {listed or 'none'}")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
