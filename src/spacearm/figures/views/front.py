"""``front.html``: a Pareto front to turn and hover, with the robot of a picked design.

Each search's non-dominated designs are drawn in objective space (3-D for three or more
objectives, the first three as axes; 2-D for two); hovering a point shows every design
variable and objective, and clicking a point of the gradient front draws that design's
robot beside the front (its kinematic model rides in the page, at most `MAX_ROBOTS` designs).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import jax
import numpy as np

from .model import view_model
from .page import write_page

__all__ = ["MAX_ROBOTS", "front_view", "write_front_view"]

MAX_ROBOTS = 120
_STYLE = {
    "gradient": dict(color="#d62728", symbol="circle", name="gradient search front"),
    "nsga2": dict(color="#1f77b4", symbol="square", name="NSGA-II front"),
    "grid": dict(color="#555555", symbol="diamond", name="dense grid front"),
}


def _hover(method: str, variables, objectives, x, f) -> str:
    rows = [f"<b>{method}</b>"]
    rows += [f"{name} = {value:.6g}" for name, value in zip(objectives, f, strict=False)]
    rows += [f"{name} = {value:.6g}" for name, value in zip(variables, x, strict=False)]
    return "<br>".join(rows)


def write_front_view(
    path: str | Path,
    *,
    objective_names,
    variable_names,
    fronts: Mapping[str, tuple],
    robots: Mapping[int, object] | None = None,
    title: str = "Pareto front",
) -> Path:
    """Write the front page.

    Args:
        path: the HTML file to write.
        objective_names: ``m`` objective names (all maximized).
        variable_names: ``d`` design variable names.
        fronts: method -> ``(designs (k, d), objectives (k, m))`` of its non-dominated designs.
        robots: row of ``fronts["gradient"]`` -> its robot, drawn when that point is clicked.

    Raises:
        MissingViewExtra: plotly is not installed.
    """
    names = list(objective_names)
    three = len(names) >= 3
    traces, models, index = [], [], {}
    for row, robot in (robots or {}).items():
        index[row] = len(models)
        model = view_model(robot)
        models.append(dict(model=model, posture=np.zeros(model["posture"]["size"]), extent=model["extent"]))
    for method, (designs, objectives) in fronts.items():
        designs, objectives = np.asarray(designs, float), np.asarray(objectives, float)
        order = np.argsort(objectives[:, 0])
        style = dict(_STYLE.get(method, dict(color="#2ca02c", symbol="circle", name=method)))
        trace = dict(
            type="scatter3d" if three else "scatter",
            mode="markers" if three or method != "grid" else "lines+markers",
            name=f"{style.pop('name')} ({len(designs)})",
            x=objectives[order, 0],
            y=objectives[order, 1],
            marker=dict(size=5 if three else 7, color=style["color"], symbol=style["symbol"]),
            text=[_hover(method, variable_names, names, designs[i], objectives[i]) for i in order],
            hoverinfo="text",
            customdata=[index.get(int(i)) if method == "gradient" else None for i in order],
        )
        if three:
            trace["z"] = objectives[order, 2]
        traces.append(trace)
    axis = lambda i: dict(title=dict(text=f"{names[i]} (maximized)"))
    layout = dict(
        margin=dict(l=60, r=10, t=40, b=50), title=dict(text=title, font=dict(size=14)), legend=dict(x=0, y=1)
    )
    if three:
        layout["scene"] = dict(xaxis=axis(0), yaxis=axis(1), zaxis=axis(2))
    else:
        layout.update(xaxis=axis(0), yaxis=axis(1))
    note = (
        "Hover a point for its design variables and objectives; click a point of the gradient front to "
        "draw that design's robot below (joints at zero)."
    )
    readout = "objectives: " + ", ".join(names) + "\nvariables: " + ", ".join(variable_names)
    data = dict(mode="front", traces=traces, layout=layout, robots=models, readout=readout)
    return write_page(path, title=title, note=note, data=data)


def front_view(problem, results: Mapping, summary: Mapping, out_dir: Path) -> list[Path]:
    """``front.html`` for `spacearm.design.run_problem` (a `spacearm.design.run.ProblemOutput`):
    every search's front, and the robots of up to `MAX_ROBOTS` gradient-front designs."""
    fronts, robots = {}, {}
    for method, result in results.items():
        keep = result.front()
        fronts[method] = (result.designs[keep], result.objectives[keep])
    if "gradient" in fronts:
        designs = fronts["gradient"][0]
        picked = np.unique(np.linspace(0, len(designs) - 1, min(len(designs), MAX_ROBOTS)).round().astype(int))
        batch = jax.tree_util.tree_map(np.asarray, jax.jit(jax.vmap(problem.robot))(designs[picked]))
        for k, row in enumerate(picked):
            robots[int(row)] = jax.tree_util.tree_map(lambda leaf, k=k: leaf[k], batch)
    title = f"{problem.name}: Pareto front of " + ", ".join(problem.objectives)
    return [
        write_front_view(
            Path(out_dir) / "front.html",
            objective_names=problem.objectives,
            variable_names=problem.variable_names,
            fronts=fronts,
            robots=robots,
            title=title,
        )
    ]
