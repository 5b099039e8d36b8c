"""The one control flow of reorientation planning, over the base-attitude group.

A closed joint loop through q0, repeated N times, turns the base by the N-th power of
the loop's holonomy (the attitude rate does not depend on the attitude). Every family
plans the same way: check the request, optimize a batch of candidate loops (one per
repetition count and start), check every candidate with the integrator and the joint
limits, keep the valid candidate with the least joint travel. A `LoopSteps` holds the
numerics of each step for one group (the SO(2) closed-form-curl optimizer or the SO(3)
Adam + Gauss-Newton one); `plan_loop` runs them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np

from .._core.errors import ConfigError

__all__ = ["LoopSteps", "plan_loop"]


@dataclasses.dataclass(frozen=True)
class LoopSteps:
    """The numerics of `plan_loop` for one attitude group.

    Attributes:
        check: ``(robot, start, target, settings, **options) -> job`` (a dict with at
            least ``tolerance``), raising `ConfigError` by name.
        still: ``job -> result or None``: the plan when the target is the identity.
        candidates: ``job -> dict`` of per-candidate arrays: ``error`` (rad; inf where a
            candidate leaves the joint limits or its bounds) and ``travel`` (rad).
        failure: ``(job, candidates) -> message`` when no candidate is valid.
        record: ``(job, candidates, best) -> result``: the chosen candidate's plan.
    """

    check: Callable
    still: Callable
    candidates: Callable
    failure: Callable
    record: Callable


def plan_loop(steps: LoopSteps, robot, start, target, settings, **options) -> Any:
    """Plan a closed joint loop from ``start`` that turns the base by ``target`` (the
    group's steps): the valid candidate with the least joint travel."""
    job = steps.check(robot, start, target, settings, **options)
    still = steps.still(job)
    if still is not None:
        return still
    candidates = steps.candidates(job)
    valid = np.asarray(candidates["error"]) <= job["tolerance"]
    if not np.any(valid):
        raise ConfigError(steps.failure(job, candidates))
    best = int(np.argmin(np.where(valid, np.asarray(candidates["travel"]), np.inf)))
    return steps.record(job, candidates, best)
