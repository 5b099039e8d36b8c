"""The family steps the one reach planner (`spacearm.planning.reach.plan_reach`) runs.

`plan_reach` holds the control flow for every family: argument checks, the
reachability pre-check against the family's tip shell, the straight attempt, the search
over candidate base rotations from the attitude group, the reorientation loop with the
final straight leg, and the repositioning fallback. A `ReachSteps` holds what differs
between the groups SO(2) and SO(3): the numerics of each step and the plan's record.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
from collections.abc import Callable
from typing import Any

__all__ = ["MODE_REORIENT", "MODE_REPOSITION", "MODE_STRAIGHT", "PHASE_LOOP", "PHASE_REPOSITION", "PHASE_STRAIGHT"]

MODE_STRAIGHT = "straight"
MODE_REORIENT = "reorient"
MODE_REPOSITION = "reposition"

PHASE_REPOSITION = 0
PHASE_LOOP = 1
PHASE_STRAIGHT = 2


@dataclasses.dataclass
class ReachJob:
    """One reach request after the checks: what every step reads.

    Attributes:
        robot: one design; family: its `spacearm.models.family.RobotFamily`.
        start: the checked start (planar posture [phi0, q]; spatial joints q).
        attitude: the start base attitude (a group element).
        target: ``(space,)`` inertial target about the system centroid, m.
        tolerance: accepted end error, m.
        rotation_grid: number of candidate base rotations; history_samples: samples of
            the final straight leg; settings: the family's loop settings; modes: allowed
            strategies.
        options: the family's own checked options.
        ahead: programs compiling on a second core, by name.
    """

    robot: Any
    family: Any
    start: Any
    attitude: Any
    target: Any
    tolerance: float
    rotation_grid: int
    history_samples: int
    settings: Any
    modes: tuple[str, ...]
    options: dict = dataclasses.field(default_factory=dict)
    ahead: dict = dataclasses.field(default_factory=dict)

    def wait(self, name: str) -> None:
        """Wait for a program compiling ahead (a failed compile is only a missed head start)."""
        future = self.ahead.get(name)
        if future is not None:
            concurrent.futures.wait([future])


@dataclasses.dataclass(frozen=True)
class ReachSteps:
    """The numerics of each step of `plan_reach` for one attitude group.

    Attributes:
        modes: the strategies offered, in the order they are tried.
        rotation_grid, history_samples: defaults.
        settings_type: the loop settings class (its default instance is the default).
        check: ``(robot, start, target, options) -> (start, attitude, target, options)``:
            checks the family's inputs and options (raising `ConfigError` by name).
        compile_history, compile_loop: ``job -> None`` programs compiled ahead (or None).
        straight: ``job -> plan or None``, the straight tip path from the start.
        search: ``(job, vectors (c, dim) smallest first) -> algebra vector or None``,
            the base rotation after which the straight path reaches.
        reorient: ``(job, vector) -> plan``: the loop, then the straight leg.
        reposition: ``job -> plan`` (None: not offered).
        failure: ``(job, searched) -> message`` when no strategy reaches.
    """

    modes: tuple[str, ...]
    rotation_grid: int
    history_samples: int
    settings_type: type
    check: Callable
    compile_history: Callable | None
    compile_loop: Callable
    straight: Callable
    search: Callable
    reorient: Callable
    reposition: Callable | None
    failure: Callable
