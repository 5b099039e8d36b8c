"""Time to first result: each command in a fresh process, cold (empty compile cache) and warm.

Run: python benchmarks/bench_startup.py [--repeat 1] [--only reach,optimize] [--programs]
     python benchmarks/bench_startup.py --spatial [--only straight,radius]

Every command runs as the console script does (``spacearm.cli.console_main``: one JAX
device per core, float64, the persistent compilation cache) in a new Python process.
"cold" points ``SPACEARM_CACHE_DIR`` at a fresh empty folder; "warm" runs the same
command again with the folder the cold run filled (``enable_compilation_cache`` keeps
every program by default; with a ``min_compile_seconds`` above 0 a warm run still
compiles the programs below it). Each run reports its wall time, its CPU time (user + sys of the child,
which does not depend on how busy the machine is as much as wall time does), and from
``jax.monitoring`` the number of XLA compilations, the seconds spent tracing, lowering
and compiling, and the compile share (those seconds over the wall time).
``--programs`` lists, per command, how often each program was compiled: a program
compiled twice in one job is a recompilation bug (DESIGN.md, "Scale").

``--spatial`` times the spatial entry points instead (UR5 smallsat): a straight tip path
in 64 directions, ``plan_reach`` towards a point the straight path reaches, ``spacearm
optimize`` on the UR5 mount problem, and the path-independent radius. A library entry
point runs as a user's script would (``sa.enable_x64()``, ``sa.enable_compilation_cache()``,
the robot loaded, then the call), in a fresh process: its first call (CPU seconds, XLA
programs built, compile seconds from ``jax.monitoring``) and its second call in the same
process (warm: nothing left to compile), cold and again with the cache the cold run filled.
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

# Spatial entry points: (label, argv) for a command, or (label, (set-up, call)) for a
# library call; the set-up (imports, robot, inputs) is timed apart from the call.
_UR5 = (
    "import numpy as np, spacearm as sa\n"
    "from spacearm.analysis import workspace_search\n"
    "sa.enable_x64(); sa.enable_compilation_cache()\n"
    "robot = sa.load_robot('configs/ur5-smallsat.yaml')\n"
    "rng = np.random.default_rng(0)\n"
    "q0 = np.array([0.3, -1.2, 1.4, -0.6, 0.8, 0.2])\n"
    "d = rng.normal(size=(64, 3)); d /= np.linalg.norm(d, axis=1, keepdims=True)\n"
    "target = np.asarray(sa.tip_position(robot, q0)) + 0.05 * d[0]\n"
    "def radius(robot):\n"
    "    try:\n"
    "        return sa.path_independent_radius(robot)\n"
    "    except (TypeError, AttributeError, ValueError):  # planar-only by that name: the spatial kernel\n"
    "        return workspace_search.singular_radius(robot)[0]\n"
)
SPATIAL: tuple[tuple[str, object], ...] = (
    ("UR5 straight path, 64 directions", (_UR5, "sa.straight_tip_path(robot, q0, d).length")),
    ("UR5 plan_reach (straight)", (_UR5, "sa.plan_reach(robot, q0, target).error")),
    (
        "optimize pareto-mount-ur5 --no-baselines",
        ["optimize", "sweeps/pareto-mount-ur5.yaml", "--no-baselines", "--out", "TMP"],
    ),
    ("UR5 path-independent radius", (_UR5, "radius(robot)")),
)

# A library entry point in the child: set-up, then the call twice (first, warm), each
# with its CPU seconds, wall seconds and compile events.
_LIBRARY_CHILD = r"""
import json, time
import jax, jax.monitoring as monitoring
phase = {"compiles": 0, "compile_s": 0.0, "trace_s": 0.0, "lower_s": 0.0, "cache_hits": 0, "programs": {}}
EVENTS = {"/jax/core/compile/backend_compile_duration": "compile_s",
          "/jax/core/compile/jaxpr_trace_duration": "trace_s",
          "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower_s"}
def on_duration(event, seconds, **kwargs):
    key = EVENTS.get(event)
    if key is not None:
        phase[key] += seconds
        if key == "compile_s":
            phase["compiles"] += 1
            name = kwargs.get("fun_name", "?")
            count, total = phase["programs"].get(name, (0, 0.0))
            phase["programs"][name] = (count + 1, total + seconds)
def on_event(event, **kwargs):
    if event == "/jax/compilation_cache/cache_hits":
        phase["cache_hits"] += 1
monitoring.register_event_duration_secs_listener(on_duration)
monitoring.register_event_listener(on_event)
def timed(source, mode):
    for key in phase:
        phase[key] = {} if key == "programs" else 0
    cpu, wall = time.process_time(), time.perf_counter()
    jax.block_until_ready(exec(source, globals()) if mode == "exec" else eval(source, globals()))
    return dict(phase, cpu_s=time.process_time() - cpu, wall_s=time.perf_counter() - wall)
