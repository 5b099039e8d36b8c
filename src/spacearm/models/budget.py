"""A robot's mass budget: the bus, each rigid root body with the links merged into it,
the moving links of each arm, and the total.

Every robot file turns URDF links into a few rigid bodies (fixed joints merged, locked
joints held, side branches held or dropped), so the mass a model carries is not always
the mass a user pictures. The budget shows where every kilogram sits.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .planar import PlanarRobot
from .spatial import SpatialRobot
from .tree.robot import TreeRobot

__all__ = ["MassLine", "format_mass_budget", "mass_budget", "shared_links"]


@dataclasses.dataclass(frozen=True)
class MassLine:
    """One line of a mass budget.

    Attributes:
        part: what it is (``"bus"``, ``"root left"``, ``"moving links of left"``, ``"total"``).
        kg: its mass.
        links: the URDF links it holds, where the robot came from a URDF.
    """

    part: str
    kg: float
    links: tuple[str, ...] = ()


def mass_budget(robot) -> tuple[MassLine, ...]:
    """The bus, each root body, the moving links of each arm, then the total (kg)."""
    lines = [MassLine("bus", float(robot.base_mass))]
    if isinstance(robot, PlanarRobot):
        lines.append(MassLine(f"moving links ({robot.n_links})", float(np.sum(robot.link_mass))))
    elif isinstance(robot, SpatialRobot):
        links = robot.labels.body_links
        lines.append(MassLine(f"root {robot.labels.root_link}", float(robot.root_mass), links[0] if links else ()))
        moving = tuple(name for group in links[1:] for name in group)
        lines.append(MassLine(f"moving links ({robot.n_joints} bodies)", float(np.sum(robot.link_mass)), moving))
    elif isinstance(robot, TreeRobot):
        bus_links, arms = _tree_lines(robot)
        lines = [dataclasses.replace(lines[0], links=bus_links), *arms]
    total = sum(line.kg for line in lines)
    return (*lines, MassLine("total", total))


def _tree_lines(robot: TreeRobot) -> tuple[tuple[str, ...], list[MassLine]]:
    """The links merged into the bus (a ``system:`` file's base link without a ``base:``),
    and the lines of the roots and arms."""
    labels = robot.labels
    roots = np.atleast_1d(np.asarray(robot.root_mass))
    link_mass = np.asarray(robot.link_mass)
    bus_links: tuple[str, ...] = ()
    lines = []
    for r, name in enumerate(labels.root_names):
        merged = tuple(labels.root_links[r]) if r < len(labels.root_links) else ()
        if roots[r] > 0:
            lines.append(MassLine(f"root {name}", float(roots[r]), merged))
        else:  # the root is the bus itself
            bus_links += merged
        bodies = [j for j, root in enumerate(labels.joint_roots) if root == r]
        links = tuple(link for j in bodies for link in (labels.body_links[j] if j < len(labels.body_links) else ()))
        lines.append(MassLine(f"moving links of {name} ({len(bodies)} bodies)", float(link_mass[bodies].sum()), links))
    return bus_links, lines


def shared_links(robot) -> tuple[str, ...]:
    """URDF links that move with one arm of a tree and are also merged, held, into
    another arm's root: one physical part counted twice (two arms cut from one humanoid
    file). Arms that are whole copies of one URDF (two UR5s) are not reported."""
    if not isinstance(robot, TreeRobot) or len(robot.labels.root_names) < 2:
        return ()
    labels = robot.labels
    roots = [set(links) for links in labels.root_links]
    moving = [set() for _ in roots]
    for j, r in enumerate(labels.joint_roots):
        if r < len(moving) and j < len(labels.body_links):
            moving[r].update(labels.body_links[j])
    shared = {link for a, links in enumerate(moving) for b, root in enumerate(roots) if a != b for link in links & root}
    return tuple(sorted(shared))


def format_mass_budget(robot, *, shown_links: int = 6) -> str:
    """The budget as aligned lines, kg to 1e-6, each with the first links it merges."""
    lines = mass_budget(robot)
    width = max(len(line.part) for line in lines)
    out = [f"mass budget of {robot.name} (kg)"]
    for line in lines:
        merged = ""
        if line.links:
            names = ", ".join(line.links[:shown_links])
            more = f" and {len(line.links) - shown_links} more" if len(line.links) > shown_links else ""
            merged = f"   {names}{more}"
        out.append(f"  {line.part:<{width}}  {line.kg:14.6f}{merged}")
    shared = shared_links(robot)
    if shared:
        names = ", ".join(shared[:shown_links]) + (
            f" and {len(shared) - shown_links} more" if len(shared) > shown_links else ""
        )
        out.append(
            f"  note: {len(shared)} links are carried by more than one arm ({names}); if they are one part, "
            "describe the robot as one system: file, or set drop_others and a root_link below them"
        )
    return "\n".join(out)
