"""The design objectives, all maximized.

Planar closed forms: w-bar (eq. 12), S_G (eq. 8) and S_M, over pi L^2. Joint-box
averages (`AVERAGE_OBJECTIVES`): the mean translational w*, the global conditioning index,
minus the mean base disturbance and the mean dynamic manipulability (spatial robots and
trees), and the impact averages below (every family), evaluated together by
`spacearm.analysis.averages.joint_averages`. On a robot with several
tips (a tree) the per-tip averages name their tip, ``w_avg[left/tool0]``; the disturbance
is of the whole system (C_w over every joint) and ``low_total_mass`` counts every arm.

``reach_radius`` (single-arm robots of either family): the path-independent workspace
radius (Papadopoulos & Dubowsky 1991; Umetani & Yoshida 1990, sec. 3), the closest
approach of a dynamic-singular tip position to the system centroid, by
`spacearm.analysis.workspace_search.singular_radius`. Its gradient is the envelope
theorem's: the search over the singular set runs with the design's gradient stopped, and
the derivative is taken at the minimizing posture, the set's motion included through its
Lagrange multipliers.

Impact objectives (every family; `IMPACT_OBJECTIVES`, joint-box averages of
`spacearm.analysis.impacts` on the same rule, per tip on a tree): minus the mean virtual
mass of the tip along a direction, minus the mean bus angular-rate jump per unit tip
impulse, minus the mean bus rate after capturing the problem's reference target.

Task objectives (every family; `TASK_OBJECTIVES`): minus the peak joint torque, minus the
peak force and minus the peak torque that hold the bus at rest, minus the peak reaction-wheel
momentum and torque that keep it from turning, along the problem's timed task
(`spacearm.motion.tasks.task_peaks` and `~spacearm.motion.tasks.wheel_peaks`, zero momentum).
A peak is a maximum over the task's samples, differentiable wherever one sample attains it
(almost everywhere); its gradient is that sample's.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from typing import Any

import jax
import jax.numpy as jnp

from .._core.errors import ConfigError
from ..analysis.averages import split_metric, tip_metric
from ..analysis.workspace_search import singular_radius
from ..models.family import RobotFamily, family_of
from ..motion.tasks import TimedTask, task_peaks, wheel_peaks
from ..paper import PlanarRobot, normalized_wbar, tip_coefficients

__all__ = [
    "AVERAGE_OBJECTIVES",
    "DESIGN_OBJECTIVES",
    "IMPACT_OBJECTIVES",
    "OBJECTIVES",
    "RADIUS_OBJECTIVES",
    "RADIUS_OPTIONS",
    "TASK_OBJECTIVES",
    "average_objective",
    "guaranteed_area",
    "maximum_reachable_area",
    "objective",
    "objective_name",
    "objectives_for",
    "reach_radius",
    "split_objective",
    "task_objective",
    "task_objectives",
    "total_mass_objective",
]

OBJECTIVES = ("wbar", "S_G", "S_M")

# Objective name -> (joint_average metric, sign): all maximized.
AVERAGE_OBJECTIVES = {
    "w_avg": ("manipulability", 1.0),  # mean translational w*, m^3
    "gci": ("conditioning", 1.0),  # global conditioning index, mean 1/kappa(J*_v)
    "low_disturbance": ("base_disturbance", -1.0),  # minus the mean ||C_w||_F, rad/rad
    "w_d_avg": ("dynamic_manipulability", 1.0),  # mean dynamic manipulability
}
# Joint-box averages of the impact quantities (`spacearm.analysis.impacts`), every family.
IMPACT_OBJECTIVES = {
    "low_virtual_mass": ("virtual_mass", -1.0),  # minus the mean virtual mass along u, kg
    "low_bus_rate_jump": ("bus_rate_jump", -1.0),  # minus the mean bus rate jump per tip impulse, rad/s/(N s)
    "low_capture_bus_rate": ("capture_bus_rate", -1.0),  # minus the mean bus rate after the capture, rad/s
}
AVERAGE_OBJECTIVES.update(IMPACT_OBJECTIVES)

# Objectives of the design itself, not averaged over postures (closed forms of the design numbers).
DESIGN_OBJECTIVES = ("low_total_mass",)  # minus the bus mass plus every arm mass, kg

# Objectives found by a search over the joint box, differentiable by the envelope theorem.
RADIUS_OBJECTIVES = ("reach_radius",)  # the path-independent workspace radius, m

# Objectives along the problem's timed task (`TimedTask`), every family: minus a peak of `TaskPeaks`.
TASK_OBJECTIVES = {
    "low_peak_joint_torque": "max_joint_torque",  # minus the largest |tau_i| (free bus), N m
    "low_peak_held_force": "held_force",  # minus the largest force holding the bus at rest, N
    "low_peak_held_torque": "held_torque",  # minus the largest torque holding the bus at rest, N m
    "low_peak_wheel_momentum": "wheel_momentum",  # minus the largest reaction-wheel momentum, N m s
    "low_peak_wheel_torque": "wheel_torque",  # minus the largest reaction-wheel torque, N m
}
_WHEEL_FIELDS = {"wheel_momentum": "momentum", "wheel_torque": "torque"}  # of `WheelPeaks`

# The options of `reach_radius` (those of `singular_radius`) and their defaults in a design
# problem: 4x fewer samples, half the kept postures and 80 descent steps instead of the
# sweep metric's 2^14, 2048 and 150, about half its cost; on 32 UR5 mounts every radius
# agreed with a 2^15-sample search to 4e-9 m. Fewer kept postures or candidates (512 and
# 16) can miss the global minimum.
RADIUS_OPTIONS = {"samples": 4096, "keep": 1024, "candidates": 32, "descent_steps": 80, "newton_steps": 4, "seed": 0}


def objectives_for(family: RobotFamily) -> tuple[str, ...]:
    """The objective names a design problem over robots of ``family`` may use, from what the
    family declares (`RobotFamily.capabilities`): the paper's closed forms (`OBJECTIVES`) where it
    has the virtual manipulator's, the joint-box averages and the launch mass where it has those.
    ``reach_radius`` is listed for every family, so that asking for it where the family has no
    one-tip search gets `objective_name`'s reason, not a guess. The impact and task objectives
    (`IMPACT_OBJECTIVES`, `TASK_OBJECTIVES`) serve every family: the dynamics do."""
    capabilities = family.capabilities
    offered = OBJECTIVES if capabilities.virtual_manipulator else ()
    if capabilities.joint_box_averages:
        kinematic = [name for name in AVERAGE_OBJECTIVES if name not in IMPACT_OBJECTIVES]
        offered = (*offered, *kinematic, *DESIGN_OBJECTIVES)
    return (*offered, *IMPACT_OBJECTIVES, *RADIUS_OBJECTIVES, *TASK_OBJECTIVES)


def guaranteed_area(robot: PlanarRobot, *, clamp: bool = True) -> jax.Array:
    """Normalized area of the Guaranteed Workspace, S_G = r_G^2 / L^2 (eq. 8, Table 2).

    The paper's radius is r_G = |K0 - (K1 + ... + Kn)| (eq. 8). Its absolute value has
    a kink where K0 = K1 + ... + Kn, and past it the formula grows again although the
    disc is then not a workspace at all: with K0 > K1 + ... + Kn the tip stays at
    least K0 - (K1 + ... + Kn) away from the system centroid (triangle inequality on
    eq. 1), so nothing inside that circle is reachable. The honest area is therefore
    max(K1 + ... + Kn - K0, 0)^2 / L^2 (``clamp=True``): equal to the paper's formula
    wherever the disc exists, zero where it does not, and continuously differentiable
    everywhere (the square of a ramp has a zero slope at the crossing, so no kink is
    left for the optimizer). ``clamp=False`` gives the paper's (K0 - sum K)^2 / L^2.

    Args:
        robot: a design or a batch of designs.

    Returns:
        ``(...)`` dimensionless area normalized by pi L^2.
    """
    K = tip_coefficients(robot)
    margin = jnp.sum(K[..., 1:], axis=-1) - K[..., 0]
    if clamp:
        margin = jnp.maximum(margin, 0.0)
    return margin**2 / robot.reach**2


def maximum_reachable_area(robot: PlanarRobot) -> jax.Array:
    """``(...)`` S_M = (K0 + K1 + ... + Kn)^2 / L^2, the Maximum Reachable Space over pi L^2 (Table 2)."""
    K = tip_coefficients(robot)
    return jnp.sum(K, axis=-1) ** 2 / robot.reach**2


def total_mass_objective(robot) -> jax.Array:
    """``(...)`` minus the launch mass of a spatial design or a tree: bus plus every arm body, kg (maximized)."""
    return -(robot.base_mass + family_of(robot).fields.arm_mass(robot))


def reach_radius(robot, **options) -> jax.Array:
    """``()`` the path-independent workspace radius of one single-arm design, m (maximized).

    The closest approach to the system centroid of a tip position where J*_v loses rank
    (`singular_radius` with ``jacobian="generalized"``; options and defaults
    `RADIUS_OPTIONS`): inside this sphere no tip path meets a dynamic singularity,
    whatever the base attitude. ``inf`` where no sampled posture reached the singular
    set (the search then counts the design as infeasible).

    Its gradient (envelope theorem for a constrained minimum, with the minimizer polished
    by Newton steps on its KKT system, ``polish=True``): the derivative of |tip|
    at the minimizing posture held fixed, minus the Lagrange multipliers times the
    derivative of the singular-set equation there; no derivative flows through the
    sampling, descent or Newton iterations (tests/test_reach_radius.py checks it against
    central differences of the radius recomputed from scratch).
    """
    return singular_radius(robot, "generalized", **{**RADIUS_OPTIONS, **options}, polish=True)[0]


def task_objectives(names, robot, task: TimedTask) -> dict[str, jax.Array]:
    """``{name: ()}`` the task objectives among ``names`` (`TASK_OBJECTIVES`) of one design:
    minus peaks along ``task``, from at most one `task_peaks` call (joint torques with the bus
    free, the wrench holding it at rest) and one `wheel_peaks` call."""
    fields = {name: TASK_OBJECTIVES[name] for name in names if name in TASK_OBJECTIVES}
    efforts = task_peaks(robot, task) if any(f not in _WHEEL_FIELDS for f in fields.values()) else None
    wheels = wheel_peaks(robot, task) if any(f in _WHEEL_FIELDS for f in fields.values()) else None
    return {
        name: -(getattr(wheels, _WHEEL_FIELDS[field]) if field in _WHEEL_FIELDS else getattr(efforts, field))
        for name, field in fields.items()
    }


def task_objective(name: str, robot, task: TimedTask) -> jax.Array:
    """``()`` the task objective ``name`` (`TASK_OBJECTIVES`) of one design (`task_objectives`)."""
    return task_objectives((name,), robot, task)[name]


_TIP_OBJECTIVE = re.compile(r"^(\w+)\[(.+)\]$")


def split_objective(name: str) -> tuple[str, str | None]:
    """``("w_avg", "left/tool0")`` for the per-tip objective ``"w_avg[left/tool0]"``; ``(name, None)`` otherwise."""
    match = _TIP_OBJECTIVE.match(name)
    return (match.group(1), match.group(2)) if match else (name, None)


def _tip(robot, tip: str | None) -> str | int | None:
    """A tip named in an objective: its name, or its index where the robot's tips have no names."""
    if tip is not None and tip.isdigit() and tip not in getattr(robot.labels, "tip_names", ()):
        return int(tip)
    return tip


