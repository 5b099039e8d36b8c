"""``spacearm capture ROBOT --target FILE.yaml``: what a rigid grasp of a drifting target does to the robot.

The tip frame grasps a target rigidly and perfectly plastically (`spacearm.capture`: momentum
balance of the robot and of the target through Yoshida's extended inversed inertia tensor;
Yoshida & Nenchev, "Space robot impact analysis and satellite-base impulse minimization using
reaction null-space", ICRA 1995; Yoshida, Kurazume & Umetani, "Dual arm coordination in space
free-flying robot", ICRA 1991). The robot's state at the grasp comes from ``--posture``,
``--rates``, ``--attitude-rpy`` and ``--momentum`` (the robot's own momentum before the grasp),
read as `spacearm simulate` reads them. ``--joints free`` lets the joints give way (no impulsive
joint torque), ``--joints locked`` holds them (their rates unchanged by the impact).

The target file (YAML, inertial axes at the grasp; the format of a sweep's reference
target, `spacearm.analysis.impacts.target_from_mapping`)::

    mass: 50.0                                   # kg, > 0
    inertia: [[2.54, 0, 0], [0, 2.17, 0], [0, 0, 1.71]]   # kg m^2 about its centroid
    offset: [0.25, 0.05, 0.0]                    # m, its centroid minus the tip frame's origin
    velocity: [0.02, -0.01, 0.0, 0.01, 0.02, 0.03]   # [v of its centroid, m/s; w, rad/s]

``offset`` defaults to zero (grasped at its centroid) and ``velocity`` to zero (at rest).
Planar robots take ``offset`` [x, y] (or three numbers), ``velocity`` [vx, vy, w] and the
inertia as its moment about the plane's normal (a number) or a 3x3. The inertia must be
symmetric and positive definite.

Prints the joint rates, the bus velocity and angular rate after the grasp, the impulse on the
tip and the target's speed change, and writes into ``--out``:

- ``capture.json``: the resolved inputs and the post-grasp state, SI units, inertial axes;
- ``capture.html``: the replay of the next ``--seconds`` (`spacearm.simulate` without joint
  torques from the post-grasp state; `spacearm.figures.views.replay`), when the ``view`` extra
  is installed (``--no-html`` leaves it out);
- ``manifest.json``: the resolved run, the target file's SHA-256, versions, timings.

The replay is of the robot holding the target: after a rigid grasp the target moves with the
tip frame, so it is welded to the tip's body (`spacearm.grasped_robot`: its mass, centroid and
inertia turned into tip axes at the grasp and merged by the parallel-axis theorem), and the
combined system starts at the post-grasp bus velocity and joint rates, whose momentum
(`spacearm.system_momentum`) is the robot's plus the target's after the grasp. A planar link
holds its centroid on its line, so a planar robot's replay needs the target's centroid on the
last link's line at the grasp; otherwise no replay is written and the command prints why (the
numbers, which include the target, are printed and written as always).
The folder changes as a whole or not at all (`spacearm.io.folders`); invalid input ends with
exit status 2 and one message naming the file or option and the field, before anything is written.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from .._core.errors import ConfigError
from .._core.schema import read_yaml
from ..io.folders import check_output_folder, claimed_folder, replacing_folder
from ._args import add_state_options, check_finite, robot_state, write_run_manifest
from .simulate import write_replay

# The files a capture run writes; the other entries of --out are kept.
_FILES = frozenset({"capture.json", "capture.html", "manifest.json"})
_MAX_INTERVALS = 100_000


def register(subparsers) -> None:
    """Register ``spacearm capture ROBOT.yaml --target FILE.yaml``."""
    parser = subparsers.add_parser(
        "capture",
        help="grasp a drifting target: the joint rates, bus rate and impulse after the grasp, and a replay",
        description=(
            "A rigid, perfectly plastic grasp of a target by the tip frame (spacearm.capture, Yoshida's extended "
            "inversed inertia tensor): prints the joint rates, the bus velocity and angular rate, the impulse and "
            "the target's speed change after the grasp, and writes capture.json, capture.html (the next --seconds "
            "of the robot, with the 'view' extra) and manifest.json into --out."
        ),
    )
    parser.add_argument("robot", help="robot YAML file, e.g. configs/ur5-smallsat.yaml or configs/umetani1990.yaml")
    parser.add_argument(
        "--target",
        required=True,
        metavar="FILE.yaml",
        help="the target: mass (kg), inertia (3x3 about its centroid, kg m^2; planar robots also a number), offset "
        "(its centroid minus the tip frame's origin, m) and velocity ([v of its centroid; w], m/s and rad/s), "
        "inertial axes; e.g. configs/targets/client-50kg.yaml",
    )
    add_state_options(parser, "at the grasp")
    parser.add_argument(
        "--tip", default=None, metavar="NAME", help="several arms on one bus: the tip that grasps, a name or an index"
    )
    parser.add_argument(
        "--joints",
        choices=("free", "locked"),
        default="free",
        help="free: the joints give way (no impulsive joint torque); locked: they hold (default free)",
    )
    parser.add_argument("--seconds", type=float, default=5.0, help="the replay's length after the grasp, s (default 5)")
    parser.add_argument("--dt", type=float, default=0.01, metavar="SECONDS", help="the replay's sample interval, s")
    parser.add_argument("--no-html", action="store_true", help="do not write the replay capture.html")
    parser.add_argument("--out", default="results/capture", help="output folder (default results/capture)")


def read_target(path: str, robot) -> dict:
    """The target file's mass, inertia, offset and velocity as arrays (SI units, inertial
    axes), by the rules of a sweep's reference target
    (`spacearm.analysis.impacts.target_from_mapping`); ConfigError naming the file and the field."""
    from ..analysis.impacts import target_from_mapping

    return target_from_mapping(f"{path}: target", read_yaml(path, what="target file"), robot)


def _numbers(values, digits: int = 6) -> str:
    return ", ".join(f"{float(v):.{digits}g}" for v in np.ravel(values))


def _check_options(args: argparse.Namespace) -> int:
    """The replay's number of intervals, checked."""
    for option, value in (("--seconds", args.seconds), ("--dt", args.dt)):
        if not (math.isfinite(value) and value > 0.0):
            raise ConfigError(f"{option} {value:g}: expected a positive finite time in seconds")
    intervals = round(args.seconds / args.dt)
    if not 1 <= intervals <= _MAX_INTERVALS:
        raise ConfigError(
            f"--seconds {args.seconds:g}, --dt {args.dt:g}: {intervals} intervals; expected 1 to {_MAX_INTERVALS:,}"
        )
    return intervals


