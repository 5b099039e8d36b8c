"""One memory estimator for every metric, objective and search.

Each metric's kernel builds a few arrays at once (quadrature grids, sample blocks,
multi-start batches). `working_numbers` gives their size, in float64 numbers per design,
from the options that set it. `check_working_memory` multiplies that by the number of
designs computed side by side and refuses, through `spacearm._core.schema.check_memory`,
anything above half of this machine's memory, naming the estimate and the option to
lower. The estimate is coarse on purpose: it catches options that are off by orders of
magnitude (``order: 1e9``) before anything is allocated, not a few percent.
"""

from __future__ import annotations

from collections.abc import Mapping

from .schema import check_memory

__all__ = ["TEMPORARIES", "check_working_memory", "working_numbers"]

# The temporaries XLA keeps alive beside the arrays a kernel names (products, gradients).
TEMPORARIES = 16


def working_numbers(name: str, options: Mapping, n: int, *, joint_average: bool = False) -> tuple[float, str]:
    """(float64 numbers one design of metric ``name`` holds at once, the option that sizes it).

    Args:
        name: a sweep metric or design objective (``wbar``, ``straight_path_area``,
            ``reach_radii``, ``path_independent_radius``, a joint-box average, ...).
        options: its options as given in the file (defaults filled in here).
        n: joints (links) of the robot.
        joint_average: the metric is a joint-box average (sized by ``block`` x ``randomizations``).
    """
    if name == "wbar":
        order = options.get("order", 8)
        if options.get("measure", "area") == "joint" and n > 2:
            return float(options.get("n_points_joint", 48)) ** n, "n_points_joint"
        phi1 = options.get("phi1_panels", 8) * order
        phi2 = (options.get("phi2_panels", 8) + 2 * options.get("phi1_panels", 8) + 4) * 2 * order
        return float(phi1 * phi2), "order or phi1_panels/phi2_panels"
    if name == "straight_path_area":
        return float(options.get("n_directions", 72)) * 4096 * (n + 1), "n_directions"
    if name == "reach_radii":
        return float(options.get("starts", 128)) * (9 * n + 16), "starts"
    if name == "path_independent_radius":
        return float(options.get("samples", 2**14)) * (6 * n + 36) + options.get("keep", 2048) * 36 * n, "samples"
    if joint_average:
        return float(options.get("block", 1024)) * options.get("randomizations", 8) * (6 * n + 36), "block"
    if "samples" in options:  # a design problem's joint-box objectives
        return float(options["samples"]) * (6 * n + 36), "samples"
    return 4096.0 * (n + 1), ""


def check_working_memory(
    where: str, designs_at_once: int, numbers: float, what: str, advice: str, extra_bytes: float = 0.0
) -> float:
    """Refuse work whose estimate (``designs_at_once`` x ``numbers`` x `TEMPORARIES` float64
    numbers, plus ``extra_bytes``) is over half of this machine's memory; return the estimate
    in bytes. `ConfigError` names ``where``, the estimate and ``advice``."""
    need = 8.0 * designs_at_once * numbers * TEMPORARIES + extra_bytes
    check_memory(where, need, what, advice)
    return need
