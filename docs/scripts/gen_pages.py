"""Build-time pages for the documentation site (run by the mkdocs-gen-files plugin).

Generates, on every ``mkdocs build`` / ``mkdocs serve``:

* ``reference/cli.md``: the help of ``spacearm`` and of every subcommand, rendered from
  ``spacearm.cli.build_parser()``, so the page never goes stale;
* ``reference/api/*.md`` and its ``SUMMARY.md`` (read by mkdocs-literate-nav, then
  dropped by ``docs/scripts/hooks.py`` so it is not built as a page): one
  mkdocstrings ``::: module`` page per entry of :data:`API_MODULES`;
* ``reference/api/spacearm.md``: the top-level package with a table of every public
  name and the module that defines it (``spacearm/__init__.py`` resolves some names
  lazily through ``_LAZY``, which griffe's static analysis cannot follow);
* ``reference/layout.md``: the package layout table, from the same list;
* ``reference/table2-report.md``: ``results/table2/table.md`` as written by the sweep;
* ``assets/results/<folder>/<name>.png``: every figure under ``results/*/``, copied at
  build time so the PNGs are not duplicated in git.

API_MODULES is the ONE place where module paths live: when modules move, update it
(the build warns, and ``mkdocs build --strict`` fails, on a listed module that does not
exist or a public module that is not listed).
"""

from __future__ import annotations

import argparse
import inspect
import logging
import os
import pkgutil
import sys
from pathlib import Path

import mkdocs_gen_files

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))  # document this checkout, installed or not

log = logging.getLogger("mkdocs.plugins.gen_pages")

