"""The metric registry of sweeps: each metric's per-design function, its table columns and
the checks of its options (run when a sweep is loaded, so ``spacearm validate`` refuses
what a run would).
"""

from __future__ import annotations

import dataclasses
import functools
import json
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import jax.numpy as jnp

from .._core.errors import ConfigError
from .._core.schema import check_keys, choice, did_you_mean, integer, is_number
from ..analysis.averages import PER_TIP_METRICS, joint_average, joint_averages, split_metric, tip_metric
from ..analysis.impacts import DEFAULT_DIRECTION, IMPACT_METRICS, impact_setup
from ..analysis.joint_box import check_joint_box
from ..analysis.workspace_search import reachable_radii, singular_radius
from ..dynamics import BASE_MODES
from ..kinematics import base_rate_matrix, generalized_jacobian, manipulability
from ..models.family import Capabilities, family_of, known_families
from ..motion.tasks import TimedTask, task_from_mapping, task_peaks, wheel_peaks
from ..paper import (
    PlanarRobot,
    attachment_condition,
    check_average_options,
    normalized_areas,
    normalized_wbar,
    normalized_workspace_areas,
    straight_path_workspace,
    tip_coefficients,
)

__all__ = [
    "METRICS",
    "WBAR_OPTIONS",
    "Metric",
    "MetricSpec",
    "attach_task",
    "design_function",
    "metric_columns",
    "metric_specs",
    "resolve_tips",
]


@dataclasses.dataclass(frozen=True)
class MetricSpec:
    """A metric of a sweep file: its name and options."""

    name: str
    options: dict


@dataclasses.dataclass(frozen=True)
class Metric:
    """Per-design scalars: ``fn(robot, options) -> {column: value}``, traceable."""

    fn: Callable[[Any, dict], dict]
    columns: Callable[[dict], list[str]]
    check: Callable[[str, dict], None] = lambda where, options: _no_options(where, options)
    description: str = ""
    # Checks that need the base robot (e.g. its number of links).
    check_robot: Callable[[str, dict, Any], None] = lambda where, options, robot: None
    # Whether a family offers the metric, from what it declares (`RobotFamily.capabilities`);
    # by default the paper's virtual-manipulator closed forms.
    offered: Callable[[Capabilities], bool] = lambda capabilities: capabilities.virtual_manipulator
    # At most this many designs vmapped together per device step (None: the runner's
    # default). Adaptive loops (the joint-box averages) run a vmapped step until its
    # slowest design is done, so they want small steps.
    designs_per_step: int | None = None
    # Whether the metric is taken along the sweep's timed task (``task:``, `attach_task`).
    needs_task: bool = False

    @property
    def families(self) -> tuple[str, ...]:
        """The names of the families that offer the metric (for messages and help)."""
        return tuple(family.name for family in known_families() if self.offered(family.capabilities))


def _no_options(where: str, options: dict) -> None:
    if options:
        raise ConfigError(f"{where}: this metric takes no options, got {', '.join(options)}")


# The options of spacearm.paper.normalized_wbar a sweep file may set (the rest are
# about batching, which the sweep does itself).
WBAR_OPTIONS = ("measure", "elbow", "rule", "phi1_panels", "phi2_panels", "order", "newton_steps", "n_points_joint")


def _check_wbar(where: str, options: dict) -> None:
    check_keys(f"{where}: ", options, WBAR_OPTIONS)
    check_average_options(where=f"{where}.", **options)


def _check_wbar_robot(where: str, options: dict, robot: PlanarRobot) -> None:
    if robot.n_links != 2 and options.get("measure", "area") == "area":
        raise ConfigError(
            f"{where}: wbar's area average (eq. 12) is defined for 2 links, the robot has {robot.n_links}; "
            "use {name: wbar, measure: joint}"
        )


def _check_straight_robot(where: str, options: dict, robot: PlanarRobot) -> None:
    phi = options.get("phi_start_deg", [0.0, -60.0, 120.0])
    if len(phi) != robot.n_links + 1:
        raise ConfigError(
            f"{where}.phi_start_deg: needs {robot.n_links + 1} angles [phi0, phi1, ..., phi{robot.n_links}] "
            f"for a {robot.n_links}-link robot, got {len(phi)}"
        )


