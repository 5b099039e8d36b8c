"""``spacearm simulate ROBOT --torques FILE.csv --dt SECONDS``: the free-floating robot under joint torques.

Reads the joint torques (one row per sample interval, one column per joint, held over the
interval), runs `spacearm.simulate` from ``--posture``/``--rates`` (default zero) with the
system momentum ``--momentum`` (default zero) and writes into ``--out``:

- ``simulation.npz``: time (T+1,), joints, rates (T+1, n), the attitude (planar ``phi``
  (T+1, n+1); otherwise ``base_rotation`` (T+1, 3, 3)), ``bus_rate`` (T+1, d) in bus axes,
  ``base_velocity``, ``tip`` (about the system centroid, inertial), the torques and the stop;
- ``simulation.csv``: time, the attitude (phi0, or R row by row), joints, rates, bus rate;
- ``simulation.png``: joints, the bus rotation from the start and the bus rate over time;
- ``simulation.html``: the replay (`spacearm.figures.views.replay`), when the ``view`` extra
  is installed (``--no-html`` leaves it out);
- ``manifest.json``: the resolved run, the torque file's SHA-256, versions, timings.

The folder changes as a whole or not at all (`spacearm.io.folders`); invalid input ends with
exit status 2 and one message naming the file or option and the field, before anything is written.
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from pathlib import Path

import numpy as np

from .._core.errors import ConfigError
from ..io.folders import check_output_folder, claimed_folder, replacing_folder
from ._args import add_state_options, check_finite, robot_state, write_run_manifest

# The files a simulate run writes; the other entries of --out are kept.
_FILES = frozenset({"simulation.npz", "simulation.csv", "simulation.png", "simulation.html", "manifest.json"})
_REPLAY_FRAMES = 400  # at most this many frames in the replay (every k-th sample)
_STOP_NAMES = {1: "joint limit", 2: "bus rate above the bound"}


def register(subparsers) -> None:
    """Register ``spacearm simulate ROBOT.yaml --torques FILE.csv --dt SECONDS``."""
    parser = subparsers.add_parser(
        "simulate",
        help="simulate the free-floating robot under joint torques (trajectory, plots, replay)",
        description=(
            "Integrate the free-floating robot (gravity zero, no external wrench, the system momentum "
            "constant) under joint torques held over each sample interval: the bus attitude on its group, "
            "the joints and rates by the free-floating forward dynamics (spacearm.simulate). Writes "
            "simulation.npz, simulation.csv, simulation.png, simulation.html (with the 'view' extra) and "
            "manifest.json into --out."
        ),
    )
    parser.add_argument("robot", help="robot YAML file, e.g. configs/ur5-smallsat.yaml or configs/umetani1990.yaml")
    parser.add_argument(
        "--torques",
        required=True,
        metavar="FILE.csv",
        help="joint torques, N m (N for prismatic joints): one row per sample interval, one column per joint "
        "in the robot's joint order; a first row of names is a header",
    )
    parser.add_argument("--dt", required=True, type=float, metavar="SECONDS", help="the sample interval, s")
    add_state_options(parser, "at the start")
    parser.add_argument("--substeps", type=int, default=None, help="integrator steps per interval (default 2)")
    parser.add_argument("--stop-at-limits", action="store_true", help="stop where a joint reaches its limit")
    parser.add_argument(
        "--max-bus-rate",
        type=float,
        default=None,
        metavar="RATE",
        help="stop where the bus angular speed exceeds RATE, deg/s (rad/s with --radians)",
    )
    parser.add_argument("--no-html", action="store_true", help="do not write the replay simulation.html")
    parser.add_argument("--out", default="results/simulate", help="output folder (default results/simulate)")


def read_torques(path: str, n: int) -> np.ndarray:
    """``(T, n)`` finite torques from a CSV file; ConfigError naming the file, the line and the joint."""
    try:
        with open(path, encoding="utf-8", newline="") as handle:
            reader = csv.reader(handle)
            rows = [(reader.line_num, row) for row in reader if any(cell.strip() for cell in row)]
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise ConfigError(f"--torques {path}: cannot read it ({getattr(error, 'strerror', None) or error})") from None
    if rows and not _numeric(rows[0][1][0]):
        rows = rows[1:]  # a header
    if not rows:
        raise ConfigError(f"--torques {path}: no rows of torques (one row per sample interval, {n} columns)")
    values = np.empty((len(rows), n))
    for i, (line, row) in enumerate(rows):
        if len(row) != n:
            raise ConfigError(f"--torques {path}: line {line} has {len(row)} columns; the robot has {n} joints")
        for j, cell in enumerate(row):
            if not _numeric(cell) or not math.isfinite(float(cell)):
                raise ConfigError(
                    f"--torques {path}: line {line}, joint {j + 1}: expected a finite number, got {cell!r}"
                )
            values[i, j] = float(cell)
    return values


def _numeric(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _check_options(args: argparse.Namespace) -> None:
    if not (math.isfinite(args.dt) and args.dt > 0.0):
        raise ConfigError(f"--dt {args.dt:g}: expected a positive finite interval in seconds")
    if args.substeps is not None and not 1 <= args.substeps <= 64:
        raise ConfigError(f"--substeps {args.substeps}: expected 1 to 64")
    if args.max_bus_rate is not None and not (math.isfinite(args.max_bus_rate) and args.max_bus_rate > 0.0):
        raise ConfigError(f"--max-bus-rate {args.max_bus_rate:g}: expected a positive finite rate")


def run(args: argparse.Namespace) -> int:
    from ..figures.views.page import view_extra_available
    from ..io import git_state
    from ..models import load_robot
    from ..models.family import family_of

    _check_options(args)
    robot = load_robot(args.robot)
    family = family_of(robot)
    torques = read_torques(args.torques, family.joint_count(robot))
    start = robot_state(args, robot, family)
    html = not args.no_html and view_extra_available()
    out = Path(args.out)
    check_output_folder(out)
    git = git_state()  # before anything is written
    with claimed_folder(out, "simulate", label=f"--out {out}"):
        began = time.perf_counter()
        arrays = _simulate(args, robot, family, torques, start)
        seconds = time.perf_counter() - began
        check_finite(arrays, "the simulation's")
        with replacing_folder(out, keep=lambda name: name not in _FILES) as staging:
            files = _write(args, robot, family, arrays, staging, html)
            config = _config(args, start, torques)
            write_run_manifest(staging, "simulate", config, files, git, seconds)
    _summary(args, family, arrays, out, files, html)
    return 0


def _simulate(args: argparse.Namespace, robot, family, torques: np.ndarray, start) -> dict:
    """The run and what the files hold, as host arrays (see the module docstring)."""
    from .. import base_velocity, simulate, tip_position
    from ..motion.simulation import DEFAULT_SUBSTEPS

    posture, rates, rotation, momentum = start
    group = family.attitude
    offset = family.posture_offset
    options = dict(momentum=momentum, substeps=args.substeps or DEFAULT_SUBSTEPS, stop_at_limits=args.stop_at_limits)
    if args.max_bus_rate is not None:
        options["max_bus_rate"] = args.max_bus_rate if args.radians else math.radians(args.max_bus_rate)
    if not offset:
        options["base_rotation"] = rotation
    result = simulate(robot, posture, rates, torques, args.dt, **options)
    events = args.stop_at_limits or args.max_bus_rate is not None
    states = [np.asarray(x) for x in (result[:-1] if events else result)]
    step, reason = (int(result[-1].step), int(result[-1].reason)) if events else (len(torques), 0)
    if offset:  # the posture holds the attitude
        postures, qd = states
        R, attitude = None, group.from_coords(postures[:, :offset])
        joints = postures[:, offset:]
        held = {"phi": postures}
    else:
        R, joints, qd = states
        postures, attitude = joints, R
        held = {"base_rotation": R}
    nu = np.asarray(base_velocity(robot, postures, qd, base_rotation=R, momentum=momentum))
    change = np.asarray(group.log(group.compose(group.inverse(attitude[:1]), attitude)))
    return dict(
        time=args.dt * np.arange(len(torques) + 1),
        joints=joints,
        rates=qd,
        **held,
        bus_rate=nu[:, -group.dim :],
        base_velocity=nu,
        attitude_change=change,
        tip=np.asarray(tip_position(robot, postures, base_rotation=R)),
        torques=torques,
        momentum=momentum,
        stop_step=np.asarray(step),
        stop_reason=np.asarray(reason),
    )


def _table(robot, family, arrays: dict) -> dict:
    """The CSV's columns: time, the attitude, joints, rates and the bus rate (SI units in the names)."""
    kinds = family.joint_kinds(robot)
    columns = {"time_s": arrays["time"]}
    if "phi" in arrays:
        for i in range(family.posture_offset):
            columns[f"phi{i}_rad"] = arrays["phi"][:, i]
    else:
        for i in range(3):
            for j in range(3):
                columns[f"R{i + 1}{j + 1}"] = arrays["base_rotation"][:, i, j]
    for name, unit in (("q", ""), ("qd", "_s")):
        values = arrays["joints" if name == "q" else "rates"]
        for j, kind in enumerate(kinds):
            columns[f"{name}{j + 1}_{'m' if kind == 'prismatic' else 'rad'}{unit}"] = values[:, j]
    for i, axis in enumerate(family.attitude.angular_axes):
        columns[f"w{'xyz'[axis]}_rad_s"] = arrays["bus_rate"][:, i]
    return columns


