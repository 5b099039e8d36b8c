"""A shell about the system centroid that holds every tip position of a spatial arm.

The virtual manipulator (Vafa & Dubowsky 1990; the planar K_0..K_n of Umetani &
Yoshida 1990, eq. 1, are its link lengths): with zero linear momentum the system
centroid G stays put, and the tip about it is a sum of vectors each fixed in one body,

    tip - G = sum_k V_k,   V_k = (m_k (x_k - g_k) + M_<k (x_k - e_k)) / M,

where body k (0 = bus with the root link) has mass m_k, centroid g_k, entry joint e_k
and exit point x_k (the next joint, or the tip for the last body), M_<k is the mass of
the bodies before k and M the total mass. A revolute joint turns body k about an axis
through e_k, so |V_k| is a design constant; a prismatic one slides e_k along its axis,
so |V_k| ranges over an interval set by the joint limits. Hence, whatever the joints
and the bus attitude,

    max(0, 2 |V_j| - sum_k |V_k|)  <=  |tip - G|  <=  sum_k |V_k|,

a shell that contains the Maximum Reachable space (equal to it when every V_k can be
aligned, as for a planar arm without limits). Host-side NumPy: no program is compiled.
"""

from __future__ import annotations

import numpy as np

from .urdf import rpy_matrix

__all__ = ["tip_shell", "virtual_link_lengths"]


def _segment_norms(u: np.ndarray, a: np.ndarray, lo: float, hi: float) -> tuple[float, float]:
    """min and max of |u + t a| for t in [lo, hi] (a non-zero)."""
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return (0.0, np.inf)
    t_star = float(np.clip(-(u @ a) / (a @ a), lo, hi))
    low = float(np.linalg.norm(u + t_star * a))
    high = max(float(np.linalg.norm(u + lo * a)), float(np.linalg.norm(u + hi * a)))
    return low, high


def virtual_link_lengths(robot) -> np.ndarray:
    """``(n + 1, 2)`` the smallest and largest |V_k| of the virtual links, m (one design).

    Row 0 is the bus with the root link; row k the body after joint k. The two columns
    are equal for revolute joints.
    """
    f = lambda name: np.asarray(getattr(robot, name), float)
    n = robot.n_joints
    mount = rpy_matrix(f("mount_rpy"))
    base_mass, root_mass, link_mass = float(f("base_mass")), float(f("root_mass")), f("link_mass")
    total = base_mass + root_mass + float(np.sum(link_mass))
    translation, link_com = f("joint_translation"), f("link_com")
    exits = np.concatenate([translation[1:], f("tip_translation")[None]], axis=0)  # x_k in body k, (n, 3)
    root_com = f("mount_xyz") + mount @ f("root_com")
    exit0 = f("mount_xyz") + mount @ translation[0]
    v0 = (base_mass * (exit0 - f("base_com")) + root_mass * (exit0 - root_com)) / total
    lengths = [(float(np.linalg.norm(v0)),) * 2]
    before = base_mass + root_mass
    lower, upper = f("joint_lower"), f("joint_upper")
    axes = f("joint_axis")
    for k in range(n):
        u = (link_mass[k] * (exits[k] - link_com[k]) + before * exits[k]) / total
        if robot.joint_kinds[k] == "prismatic":  # entry e_k = -q a in body k's frame
            a = axes[k] / np.linalg.norm(axes[k])
            lengths.append(_segment_norms(u, before / total * a, lower[k], upper[k]))
        else:
            lengths.append((float(np.linalg.norm(u)),) * 2)
        before += link_mass[k]
    return np.asarray(lengths)


def tip_shell(robot) -> tuple[float, float]:
    """``(inner, outer)`` radii about the system centroid, m, between which every tip lies.

    outer = sum_k max |V_k|; inner = max(0, max_j (min |V_j| - sum_{k != j} max |V_k|)).
    """
    lengths = virtual_link_lengths(robot)
    low, high = lengths[:, 0], lengths[:, 1]
    outer = float(np.sum(high))
    inner = float(np.max(low - (outer - high))) if np.isfinite(outer) else 0.0
    return max(0.0, inner), outer