def objective_name(where: str, robot, name: str, tip: str | int | None = None) -> str:
    """The canonical name of an objective on ``robot``: a per-tip average on a robot with
    several tips carries its tip's name (``w_avg[left/tool0]``); checked (`tip_metric`)."""
    base, written = split_objective(name)
    if base in RADIUS_OBJECTIVES and not family_of(robot).capabilities.tip_radius_search:
        raise ConfigError(
            f"{where}: {base}: single-arm robots only (planar or spatial); the path-independent "
            f"radius of a robot with several tips is not built yet"
        )
    if written is not None:
        if tip is not None:
            raise ConfigError(f"{where}: give the tip once, in the name ({name}) or as tip: ({tip})")
        tip = _tip(robot, written)
    if base not in AVERAGE_OBJECTIVES:
        if tip is not None:
            raise ConfigError(f"{where}.tip: {base} is not an average over the joint box; it takes no tip")
        return base
    metric = tip_metric(where, robot, AVERAGE_OBJECTIVES[base][0], tip, label=base)
    _, index = split_metric(metric)
    if tip is None:
        return base  # one tip, or a whole-system quantity
    names = tuple(robot.labels.tip_names)
    return f"{base}[{names[index] if names else index}]"


def average_objective(name: str, robot) -> tuple[str, float] | None:
    """``(joint_averages metric, sign)`` of an average objective on ``robot`` (a per-tip one
    with its tip's index, ``manipulability[1]``), or None for an objective of the design itself."""
    base, tip = split_objective(name)
    if base not in AVERAGE_OBJECTIVES:
        return None
    metric, sign = AVERAGE_OBJECTIVES[base]
    return tip_metric("objectives", robot, metric, _tip(robot, tip), label=base), sign