def _tip(args: argparse.Namespace, robot, family) -> tuple[int, str]:
    """The grasping tip's index and name (``--tip`` on several arms; the one tip otherwise)."""
    if family.tip_count(robot) is None:
        if args.tip is not None:
            raise ConfigError("--tip: applies to robots with several arms (files with arms: or system:)")
        return 0, "tip"
    names = tuple(robot.tip_names)
    tip = names[0] if args.tip is None else args.tip
    if tip not in names and tip.isdigit():
        tip = int(tip)
    try:
        index = robot.focus(tip=tip).active_tip
    except ConfigError as error:
        raise ConfigError(f"--{error}") from None
    return index, names[index]


def run(args: argparse.Namespace) -> int:
    from ..figures.views.page import view_extra_available
    from ..io import git_state
    from ..models import load_robot
    from ..models.family import family_of

    intervals = _check_options(args)
    robot = load_robot(args.robot)
    family = family_of(robot)
    target = read_target(args.target, robot)
    state = robot_state(args, robot, family)
    tip = _tip(args, robot, family)
    html = not args.no_html and view_extra_available()
    out = Path(args.out)
    check_output_folder(out)
    git = git_state()  # before anything is written
    with claimed_folder(out, "capture", label=f"--out {out}"):
        began = time.perf_counter()
        result = grasp(robot, family, state, target, tip[0], args.joints)
        carried, payload = holding(robot, state, target, tip[0], result)
        check_finite(result, "the capture's")
        arrays = None
        if html and carried is not None:
            arrays = _replay_run(carried, family, state, result, intervals, args.dt, tip[0])
        if arrays is not None:
            check_finite(arrays, "the replay's")
        seconds = time.perf_counter() - began
        config = _config(args, state, target, tip, intervals, payload)
        with replacing_folder(out, keep=lambda name: name not in _FILES) as staging:
            files = _write(carried, staging, config, result, arrays)
            write_run_manifest(staging, "capture", config, files, git, seconds)
    _summary(args, robot, tip, target, result, out, files, html, payload)
    return 0