# ---------------------------------------------------------------------------------------
# Module paths: the only list of them in the docs. (module, section, what it holds)
# ---------------------------------------------------------------------------------------
API_MODULES: list[tuple[str, str, str]] = [
    ("spacearm", "Package", "the public API: curated re-exports (some resolved lazily, see the table)"),
    ("spacearm.models", "Models", "the robot families and `load_robot` (a file with `arm:` is spatial)"),
    ("spacearm.models.family", "Models", "the seam: the per-posture primitives every family implements"),
    ("spacearm.models.budget", "Models", "the mass budget: the bus, each root body, the moving links, the total"),
    ("spacearm.models.view_model", "Models", "a robot as one family-free tree of bodies on a free bus, for drawing"),
    ("spacearm.models.payload", "Models", "a rigid payload welded to a tip: mass properties merged into its body"),
    (
        "spacearm.models.dynamics",
        "Models",
        "the one model's dynamics: the system mass matrix, bias forces and tip maps on the tree pass",
    ),
    ("spacearm.models.planar", "Models", "the planar family of the paper"),
    ("spacearm.models.planar.robot", "Models", "the `PlanarRobot` pytree and its validation"),
    ("spacearm.models.planar.schema", "Models", "the planar robot file, the Table 1 preset"),
    (
        "spacearm.models.planar.closed_forms",
        "Models",
        "design coefficients (virtual manipulator), eq. 1, 2, 5, 6, 10 in closed form",
    ),
    (
        "spacearm.models.planar.embedding",
        "Models",
        "the planar arm as the one-tip tree in the bus's x-y plane (its dynamics)",
    ),
    ("spacearm.models.planar.family", "Models", "the planar primitives and the closed forms registered as fast paths"),
    (
        "spacearm.models.planar.view",
        "Models",
        "the planar arm as the view tree: joints about z, the bus turned by phi0",
    ),
    (
        "spacearm.models.planar.fields",
        "Models",
        "named planar design numbers (base, links, shares, arm mass and split)",
    ),
    ("spacearm.models.spatial", "Models", "the spatial family: URDF arms on a free-floating bus"),
    (
        "spacearm.models.spatial.urdf",
        "Models",
        "the URDF reader (standard-library XML; fixed and locked joints merged)",
    ),
    ("spacearm.models.spatial.robot", "Models", "the `SpatialRobot` pytree and its validation"),
    ("spacearm.models.spatial.schema", "Models", "the spatial robot file (`arm:` key)"),
    ("spacearm.models.spatial.primitives", "Models", "the spatial primitives: the tree pass on the arm's one-tip view"),
    ("spacearm.models.spatial.family", "Models", "the spatial family and its fast paths"),
    ("spacearm.models.spatial.view", "Models", "the arm as the view tree of bodies"),
    (
        "spacearm.models.spatial.fields",
        "Models",
        "named spatial design numbers (mount, bus, arm scale factors, link masses)",
    ),
    ("spacearm.models.tree", "Models", "the tree family: several arms, or one branched URDF, on a free-floating bus"),
    (
        "spacearm.models.tree.robot",
        "Models",
        "the `TreeRobot` pytree (static parents and tip bodies) and its validation",
    ),
    (
        "spacearm.models.tree.schema",
        "Models",
        "the tree robot file: several arms on one bus (`arms:`) or one whole-system URDF (`system:`)",
    ),
    (
        "spacearm.models.tree.urdf",
        "Models",
        "the whole-system URDF reader: the bus link, the paths to the tips, lock_others",
    ),
    ("spacearm.models.tree.algebra", "Models", "the scalar algebra of the pass and its forward and backward steps"),
    ("spacearm.models.tree.primitives", "Models", "the pass over the tree: k tips, one pass per posture"),
    ("spacearm.models.tree.view", "Models", "the tree as the view tree of bodies"),
    ("spacearm.models.tree.family", "Models", "the tree family and its fast paths"),
    (
        "spacearm.models.tree.fields",
        "Models",
        "named tree design numbers (each arm's mount, mass and length factors, the bus, link masses and lengths)",
    ),
    (
        "spacearm.models.tree.shell",
        "Models",
        "the virtual manipulator's shell of one tip of a tree: radii between which it lies",
    ),
    ("spacearm.inertia", "Kinematics", "rotational and dynamic manipulability, C(q), ellipsoids: every robot"),
    (
        "spacearm.dynamics",
        "Dynamics",
        "free-floating dynamics with any momentum: H, bias, forward and inverse dynamics, G, impulses",
    ),
    ("spacearm.dynamics.state", "Dynamics", "the state the kernels share: posture, attitude, momentum, axes"),
    ("spacearm.dynamics.equations", "Dynamics", "H, c, H*, c*, forward dynamics, inverse dynamics with three buses"),
    ("spacearm.dynamics.velocities", "Dynamics", "the bus's and the tip's velocity for any momentum"),
    ("spacearm.dynamics.impacts", "Dynamics", "G (extended inversed inertia), the impulse response, capture"),
    ("spacearm.dynamics.wheels", "Dynamics", "the reaction-wheel momentum that holds the bus attitude"),
    ("spacearm.dynamics.payload", "Dynamics", "a grasped target as a tip payload; the momentum of a given velocity"),
    (
        "spacearm.kinematics",
        "Kinematics",
        "J*, w*, ellipsoids, base rates, straight-path rates: written once over the primitives",
    ),
    ("spacearm.motion", "Motion", "the base attitude along joint paths and straight tip paths"),
    ("spacearm.motion.joint_paths", "Motion", "eq. 5 along joint polylines (Gauss-Legendre line integral)"),
    (
        "spacearm.motion.straight_paths",
        "Motion",
        "straight tip paths of every family (adaptive DOP853 to the singular end), go-and-back",
    ),
    (
        "spacearm.motion.attitude",
        "Motion",
        "the bus attitude on SO(3) along joint paths (Magnus on Gauss nodes), SO(3) helpers",
    ),
    ("spacearm.motion.spatial_paths", "Motion", "straight tip paths of spatial arms, (q, R) integrated together"),
    (
        "spacearm.motion.pose_paths",
        "Motion",
        "straight pose paths: tip on a line, axes on the SO(3) geodesic, through the whole J*",
    ),
    ("spacearm.motion.path_ends", "Motion", "why a straight tip path ended: the reason codes"),
    (
        "spacearm.motion.lanes",
        "Motion",
        "the one lane integrator: DOP853 with event location, lane refill, power-of-two buckets",
    ),
    ("spacearm.motion.dop853", "Motion", "the DOP853 tableau, one step, the error norm"),
    ("spacearm.motion.batching", "Motion", "designs and paths flattened to one batch axis"),
    (
        "spacearm.motion.tasks",
        "Motion",
        "timed tasks (waypoints, duration, quintic time law) and the peak torques and held wrench",
    ),
    (
        "spacearm.motion.simulation",
        "Motion",
        "the free-floating robot under joint torques: RKMK-DOP853 on the attitude group, events",
    ),
    ("spacearm.analysis", "Analysis", "workspaces, singular sets, areas, averaged metrics, maps"),
    (
        "spacearm.paper.workspaces",
        "Analysis",
        "the five workspaces in closed form, S_M and S_G, section 3.2 relations",
    ),
    (
        "spacearm.models.planar.singularities",
        "Analysis",
        "dynamic singularities (det J* = 0) and the path-independent radius",
    ),
    ("spacearm.paper.straight_workspace", "Analysis", "the Straight-Path workspace (Area 4) by integration"),
    ("spacearm.analysis.reaction", "Analysis", "reaction null space, base disturbance maps, reaction-free tip motion"),
    ("spacearm.analysis.joint_box", "Analysis", "the joint box with its uniform measure; randomized Sobol points"),
    (
        "spacearm.analysis.averages",
        "Analysis",
        "averages over the joint box (w*, conditioning, base disturbance, w_d) by randomized QMC, with error estimates",
    ),
    (
        "spacearm.analysis.impacts",
        "Analysis",
        "impact quantities as joint-box metrics: virtual mass, bus-rate jump, bus rate after a reference capture",
    ),
    (
        "spacearm.analysis.workspace_search",
        "Analysis",
        "spatial reach radii, dynamic singular sets, the path-independent radius, the 3-D straight-path workspace",
    ),
    ("spacearm.paper.manipulability_average", "Analysis", "w-bar (eq. 12): the adaptive quadrature"),
    (
        "spacearm.paper.manipulability_maps",
        "Analysis",
        "posture grids, manipulability maps over joints and the tip plane",
    ),
    ("spacearm.planning", "Planning", "reorientation loops and reaching a point"),
    ("spacearm.planning.reorientation", "Planning", "cyclic joint loops that turn the base (optax through eq. 5)"),
    ("spacearm.planning.reach", "Planning", "reaching point C: reorient, then a straight path"),
    (
        "spacearm.planning.spatial_reorientation",
        "Planning",
        "closed joint loops that turn a spatial bus by a target rotation",
    ),
    ("spacearm.planning.spatial_reach", "Planning", "reaching a point in 3-D: turn the bus, then a straight path"),
    ("spacearm.planning.pose_reach", "Planning", "reaching a pose: the tip-shell check, then one straight pose path"),
    ("spacearm.paper", "Paper", "the paper's planar quantities: normalized w-bar (eq. 12), workspaces, Table 2 areas"),
    ("spacearm.paper.planar_parts", "Paper", "the planar closed forms' building blocks the paper's studies assemble"),
    ("spacearm.design", "Design", "gradient Pareto search over design numbers"),
    ("spacearm.design.problem", "Design", "design problems: variables, objectives, settings, the problem file"),
    ("spacearm.design.objectives", "Design", "the objective functions"),
    ("spacearm.design.fronts", "Design", "non-dominated sets and hypervolume"),
    ("spacearm.design.search", "Design", "the scalarized (Chebyshev) gradient Pareto search"),
    ("spacearm.design.hypervolume", "Design", "the exact hypervolume of 2 to 4 objectives in JAX and its gradient"),
    ("spacearm.design.hybrid", "Design", "the default search: evolution and hypervolume-gradient steps"),
    ("spacearm.design.baselines", "Design", "grid and NSGA-II baselines"),
    ("spacearm.design.run", "Design", "a whole optimization job: searches, baselines, tables, manifest"),
    ("spacearm.studies", "Studies", "sweeps over designs from YAML"),
    ("spacearm.studies.spec", "Studies", "the sweep file and its overrides"),
    ("spacearm.studies.designs", "Studies", "design fields, axes and the batch of designs a sweep builds"),
    ("spacearm.studies.metrics", "Studies", "the metric registry of sweeps"),
    ("spacearm.studies.runner", "Studies", "the chunked, sharded, resumable sweep runner"),
    ("spacearm.studies.table2", "Studies", "the Table 2 report: paper beside ours, readings of w-bar"),
    (
        "spacearm.studies.table2_readings",
        "Studies",
        "the derivation variants and averaging rules behind the Table 2 readings",
    ),
    ("spacearm.io", "Results on disk", "results on disk"),
    ("spacearm.io.files", "Results on disk", "atomic writes, CSV tables, `.npz` grids"),
    ("spacearm.io.manifest", "Results on disk", "the manifest that lets anyone rerun a result"),
    ("spacearm.io.folders", "Results on disk", "result folders swapped in whole, one writer at a time (a lock)"),
    ("spacearm.io.grids", "Results on disk", "`open_results`: a sweep's grids as a labelled xarray Dataset"),
    ("spacearm.figures", "Figures", "the figure registry"),
    ("spacearm.figures.robot", "Figures", "the one drawing of a planar robot"),
    ("spacearm.figures.maps", "Figures", "Fig. 6, 7, 8 and 10: ellipses and manipulability maps"),
    ("spacearm.figures.motion", "Figures", "Fig. 2, 3a, 9: cyclic loops, straight paths, go-and-back"),
    ("spacearm.figures.workspace", "Figures", "Fig. 3, 4, 5 and the dynamic singularities"),
    ("spacearm.figures.planning", "Figures", "reaching point C: plan drawing and animation"),
    (
        "spacearm.figures.spatial",
        "Figures",
        "3-D figures: the arm on its bus along a loop, attitude history, straight paths",
    ),
    ("spacearm.figures.spatial_analysis", "Figures", "workspace shells and w* maps on joint slices of spatial arms"),
    ("spacearm.figures.sweep", "Figures", "a sweep's heat maps and metric plots"),
    ("spacearm.figures.design", "Figures", "Pareto fronts, convergence, the best designs"),
    ("spacearm.figures.dynamics", "Figures", "a simulated run: joints, bus attitude and bus rate"),
    ("spacearm.figures.views", "Figures", "interactive offline HTML views (the `view` extra)"),
    ("spacearm.figures.views.model", "Figures", "the kinematic model as JSON for the browser's forward kinematics"),
    ("spacearm.figures.views.page", "Figures", "one self-contained page: plotly.js, fk.js and the data inlined"),
    ("spacearm.figures.views.arm", "Figures", "a robot on its bus with a slider per joint"),
    ("spacearm.figures.views.replay", "Figures", "a recorded maneuver replayed frame by frame"),
    ("spacearm.figures.views.front", "Figures", "a Pareto front with the variables on hover and the picked robot"),
    (
        "spacearm.figures.views.shells",
        "Figures",
        "a sweep's workspace shells about the system centroid, design by design",
    ),
    ("spacearm.cli", "Command line", "the `spacearm` command: one module per subcommand"),
    ("spacearm.cli.validate", "Command line", "`spacearm validate`"),
    ("spacearm.cli.info", "Command line", "`spacearm info`"),
    ("spacearm.cli.sweep", "Command line", "`spacearm sweep`"),
    ("spacearm.cli.figures", "Command line", "`spacearm figures`"),
    ("spacearm.cli.reach", "Command line", "`spacearm reach`"),
    ("spacearm.cli.optimize", "Command line", "`spacearm optimize`"),
    ("spacearm.cli.view", "Command line", "`spacearm view`"),
    ("spacearm.cli.simulate", "Command line", "`spacearm simulate`"),
    ("spacearm.cli.capture", "Command line", "`spacearm capture`"),
]