def _wbar(robot, options):
    return {"wbar": normalized_wbar(robot, **options)}


def _areas(robot, options):
    s_m, s_g = normalized_areas(robot)
    return {"S_M": s_m, "S_G": s_g}


def _radii(robot, options):
    K = tip_coefficients(robot)
    arm = jnp.sum(K[1:])
    return {
        "K0_m": K[0],
        "R_attitude_m": arm,
        "R_max_m": K[0] + arm,
        "R_guaranteed_m": jnp.abs(K[0] - arm),
        "L_m": robot.reach,
    }


def _workspace_areas(robot, options):
    areas = normalized_workspace_areas(robot)
    return {
        "S_fixed_vehicle": areas["fixed_vehicle"],
        "S_attitude_constraint": areas["attitude_constraint"],
        "S_maximum_reachable": areas["maximum_reachable"],
        "S_guaranteed": areas["guaranteed"],
        "eq9_holds": attachment_condition(robot).astype(areas["guaranteed"].dtype),
    }


def _check_straight(where: str, options: dict) -> None:
    allowed = {"phi_start_deg", "n_directions"}
    check_keys(f"{where}: ", options, allowed)
    phi = options.get("phi_start_deg", [0.0, -60.0, 120.0])
    if not isinstance(phi, (list, tuple)) or not all(is_number(v) for v in phi):
        raise ConfigError(f"{where}.phi_start_deg: must be a list of numbers [phi0, phi1, ..., phin] in degrees")
    integer(f"{where}.n_directions", options.get("n_directions", 72), least=8)


def _straight_area(robot, options):
    phi = jnp.radians(jnp.asarray(options.get("phi_start_deg", [0.0, -60.0, 120.0]), dtype=float))
    boundary = straight_path_workspace(robot, phi, n_directions=options.get("n_directions", 72))
    x, y = boundary[:, 0], boundary[:, 1]
    area = 0.5 * jnp.abs(jnp.sum(x * jnp.roll(y, -1) - jnp.roll(x, -1) * y))  # shoelace
    return {"S_straight": area / (jnp.pi * robot.reach**2)}


def _check_posture(where: str, options: dict) -> None:
    check_keys(f"{where}: ", options, {"q_deg", "tip"})
    tip = options.get("tip")
    if tip is not None and (isinstance(tip, bool) or not isinstance(tip, (str, int))):
        raise ConfigError(f"{where}.tip: a tip's name or index, got {tip!r}")
    q = options.get("q_deg")
    if q is not None and (not isinstance(q, (list, tuple)) or not all(is_number(v) for v in q)):
        raise ConfigError(f"{where}.q_deg: must be a list of joint positions in degrees, one per joint")


def _posture_tip(options: dict, robot, where: str = "metrics") -> int | None:
    """The tip index the ``posture`` metric reads on a robot with several tips (None: one tip)."""
    return split_metric(tip_metric(where, robot, "manipulability", options.get("tip"), label="posture"))[1]


def _posture_columns(options: dict) -> list[str]:
    """w*, 1/kappa (of the chosen tip, named in the column on a robot with several) and ||C_w||_F."""
    tip = f"[{options['tip']}]" if options.get("tip") is not None else ""
    return [f"w_star_m3{tip}", f"inverse_condition{tip}", "C_w_fro"]


def _check_posture_robot(where: str, options: dict, robot) -> None:
    _posture_tip(options, robot, where)
    q = options.get("q_deg")
    if q is not None and len(q) != robot.n_joints:
        raise ConfigError(f"{where}.q_deg: needs {robot.n_joints} joint positions (one per joint), got {len(q)}")


