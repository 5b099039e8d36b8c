"""``reach.html``: a recorded maneuver replayed frame by frame (arm, bus attitude, tip trace).

The page holds the joint history and the bus attitudes; each frame's arm is drawn by
`fk.js` from them, and the tip trace is the recorded tip (the two agree: the tests
compare them at every frame).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..._core.errors import ConfigError
from ...models.planar import PlanarRobot
from .model import chain_model, scene_extent
from .page import write_page

__all__ = ["replay_from_npz", "write_replay_view"]


def write_replay_view(
    robot,
    path: str | Path,
    *,
    joints=None,
    base_rotation=None,
    phi=None,
    tip,
    target=None,
    phase=None,
    seconds: float = 6.0,
    title: str | None = None,
) -> Path:
    """Write the replay of a maneuver.

    Args:
        robot: the planar or spatial robot that moved (one design).
        path: the HTML file to write.
        joints: spatial robots: ``(k, n)`` joint values along the maneuver, rad (m for prismatic joints).
        base_rotation: spatial robots: ``(k, 3, 3)`` the bus attitude at each frame.
        phi: planar robots: ``(k, n+1)`` postures [phi0, phi1..phin], rad.
        tip: ``(k, 2)`` or ``(k, 3)`` the tip about the system centroid, inertial axes, m.
        target: ``(2,)`` or ``(3,)`` the point reached, drawn when given.
        phase: ``(k,)`` a label per frame (e.g. ``"loop"``, ``"straight"``), shown with the frame; the
            integer phases of a planar reach plan (0, 1, 2) are shown by name.
        seconds: the length of one playback.

    Raises:
        MissingViewExtra: plotly is not installed.
        ValueError: the arrays do not fit the robot or each other.
    """
    model = chain_model(robot)
    n = len(model["joint_kinds"])
    tip = np.asarray(tip, float)
    if isinstance(robot, PlanarRobot):
        if phi is None:
            raise ValueError("phi: a planar replay needs the postures (k, n+1)")
        q, R = np.asarray(phi, float), None
        if q.ndim != 2 or q.shape[1] != n + 1:
            raise ValueError(f"phi: expected shape (k, {n + 1}), got {q.shape}")
    else:
        if joints is None:
            raise ValueError("joints: a spatial replay needs the joint history (k, n)")
        q = np.asarray(joints, float)
        if q.ndim != 2 or q.shape[1] != n:
            raise ValueError(f"joints: expected shape (k, {n}), got {q.shape}")
        R = np.broadcast_to(np.eye(3), (len(q), 3, 3)) if base_rotation is None else np.asarray(base_rotation, float)
        if R.shape != (len(q), 3, 3):
            raise ValueError(f"base_rotation: expected shape ({len(q)}, 3, 3), got {R.shape}")
    if tip.ndim != 2 or tip.shape[0] != len(q):
        raise ValueError(f"tip: expected {len(q)} rows, got shape {tip.shape}")
    frames = dict(
        q=q, R=R, tip=tip, phase=None if phase is None else [_phase_name(p) for p in np.asarray(phase).ravel()]
    )
    reach = float(np.max(np.linalg.norm(tip, axis=-1)))
    extent = max(scene_extent(robot), 1.1 * reach, 0.0 if target is None else 1.1 * float(np.linalg.norm(target)))
    data = dict(
        mode="replay",
        model=model,
        frames=frames,
        extent=extent,
        seconds=float(seconds),
        target=None if target is None else np.asarray(target, float),
        title=title or f"{model['name']}: {len(q)} frames",
    )
    note = (
        "Press play or drag the frame slider. The arm is redrawn at every frame from the recorded joints and "
        "bus attitude; the red line is the recorded tip. Positions about the system centroid, inertial axes."
    )
    return write_page(path, title=f"spacearm replay: {model['name']}", note=note, data=data)


# The integer phases of spacearm.planning.reach.ReachPlan.phase.
_PHASES = {0: "repositioning move", 1: "reorientation loop", 2: "straight tip path"}


def _phase_name(value) -> str:
    if isinstance(value, (int, np.integer)) or (isinstance(value, (float, np.floating)) and float(value).is_integer()):
        return _PHASES.get(int(value), str(value))
    return str(value)


def replay_from_npz(robot, npz_path: str | Path, path: str | Path, **options) -> Path:
    """The replay of a ``reach.npz`` history: keys ``joints`` and ``base_rotation``
    (spatial) or ``phi`` (planar), and ``tip``; the planar ``postures_rad`` and ``tips_m``
    are read too, and ``target_m`` and ``phase`` when present.

    Raises:
        ConfigError: the file holds no joint history (naming the file and the keys).
    """
    with np.load(npz_path) as archive:
        arrays = {key: archive[key] for key in archive.files}
    tip = arrays.get("tip", arrays.get("tips_m"))
    target = arrays.get("target", arrays.get("target_m"))
    phase = arrays.get("phase")
    if isinstance(robot, PlanarRobot):
        phi = arrays.get("phi", arrays.get("postures_rad"))
        if phi is None or tip is None:
            raise ConfigError(f"{npz_path}: no history to replay (needs 'phi' or 'postures_rad', and 'tip')")
        return write_replay_view(robot, path, phi=phi, tip=tip, target=target, phase=phase, **options)
    joints = arrays.get("joints")
    if joints is None or tip is None:
        raise ConfigError(f"{npz_path}: no history to replay (needs 'joints', 'base_rotation' and 'tip')")
    return write_replay_view(
        robot,
        path,
        joints=joints,
        base_rotation=arrays.get("base_rotation"),
        tip=tip,
        target=target,
        phase=phase,
        **options,
    )