def holding(robot, state, target: dict, tip: int, result: dict):
    """The robot with the target welded to its tip at the grasp (`spacearm.grasped_robot`: the
    target in tip axes, `spacearm.target_in_tip_frame`, merged by `spacearm.with_payload`) and
    that payload as lists, or ``(None, {"skipped": reason})`` where the family cannot hold it (a
    planar target centred off the last link's line).

    Adds ``momentum_with_target`` to ``result``: the combined system's momentum at the
    post-grasp bus velocity and joint rates (`spacearm.system_momentum`), the state the replay
    starts from (the robot's momentum after plus the target's after, as the grasp conserves it).
    """
    from .. import system_momentum, target_in_tip_frame, with_payload

    posture, _, rotation, _ = state
    payload = {
        key: np.asarray(value) for key, value in target_in_tip_frame(robot, posture, target, rotation, tip).items()
    }
    try:
        carried = with_payload(robot, payload["mass"], payload["com"], payload["inertia"], tip)
    except ConfigError as error:
        return None, {"skipped": str(error)}
    result["momentum_with_target"] = np.asarray(
        system_momentum(carried, posture, result["qd_after"], result["base_after"], rotation)
    )
    return carried, {key: value.tolist() for key, value in payload.items()}


def grasp(robot, family, state, target: dict, tip: int, joints: str) -> dict:
    """`spacearm.capture` at the state and what follows from it, host arrays, inertial axes:

    - ``qd_after``, ``base_after`` ([v of the bus centroid; w]) and ``impulse`` (on the tip
      frame [linear; angular about its origin]): `spacearm.capture`'s;
    - ``base_before``: `spacearm.base_velocity` at the state, turned to inertial axes;
    - ``momentum_after``: the robot's own momentum after the grasp, [P + F; L + N + r x F]
      with r the tip about the system centroid (which an impulse does not move);
    - ``target_after``: the target's [v of its centroid; w] after, from its momentum balance
      under the impulse's reaction: dv = -F/m, dw = I^-1 (-N + offset x F).
    """
    from .. import base_velocity, capture, tip_position

    posture, rates, rotation, momentum = state
    qd_after, base_after, impulse = (
        np.asarray(x) for x in capture(robot, posture, rates, target, rotation, momentum, tip=tip, joints=joints)
    )
    r = np.asarray(tip_position(robot, posture, base_rotation=rotation))
    r = r[tip] if r.ndim == 2 else r
    force, torque = _split(impulse)
    planar = family.posture_offset > 0
    axes = _bus_axes(posture, rotation, planar)
    before = np.asarray(base_velocity(robot, posture, rates, base_rotation=rotation, momentum=momentum))
    offset = target["offset"][:2] if planar else target["offset"]
    inertia = np.asarray(target["inertia"])
    dv = -force / target["mass"]
    if planar:
        moment = inertia if inertia.ndim == 0 else inertia[2, 2]
        dw = np.atleast_1d((-torque + _cross2(offset, force)) / moment)
        gained = np.r_[force, torque + _cross2(r, force)]
    else:
        dw = np.linalg.solve(inertia, -torque + np.cross(offset, force))
        gained = np.r_[force, torque + np.cross(r, force)]
    return {
        "qd_after": qd_after,
        "base_after": base_after,
        "impulse": impulse,
        "base_before": _turned(axes, before),
        "momentum_after": momentum + gained,
        "target_after": target["velocity"] + np.r_[dv, dw],
    }


def _split(twist_or_wrench: np.ndarray):
    """``(linear, angular)`` of a twist or wrench: planar [x, y, rz] gives ((2,), a number), spatial ((3,), (3,))."""
    if twist_or_wrench.shape[-1] == 3:
        return twist_or_wrench[:2], twist_or_wrench[2]
    return twist_or_wrench[:3], twist_or_wrench[3:]


