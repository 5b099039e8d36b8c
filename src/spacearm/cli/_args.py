"""Argument parsing, result checks and manifests shared by the commands."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .._core.errors import ConfigError, RunError
from .._core.groups import rpy_matrix

__all__ = [
    "add_state_options",
    "check_finite",
    "check_limits",
    "comma_numbers",
    "robot_state",
    "write_run_manifest",
]


def comma_numbers(text: str, count: int, what: str) -> np.ndarray:
    """``count`` finite numbers from ``"a,b,c"`` (an option's value); ConfigError naming ``what``."""
    try:
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise ConfigError(f"{what}: expected {count} comma-separated numbers, got {text!r}") from None
    if values.size != count or not np.all(np.isfinite(values)):
        raise ConfigError(f"{what}: expected {count} finite comma-separated numbers, got {text!r}")
    return values


def check_limits(what: str, values, lower, upper, *, degrees, prismatic=False, names=None) -> None:
    """ConfigError naming the first of ``values`` (rad, or m where ``prismatic``) outside
    ``[lower, upper]``, in the units the user typed: degrees for a revolute joint when
    ``degrees`` (flags per joint, or one for all)."""
    values, lower, upper = (np.asarray(a, dtype=float) for a in (values, lower, upper))
    outside = (values < lower) | (values > upper)
    if not np.any(outside):
        return
    j = int(np.argmax(outside))
    if np.broadcast_to(prismatic, values.shape)[j]:
        scale, unit = 1.0, "m"
    else:
        scale, unit = (180.0 / np.pi, "deg") if np.broadcast_to(degrees, values.shape)[j] else (1.0, "rad")
    name = f" ({names[j]})" if names is not None else ""
    raise ConfigError(
        f"{what}: joint {j + 1}{name} = {values[j] * scale:.6g} {unit} is outside its limits "
        f"[{lower[j] * scale:.6g}, {upper[j] * scale:.6g}] {unit}"
    )


def add_state_options(parser: argparse.ArgumentParser, when: str) -> None:
    """``--posture``, ``--rates``, ``--attitude-rpy``, ``--momentum`` and ``--radians``: the
    free-floating robot's state ``when`` (``"at the start"``), read by `robot_state`."""
    parser.add_argument(
        "--posture",
        default=None,
        metavar="Q1,Q2,..",
        help=f"the posture {when}, DEGREES (radians with --radians; m for prismatic joints): planar robots the "
        "bus attitude then the joints, others the joints; default all zero (--posture=-10,20 for a negative first "
        "value)",
    )
    parser.add_argument(
        "--rates",
        default=None,
        metavar="QD1,..",
        help=f"the joint rates {when}, deg/s (rad/s with --radians); default zero",
    )
    parser.add_argument(
        "--attitude-rpy",
        dest="attitude",
        default=None,
        metavar="R,P,Y",
        help=f"the bus attitude {when} as roll, pitch, yaw (URDF convention), degrees, for robots whose posture "
        "does not hold it; default the identity",
    )
    parser.add_argument(
        "--momentum",
        default=None,
        metavar="PX,PY,..",
        help=f"the system momentum {when} [P; L about the system centroid], inertial axes, kg m/s and kg m^2/s: six "
        "numbers, planar robots three (Px, Py, L); default zero",
    )
    parser.add_argument("--radians", action="store_true", help="read --posture, --rates, --attitude-rpy in radians")


def robot_state(args: argparse.Namespace, robot, family):
    """``(posture, rates, base rotation or None, momentum)`` from `add_state_options`' options,
    in SI units (rad, rad/s; m and m/s for prismatic joints); ConfigError naming the option."""
    n = family.joint_count(robot)
    offset = family.posture_offset
    kinds = np.array([kind == "prismatic" for kind in family.joint_kinds(robot)])
    prismatic = np.r_[np.zeros(offset, bool), kinds]
    posture = np.zeros(n + offset) if args.posture is None else comma_numbers(args.posture, n + offset, "--posture")
    rates = np.zeros(n) if args.rates is None else comma_numbers(args.rates, n, "--rates")
    if not args.radians:
        posture = np.where(prismatic, posture, np.radians(posture))
        rates = np.where(kinds, rates, np.radians(rates))
    names = family.joint_names(robot) or None
    lower, upper = robot.joint_lower, robot.joint_upper
    check_limits("--posture", posture[offset:], lower, upper, degrees=not args.radians, prismatic=kinds, names=names)
    rotation = None
    if args.attitude is not None:
        if offset:
            raise ConfigError(
                "--attitude-rpy: this robot's posture holds its bus attitude; give it as the first --posture value"
            )
        rpy = comma_numbers(args.attitude, 3, "--attitude-rpy")
        rotation = rpy_matrix(rpy if args.radians else np.radians(rpy))
    axes = len(family.twist_axes)
    momentum = np.zeros(axes) if args.momentum is None else comma_numbers(args.momentum, axes, "--momentum")
    return posture, rates, rotation, momentum


def check_finite(arrays: Mapping[str, object], what: str) -> None:
    """RunError (exit 1) naming the first of ``arrays`` that holds a NaN or an infinity, as
    ``what``'s quantity (``"the simulation's"``), before anything is written."""
    for name, value in arrays.items():
        values = np.asarray(value, dtype=float)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            where = f" at index {tuple(int(i) for i in np.unravel_index(bad[0], values.shape))}" if values.ndim else ""
            raise RunError(
                f"{what} {name} is {float(values.flat[bad[0]])}{where} "
                f"({bad.size} non-finite of {values.size}); nothing was written"
            )


def write_run_manifest(staging: Path, kind: str, config: dict, files: list[Path], git: dict, seconds: float) -> Path:
    """``manifest.json`` of a ``spacearm <kind>`` run in ``staging``: the resolved ``config``,
    the files written, the command line, versions, git state and the run's time."""
    from ..io import build_manifest, write_json

    names = [path.name for path in files] + ["manifest.json"]
    data = build_manifest(
        config, command=sys.argv, timings={kind: seconds}, git=git, extra={"kind": kind, "files": names}
    )
    return write_json(staging / "manifest.json", data)
