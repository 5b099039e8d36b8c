"""Impact and capture quantities at a posture, as the joint-box averages read them.

Three posture metrics of one tip (a tree names its tip), each with the bus at rest, its
attitude the identity (inertial axes = bus axes) and zero system momentum:

- ``virtual_mass``: 1 / (u^T G_v u), kg, the mass a point target striking the hand along the
  unit direction u meets (`spacearm.dynamics.virtual_mass`; G Yoshida's extended inversed
  inertia tensor);
- ``bus_rate_jump``: ||dw_bus|| under a unit linear impulse at the tip along u, rad/s per N s
  (`spacearm.dynamics.bus_rate_jump`);
- ``capture_bus_rate``: ||w_bus|| right after a rigid, plastic grasp of a reference target by
  the resting robot, rad/s (`spacearm.dynamics.capture`). The target is held the same way at
  every posture: its offset and inertia are given in the TIP frame (turned to inertial axes
  at each posture by `spacearm.dynamics.payload.target_from_tip_frame`), its velocity in
  bus axes (a client drifting past the servicer, whatever the arm's posture).

`ImpactSetup` carries what they need besides the posture: the direction u (bus axes; default
`DEFAULT_DIRECTION`, the bus x axis), the reference target (`target_from_mapping`) and whether
the joints are free or locked during the impact (default free: no impulsive joint torque).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError
from .._core.groups import safe_norm
from .._core.schema import check_keys, choice, number
from ..dynamics import JOINT_MODES, bus_rate_jump, capture, virtual_mass
from ..dynamics.payload import target_from_tip_frame
from ..models.family import family_of

__all__ = [
    "DEFAULT_DIRECTION",
    "IMPACT_METRICS",
    "ImpactSetup",
    "impact_metric",
    "impact_setup",
    "linear_axes",
    "target_from_mapping",
]

DEFAULT_DIRECTION = (1.0, 0.0, 0.0)  # the bus x axis (planar robots: its first two components)
TARGET_KEYS = ("mass", "inertia", "offset", "velocity")


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class ImpactSetup:
    """What the impact metrics need besides the posture (a pytree: the arrays are traced,
    ``joints`` is static).

    Attributes:
        direction: ``(d,)`` unit direction of the tip impulse, bus axes (d = 3; planar 2).
        target: the reference target (a dict of arrays: ``mass``; ``offset`` and ``inertia``
            in TIP axes, the hand holding it the same way at every posture; ``velocity`` in
            bus axes), or None when no capture metric is asked for.
        joints: ``"free"`` or ``"locked"`` during the impact.
    """

    direction: jax.Array
    target: dict | None = None
    joints: str = dataclasses.field(default="free", metadata={"static": True})


def linear_axes(robot) -> int:
    """How many linear components a tip impulse of the robot's family has (3; planar 2)."""
    return int(np.sum(np.asarray(family_of(robot).twist_axes) < 3))


def _vector(where: str, value: Any, sizes: tuple[int, ...]) -> np.ndarray:
    if not isinstance(value, (list, tuple)) or len(value) not in sizes:
        wanted = " or ".join(str(size) for size in sizes)
        raise ConfigError(f"{where}: must be a list of {wanted} numbers, got {value!r}")
    return np.array([number(f"{where}[{i}]", v) for i, v in enumerate(value)])


def _inertia(where: str, value: Any, planar: bool) -> np.ndarray:
    """A 3x3 symmetric positive-definite inertia (kg m^2); a planar target may give Izz alone."""
    if planar and not isinstance(value, (list, tuple)):
        izz = number(where, value)
        if izz <= 0:
            raise ConfigError(f"{where}: must be positive (kg m^2), got {izz:g}")
        return np.asarray(izz)
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        scalar = " (or Izz alone, a number)" if planar else ""
        raise ConfigError(f"{where}: must be a 3x3 matrix about the target's centroid, kg m^2{scalar}")
    matrix = np.array([_vector(f"{where}[{i}]", row, (3,)) for i, row in enumerate(value)])
    if not np.allclose(matrix, matrix.T, rtol=1e-9, atol=1e-12 * np.max(np.abs(matrix))):
        raise ConfigError(f"{where}: must be symmetric, got {matrix.tolist()}")
    moments = np.linalg.eigvalsh(matrix)
    if moments[0] <= 0:
        raise ConfigError(f"{where}: must be positive definite (every principal moment > 0)")
    if moments[2] > moments[0] + moments[1] * (1 + 1e-12):
        raise ConfigError(
            f"{where}: no rigid body has these principal moments ({', '.join(f'{m:g}' for m in moments)}): "
            "the largest must not exceed the sum of the other two"
        )
    return matrix


