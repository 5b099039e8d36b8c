"""Pareto fronts and their quality: non-dominated subsets and the exact hypervolume
(our 2-D sweep; moocore for three or more objectives).

All objectives are maximized.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = [
    "hypervolume",
    "hypervolume_2d",
    "hypervolume_history",
    "layer_face_areas",
    "nondominated",
    "nondominated_mask",
    "reference_from_population",
]


def nondominated_mask(objectives: np.ndarray) -> np.ndarray:
    """``(N,)`` bool: True for points no other point dominates (all objectives maximized).

    Duplicates keep their first occurrence only. Two objectives: O(N log N) sweep;
    more: moocore's ``is_nondominated`` (pairwise comparison without it).

    Args:
        objectives: ``(N, m)`` objective values.
    """
    f = np.asarray(objectives, dtype=np.float64)
    count = f.shape[0]
    mask = np.zeros(count, dtype=bool)
    if count == 0:
        return mask
    finite = np.all(np.isfinite(f), axis=1)
    if f.shape[1] == 2:
        # Sort by f1 descending, then f2 descending; a point survives when its f2 beats
        # every f2 before it (an equal f2 with a larger-or-equal f1 dominates it).
        order = np.lexsort((-f[:, 1], -f[:, 0]))
        order = order[finite[order]]
        f2 = f[order, 1]
        best_before = np.concatenate([[-np.inf], np.maximum.accumulate(f2)[:-1]])
        mask[order[f2 > best_before]] = True
        return mask
    rows = np.flatnonzero(finite)
    try:
        import moocore  # noqa: PLC0415
    except ImportError:  # pragma: no cover - optional extra
        moocore = None
    if moocore is not None and rows.size:
        mask[rows] = moocore.is_nondominated(f[rows], maximise=True, keep_weakly=True)
    else:  # pragma: no cover - pairwise dominance, vectorized in blocks of rows
        others = f[rows]
        for begin in range(0, rows.size, 512):
            block = others[begin : begin + 512]
            geq = np.all(others[None, :, :] >= block[:, None, :], axis=2)
            gt = np.any(others[None, :, :] > block[:, None, :], axis=2)
            mask[rows[begin : begin + 512]] = ~np.any(geq & gt, axis=1)
    # Drop exact duplicates after the first.
    _, first = np.unique(f[mask], axis=0, return_index=True)
    keep = np.flatnonzero(mask)[np.sort(first)]
    mask[:] = False
    mask[keep] = True
    return mask


def nondominated(objectives: np.ndarray) -> np.ndarray:
    """Indices of the non-dominated points, sorted by the first objective ascending."""
    f = np.asarray(objectives)
    index = np.flatnonzero(nondominated_mask(f))
    return index[np.argsort(f[index, 0], kind="stable")]


def hypervolume_2d(objectives: np.ndarray, reference: Sequence[float] = (0.0, 0.0)) -> float:
    """Exact hypervolume of a 2-D point set (both objectives maximized).

    The area of the union of the boxes [r1, f1] x [r2, f2] over the points that beat
    the reference point in both objectives: a sweep in f1 descending adds one strip
    per front point, (f1 - r1)(f2 - best f2 so far).

    Args:
        objectives: ``(N, 2)`` points (any order, dominated ones allowed).
        reference: ``(2,)`` the reference point.
    """
    f = np.asarray(objectives, dtype=np.float64).reshape(-1, 2)
    r1, r2 = float(reference[0]), float(reference[1])
    f = f[np.all(np.isfinite(f), axis=1) & (f[:, 0] > r1) & (f[:, 1] > r2)]
    if f.size == 0:
        return 0.0
    front = f[nondominated_mask(f)]
    front = front[np.argsort(-front[:, 0])]  # f1 descending, so f2 ascending
    below = np.concatenate([[r2], front[:-1, 1]])
    return float(np.sum((front[:, 0] - r1) * (front[:, 1] - below)))


def hypervolume(objectives: np.ndarray, reference: Sequence[float]) -> float:
    """Exact hypervolume of a point set (all objectives maximized) above ``reference``.

    Two objectives: `hypervolume_2d`. Three or more: moocore's exact algorithms
    (``moocore.hypervolume``, a maintained C library; pip install moocore, in the
    ``optimize`` extra).

    Args:
        objectives: ``(N, m)`` points (any order, dominated ones allowed).
        reference: ``(m,)`` the reference point.
    """
    reference = np.asarray(reference, dtype=np.float64)
    f = np.asarray(objectives, dtype=np.float64).reshape(-1, reference.size)
    if reference.size == 2:
        return hypervolume_2d(f, reference)
    f = f[np.all(np.isfinite(f), axis=1) & np.all(f > reference, axis=1)]
    if f.shape[0] == 0:
        return 0.0
    try:
        import moocore  # noqa: PLC0415
    except ImportError as error:  # pragma: no cover - optional extra
        raise ImportError(
            "hypervolume of 3 or more objectives needs moocore (pip install 'spacearm[optimize]')"
        ) from error
    return float(moocore.hypervolume(f[nondominated_mask(f)], ref=reference, maximise=True))


def hypervolume_history(batches: Sequence[np.ndarray], reference: Sequence[float]) -> np.ndarray:
    """Hypervolume of the growing archive after each batch of evaluated points.

    Args:
        batches: a sequence of ``(B_k, m)`` objective arrays, in evaluation order.

    Returns:
        ``(len(batches),)`` hypervolume of the union of the first k+1 batches.
    """
    m = len(reference)
    front = np.zeros((0, m))
    values = []
    for batch in batches:
        merged = np.concatenate([front, np.asarray(batch, dtype=np.float64).reshape(-1, m)])
        front = merged[nondominated_mask(merged)]
        values.append(hypervolume(front, reference))
    return np.array(values)


def reference_from_population(objectives: np.ndarray, margin: float) -> np.ndarray:
    """A reference point below the nadir of a population's front, by ``margin`` of its range.

    Args:
        objectives: ``(N, m)`` the first population's objectives (maximized).
        margin: share of the front's range (ideal - nadir) put below the nadir; a flat
            objective gets the margin of its magnitude (or ``margin`` itself at zero).
    """
    f = np.asarray(objectives, dtype=np.float64)
    f = f[np.all(np.isfinite(f), axis=1)]
    if f.shape[0] == 0:
        raise ValueError("reference_point: no finite objective values in the first population")
    front = f[nondominated_mask(f)]
    nadir, ideal = front.min(axis=0), front.max(axis=0)
    span = ideal - nadir
    span = np.where(span > 0, span, np.where(np.abs(nadir) > 0, np.abs(nadir), 1.0))
    return nadir - margin * span


def layer_face_areas(objectives: np.ndarray, reference: Sequence[float], layer: np.ndarray) -> np.ndarray:
    """``(N, m)`` each point's hypervolume gradient within its own layer, 2 or 3 objectives, in NumPy.

    The derivative of a layer's hypervolume along objective j at a point of it is the
    (m-1)-volume of the face of the point's exclusive region normal to j (Emmerich &
    Deutz, EVOLVE III, 2014): the box [r, f_i] without objective j, less the boxes of the
    layer's points k with f_kj > f_ij, clipped to it. Vectorized over all points at once
    (``(N, N)`` arrays), so it costs no compiled program; at points in general position it
    equals `spacearm.design.hypervolume.layer_hypervolume_gradients` (autodiff of the
    exact hypervolume), and at ties it is one of the one-sided derivatives.

    Args:
        objectives: ``(N, m)`` points, m = 2 or 3, all maximized (finite).
        reference: ``(m,)`` the reference point; coordinates below it get zero.
        layer: ``(N,)`` int, each point's non-dominated-sorting layer; a negative layer
            leaves the point out (zero gradient, and it covers no other point's face).
    """
    reference = np.asarray(reference, dtype=np.float64)
    f = np.maximum(np.asarray(objectives, dtype=np.float64), reference)
    layer = np.asarray(layer)
    count, m = f.shape
    if m not in (2, 3):
        raise ValueError(f"layer_face_areas: 2 or 3 objectives, got {m}")
    gradient = np.zeros((count, m))
    same = (layer[:, None] == layer[None, :]) & (layer[:, None] >= 0)
    for j in range(m):  # over objectives, not points
        others = [k for k in range(m) if k != j]
        own = f[:, others] - reference[others]  # (N, m-1) the face's box, from the reference
        # covers[i, k]: point k lies above point i along j, in i's layer; its box, clipped to i's.
        covers = same & (f[None, :, j] > f[:, None, j])
        clipped = np.where(covers[:, :, None], np.minimum(own[None, :, :], own[:, None, :]), 0.0)  # (N, N, m-1)
        if m == 2:
            covered = clipped[:, :, 0].max(axis=1)
        else:
            # Per row i, the 2-D hypervolume of the clipped boxes (from the origin):
            # sort by the first coordinate descending, strips above the running maximum.
            order = np.argsort(-clipped[:, :, 0], axis=1, kind="stable")
            a = np.take_along_axis(clipped[:, :, 0], order, axis=1)
            b = np.take_along_axis(clipped[:, :, 1], order, axis=1)
            before = np.concatenate([np.zeros((count, 1)), np.maximum.accumulate(b, axis=1)[:, :-1]], axis=1)
            covered = np.sum(a * np.maximum(b - before, 0.0), axis=1)
        gradient[:, j] = np.prod(own, axis=1) - covered
    below = np.asarray(objectives, dtype=np.float64) < reference
    return np.where((layer[:, None] >= 0) & ~below, np.maximum(gradient, 0.0), 0.0)