def _posture(robot, options):
    """w*, 1/kappa(J*_v) and ||C_w||_F at one posture (joint positions in degrees,
    default 30 deg for every joint; a prismatic joint's entry is taken in m)."""
    n = len(robot.joint_kinds)
    q_deg = jnp.asarray(options.get("q_deg", [30.0] * n), dtype=robot.base_mass.dtype)
    prismatic = jnp.asarray([kind == "prismatic" for kind in robot.joint_kinds])
    q = jnp.where(prismatic, q_deg, jnp.radians(q_deg))
    J, w = generalized_jacobian(robot, q), manipulability(robot, q)
    tip = _posture_tip(options, robot)
    if tip is not None:  # several tips: the chosen tip's rows of J* over every joint
        J, w = J[tip], w[tip]
    singular = jnp.linalg.svd(J[:3], compute_uv=False)
    largest = singular[0]
    w_star, inverse_condition, disturbance = _posture_columns(options)
    return {
        w_star: w,
        inverse_condition: jnp.where(largest > 0, singular[-1] / jnp.where(largest > 0, largest, 1.0), 0.0),
        disturbance: jnp.linalg.norm(base_rate_matrix(robot, q)[3:]),
    }


# Options of analysis.averages.joint_average a sweep file may set (designs_per_chunk is
# the sweep's own business). The sweep default rtol is 1e-3, the library's 1e-4.
AVERAGE_OPTIONS = ("rtol", "randomizations", "block", "min_samples", "max_samples", "seed")
SWEEP_RTOL = 1e-3


def _check_average(where: str, options: dict) -> None:
    check_keys(f"{where}: ", options, (*AVERAGE_OPTIONS, "tip"))
    tip = options.get("tip")
    if tip is not None and (isinstance(tip, bool) or not isinstance(tip, (str, int))):
        raise ConfigError(f"{where}.tip: a tip's name or index, got {tip!r}")
    rtol = options.get("rtol", SWEEP_RTOL)
    if not is_number(rtol) or not rtol > 0:
        raise ConfigError(f"{where}.rtol: must be a positive number (the relative standard error), got {rtol!r}")
    integer(f"{where}.randomizations", options.get("randomizations", 8), least=2)
    block = integer(f"{where}.block", options.get("block", 1024), least=1)
    if block & (block - 1):
        raise ConfigError(f"{where}.block: must be a power of two, got {block}")
    least = integer(f"{where}.min_samples", options.get("min_samples", 2**14), least=1)
    most = integer(f"{where}.max_samples", options.get("max_samples", 2**24), least=1)
    if most < least:
        raise ConfigError(f"{where}.max_samples: must be at least min_samples ({least}), got {most}")
    integer(f"{where}.seed", options.get("seed", 0), least=0)


def _check_average_robot(where: str, options: dict, robot) -> None:
    try:
        check_joint_box(robot)
    except ConfigError as error:
        raise ConfigError(f"{where}: {error}") from None


# The options of the impact averages besides those of every average: the impulse direction
# (bus axes), the joints during the impact and, for the capture, the reference target.
IMPACT_OPTIONS = ("direction", "joints", "target")


def _split_options(options: dict) -> tuple[dict, dict]:
    """``(estimator options, impact options)`` of an average's options (the tip left out)."""
    average = {key: value for key, value in options.items() if key not in (*IMPACT_OPTIONS, "tip")}
    return average, {key: value for key, value in options.items() if key in IMPACT_OPTIONS}


def _check_impact(name: str):
    allowed = ("joints", "target") if name == "capture_bus_rate" else ("direction", "joints")

    def check(where: str, options: dict) -> None:
        average, impact = _split_options(options)
        _check_average(where, {**average, **({"tip": options["tip"]} if "tip" in options else {})})
        check_keys(f"{where}: ", impact, allowed)
        if name == "capture_bus_rate" and "target" not in options:
            raise ConfigError(
                f"{where}.target: missing; the bus rate after a capture needs the reference target "
                "{mass: kg, inertia: [[...], ...], offset: [...], velocity: [...]}"
            )

    return check


def _check_impact_robot(where: str, options: dict, robot) -> None:
    _check_average_robot(where, options, robot)
    impact_setup(where, _split_options(options)[1], robot, need_target="target" in options)


def _impact_of(options: dict, robot):
    """The `ImpactSetup` of an average's options (None for a kinematic average's)."""
    impact = _split_options(options)[1]
    return impact_setup("metrics", impact, robot, need_target="target" in impact)