report = {"setup": timed(SETUP, "exec"), "first": timed(CALL, "eval"), "warm": timed(CALL, "eval")}
with open(REPORT, "w") as file:
    json.dump(report, file)
"""

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


def run_library_once(setup: str, call: str, cache_dir: str) -> dict:
    """One fresh process: set-up, first call and warm call of a library entry point."""
    with tempfile.NamedTemporaryFile(suffix=".json") as report:
        code = (
            _LIBRARY_CHILD.replace("REPORT", repr(report.name))
            .replace("SETUP", repr(setup))
            .replace("CALL", repr(call))
        )
        env = dict(os.environ, SPACEARM_CACHE_DIR=cache_dir, PYTHONPATH=str(ROOT / "src"))
        env.pop("JAX_LOG_COMPILES", None)
        done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True)
        if done.returncode != 0:
            raise SystemExit(f"{call} failed ({done.returncode}):\n{done.stderr[-2000:]}")
        return json.loads(Path(report.name).read_text())


def measure_spatial(entry, repeat: int) -> tuple[dict, dict]:
    """Cold (empty cache) and warm-cache runs of a spatial entry point, in the form of
    the library runs (a command counts as one call with no warm call)."""
    if isinstance(entry, list):
        cold, warm = measure(entry, repeat)
        as_call = lambda stats: {"first": stats, "warm": None}
        return as_call(cold), as_call(warm)
    setup, call = entry
    colds, warms = [], []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory(prefix="spacearm-cache-") as cache:
            colds.append(run_library_once(setup, call, cache))
            warms.append(run_library_once(setup, call, cache))
    best = lambda runs: min(runs, key=lambda stats: stats["first"]["cpu_s"])
    return best(colds), best(warms)


def spatial_main(args, picks: list[str]) -> None:
    """The spatial entry points' table (``--spatial``)."""
    entries = [(label, entry) for label, entry in SPATIAL if not picks or any(p in label for p in picks)]
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    header = (
        "| entry point | cold: first call CPU s | programs | XLA compile s | warm call CPU s | warm call wall s "
        "| warm cache: first call CPU s | programs compiled |"
    )
    print(header)
    print("|" + "---|" * header.count(" | ") + "---|")
    results = {}
    for label, entry in entries:
        cold, warm = measure_spatial(entry, args.repeat)
        results[label] = {"cold": cold, "warm_cache": warm}
        first, again, cached = cold["first"], cold["warm"], warm["first"]
        warm_cells = f"{again['cpu_s']:.2f} | {again['wall_s']:.2f}" if again else "- | -"
        print(
            f"| {label} | {first['cpu_s']:.1f} | {first['compiles']} | {first['compile_s']:.1f} | {warm_cells} "
            f"| {cached['cpu_s']:.1f} | {cached['compiles'] - cached['cache_hits']} |",
            flush=True,
        )
    if args.programs:
        for label, result in results.items():
            programs = sorted(result["cold"]["first"]["programs"].items(), key=lambda item: -item[1][1])
            listed = ", ".join(f"{name} x{count} {seconds:.2f}s" for name, (count, seconds) in programs)
            print(f"\n{label} (XLA compile seconds, slowest first): {listed or 'none'}")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))


def measure(argv: list[str], repeat: int) -> tuple[dict, dict]:
    """The best cold and warm runs of a command out of ``repeat`` (each cold run in a new cache)."""
    colds, warms = [], []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory(prefix="spacearm-cache-") as cache:
            colds.append(run_once(argv, cache))
            warms.append(run_once(argv, cache))
    best = lambda runs: min(runs, key=lambda stats: stats["wall_s"])
    return best(colds), best(warms)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1, help="runs per command; the fastest is shown")
    parser.add_argument("--only", default="", help="comma-separated words picking commands (e.g. reach,optimize)")
    parser.add_argument("--programs", action="store_true", help="list each command's compiled programs")
    parser.add_argument("--json", help="also write the numbers to this file")
    parser.add_argument("--spatial", action="store_true", help="time the spatial entry points (UR5) instead")
    args = parser.parse_args()
    picks = [word for word in args.only.split(",") if word]
    if args.spatial:
        spatial_main(args, picks)
        return
    commands = [(label, argv) for label, argv in COMMANDS if not picks or any(p in label for p in picks)]

    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    header = (
        "| command | compiles | cold wall s | cold CPU s | compile share | warm wall s | warm CPU s | warm compiles |"
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
