"""A shell about the system centroid that holds every position of one tip of a tree.

The virtual manipulator (Vafa & Dubowsky 1990) of a branched system: with zero linear
momentum the system centroid G stays put, and

    tip_t - G = sum_b (m_b / M) (tip_t - c_b)

over every body b (the bus and its root bodies, the links of every arm). The vector
from c_b to the tip runs along the tree: up from b to the first body on tip t's path
from the bus, then down that path to the tip. Each piece lies in one body (from a
joint origin, or from c_b, to the next joint origin), so grouping the pieces by body,

    tip_t - G = sum_k V_k,   V_k = (1 / M) sum_b m_b u_{b,k}  (fixed in body k),

and |V_k| is a design constant for a body entered by a revolute joint; a prismatic
joint slides the entry point along its axis, so |V_k| ranges over an interval set by
the joint limits. Whatever the joints (of every arm) and the bus attitude,

    max(0, max_j (min |V_j| - sum_{k != j} max |V_k|))  <=  |tip_t - G|  <=  sum_k max |V_k|,

a shell that contains every position of the tip (equal to the Maximum Reachable space
when every V_k can be aligned, as for a planar arm without limits; a serial arm is the
one-arm tree, `spacearm.models.spatial.primitives.as_tree`).
Host-side NumPy: no program is compiled.
"""

from __future__ import annotations

import numpy as np

from ..._core.groups import rpy_matrix

__all__ = ["tip_shell", "virtual_link_lengths"]


def _segment_norms(u: np.ndarray, a: np.ndarray, lo: float, hi: float) -> tuple[float, float]:
    """min and max of |u + t a| for t in [lo, hi] (a non-zero)."""
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return (0.0, np.inf)
    t_star = float(np.clip(-(u @ a) / (a @ a), lo, hi))
    low = float(np.linalg.norm(u + t_star * a))
    high = max(float(np.linalg.norm(u + lo * a)), float(np.linalg.norm(u + hi * a)))
    return low, high


def virtual_link_lengths(robot, tip: int) -> np.ndarray:
    """``(n + 1, 2)`` smallest and largest |V_k| for tip ``tip``, m (one design).

    Rows 0..n-1 are the bodies after joints 0..n-1 (zero off the tip's path and its
    branches' pieces included), row n the bus with its root bodies.
    """
    f = lambda name: np.asarray(getattr(robot, name), float)
    n, parents = robot.n_joints, robot.parents
    mounts = [rpy_matrix(rpy) for rpy in f("mount_rpy")]
    mount_xyz, translation = f("mount_xyz"), f("joint_translation")
    bus = n  # the node index of the bus (with the roots)

    def node(j):  # the node joint j hangs from
        return parents[j] if parents[j] >= 0 else bus

    def origin(j):  # joint j's origin in the frame of its parent node
        if parents[j] >= 0:
            return translation[j]
        r = -1 - parents[j]
        return mount_xyz[r] + mounts[r] @ translation[j]

    path = []  # tip t's path from the tip body up to the bus
    body = robot.tip_bodies[tip]
    while body >= 0:
        path.append(body)
        body = parents[body]
    on_path = set(path) | {bus}
    exits = {path[0]: f("tip_translation")[tip]}  # x_k: where the path leaves node k
    for child in path:
        exits[node(child)] = origin(child)
    below = {bus: path[::-1]}  # the path nodes after each path node, from the bus down
    for i, k in enumerate(path):
        below[k] = path[:i][::-1]

    masses = [(f("base_mass"), bus, f("base_com"))]
    masses += [
        (m, bus, mount_xyz[r] + mounts[r] @ c)
        for r, (m, c) in enumerate(zip(f("root_mass"), f("root_com"), strict=True))
    ]
    masses += [(m, j, c) for j, (m, c) in enumerate(zip(f("link_mass"), f("link_com"), strict=True))]
    total = sum(float(m) for m, _, _ in masses)
    fixed = np.zeros((n + 1, 3))  # M V_k = fixed_k + slide_k q_k a_k (a_k unit, prismatic k)
    slide = np.zeros(n + 1)
    for mass, k, point in masses:
        while k not in on_path:  # up the branch: c (or the child's joint) -> this body's entry
            fixed[k] -= mass * point  # the entry e_k = -q a_k in body k's frame
            slide[k] -= mass
            point, k = origin(k), node(k)
        fixed[k] += mass * (exits[k] - point)
        for j in below[k]:  # down the tip's path: entry -> exit of each body
            fixed[j] += mass * exits[j]
            slide[j] += mass
    lower, upper, axes = f("joint_lower"), f("joint_upper"), f("joint_axis")
    lengths = []
    for k in range(n + 1):
        u = fixed[k] / total
        if k < n and robot.joint_kinds[k] == "prismatic" and slide[k] != 0.0:
            a = axes[k] / np.linalg.norm(axes[k])
            lengths.append(_segment_norms(u, slide[k] / total * a, lower[k], upper[k]))
        else:
            lengths.append((float(np.linalg.norm(u)),) * 2)
    return np.asarray(lengths)


def tip_shell(robot, tip: int) -> tuple[float, float]:
    """``(inner, outer)`` radii about the system centroid, m, between which tip ``tip`` lies.

    outer = sum_k max |V_k|; inner = max(0, max_j (min |V_j| - sum_{k != j} max |V_k|)).
    """
    lengths = virtual_link_lengths(robot, tip)
    low, high = lengths[:, 0], lengths[:, 1]
    outer = float(np.sum(high))
    inner = float(np.max(low - (outer - high))) if np.isfinite(outer) else 0.0
    return max(0.0, inner), outer