def _average_kind(name: str, options: dict, robot, where: str = "metrics") -> str:
    """The `joint_averages` metric of sweep metric ``name`` on ``robot``: a per-tip metric
    of a robot with several tips carries its tip's index (``manipulability[1]``)."""
    return tip_metric(where, robot, _AVERAGES[name][0], options.get("tip"), label=name)


def _average_columns(name: str, options: dict) -> list[str]:
    """The value, error and sample-count columns of a joint-box average; a per-tip one
    names its tip (``w_avg_m3[left/tool0]``, ``w_avg_m3[left/tool0]_error``,
    ``w_avg_m3[left/tool0]_samples``)."""
    column = _AVERAGES[name][1]
    if options.get("tip") is not None:
        column = f"{column}[{options['tip']}]"
    return [column, f"{column}_error", f"{column}_samples"]


def _average_values(name: str, options: dict, average) -> dict:
    """The columns of one joint-box average (`_average_columns`) from its `JointAverage`."""
    column, error, samples = _average_columns(name, options)
    return {column: average.value, error: average.error, samples: average.samples.astype(average.value.dtype)}


def _joint_average(name: str):
    """A joint-box average as sweep columns: the value, its standard error (same unit) and
    the number of postures it averaged."""

    def evaluate(robot, options):
        settings, _ = _split_options(options)
        kind = _average_kind(name, options, robot)
        impact = _impact_of(options, robot)
        average = joint_average(robot, kind, **{"rtol": SWEEP_RTOL, **settings}, designs_per_chunk=1, impact=impact)
        return _average_values(name, options, average)

    return evaluate


def resolve_tips(where: str, metrics: Sequence[MetricSpec], robot) -> tuple[MetricSpec, ...]:
    """The metrics with every ``tip`` option checked against the robot and written as the
    tip's name (an index becomes the name; the table columns carry it).

    Raises:
        ConfigError: naming ``where``, the metric and its tip (`tip_metric`).
    """
    resolved = []
    for i, metric in enumerate(metrics):
        if metric.name in _AVERAGES or metric.name == "posture":
            if metric.name == "posture":
                tip = _posture_tip(metric.options, robot, where=f"{where}[{i}]")
            else:
                _, tip = split_metric(_average_kind(metric.name, metric.options, robot, where=f"{where}[{i}]"))
            if metric.options.get("tip") is not None:
                names = tuple(robot.labels.tip_names)
                metric = MetricSpec(metric.name, {**metric.options, "tip": names[tip] if names else tip})
        resolved.append(metric)
    keys = [(m.name, m.options.get("tip")) for m in resolved]
    for i, key in enumerate(keys):
        if key in keys[:i]:
            raise ConfigError(f"{where}[{i}]: {key[0]} is listed twice" + (f" for tip {key[1]}" if key[1] else ""))
    return tuple(resolved)


_REACH_OPTIONS = {"starts": 1, "steps": 1, "seed": 0}
_SINGULAR_OPTIONS = {"samples": 1, "keep": 1, "candidates": 1, "descent_steps": 1, "newton_steps": 0, "seed": 0}


def _integer_options(allowed: dict):
    def check(where: str, options: dict) -> None:
        check_keys(f"{where}: ", options, allowed)
        for key, value in options.items():
            integer(f"{where}.{key}", value, least=allowed[key])

    return check


def _reach(robot, options):
    radii = reachable_radii(robot, **options)
    return {"R_max_m": radii.outer, "R_inner_m": radii.inner}


def _path_independent(robot, options):
    radius, _ = singular_radius(robot, "generalized", **options)
    return {"R_path_independent_m": radius}