def _cross2(a: np.ndarray, b: np.ndarray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def _bus_axes(posture: np.ndarray, rotation, planar: bool) -> np.ndarray:
    """The bus attitude at the grasp: bus axes -> inertial (planar: the 2x2 of phi0)."""
    if planar:
        c, s = math.cos(posture[0]), math.sin(posture[0])
        return np.array([[c, -s], [s, c]])
    return np.eye(3) if rotation is None else np.asarray(rotation)


def _turned(axes: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """A bus twist [v; w] from bus axes to inertial axes (planar w is about the normal)."""
    linear, angular = _split(twist)
    return np.r_[axes @ linear, angular if axes.shape == (2, 2) else axes @ angular]


def _replay_run(robot, family, state, result: dict, intervals: int, dt: float, tip: int) -> dict:
    """The robot holding the target (`holding`) for ``intervals`` of ``dt`` after the grasp,
    without joint torques, from the post-grasp joint rates and the combined system's momentum
    (``momentum_with_target``): the arrays `write_replay` draws."""
    from .. import simulate, tip_position

    posture, _, rotation, _ = state
    n = family.joint_count(robot)
    torques = np.zeros((intervals, n))
    momentum = result["momentum_with_target"]
    times = dt * np.arange(intervals + 1)
    if family.posture_offset:
        phi, _ = simulate(robot, posture, result["qd_after"], torques, dt, momentum=momentum)
        arrays = {"time": times, "phi": np.asarray(phi)}
        rotations = None
    else:
        R, joints, _ = simulate(
            robot, posture, result["qd_after"], torques, dt, base_rotation=rotation, momentum=momentum
        )
        arrays = {"time": times, "joints": np.asarray(joints), "base_rotation": np.asarray(R)}
        rotations = arrays["base_rotation"]
    postures = arrays.get("phi", arrays.get("joints"))
    tips = np.asarray(tip_position(robot, postures, base_rotation=rotations))
    arrays["tip"] = tips[:, tip] if tips.ndim == 3 else tips
    return arrays


def _config(args: argparse.Namespace, state, target: dict, tip: tuple[int, str], intervals: int, payload: dict) -> dict:
    """The resolved inputs, SI units (capture.json's and the manifest's config)."""
    from ..io.manifest import file_sha256

    posture, rates, rotation, momentum = state
    return {
        "robot": args.robot,
        "target": {
            "path": args.target,
            "sha256": file_sha256(args.target),
            **{key: np.asarray(value).tolist() for key, value in target.items()},
        },
        "posture": posture.tolist(),
        "rates": rates.tolist(),
        "base_rotation": None if rotation is None else np.asarray(rotation).tolist(),
        "momentum": momentum.tolist(),
        "tip": {"index": tip[0], "name": tip[1]},
        "joints": args.joints,
        "replay": {"seconds": intervals * args.dt, "dt_s": args.dt, "intervals": intervals, "payload": payload},
    }


def _write(robot, staging: Path, config: dict, result: dict, arrays: dict | None) -> list[Path]:
    from ..io import write_json

    units = {
        "qd_after": "rad/s (m/s for prismatic joints)",
        "base_after": "[v of the bus centroid, m/s; w, rad/s], inertial axes",
        "base_before": "[v of the bus centroid, m/s; w, rad/s], inertial axes",
        "impulse": "on the tip frame: [linear, N s; angular about its origin, N m s], inertial axes",
        "momentum_after": "the robot's own [P, kg m/s; L about its centroid, kg m^2/s], inertial axes",
        "momentum_with_target": "robot and target welded: [P, kg m/s; L about their centroid, kg m^2/s], inertial axes",
        "target_after": "[v of its centroid, m/s; w, rad/s], inertial axes",
    }
    state = {name: np.asarray(value).tolist() for name, value in result.items()}
    files = [write_json(staging / "capture.json", {"inputs": config, "after": state, "units": units})]
    if arrays is not None:
        files.append(write_replay(robot, arrays, staging / "capture.html"))
    return files


def _summary(args, robot, tip, target: dict, result: dict, out: Path, files: list[Path], html: bool, payload) -> None:
    force, torque = _split(result["impulse"])
    v_after, w_after = _split(result["base_after"])
    _, w_before = _split(result["base_before"])
    v0, w0 = _split(target["velocity"])
    v1, w1 = _split(result["target_after"])
    degrees = np.degrees
    lines = [
        f"grasp          {robot.name}, tip {tip[0]} ({tip[1]}), joints {args.joints}; target {target['mass']:g} kg",
        f"joint rates    {_numbers(result['qd_after'])} rad/s after ({_numbers(degrees(result['qd_after']))} deg/s)",
        f"bus velocity   {_numbers(v_after)} m/s after (bus centroid, inertial axes)",
        f"bus rate       {_numbers(w_after)} rad/s after = {_numbers(degrees(w_after))} deg/s "
        f"(|w| {np.degrees(np.linalg.norm(w_before)):.6g} -> {np.degrees(np.linalg.norm(w_after)):.6g} deg/s)",
        f"impulse        {_numbers(force)} N s, {_numbers(torque)} N m s (on the tip, about its origin, inertial)",
        f"target speed   {np.linalg.norm(v0):.6g} -> {np.linalg.norm(v1):.6g} m/s (change {np.linalg.norm(v1 - v0):.6g}"
        f" m/s); spin {degrees(np.linalg.norm(w0)):.6g} -> {degrees(np.linalg.norm(w1)):.6g} deg/s",
    ]
    lines += [f"wrote          {out / path.name}" for path in files] + [f"manifest       {out / 'manifest.json'}"]
    if "skipped" in payload:
        lines.append(f"replay         not written: {payload['skipped']} (the numbers above include the target)")
    elif html:
        length = round(args.seconds / args.dt) * args.dt  # whole intervals of --dt
        lines.append(f"replay         {length:g} s of the robot holding the target (welded to the tip)")
    elif not args.no_html:
        lines.append("replay         not written: it needs the 'view' extra (pip install -e \".[view]\")")
    print("\n".join(lines))