def objective(
    name: str,
    *,
    wbar_options: Mapping[str, Any] | None = None,
    clamp_guaranteed: bool = True,
    radius_options: Mapping[str, Any] | None = None,
    task: TimedTask | None = None,
) -> Callable[[PlanarRobot], jax.Array]:
    """The objective ``name`` as ``f(robot) -> scalar`` (options checked by the problem's loader).

    Args:
        name: one of `OBJECTIVES` or `DESIGN_OBJECTIVES`.
        wbar_options: keyword arguments of `spacearm.paper.normalized_wbar`.
        clamp_guaranteed: see `guaranteed_area`.
        radius_options: keyword arguments of `reach_radius` (objective ``reach_radius``).
        task: the timed task of a `TASK_OBJECTIVES` objective.
    """
    if name == "wbar":
        options = dict(wbar_options or {})
        return lambda robot: normalized_wbar(robot, **options)
    if name == "S_G":
        return lambda robot: guaranteed_area(robot, clamp=clamp_guaranteed)
    if name == "S_M":
        return maximum_reachable_area
    if name == "low_total_mass":
        return total_mass_objective
    if name == "reach_radius":
        options = dict(radius_options or {})
        return lambda robot: reach_radius(robot, **options)
    if name in TASK_OBJECTIVES:
        if task is None:
            raise ValueError(f"objective {name!r} is taken along a timed task: pass task=")
        return lambda robot: task_objective(name, robot, task)
    raise ValueError(
        f"unknown objective {name!r}; known: "
        f"{', '.join((*OBJECTIVES, *DESIGN_OBJECTIVES, *RADIUS_OBJECTIVES, *TASK_OBJECTIVES))}"
    )