_AVERAGES = {
    # metric name: (joint_average metric, column, description)
    "w_avg": ("manipulability", "w_avg_m3", "mean translational w* over the joint box (m^3), with its standard error"),
    "gci": ("conditioning", "gci", "global conditioning index: mean 1/kappa(J*_v) over the joint box"),
    "base_disturbance": (
        "base_disturbance",
        "C_w_avg",
        "mean ||C_w||_F over the joint box (bus rad/s per joint rad/s)",
    ),
    "dynamic_manipulability": (
        "dynamic_manipulability",
        "w_d_avg",
        "mean dynamic manipulability w_d over the joint box",
    ),
}
_DIRECTION_TEXT = f"option direction (bus axes, default {list(DEFAULT_DIRECTION)}; planar its first two)"
_IMPACT_AVERAGES = {
    "virtual_mass": (
        "virtual_mass",
        "virtual_mass_kg",
        f"mean virtual mass 1/(u^T G_v u) of the tip along u over the joint box (kg); {_DIRECTION_TEXT}, "
        "joints free (default) or locked",
    ),
    "bus_rate_jump": (
        "bus_rate_jump",
        "bus_rate_jump_radps_per_Ns",
        f"mean bus angular-rate jump per unit tip impulse along u over the joint box (rad/s per N s); "
        f"{_DIRECTION_TEXT}, joints free (default) or locked",
    ),
    "capture_bus_rate": (
        "capture_bus_rate",
        "capture_bus_rate_radps",
        "mean bus angular rate right after the resting robot grasps the reference target (option target: "
        "mass, inertia and offset in tip axes, velocity in bus axes), over the joint box (rad/s); joints free "
        "(default) or locked",
    ),
}
assert set(_IMPACT_AVERAGES) == set(IMPACT_METRICS)
_AVERAGES.update(_IMPACT_AVERAGES)


METRICS: dict[str, Metric] = {
    "wbar": Metric(
        _wbar,
        lambda o: ["wbar"],
        check=_check_wbar,
        check_robot=_check_wbar_robot,
        description="eq. 12: average of w*/L^2 over the elbow-down area, robot frame",
    ),
    "S_M": Metric(_areas, lambda o: ["S_M"], description="Maximum Reachable area / (pi L^2)"),
    "S_G": Metric(_areas, lambda o: ["S_G"], description="Guaranteed Workspace area / (pi L^2) (eq. 8)"),
    "radii": Metric(
        _radii,
        lambda o: ["K0_m", "R_attitude_m", "R_max_m", "R_guaranteed_m", "L_m"],
        description="K0, the Attitude-Constraint, Maximum-Reachable and Guaranteed radii, and L, in m",
    ),
    "workspace_areas": Metric(
        _workspace_areas,
        lambda o: ["S_fixed_vehicle", "S_attitude_constraint", "S_maximum_reachable", "S_guaranteed", "eq9_holds"],
        description="Areas 1-3 and 5 with their holes removed / (pi L^2), and eq. 9 (1 or 0)",
    ),
    "straight_path_area": Metric(
        _straight_area,
        lambda o: ["S_straight"],
        check=_check_straight,
        check_robot=_check_straight_robot,
        description="Straight-Path workspace area from phi_start_deg / (pi L^2)",
    ),
    "posture": Metric(
        _posture,
        _posture_columns,
        check=_check_posture,
        check_robot=_check_posture_robot,
        offered=lambda capabilities: capabilities.joint_box_averages,
        description="at one posture q_deg (default 30 deg each): translational w* (m^3), "
        "1/kappa(J*_v) (of one tip: option tip on a robot with several), ||C_w||_F (bus rad/s per joint rad/s)",
    ),
}


def _offers_tip_search(capabilities: Capabilities) -> bool:
    """The joint-box search for one tip's radii, where the family has no closed form for them
    (the paper's arms give theirs in closed form: metric ``radii``)."""
    return capabilities.tip_radius_search and not capabilities.virtual_manipulator