def target_from_mapping(where: str, entry: Any, robot) -> dict[str, np.ndarray]:
    """A capture target as a file gives it, checked: ``mass`` (kg), ``inertia`` (3x3 about its
    centroid, kg m^2; planar robots also Izz alone), ``offset`` (its centroid minus the tip
    frame's origin, m; default zero; planar 2 or 3 numbers, z = 0) and ``velocity`` ([v of its
    centroid; w], m/s and rad/s; default zero; planar [vx, vy, w]). The axes are the reader's:
    inertial at one grasp (``spacearm capture``); tip axes for the offset and the inertia of
    a sweep's or problem's reference target (`ImpactSetup`).

    Raises:
        ConfigError: naming ``where`` and the field.
    """
    if not isinstance(entry, Mapping):
        raise ConfigError(f"{where}: must be a mapping with mass, inertia, offset and velocity")
    check_keys(f"{where}: ", entry, TARGET_KEYS)
    for key in ("mass", "inertia"):
        if key not in entry:
            raise ConfigError(f"{where}.{key}: missing required key")
    mass = number(f"{where}.mass", entry["mass"])
    if mass <= 0:
        raise ConfigError(f"{where}.mass: must be positive (kg), got {mass:g}")
    linear = linear_axes(robot)
    planar = linear == 2
    offset = _vector(f"{where}.offset", entry.get("offset", [0.0] * linear), (2, 3) if planar else (3,))
    twist = len(family_of(robot).twist_axes)
    velocity = _vector(f"{where}.velocity", entry.get("velocity", [0.0] * twist), (twist,))
    inertia = _inertia(f"{where}.inertia", entry["inertia"], planar)
    if planar and len(offset) == 3 and offset[2] != 0:
        raise ConfigError(f"{where}.offset: a planar robot's target lies in the plane (z = 0), got {offset.tolist()}")
    if planar and inertia.ndim == 2 and np.any(inertia[[0, 1], 2] != 0):
        raise ConfigError(f"{where}.inertia: a planar robot's target turns about z alone (Ixz = Iyz = 0)")
    return {"mass": np.asarray(mass), "inertia": inertia, "offset": offset, "velocity": velocity}


def impact_setup(where: str, entry: Any, robot, *, need_target: bool) -> ImpactSetup:
    """The impact metrics' settings from a file's mapping ``{direction, joints, target}``.

    Args:
        where: names the file and section in messages.
        entry: the mapping (None: the defaults; then no target).
        need_target: whether a capture metric asks for the reference target.
    """
    entry = {} if entry is None else entry
    if not isinstance(entry, Mapping):
        raise ConfigError(f"{where}: must be a mapping with direction, joints and target")
    check_keys(f"{where}: ", entry, ("direction", "joints", "target"))
    linear = linear_axes(robot)
    direction = _vector(f"{where}.direction", entry.get("direction", list(DEFAULT_DIRECTION[:linear])), (linear,))
    if not np.linalg.norm(direction) > 0:
        raise ConfigError(f"{where}.direction: must not be zero")
    joints = choice(f"{where}.joints", entry.get("joints", "free"), JOINT_MODES)
    target = None
    if need_target:
        if "target" not in entry:
            raise ConfigError(f"{where}.target: missing; the bus rate after a capture needs the reference target")
        target = target_from_mapping(f"{where}.target", entry["target"], robot)
    elif "target" in entry:
        raise ConfigError(f"{where}.target: only the bus rate after a capture uses a reference target")
    return ImpactSetup(direction / np.linalg.norm(direction), target, joints)


def _virtual_mass(robot, posture, setup: ImpactSetup, tip: int):
    return virtual_mass(robot, posture, setup.direction, tip=tip, joints=setup.joints)


def _bus_rate_jump(robot, posture, setup: ImpactSetup, tip: int):
    return bus_rate_jump(robot, posture, setup.direction, tip=tip, joints=setup.joints)


def _capture_bus_rate(robot, posture, setup: ImpactSetup, tip: int):
    n = family_of(robot).joint_count(robot)
    rest = jnp.zeros(posture.shape[:-1] + (n,), posture.dtype)
    target = target_from_tip_frame(robot, posture, setup.target, tip=tip)
    _, base, _ = capture(robot, posture, rest, target, tip=tip, joints=setup.joints)
    return safe_norm(base[..., linear_axes(robot) :])[0]  # finite gradient where a target at rest gives 0


# Metric name -> the per-posture function (robot, postures (..., p), setup, tip) -> (...).
IMPACT_METRICS = {
    "virtual_mass": _virtual_mass,
    "bus_rate_jump": _bus_rate_jump,
    "capture_bus_rate": _capture_bus_rate,
}


def impact_metric(name: str, robot, posture: jax.Array, setup: ImpactSetup | None, tip: int | None) -> jax.Array:
    """``(...)`` the impact metric ``name`` (`IMPACT_METRICS`) at postures ``(..., p)`` of one
    design, at tip ``tip`` (None: the robot's one tip)."""
    if setup is None:
        raise ConfigError(f"metric: {name} needs its impact settings (impact=ImpactSetup(...))")
    if name == "capture_bus_rate" and setup.target is None:
        raise ConfigError("metric: capture_bus_rate needs the reference target (ImpactSetup.target)")
    return IMPACT_METRICS[name](robot, posture, setup, 0 if tip is None else tip)
