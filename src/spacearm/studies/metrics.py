"""The metric registry of sweeps: each metric's per-design function, its table columns and
the checks of its options (run when a sweep is loaded, so ``spacearm validate`` refuses
what a run would).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import jax.numpy as jnp

from .._core.errors import ConfigError
from .._core.schema import check_keys, did_you_mean, integer, is_number
from ..analysis import (
    attachment_condition,
    average_manipulability,
    check_average_options,
    normalized_areas,
    normalized_workspace_areas,
    straight_path_workspace,
)
from ..models.planar import PlanarRobot
from ..models.planar.closed_forms import tip_coefficients

__all__ = ["Metric", "MetricSpec", "METRICS", "WBAR_OPTIONS", "metric_specs", "metric_columns", "design_function"]


@dataclasses.dataclass(frozen=True)
class MetricSpec:
    """A metric of a sweep file: its name and options."""

    name: str
    options: dict


@dataclasses.dataclass(frozen=True)
class Metric:
    """Per-design scalars: ``fn(robot, options) -> {column: value}``, traceable."""

    fn: Callable[[PlanarRobot, dict], dict]
    columns: Callable[[dict], list[str]]
    check: Callable[[str, dict], None] = lambda where, options: _no_options(where, options)
    description: str = ""
    # Checks that need the base robot (e.g. its number of links).
    check_robot: Callable[[str, dict, PlanarRobot], None] = lambda where, options, robot: None


def _no_options(where: str, options: dict) -> None:
    if options:
        raise ConfigError(f"{where}: this metric takes no options, got {', '.join(options)}")


# The options of analysis.average_manipulability a sweep file may set (the rest are
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
    return {"wbar": average_manipulability(robot, **options)}


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


METRICS: dict[str, Metric] = {
    "wbar": Metric(_wbar, lambda o: ["wbar"], check=_check_wbar, check_robot=_check_wbar_robot, description="eq. 12: average of w*/L^2 over the elbow-down area, robot frame"),
    "S_M": Metric(_areas, lambda o: ["S_M"], description="Maximum Reachable area / (pi L^2)"),
    "S_G": Metric(_areas, lambda o: ["S_G"], description="Guaranteed Workspace area / (pi L^2) (eq. 8)"),
    "radii": Metric(_radii, lambda o: ["K0_m", "R_attitude_m", "R_max_m", "R_guaranteed_m", "L_m"],
                    description="K0, the Attitude-Constraint, Maximum-Reachable and Guaranteed radii, and L, in m"),
    "workspace_areas": Metric(_workspace_areas, lambda o: ["S_fixed_vehicle", "S_attitude_constraint",
                                                          "S_maximum_reachable", "S_guaranteed", "eq9_holds"],
                              description="Areas 1-3 and 5 with their holes removed / (pi L^2), and eq. 9 (1 or 0)"),
    "straight_path_area": Metric(_straight_area, lambda o: ["S_straight"], check=_check_straight,
                                 check_robot=_check_straight_robot,
                                 description="Straight-Path workspace area from phi_start_deg / (pi L^2)"),
}


def metric_columns(metrics: Sequence[MetricSpec]) -> list[str]:
    """The table columns the metrics of a sweep write, in order, each once."""
    names: list[str] = []
    for metric in metrics:
        for column in METRICS[metric.name].columns(metric.options):
            if column not in names:
                names.append(column)
    return names


def design_function(metrics: Sequence[MetricSpec]) -> Callable[[PlanarRobot], dict]:
    """The per-design function of a sweep's metrics: robot -> {column: scalar}, traceable."""
    wanted = metric_columns(metrics)

    def evaluate(robot: PlanarRobot) -> dict:
        values: dict = {}
        done: set = set()
        for metric in metrics:
            entry = METRICS[metric.name]
            if entry.fn in done:
                continue
            done.add(entry.fn)
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
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        raise ConfigError(f"{where}: a metric is listed twice")
    return tuple(specs)