METRICS["reach_radii"] = Metric(
    _reach,
    lambda o: ["R_max_m", "R_inner_m"],
    check=_integer_options(_REACH_OPTIONS),
    check_robot=_check_average_robot,
    offered=_offers_tip_search,
    designs_per_step=8,
    description="Maximum Reachable shell about the system centroid (outer and inner radius, m) by multi-start "
    "search over the joint box; options starts, steps, seed",
)
METRICS["path_independent_radius"] = Metric(
    _path_independent,
    lambda o: ["R_path_independent_m"],
    check=_integer_options(_SINGULAR_OPTIONS),
    check_robot=_check_average_robot,
    offered=_offers_tip_search,
    designs_per_step=8,
    description="path-independent workspace radius (Papadopoulos & Dubowsky), m: the closest dynamic-singular tip "
    "position to the centroid (inf: none found); options samples, keep, candidates, descent_steps, "
    "newton_steps, seed",
)
for _name, (_kind, _column, _text) in _AVERAGES.items():
    _per_tip = _kind in PER_TIP_METRICS
    _impact = _name in _IMPACT_AVERAGES
    METRICS[_name] = Metric(
        _joint_average(_name),
        functools.partial(_average_columns, _name),
        check=_check_impact(_name) if _impact else _check_average,
        check_robot=_check_impact_robot if _impact else _check_average_robot,
        # The impact quantities come from the dynamics, which serve every family.
        offered=(lambda capabilities: True) if _impact else (lambda capabilities: capabilities.joint_box_averages),
        designs_per_step=8,
        description=_text
        + (" (of one tip: option tip, a name or an index, on a robot with several)" if _per_tip else "")
        + f"; options {', '.join(AVERAGE_OPTIONS)} (rtol default {SWEEP_RTOL:g})",
    )


# Timed tasks (`spacearm.motion.tasks`): peaks of the joint torques and of the held wrench.


def _check_task_metric(allowed: tuple[str, ...]):
    def check(where: str, options: dict) -> None:
        check_keys(f"{where}: ", options, allowed)
        if "base" in options:
            choice(f"{where}.base", options["base"], BASE_MODES)
        if "task" in options and not isinstance(options["task"], Mapping):
            raise ConfigError(f"{where}.task: must be a mapping {{waypoints: [[...], ...], duration: seconds}}")

    return check


def _task(options: dict) -> TimedTask:
    """The metric's task, as `attach_task` wrote it into its options (rad, s)."""
    return TimedTask(options["task"]["waypoints"], options["task"]["duration"])


def _peak_joint_torque(robot, options):
    peaks = task_peaks(robot, _task(options), base=options.get("base", "free"))
    return {"peak_joint_torque_Nm": peaks.max_joint_torque}


def _peak_held_wrench(robot, options):
    peaks = task_peaks(robot, _task(options), base="held")
    return {"peak_held_force_N": peaks.held_force, "peak_held_torque_Nm": peaks.held_torque}


METRICS["peak_joint_torque"] = Metric(
    _peak_joint_torque,
    lambda o: ["peak_joint_torque_Nm"],
    check=_check_task_metric(("task", "base")),
    offered=lambda capabilities: True,  # the dynamics serve every family
    needs_task=True,
    description="the largest |tau_i| of any joint along the sweep's task (N m; N for a prismatic joint), "
    "at zero momentum; option base: free (default), held or attitude",
)


def _peak_wheel(robot, options):
    peaks = wheel_peaks(robot, _task(options))
    return {"peak_wheel_momentum_Nms": peaks.momentum, "peak_wheel_torque_Nm": peaks.torque}


METRICS["peak_wheel"] = Metric(
    _peak_wheel,
    lambda o: ["peak_wheel_momentum_Nms", "peak_wheel_torque_Nm"],
    check=_check_task_metric(("task",)),
    offered=lambda capabilities: True,
    needs_task=True,
    description="the largest momentum (N m s) and torque (N m) reaction wheels hold and apply to keep the bus "
    "from turning along the sweep's task (the bus free to translate), at zero momentum",
)
METRICS["peak_held_wrench"] = Metric(
    _peak_held_wrench,
    lambda o: ["peak_held_force_N", "peak_held_torque_Nm"],
    check=_check_task_metric(("task",)),
    offered=lambda capabilities: True,
    needs_task=True,
    description="the largest force (N) and torque (N m) the bus's thrusters and wheels apply to hold the bus "
    "at rest along the sweep's task (at the bus centroid)",
)