def _write(args: argparse.Namespace, robot, family, arrays: dict, staging: Path, html: bool) -> list[Path]:
    from ..figures.dynamics import draw_simulation
    from ..io import write_csv, write_npz

    names = family.joint_names(robot) or tuple(f"joint {j + 1}" for j in range(family.joint_count(robot)))
    files = [write_npz(staging / "simulation.npz", joint_names=np.array(names), **arrays)]
    files.append(write_csv(staging / "simulation.csv", _table(robot, family, arrays)))
    step, reason = int(arrays["stop_step"]), int(arrays["stop_reason"])
    files.append(
        draw_simulation(
            staging / "simulation.png",
            arrays["time"],
            arrays["joints"],
            arrays["attitude_change"],
            arrays["bus_rate"],
            joint_labels=names,
            prismatic=[kind == "prismatic" for kind in family.joint_kinds(robot)],
            axis_labels=["xyz"[axis] for axis in family.attitude.angular_axes],
            stop_time=float(arrays["time"][step]) if reason else None,
            stop_label=_STOP_NAMES.get(reason, ""),
            title=f"{robot.name}: {len(arrays['torques'])} intervals of {args.dt:g} s",
        )
    )
    if html:
        files.append(write_replay(robot, arrays, staging / "simulation.html"))
    return files


