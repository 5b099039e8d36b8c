"""``reach.html``: a recorded maneuver replayed frame by frame (arm, bus attitude, tip trace).

The page holds the joint history and the bus attitudes; each frame's arm is drawn by
`fk.js` from them, and the tip trace is the recorded tip (the two agree: the tests
compare them at every frame).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..._core.errors import ConfigError
from .model import view_model
from .page import write_page

__all__ = ["replay_from_npz", "write_replay_view"]


def write_replay_view(
    robot,
    path: str | Path,
    postures=None,
    *,
    base_rotation=None,
    tip,
    target=None,
    phase=None,
    seconds: float = 6.0,
    title: str | None = None,
    joints=None,
    phi=None,
) -> Path:
    """Write the replay of a maneuver.

    Args:
        robot: the robot that moved (one design).
        path: the HTML file to write.
        postures: ``(k, size)`` the postures along the maneuver, laid out as the robot's family
            lays them out (``view_model(robot)["posture"]``: a planar arm's [phi0, phi1..phin];
            a spatial or tree robot's joints), rad (m for prismatic joints). ``joints`` and
            ``phi`` are other names for it (what spatial and planar histories call it).
        base_rotation: ``(k, 3, 3)`` the bus attitude at each frame, for robots whose posture
            does not hold it (identity when absent).
        tip: ``(k, 2)`` or ``(k, 3)`` the tip about the system centroid, inertial axes, m.
        target: ``(2,)`` or ``(3,)`` the point reached, drawn when given.
        phase: ``(k,)`` a label per frame (e.g. ``"loop"``, ``"straight"``), shown with the frame; the
            integer phases of a planar reach plan (0, 1, 2) are shown by name.
        seconds: the length of one playback.

    Raises:
        MissingViewExtra: plotly is not installed.
        ValueError: the arrays do not fit the robot or each other.
    """
    model = view_model(robot)
    given = [x for x in (postures, joints, phi) if x is not None]
    if len(given) != 1:
        raise ValueError("postures: give the posture history (k, size) once (postures, joints or phi)")
    q, size = np.asarray(given[0], float), model["posture"]["size"]
    if q.ndim != 2 or q.shape[1] != size:
        raise ValueError(f"postures: expected shape (k, {size}), got {q.shape}")
    R = _attitudes(model, base_rotation, len(q))
    tip = np.asarray(tip, float)
    if tip.ndim != 2 or tip.shape[0] != len(q):
        raise ValueError(f"tip: expected {len(q)} rows, got shape {tip.shape}")
    frames = dict(
        q=q, R=R, tip=tip, phase=None if phase is None else [_phase_name(p) for p in np.asarray(phase).ravel()]
    )
    reach = float(np.max(np.linalg.norm(tip, axis=-1)))
    extent = max(model["extent"], 1.1 * reach, 0.0 if target is None else 1.1 * float(np.linalg.norm(target)))
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


def _attitudes(model: dict, base_rotation, count: int):
    """The ``(count, 3, 3)`` bus attitudes a replay carries, or ``None`` where the posture holds
    the attitude (the page turns the bus from the posture itself)."""
    if model["posture"]["base_turn"] is not None:
        if base_rotation is not None:
            raise ValueError("base_rotation: this robot's posture holds its bus attitude; give the postures alone")
        return None
    if base_rotation is None:
        return np.broadcast_to(np.eye(3), (count, 3, 3))
    R = np.asarray(base_rotation, float)
    if R.shape != (count, 3, 3):
        raise ValueError(f"base_rotation: expected shape ({count}, 3, 3), got {R.shape}")
    return R


# The integer phases of spacearm.planning.reach.ReachPlan.phase.
_PHASES = {0: "repositioning move", 1: "reorientation loop", 2: "straight tip path"}


def _phase_name(value) -> str:
    if isinstance(value, (int, np.integer)) or (isinstance(value, (float, np.floating)) and float(value).is_integer()):
        return _PHASES.get(int(value), str(value))
    return str(value)


def replay_from_npz(robot, npz_path: str | Path, path: str | Path, **options) -> Path:
    """The replay of a ``reach.npz`` history: the postures (the first of the keys
    ``postures_rad``, ``phi`` and ``joints`` with the robot's posture size), the tip (``tip`` or ``tips_m``), and ``base_rotation``, ``target``
    (or ``target_m``) and ``phase`` when present.

    Raises:
        ConfigError: the file holds no history (naming the file and the keys).
    """
    with np.load(npz_path) as archive:
        arrays = {key: archive[key] for key in archive.files}
    # The first of these keys that holds whole postures of this robot: a planar history keeps
    # its joints apart from its postures, which lead with the bus attitude.
    size = view_model(robot)["posture"]["size"]
    keys = [key for key in ("postures_rad", "phi", "joints") if np.shape(arrays.get(key))[1:] == (size,)]
    postures = arrays[keys[0]] if keys else None
    tip = arrays.get("tip", arrays.get("tips_m"))
    if postures is None or tip is None:
        raise ConfigError(
            f"{npz_path}: no history to replay (needs the postures, 'joints', 'phi' or 'postures_rad', "
            "and the tip, 'tip' or 'tips_m')"
        )
    return write_replay_view(
        robot,
        path,
        postures,
        base_rotation=arrays.get("base_rotation"),
        tip=tip,
        target=arrays.get("target", arrays.get("target_m")),
        phase=arrays.get("phase"),
        **options,
    )