def attach_task(where: str, metrics: Sequence[MetricSpec], task: TimedTask | None, robot) -> tuple[MetricSpec, ...]:
    """The metrics with their timed task written into their options (rad, s): a metric's own
    ``task`` option, else the sweep's ``task:``.

    Raises:
        ConfigError: a task metric without a task, a task no metric uses, or a task that does
            not fit the robot's joints (naming ``where`` and the field).
    """
    kinds = family_of(robot).joint_kinds(robot)
    users = [name for name, entry in METRICS.items() if entry.needs_task]
    if task is not None and not any(METRICS[m.name].needs_task for m in metrics):
        raise ConfigError(f"{where}: task: no metric listed uses it (the task metrics: {', '.join(users)})")
    attached = []
    for i, metric in enumerate(metrics):
        if METRICS[metric.name].needs_task:
            own = metric.options.get("task")
            if own is not None:
                task_of = task_from_mapping(f"{where}: metrics[{i}]", own, kinds)
            elif task is None:
                raise ConfigError(
                    f"{where}: metrics[{i}]: {metric.name} is taken along a timed task; give one in the sweep "
                    "file, e.g. task: {waypoints: [[...], [...]], duration: 4.0} (joints in rad, time in s)"
                )
            else:
                task_of = task
            metric = MetricSpec(metric.name, {**metric.options, "task": task_of.to_mapping()})
        attached.append(metric)
    return tuple(attached)


def metric_columns(metrics: Sequence[MetricSpec]) -> list[str]:
    """The table columns the metrics of a sweep write, in order, each once."""
    names: list[str] = []
    for metric in metrics:
        for column in METRICS[metric.name].columns(metric.options):
            if column not in names:
                names.append(column)
    return names


def design_function(metrics: Sequence[MetricSpec]) -> Callable[[Any], dict]:
    """The per-design function of a sweep's metrics: robot -> {column: scalar}, traceable.

    Joint-box averages with the same options share one `joint_averages` call: one set
    of postures and one chain pass per posture for all of them."""
    wanted = metric_columns(metrics)
    groups: dict[str, list[MetricSpec]] = {}
    for metric in metrics:
        if metric.name in _AVERAGES:
            settings = {key: value for key, value in metric.options.items() if key != "tip"}
            groups.setdefault(json.dumps(settings, sort_keys=True), []).append(metric)

    def evaluate(robot) -> dict:
        values: dict = {}
        done: set = set()
        for group in groups.values():
            settings, _ = _split_options(group[0].options)
            kinds = tuple(_average_kind(m.name, m.options, robot) for m in group)  # several tips: one pass
            impact = _impact_of(group[0].options, robot)
            averages = joint_averages(
                robot, kinds, **{"rtol": SWEEP_RTOL, **settings}, designs_per_chunk=1, impact=impact
            )
            for metric, kind in zip(group, kinds, strict=False):
                values.update(_average_values(metric.name, metric.options, averages[kind]))
        for metric in metrics:
            entry = METRICS[metric.name]
            if metric.name in _AVERAGES or (entry.fn, str(metric.options.get("tip"))) in done:
                continue
            done.add((entry.fn, str(metric.options.get("tip"))))
            values.update(entry.fn(robot, metric.options))
        return {column: values[column] for column in wanted}

    return evaluate


def metric_specs(where: str, entries: Any) -> tuple[MetricSpec, ...]:
    if entries is None:
        raise ConfigError(f"{where}: missing required key; e.g. metrics: [wbar, S_M, S_G]")
    if not isinstance(entries, (list, tuple)) or not entries:
        raise ConfigError(f"{where}: must be a non-empty list of metric names; known: {', '.join(sorted(METRICS))}")
    specs = []
    for i, entry in enumerate(entries):
        if isinstance(entry, str):
            name, options = entry, {}
        elif isinstance(entry, Mapping) and isinstance(entry.get("name"), str):
            name, options = entry["name"], {k: v for k, v in entry.items() if k != "name"}
        else:
            raise ConfigError(f"{where}[{i}]: must be a metric name or a mapping with 'name'")
        if name not in METRICS:
            raise ConfigError(
                f"{where}[{i}]: unknown metric '{name}'{did_you_mean(name, METRICS)}; known: {', '.join(sorted(METRICS))}"
            )
        METRICS[name].check(f"{where}[{i}]", options)
        specs.append(MetricSpec(name, dict(options)))
    names = [(s.name, str(s.options.get("tip"))) for s in specs]
    if len(set(names)) != len(names):
        raise ConfigError(f"{where}: a metric is listed twice (a per-tip metric may appear once per tip)")
    return tuple(specs)
