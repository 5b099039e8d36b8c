"""``spacearm reach ROBOT --from ... --to ...``: plan how the tip reaches a point.

Planar robots: ``--from PHI0,PHI1,..,PHIn`` (base attitude, joints) and ``--to X,Y``.
Spatial robots (files with ``arm:``): ``--from Q1,..,Qn`` (joints), ``--to X,Y,Z`` and an
optional start bus attitude ``--attitude-rpy R,P,Y``. With ``--to-rpy R,P,Y`` (arms of 6 or
more joints) the target is a pose: the tip frame's axes as well, reached by one straight
pose path (`spacearm.planning.plan_pose_reach`). Several arms on one bus (files with
``arms:`` or ``system:``): the same, with ``--from`` over all n joints, ``--tip NAME`` (the
tip that reaches; default the first) and ``--moving ARM,..`` (the arms, tips or joints that
move; default all, so the other arms move too), through
`spacearm.models.tree.robot.TreeRobot.focus`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from .._core.errors import ConfigError
from .._core.groups import rpy_matrix
from ..io.folders import check_output_folder, claimed_folder, replacing_folder
from ._args import check_finite, check_limits, comma_numbers

# The files a reach run writes; the other entries of --out are kept.
_REACH_FILES = frozenset({"reach.png", "reach.npz", "reach.gif", "reach.html"})


def _result_folder(out: Path):
    """A staging folder beside ``out`` (with the entries of ``out`` that are not a reach
    run's files) that replaces ``out`` as a whole when the block ends without an error
    (`spacearm.io.folders.replacing_folder`); the caller holds the folder's lock."""
    return replacing_folder(out, keep=lambda name: name not in _REACH_FILES)


def register(subparsers) -> None:
    """Register ``spacearm reach ROBOT.yaml --from PHI0,PHI1,..,PHIn --to X,Y``."""
    parser = subparsers.add_parser(
        "reach",
        help="plan how the tip reaches an inertial point (straight path, or base reorientation first)",
        description=(
            "Plan a motion that brings the tip to an inertial target (Umetani & Yoshida 1990, sec. 3.2, "
            "points B and C): a straight tip path when the target is in the current Straight-Path "
            "workspace, otherwise a cyclic joint maneuver that turns the base first. Writes reach.png "
            "and reach.npz into --out: the whole history, joints (k, n), tip (k, 2 or 3), phase (k,) and "
            "phi (k, n+1) planar or base_rotation (k, 3, 3) spatial. Exit 2 for a target outside the "
            "Maximum Reachable space (the radius is named). Several arms on one bus: --tip chooses the "
            "tip, --moving the arms that move (reach.npz: joints over all arms, tip of the chosen tip)."
        ),
    )
    parser.add_argument("robot", help="robot YAML file, e.g. configs/umetani1990.yaml or configs/ur5-smallsat.yaml")
    parser.add_argument(
        "--from",
        dest="start",
        required=True,
        metavar="PHI0,PHI1,..",
        help="start posture, in DEGREES (radians with --radians): planar robots the base attitude then "
        "the joint angles; spatial robots the joints only (prismatic joints in m); "
        "write --from=-10,20,30 when the first value is negative",
    )
    parser.add_argument(
        "--to",
        dest="target",
        required=True,
        metavar="X,Y[,Z]",
        help="target in the inertial frame, m, origin at the system centroid: X,Y planar, X,Y,Z spatial "
        "(--to=-2,1 for a negative x)",
    )
    parser.add_argument(
        "--attitude-rpy",
        dest="attitude",
        default=None,
        metavar="R,P,Y",
        help="spatial robots: the bus attitude at the start as roll, pitch, yaw (URDF convention), "
        "degrees (radians with --radians); default the identity",
    )
    parser.add_argument(
        "--to-rpy",
        dest="target_rpy",
        default=None,
        metavar="R,P,Y",
        help="spatial arms of 6 or more joints: also aim the tip frame's axes, as roll, pitch, yaw in inertial "
        "axes (URDF convention), degrees (radians with --radians); the tip then moves along one straight "
        "pose path (position on the line, axes on the geodesic) and reach.npz also holds tip_rotation (k, 3, 3)",
    )
    parser.add_argument(
        "--tip",
        default=None,
        metavar="NAME",
        help="several arms on one bus: the tip that reaches the target (default the first tip)",
    )
    parser.add_argument(
        "--moving",
        default=None,
        metavar="ARM,..",
        help="several arms on one bus: the arms (or tips, or joints) that move, comma-separated; the "
        "others are held where they are (default: every joint moves)",
    )
    parser.add_argument("--radians", action="store_true", help="read --from, --attitude-rpy and --to-rpy in radians")
    parser.add_argument(
        "--loop-counts",
        metavar="N,..",
        default=None,
        help="when the bus must turn first: the repetition counts of the joint loop tried "
        "(default planar 1,2,3,4,6,8,12,16,24,32,48,64; spatial 1,2,4,8)",
    )
    parser.add_argument(
        "--harmonics",
        type=int,
        default=None,
        help="when the bus must turn first: Fourier harmonics of the joint loop (default planar 3, spatial 2)",
    )
    parser.add_argument("--out", default="results/reach", help="output folder (default results/reach)")
    parser.add_argument("--animate", action="store_true", help="also write reach.gif")
    parser.add_argument(
        "--html",
        action="store_true",
        help="also write reach.html: an interactive offline replay (needs the 'view' extra)",
    )


def run(args: argparse.Namespace) -> int:
    from ..models import load_robot
    from ..models.family import family_of
    from ..motion.pose_paths import check_pose_robot

    if args.html:  # the 'view' extra is checked before any work (exit 2 naming it)
        from ..figures.views.page import plotly_bundle

        plotly_bundle()
    robot = load_robot(args.robot)
    family = family_of(robot)
    spatial = family.rotates_with_base
    if not spatial and args.attitude is not None:
        raise ConfigError("--attitude-rpy: applies to spatial robots; a planar posture starts with its base attitude")
    several = family.tip_count(robot) is not None
    if several:
        robot = _focus(args, robot)
    else:
        for option, value in (("--tip", args.tip), ("--moving", args.moving)):
            if value is not None:
                raise ConfigError(f"{option}: applies to robots with several arms (files with arms: or system:)")
    if several and args.html:
        raise ConfigError("--html: the replay is not available for several arms on one bus yet (reach.npz holds it)")
    if args.target_rpy is not None:
        check_pose_robot(robot, "--to-rpy")
        if args.loop_counts is not None or args.harmonics is not None:
            raise ConfigError("--loop-counts, --harmonics: apply to --to targets (a pose path turns no loop)")
    out = Path(args.out)
    check_output_folder(out)
    # One writer at a time (a second one is refused naming the holder's PID); the files are
    # written into a staging folder that replaces --out as a whole.
    with claimed_folder(out, "reach", label=f"--out {out}"):
        if args.target_rpy is not None:
            return _run_pose(args, robot, out, several)
        return _run_spatial(args, robot, out, several) if spatial else _run_planar(args, robot, out)


def _settings(args: argparse.Namespace, robot):
    """The loop settings --loop-counts and --harmonics ask for (None: the planner's defaults)."""
    from ..planning import loop_settings

    changes = {}
    if args.loop_counts is not None:
        counts = comma_numbers(args.loop_counts, len(args.loop_counts.split(",")), "--loop-counts")
        if np.any(counts < 1) or np.any(counts != np.round(counts)) or np.any(counts > 256):
            raise ConfigError(f"--loop-counts {args.loop_counts}: expected whole numbers from 1 to 256")
        changes["loop_counts"] = tuple(int(c) for c in counts)
    if args.harmonics is not None:
        if not 1 <= args.harmonics <= 16:
            raise ConfigError(f"--harmonics {args.harmonics}: expected 1 to 16")
        changes["harmonics"] = args.harmonics
    return loop_settings(robot, **changes) if changes else None


def _focus(args: argparse.Namespace, robot):
    """The tree focused on ``--tip`` with ``--moving`` (errors name the option)."""
    tip = robot.tip_names[0] if args.tip is None else args.tip
    moving = None if args.moving is None else [name.strip() for name in args.moving.split(",")]
    try:
        robot = robot.focus(tip=tip)
    except ConfigError as error:
        raise ConfigError(f"--{error}") from None
    try:
        return robot.focus(tip=robot.active_tip, moving=moving)
    except ConfigError as error:
        raise ConfigError(f"--{error}") from None


def _run_planar(args: argparse.Namespace, robot, out: Path) -> int:
    from ..figures.planning import animate_reach, draw_reach
    from ..io import write_npz
    from ..planning import plan_reach

    phi = comma_numbers(args.start, robot.n_links + 1, "--from")
    if not args.radians:
        phi = np.radians(phi)
    check_limits("--from", phi[1:], robot.joint_lower, robot.joint_upper, degrees=not args.radians)
    target = comma_numbers(args.target, 2, "--to")
    plan = plan_reach(robot, phi, target, settings=_settings(args, robot))
    arrays = dict(
        joints=plan.postures[:, 1:],
        phi=plan.postures,
        tip=plan.tips,
        phase=plan.phase,
        postures_rad=plan.postures,
        tips_m=plan.tips,
        joint_waypoints_rad=plan.joint_waypoints,
        target_m=plan.target,
    )
    check_finite({**arrays, "tip error": plan.error, "base rotation": plan.delta_phi0}, "the plan's")
    with _result_folder(out) as staging:
        draw_reach(robot, phi, plan, staging / "reach.png")
        if args.animate:
            animate_reach(robot, plan, staging / "reach.gif")
        write_npz(staging / "reach.npz", **arrays)
        _write_replay(args, robot, staging)
    lines = [
        f"mode           {plan.mode}",
        f"start tip      ({plan.tips[0, 0]:.6f}, {plan.tips[0, 1]:.6f}) m",
        f"target         ({target[0]:.6f}, {target[1]:.6f}) m",
        f"base rotation  {np.degrees(plan.delta_phi0):.6f} deg by {plan.loops} loop(s)",
        f"joint travel   {plan.joint_travel:.6f} rad",
        f"straight path  {plan.straight_length:.6f} m",
        "end posture    " + ", ".join(f"{v:.6f}" for v in np.degrees(plan.end_posture)) + " deg",
        f"tip error      {plan.error:.3e} m",
        f"figure         {out / 'reach.png'}",
    ]
    if args.animate:
        lines.append(f"animation      {out / 'reach.gif'}")
    if args.html:
        lines.append(f"replay         {out / 'reach.html'}")
    print("\n".join(lines))
    return 0


def _run_spatial(args: argparse.Namespace, robot, out: Path, several: bool) -> int:
    from ..figures.spatial import draw_spatial_reach
    from ..io import write_npz
    from ..planning import plan_reach

    q, R0, prismatic = _spatial_start(args, robot)
    target = comma_numbers(args.target, 3, "--to")
    if args.animate:
        raise ConfigError("--animate: not available for spatial robots yet (reach.png shows the plan)")
    plan = plan_reach(robot, q, target, base_rotation=R0, settings=_settings(args, robot))
    arrays = dict(
        joints=plan.joints,
        base_rotation=plan.base_rotation,
        tip=plan.tips,
        phase=plan.phase,
        loop_waypoints=plan.loop_waypoints,
        loop_rotation=plan.loop_rotation,
        target_m=target,
    )
    tree = _tree_record(robot, arrays) if several else []
    check_finite({**arrays, "tip error": plan.error, "bus rotation": plan.bus_turn}, "the plan's")
    with _result_folder(out) as staging:
        draw_spatial_reach(robot, plan, staging / "reach.png")  # one arm or several
        write_npz(staging / "reach.npz", **arrays)
        _write_replay(args, robot, staging)
    loop = f"by {plan.loops} pass(es) of a loop, then" if plan.loops else "along"
    lines = tree + [
        f"mode           {plan.mode}",
        f"target         ({target[0]:.6f}, {target[1]:.6f}, {target[2]:.6f}) m",
        f"bus rotation   {np.degrees(plan.bus_turn):.6f} deg from start to end ({loop} the straight path)",
        f"straight path  {plan.straight_length:.6f} m",
        "end joints     "
        + ", ".join(f"{v:.6f}" for v in np.where(prismatic, plan.end_joints, np.degrees(plan.end_joints)))
        + " (deg; m for prismatic joints)",
        f"tip error      {plan.error:.3e} m",
        f"figure         {out / 'reach.png'}",
    ]
    if args.html:
        lines.append(f"replay         {out / 'reach.html'}")
    print("\n".join(lines))
    return 0


def _tree_record(robot, arrays: dict) -> list[str]:
    """Several arms on one bus (the tree `_focus` made): add the chosen tip and the moving mask
    to reach.npz's arrays; the summary's lines naming them."""
    arrays.update(tip_index=np.asarray(robot.active_tip), moving=robot.moving_mask)
    lines = [f"tip            {robot.active_tip_name}"]
    if not robot.moving_mask.all():
        lines.append(f"held joints    {int(np.sum(~robot.moving_mask))} of {robot.n_joints} (kept at --from)")
    return lines


def _spatial_start(args: argparse.Namespace, robot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(joints, start bus attitude, prismatic mask)`` from --from and --attitude-rpy."""
    q = comma_numbers(args.start, robot.n_joints, "--from")
    prismatic = np.array([kind == "prismatic" for kind in robot.joint_kinds])
    if not args.radians:
        q = np.where(prismatic, q, np.radians(q))
    check_limits(
        "--from",
        q,
        robot.joint_lower,
        robot.joint_upper,
        degrees=not args.radians,
        prismatic=prismatic,
        names=robot.joint_names,
    )
    R0 = np.eye(3)
    if args.attitude is not None:
        rpy = comma_numbers(args.attitude, 3, "--attitude-rpy")
        R0 = np.asarray(rpy_matrix(rpy if args.radians else np.radians(rpy)))
    return q, R0, prismatic


def _rpy_of(R: np.ndarray) -> np.ndarray:
    """URDF roll, pitch, yaw of a rotation matrix R = Rz(y) Ry(p) Rx(r), rad."""
    pitch = np.arcsin(np.clip(-R[2, 0], -1.0, 1.0))
    return np.array([np.arctan2(R[2, 1], R[2, 2]), pitch, np.arctan2(R[1, 0], R[0, 0])])


def _run_pose(args: argparse.Namespace, robot, out: Path, several: bool) -> int:
    from ..figures.spatial import draw_spatial_reach
    from ..io import write_npz
    from ..planning import plan_pose_reach

    q, R0, prismatic = _spatial_start(args, robot)
    target = comma_numbers(args.target, 3, "--to")
    rpy = comma_numbers(args.target_rpy, 3, "--to-rpy")
    T1 = np.asarray(rpy_matrix(rpy if args.radians else np.radians(rpy)))
    if args.animate:
        raise ConfigError("--animate: not available for spatial robots yet (reach.png shows the plan)")
    plan = plan_pose_reach(robot, q, target, T1, base_rotation=R0)
    arrays = dict(
        joints=plan.joints,
        base_rotation=plan.base_rotation,
        tip=plan.tips,
        tip_rotation=plan.tip_rotations,
        phase=plan.phase,
        progress=plan.progress,
        target_m=target,
        target_rotation=T1,
    )
    tree = _tree_record(robot, arrays) if several else []
    check_finite({**arrays, "tip error": plan.error, "tip axes error": plan.rotation_error}, "the plan's")
    with _result_folder(out) as staging:
        draw_spatial_reach(robot, plan, staging / "reach.png")  # one arm or several
        write_npz(staging / "reach.npz", **arrays)
        _write_replay(args, robot, staging)
    lines = tree + [
        f"mode           {plan.mode} (tip on a straight line, tip axes along the geodesic)",
        f"target         ({target[0]:.6f}, {target[1]:.6f}, {target[2]:.6f}) m",
        "target rpy     " + ", ".join(f"{v:.6f}" for v in np.degrees(_rpy_of(T1))) + " deg",
        f"bus rotation   {np.degrees(plan.bus_turn):.6f} deg from start to end (along the straight pose path)",
        "end bus rpy    " + ", ".join(f"{v:.6f}" for v in np.degrees(_rpy_of(plan.end_rotation))) + " deg",
        f"straight path  {plan.straight_length:.6f} m, tip axes turned {np.degrees(plan.tip_turn):.6f} deg",
        "end joints     "
        + ", ".join(f"{v:.6f}" for v in np.where(prismatic, plan.end_joints, np.degrees(plan.end_joints)))
        + " (deg; m for prismatic joints)",
        f"tip error      {plan.error:.3e} m, {plan.rotation_error:.3e} rad",
        f"sigma_min J*   {plan.min_singular:.6f} (smallest along the path)",
        f"figure         {out / 'reach.png'}",
    ]
    if args.html:
        lines.append(f"replay         {out / 'reach.html'}")
    print("\n".join(lines))
    return 0


def _write_replay(args: argparse.Namespace, robot, out: Path) -> None:
    """``--html``: reach.html, the replay of the history just written to reach.npz (figures.views)."""
    if args.html:
        from ..figures.views import replay_from_npz

        replay_from_npz(robot, out / "reach.npz", out / "reach.html")
