"""``spacearm reach ROBOT --from PHI0,..,PHIn --to X,Y``: plan how the tip reaches a point."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from .._core.errors import ConfigError


def _numbers(text: str, count: int, what: str) -> np.ndarray:
    try:
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise ConfigError(f"{what}: expected {count} comma-separated numbers, got {text!r}") from None
    if values.size != count or not np.all(np.isfinite(values)):
        raise ConfigError(f"{what}: expected {count} finite comma-separated numbers, got {text!r}")
    return values


def register(subparsers) -> None:
    """Register ``spacearm reach ROBOT.yaml --from PHI0,PHI1,..,PHIn --to X,Y``."""
    parser = subparsers.add_parser(
        "reach",
        help="plan how the tip reaches an inertial point (straight path, or base reorientation first)",
        description=(
            "Plan a motion that brings the tip to an inertial target (Umetani & Yoshida 1990, sec. 3.2, "
            "points B and C): a straight tip path when the target is in the current Straight-Path "
            "workspace, otherwise a cyclic joint maneuver that turns the base first. Writes reach.png "
            "(and reach.npz with the whole history) into --out. Exit 2 for a target outside the "
            "Maximum Reachable space."
        ),
    )
    parser.add_argument("robot", help="robot YAML file, e.g. configs/umetani1990.yaml")
    parser.add_argument(
        "--from",
        dest="start",
        required=True,
        metavar="PHI0,PHI1,..",
        help="start posture: base attitude then joint angles, in DEGREES (radians with --radians); "
        "write --from=-10,20,30 when the first value is negative",
    )
    parser.add_argument(
        "--to", dest="target", required=True, metavar="X,Y",
        help="target in the inertial frame, m, origin at the system centroid (--to=-2,1 for a negative x)",
    )
    parser.add_argument("--radians", action="store_true", help="read --from in radians")
    parser.add_argument("--out", default="results/reach", help="output folder (default results/reach)")
    parser.add_argument("--animate", action="store_true", help="also write reach.gif")


def run(args: argparse.Namespace) -> int:
    from ..figures.planning import animate_reach, draw_reach
    from ..io import write_npz
    from ..models import load_robot
    from ..planning import plan_reach

    robot = load_robot(args.robot)
    phi = _numbers(args.start, robot.n_links + 1, "--from")
    if not args.radians:
        phi = np.radians(phi)
    target = _numbers(args.target, 2, "--to")
    plan = plan_reach(robot, phi, target)
    out = Path(args.out)
    figure_path = draw_reach(robot, phi, plan, out / "reach.png")
    lines = [
        f"mode           {plan.mode}",
        f"start tip      ({plan.tips[0, 0]:.6f}, {plan.tips[0, 1]:.6f}) m",
        f"target         ({target[0]:.6f}, {target[1]:.6f}) m",
        f"base rotation  {np.degrees(plan.delta_phi0):.6f} deg by {plan.loops} loop(s)",
        f"joint travel   {plan.joint_travel:.6f} rad",
        f"straight path  {plan.straight_length:.6f} m",
        "end posture    " + ", ".join(f"{v:.6f}" for v in np.degrees(plan.end_posture)) + " deg",
        f"tip error      {plan.error:.3e} m",
        f"figure         {figure_path}",
    ]
    if args.animate:
        lines.append(f"animation      {animate_reach(robot, plan, out / 'reach.gif')}")
    write_npz(
        out / "reach.npz",
        postures_rad=plan.postures,
        tips_m=plan.tips,
        phase=plan.phase,
        joint_waypoints_rad=plan.joint_waypoints,
        target_m=plan.target,
    )
    print("\n".join(lines))
    return 0