def write_replay(robot, arrays: dict, path: Path) -> Path:
    """The replay page of the run, at most `_REPLAY_FRAMES` frames (the last sample kept)."""
    from ..figures.views import write_replay_view

    count = len(arrays["time"])
    frames = np.unique(np.r_[np.arange(0, count, max(1, math.ceil(count / _REPLAY_FRAMES))), count - 1])
    tip = arrays["tip"][frames]
    postures = arrays["phi"] if "phi" in arrays else arrays["joints"]
    rotation = arrays.get("base_rotation")
    return write_replay_view(
        robot,
        path,
        postures[frames],
        base_rotation=None if rotation is None else rotation[frames],
        tip=tip if tip.ndim == 2 else tip[:, 0],  # several tips: the first one's trace
        seconds=float(np.clip(arrays["time"][-1], 2.0, 30.0)),
        title=f"{robot.name}: simulated {arrays['time'][-1]:g} s",
    )


def _config(args: argparse.Namespace, start, torques: np.ndarray) -> dict:
    """The resolved run, SI units (the manifest's config)."""
    from ..io.manifest import file_sha256
    from ..motion.simulation import DEFAULT_SUBSTEPS

    posture, rates, rotation, momentum = start
    return {
        "robot": args.robot,
        "torques": {"path": args.torques, "sha256": file_sha256(args.torques), "intervals": len(torques)},
        "dt_s": args.dt,
        "posture": posture.tolist(),
        "rates": rates.tolist(),
        "base_rotation": None if rotation is None else np.asarray(rotation).tolist(),
        "momentum": momentum.tolist(),
        "substeps": args.substeps or DEFAULT_SUBSTEPS,
        "stop_at_limits": bool(args.stop_at_limits),
        "max_bus_rate_rad_s": None
        if args.max_bus_rate is None
        else (args.max_bus_rate if args.radians else math.radians(args.max_bus_rate)),
    }


def _summary(args: argparse.Namespace, family, arrays: dict, out: Path, files: list[Path], html: bool) -> None:
    group = family.attitude
    change = arrays["attitude_change"]
    speed = np.linalg.norm(arrays["bus_rate"], axis=1)
    step, reason = int(arrays["stop_step"]), int(arrays["stop_reason"])
    lines = [
        f"intervals      {len(arrays['torques'])} of {args.dt:g} s ({arrays['time'][-1]:g} s)",
        f"bus rotation   {np.degrees(np.linalg.norm(change[-1])):.6f} deg from start to end ({group.name})",
        f"bus rate       {np.degrees(speed.max()):.6f} deg/s at most",
        "end joints     " + ", ".join(f"{v:.6f}" for v in arrays["joints"][-1]) + " (rad; m for prismatic joints)",
    ]
    if reason:
        lines.append(f"stopped        at sample {step} ({arrays['time'][step]:g} s): {_STOP_NAMES[reason]}")
    lines += [f"wrote          {out / path.name}" for path in files] + [f"manifest       {out / 'manifest.json'}"]
    if not html and not args.no_html:
        lines.append("replay         not written: it needs the 'view' extra (pip install -e \".[view]\")")
    print("\n".join(lines))