CLI_WIDTH = "88"  # columns of the rendered --help text


def _page(module: str) -> str:
    return f"reference/api/{module}.md"


def check_module_list() -> None:
    """Warn on listed modules that are missing and public modules that are not listed."""
    import spacearm

    listed = {name for name, _, _ in API_MODULES}
    found = {"spacearm"}
    for info in pkgutil.walk_packages(spacearm.__path__, "spacearm."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            found.add(info.name)
    for name in sorted(listed - found):
        log.warning("docs/scripts/gen_pages.py: API_MODULES lists %s, which does not exist", name)
    for name in sorted(found - listed):
        log.warning("docs/scripts/gen_pages.py: public module %s is not in API_MODULES", name)


def _serves(value) -> str:
    """Which robots a public function takes: every family, planar arms only, or none."""
    try:
        parameters = list(inspect.signature(value).parameters)
    except (TypeError, ValueError):
        parameters = []
    if isinstance(value, type) or not parameters or parameters[0] not in ("robot", "robots"):
        return "-"
    return "planar arms only" if "Planar arms only" in (value.__doc__ or "") else "every family"


def public_names_table() -> str:
    """Markdown table: every public name of ``spacearm`` and the module defining it."""
    import spacearm

    documented = {name for name, _, _ in API_MODULES}
    lazy = getattr(spacearm, "_LAZY", {})
    rows = []
    for name in sorted(spacearm.__all__, key=str.lower):
        if name.startswith("_"):
            continue
        value = getattr(spacearm, name)
        module = getattr(value, "__module__", None) or f"spacearm.{lazy.get(name, '?')}"
        how = "lazy" if name in lazy else "eager"
        target = f"[`{name}`][{module}.{name}]" if module in documented else f"`{name}`"
        where = f"[`{module}`]({module}.md)" if module in documented else f"`{module}`"
        serves = _serves(value)
        rows.append(f"| {target} | {serves} | {where} | {how} |")
    return "\n".join(["| name | serves | defined in | import |", "|---|---|---|---|", *rows])


def write_api_pages() -> None:
    sections: dict[str, list[str]] = {}
    for module, section, what in API_MODULES:
        sections.setdefault(section, []).append(module)
        with mkdocs_gen_files.open(_page(module), "w") as page:
            if module == "spacearm":
                page.write("::: spacearm\n    options:\n      members: false\n\n")
                page.write(
                    "## Public names\n\n"
                    "`import spacearm as sa` gives these names (`spacearm.__all__`): the loaders and "
                    "the functions that serve every robot family, and a few planar closed forms "
                    "that say so (another family raises TypeError); other family-specific names "
                    "live in `spacearm.models.planar` and `spacearm.models.spatial`. Those marked *lazy* are "
                    "imported from their module on first use (`_LAZY` in "
                    "`spacearm/__init__.py`), which keeps `import spacearm` light; "
                    "each is documented on the page of the module that defines it.\n\n"
                )
                page.write(public_names_table() + "\n")
            else:
                page.write(f"::: {module}\n")
    lines = []
    for section, modules in sections.items():
        lines.append(f"* {section}")
        for module in modules:
            lines.append(f"    * [{module}]({module}.md)")
    with mkdocs_gen_files.open("reference/api/SUMMARY.md", "w") as summary:
        summary.write("\n".join(lines) + "\n")


def write_layout_page() -> None:
    rows = [f"| [`{m}`](api/{m}.md) | {what} |" for m, _, what in API_MODULES]
    with mkdocs_gen_files.open("reference/layout.md", "w") as page:
        page.write(
            "# Package layout\n\n"
            "Generated from `API_MODULES` in `docs/scripts/gen_pages.py`. Layers import "
            "downward only (checked in CI by `.importlinter`): cli > figures > studies, "
            "design > planning > analysis > motion > kinematics > models > io > _core. "
            "`_core` (errors, numeric settings, the YAML/schema layer, batching) is private. "
            "Benchmarks live in `benchmarks/` and print ratios "
            "against baselines measured in the same run.\n\n"
            "| module | what |\n|---|---|\n" + "\n".join(rows) + "\n"
        )


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def write_cli_page() -> None:
    from spacearm.cli import build_parser

    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = CLI_WIDTH
    try:
        parser = build_parser()
        parts = [
            "# Command line reference\n\n"
            "Rendered at build time from `spacearm.cli.build_parser()`: this is exactly "
            "what `spacearm --help` and `spacearm COMMAND --help` print.\n\n"
            "## spacearm\n\n```text\n" + parser.format_help() + "```\n"
        ]
        for name, sub in _subparsers(parser).items():
            parts.append(f"## spacearm {name}\n\n```text\n{sub.format_help()}```\n")
    finally:
        if previous is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = previous
    with mkdocs_gen_files.open("reference/cli.md", "w") as page:
        page.write("\n".join(parts))


def copy_result_figures() -> None:
    for png in sorted((ROOT / "results").glob("*/*.png")):
        target = f"assets/results/{png.parent.name}/{png.name}"
        with mkdocs_gen_files.open(target, "wb") as out:
            out.write(png.read_bytes())


def write_table2_report() -> None:
    source = ROOT / "results" / "table2" / "table.md"
    text = source.read_text()
    title, _, rest = text.partition("\n")
    note = (
        '\n\n!!! note "Generated"\n    This page is `results/table2/table.md` as '
        "`spacearm sweep sweeps/table2.yaml` wrote it, copied at build time.\n"
    )
    with mkdocs_gen_files.open("reference/table2-report.md", "w") as page:
        page.write(title + note + rest)


check_module_list()
write_api_pages()
write_layout_page()
write_cli_page()
copy_result_figures()
write_table2_report()
