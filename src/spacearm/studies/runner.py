"""Running a sweep: every design in compiled, vmapped chunks sharded over the JAX devices,
finished chunks kept on disk so an interrupted sweep resumes, then the table, the grids,
the report and the manifest (through `spacearm.io`). No figures here.

All designs are stacked into one robot pytree (planar or spatial) with a leading axis
and evaluated by one compiled function in chunks of bounded size. Under
``jax.distributed`` (``spacearm sweep --coordinator ...``) the device mesh spans every
process: each chunk is sharded over all of their devices, the results are gathered,
and process 0 alone writes the chunks, the table and the manifest; the others return
an empty `SweepResult`.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import json
import math
import os
import re
import shutil
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import jax
import numpy as np
from jax._src import distributed as jax_distributed  # the coordination service's client
from jax.experimental import multihost_utils
from tqdm.auto import tqdm

from .._core.errors import ConfigError, RunError, Stalled
from .._core.memory import TEMPORARIES, working_numbers
from .._core.numeric import PEER_TIMEOUT_S, STALL_S, wait_until_ready
from .._core.schema import check_memory
from .._version import __version__
from ..io import build_manifest, config_hash, manifest as provenance, write_csv, write_json, write_npz
from ..io.folders import check_output_folder, claimed_folder, replacing_folder
from .designs import build_designs, design_columns
from .metrics import METRICS, MetricSpec, design_function, metric_columns
from .spec import SweepSpec
from .table2 import REPORTS

__all__ = [
    "DESIGNS_PER_STEP",
    "STEP_MEMORY_BYTES",
    "NonFiniteResult",
    "SweepOutput",
    "SweepResult",
    "agree_with_peers",
    "check_finite",
    "check_sweep_memory",
    "designs_per_step",
    "differing_keys",
    "memory_estimate",
    "run_sweep",
]

# Designs vmapped together inside a chunk (see run_sweep): small enough for the cache.
DESIGNS_PER_STEP = 32
# The estimated working sets of the designs computed side by side, all devices together
# (`designs_per_step`): a dual-arm humanoid's joint-box averages then run 2 at a time.
STEP_MEMORY_BYTES = 512 * 2**20

# A writer run after the table, grids and report: (spec, out_dir, table: column -> values
# per design) -> the paths it wrote (listed in the manifest).
SweepOutput = Callable[[SweepSpec, Path, Mapping[str, np.ndarray]], "list[Path]"]


def _mesh():
    devices = np.array(jax.devices())
    return jax.sharding.Mesh(devices, ("designs",))


def _shard_map(function, *, mesh, in_specs, out_specs):
    """``jax.shard_map`` (jax >= 0.6) or its earlier home, without replication checks."""
    if hasattr(jax, "shard_map"):
        return jax.shard_map(function, mesh=mesh, in_specs=in_specs, out_specs=out_specs, check_vma=False)
    from jax.experimental.shard_map import shard_map  # noqa: PLC0415

    return shard_map(function, mesh=mesh, in_specs=in_specs, out_specs=out_specs, check_rep=False)


def _chunks(total: int, size: int) -> list[tuple[int, int]]:
    return [(start, min(start + size, total)) for start in range(0, total, size)]


def _take(robot, start: int, stop: int, size: int, devices: int):
    """Rows start:stop, padded to ``size`` by repeating the last row (static shapes),
    as ``(devices, size // devices, ...)``: one row of designs per device."""
    index = np.minimum(np.arange(start, start + size), stop - 1).reshape(devices, -1)
    return jax.tree_util.tree_map(lambda x: np.asarray(x)[index], robot)


def _shard(tree, sharding):
    """Place a host batch on the device mesh; every process supplies the shards it owns,
    so the same code runs on one device, many devices, or many hosts (jax.distributed)."""

    def place(x):
        x = np.asarray(x)
        return jax.make_array_from_callback(x.shape, sharding, lambda index: x[index])

    return jax.tree_util.tree_map(place, tree)


def _gather(array) -> np.ndarray:
    """A global result as a host array (all-gathered across processes when multi-host)."""
    if getattr(array, "is_fully_addressable", True):
        return np.asarray(array)
    return np.asarray(multihost_utils.process_allgather(array, tiled=True))


@dataclasses.dataclass
class SweepResult:
    out_dir: Path
    table: dict[str, np.ndarray]
    manifest: dict
    files: list[Path]


@functools.lru_cache(maxsize=32)
def _evaluator(metrics_key: str, per_step: int, mesh):
    """The jitted chunk program of a sweep's metrics, built once per process for each
    metric list, step size and device mesh (a second sweep of the same shape reuses it)."""
    metrics = tuple(MetricSpec(name, options) for name, options in json.loads(metrics_key))
    walk = functools.partial(jax.lax.map, design_function(metrics), batch_size=per_step)

    def step(batch):
        # Each device holds one row of designs (`_take`): walk it without a vmap of size 1,
        # which would batch every traced step of the metrics once more (tracing time,
        # paid again by every process even when the compiled program comes from the cache).
        if jax.tree_util.tree_leaves(batch)[0].shape[0] == 1:
            return jax.tree_util.tree_map(lambda v: v[None], walk(jax.tree_util.tree_map(lambda x: x[0], batch)))
        return jax.vmap(walk)(batch)

    # shard_map: each device runs its own rows with no collective inside. Under plain
    # sharded jit a data-dependent loop (the joint-box averages' while_loop, vmapped)
    # needs the loop predicate reduced across devices every iteration, and that
    # deadlocked with several CPU devices in one process.
    return jax.jit(
        _shard_map(
            lambda batch: jax.tree_util.tree_map(lambda v: v.reshape(-1), step(batch)),
            mesh=mesh,
            in_specs=jax.sharding.PartitionSpec("designs"),
            out_specs=jax.sharding.PartitionSpec("designs"),
        )
    )


def run_sweep(
    spec: SweepSpec,
    out_dir: str | os.PathLike | None = None,
    *,
    progress: bool = True,
    command: Sequence[str] | None = None,
    stop_after_chunks: int | None = None,
    outputs: Sequence[SweepOutput] = (),
    peer_timeout_s: float = PEER_TIMEOUT_S,
    stall_s: float = STALL_S,
) -> SweepResult:
    """Evaluate every design of a sweep and write ``table.csv``, ``grids.npz``, the report
    (``report:`` in the file, e.g. ``table.md``) and ``manifest.json`` into ``out_dir``
    (default: the sweep's ``output``).

    Finished chunks are saved under ``out_dir/.partial-<hash>/``; a re-run of the same
    resolved sweep loads them and computes only the rest. ``stop_after_chunks`` simulates
    an interruption (for tests). The results are written into a staging folder beside
    ``out_dir`` and swapped in whole at the end, under a lock that refuses a second
    writer (`spacearm.io.folders`): a reader never sees files of two runs.

    Args:
        outputs: further writers, each ``fn(spec, out_dir, table) -> [paths]``, run after
            the report and before the manifest, which lists their files (``spacearm sweep``
            passes `spacearm.figures.sweep.write_figures`). This layer draws nothing.
        peer_timeout_s: under ``jax.distributed``, how long to wait for the other processes
            when they compare their settings (`agree_with_peers`).
        stall_s: how long a chunk may go without this process using any CPU before the
            sweep ends with `Stalled` naming the chunk (a deadlock never finishes).

    Raises:
        ConfigError: a second writer holds ``out_dir``, it holds another command's results,
            the sweep would not fit in memory, or under ``jax.distributed`` the processes
            disagree on the config or the code.
        RunError: a metric came out non-finite, a chunk stalled (`Stalled`), or under
            ``jax.distributed`` a peer stopped or did not answer.
    """
    wall_start = time.perf_counter()
    out_dir = Path(out_dir if out_dir is not None else spec.output)
    _check_output_dir(out_dir)
    check_sweep_memory(spec)
    with contextlib.ExitStack() as stack:
        refusal = None
        if jax.process_index() == 0:  # the one writer: refuse a second one before computing
            try:
                stack.enter_context(claimed_folder(out_dir, "sweep", label=f"--out {out_dir}"))
            except ConfigError as error:
                if jax.process_count() == 1:
                    raise
                refusal = str(error)  # every process must hear it, or they would wait for process 0
        if jax.process_count() > 1:
            agree_with_peers(spec, timeout_s=peer_timeout_s, refusal=refusal)
        return _run_locked(
            spec,
            out_dir,
            wall_start,
            progress=progress,
            command=command,
            stop_after_chunks=stop_after_chunks,
            outputs=outputs,
            stall_s=stall_s,
        )


def _run_locked(
    spec: SweepSpec,
    out_dir: Path,
    wall_start: float,
    *,
    progress: bool,
    command: Sequence[str] | None,
    stop_after_chunks: int | None,
    outputs: Sequence[SweepOutput],
    stall_s: float,
) -> SweepResult:
    """`run_sweep` once this process may write ``out_dir``."""
    code_state = provenance.git_state()  # before this run changes any tracked result file
    robot, points = build_designs(spec)
    devices = jax.device_count()
    plan = _Plan(spec, devices, _chunk(spec, devices), *designs_per_step(spec, devices))
    partial = _partial_folder(plan, out_dir)
    spans = _chunks(spec.n_designs, plan.chunk)
    columns = metric_columns(spec.metrics)
    pieces = _saved_pieces(partial, spans, columns)
    todo = [n for n in range(len(spans)) if n not in pieces]
    run_start = time.perf_counter()
    compile_s = _compute_chunks(plan, robot, spans, todo, pieces, partial, progress, stop_after_chunks, stall_s)
    run_s = time.perf_counter() - run_start - compile_s
    if jax.process_index() != 0:  # multi-host: the first process writes the results
        return SweepResult(out_dir, {}, {}, [])
    metric_values = {c: np.concatenate([pieces[n][c] for n in range(len(spans))]) for c in columns}
    check_finite(spec, metric_values, points)
    table: dict[str, np.ndarray] = {"design": np.arange(spec.n_designs)}
    table.update(points)
    table.update(design_columns(robot, spec.axes))
    table.update(metric_values)
    timings = {"compile": compile_s, "run": run_s}
    run = dict(command=command, git=code_state, wall_start=wall_start, resumed=len(spans) - len(todo))
    data, files = _write_sweep(plan, out_dir, partial, table, outputs, timings, run)
    shutil.rmtree(partial, ignore_errors=True)
    _note_other_partials(out_dir)
    return SweepResult(out_dir, table, data, files)


@dataclasses.dataclass(frozen=True)
class _Plan:
    """How one sweep runs here: designs per compiled chunk, per vmapped step on each
    device (`designs_per_step`), and one design's working set in bytes."""

    spec: SweepSpec
    devices: int
    chunk: int
    per_step: int
    design_bytes: float


def _partial_folder(plan: _Plan, out_dir: Path) -> Path:
    """Where finished chunks are kept. Saved chunks are reused only by a run that would
    compute them bit for bit alike: same resolved config, effective chunk size, precision
    and package versions."""
    resume_key = {
        "config": plan.spec.config,
        "axis_order": [a.name for a in plan.spec.axes],
        "chunk": plan.chunk,
        "designs_per_step": plan.per_step,
        "float64": bool(jax.config.jax_enable_x64),
        "spacearm": __version__,
        "jax": jax.__version__,
    }
    return out_dir / f".partial-{config_hash(resume_key)[:16]}"


def _saved_pieces(partial: Path, spans: list[tuple[int, int]], columns: Sequence[str]) -> dict:
    """The chunks an earlier run finished, by number: their metric columns (a damaged file
    is removed and computed again). Many processes: process 0's saved chunks decide (only
    it writes them, and the others may not share its disk); every process must run the
    same chunks, so the others hold None for each."""
    pieces: dict[int, dict[str, np.ndarray] | None] = {}
    for number, (start, stop) in enumerate(spans):
        saved = partial / f"chunk_{number:06d}.npz"
        if saved.exists():
            try:
                with np.load(saved) as data:
                    piece = {c: data[c] for c in columns}
            except Exception:  # damaged (e.g. the disk filled up): compute it again
                saved.unlink()
                continue
            if all(v.shape == (stop - start,) for v in piece.values()):
                pieces[number] = piece
    if jax.process_count() > 1:
        saved_mask = np.array([n in pieces for n in range(len(spans))])
        saved_mask = np.asarray(multihost_utils.broadcast_one_to_all(saved_mask)).astype(bool)
        if jax.process_index() != 0:
            pieces = {n: None for n in np.flatnonzero(saved_mask)}
    return pieces


def _compute_chunks(
    plan: _Plan, robot, spans, todo: list[int], pieces: dict, partial: Path, progress: bool, stop_after, stall_s
) -> float:
    """Evaluate the chunks numbered ``todo`` into ``pieces`` (process 0 saves each under
    ``partial``) with a progress bar; returns the compile seconds.

    Each device walks its share of a chunk in vmapped steps of a few designs: the
    quadratures' intermediates then stay in cache; the step's size comes from the
    metrics' memory estimate.
    """
    spec, total = plan.spec, plan.spec.n_designs
    mesh = _mesh()
    sharding = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("designs"))
    evaluate = _evaluator(json.dumps([[m.name, m.options] for m in spec.metrics], sort_keys=True), plan.per_step, mesh)
    columns = metric_columns(spec.metrics)
    compile_s, compiled = 0.0, None
    bar = tqdm(
        total=total,
        desc=f"sweep {spec.name}",
        unit="design",
        disable=not progress,
        file=sys.stderr,
        initial=sum(stop - start for n, (start, stop) in enumerate(spans) if n in pieces),
    )
    try:
        for done, number in enumerate(todo):
            if stop_after is not None and done >= stop_after:
                raise KeyboardInterrupt
            start, stop = spans[number]
            batch = _shard(_take(robot, start, stop, plan.chunk, plan.devices), sharding)
            if compiled is None:
                t0 = time.perf_counter()
                compiled = evaluate.lower(batch).compile()
                compile_s = time.perf_counter() - t0
            values = compiled(batch)
            wait_until_ready(values, f"sweep {spec.name}: chunk {done + 1} of {len(todo)}", stall_s=stall_s)
            piece = {c: _gather(values[c])[: stop - start] for c in columns}
            if jax.process_index() == 0:
                write_npz(partial / f"chunk_{number:06d}.npz", **piece)
            pieces[number] = piece
            bar.update(stop - start)
    except Exception as error:
        failure = _chunk_failure(error, _kept_line(spans, pieces, total, partial))
        if failure is error:
            raise
        raise failure from None
    except KeyboardInterrupt:
        bar.close()
        print(_kept_line(spans, pieces, total, partial), file=sys.stderr)
        raise
    finally:
        bar.close()
    return compile_s


def _chunk_failure(error: Exception, kept: str) -> Exception:
    """What a failed chunk raises: a stall names the chunks kept; under ``jax.distributed``
    a peer that died surfaces as a collective's error, said as such."""
    if isinstance(error, Stalled):
        return Stalled(f"{error}; {kept}")
    if jax.process_count() == 1 or isinstance(error, (ConfigError, RunError, OSError)):
        return error
    reason = (str(error).strip().splitlines() or [type(error).__name__])[0][:200]
    return RunError(
        f"process {jax.process_index()} of {jax.process_count()}: a peer process stopped or failed "
        f"during the sweep ({reason}); finished chunks are kept: start every process again "
        "to resume"
    )


def _write_sweep(
    plan: _Plan, out_dir: Path, partial: Path, table: dict, outputs: Sequence[SweepOutput], timings: dict, run: dict
) -> tuple[dict, list[Path]]:
    """Write the table, the grids, the report, the outputs and the manifest into a folder
    that replaces ``out_dir`` as a whole; returns the manifest and the files written.
    ``run``: the ``command``, ``git`` state, ``wall_start`` and ``resumed`` chunks."""
    spec = plan.spec
    previous = _previous_files(out_dir)
    keep = lambda name: name not in previous and name != partial.name
    with replacing_folder(out_dir, keep=keep, before_swap=_BEFORE_SWAP) as staging:
        files = [write_csv(staging / "table.csv", table)]
        files.append(write_npz(staging / "grids.npz", **_grid_arrays(spec, table)))
        if spec.report:
            rows = [{k: float(v[i]) for k, v in table.items()} for i in range(spec.n_designs)]
            files.extend(REPORTS[spec.report](staging, rows, spec))
        for output in outputs:
            files.extend(output(spec, staging, table))
        timings = {**timings, "wall": time.perf_counter() - run["wall_start"]}
        data = build_manifest(
            spec.config,
            command=run["command"],
            timings=timings,
            git=run["git"],
            extra=_manifest_extra(plan, run, files, staging),
        )
        files.append(write_json(staging / "manifest.json", data))
    return data, [out_dir / p.relative_to(staging) for p in files]


def _grid_arrays(spec: SweepSpec, table: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """``grids.npz``: each axis's values, each metric column on the sweep's grid, and the dims."""
    arrays = {f"axis/{a.name}": a.values for a in spec.axes}
    arrays.update({f"metric/{c}": table[c].reshape(spec.shape) for c in metric_columns(spec.metrics)})
    arrays["dims"] = np.array([a.name for a in spec.axes] if spec.combine == "product" else ["design"])
    return arrays


def _manifest_extra(plan: _Plan, run: dict, files: list[Path], staging: Path) -> dict:
    """The sweep's own fields of its manifest."""
    return {
        "kind": "sweep",
        "robot_file": plan.spec.robot_source,
        "n_designs": plan.spec.n_designs,
        "chunk_size": plan.chunk,
        "designs_per_step": plan.per_step,  # side by side on each device, from the memory estimate
        "memory_estimate_bytes": round(memory_estimate(plan.spec, plan.devices)[0]),
        "design_working_set_bytes": round(plan.design_bytes),
        "resumed_chunks": run["resumed"],
        "files": sorted(str(p.relative_to(staging)) for p in files),
    }


def _note_other_partials(out_dir: Path) -> None:
    """Point out the chunks of other sweeps kept in ``out_dir``."""
    others = sorted(p.name for p in out_dir.glob(".partial-*") if p.is_dir())
    if others:
        print(
            f"note: {out_dir} also holds {', '.join(others)} (chunks of another sweep run into this folder; "
            "delete them if no run needs them)",
            file=sys.stderr,
        )


# Columns where +inf is a documented value, not a failure ("none found").
INFINITE_MEANS_NONE = frozenset({"R_path_independent_m"})

# A hook for tests: called with the staging folder just before it is swapped in.
_BEFORE_SWAP: Callable[[Path], None] | None = None


def check_finite(spec: SweepSpec, metric_values: Mapping[str, np.ndarray], points: Mapping[str, np.ndarray]) -> None:
    """Refuse a result that came out non-finite (NaN or inf): `NonFiniteResult` naming the
    metric column and the first such design, instead of a silent NaN column."""
    for column, values in metric_values.items():
        values = np.asarray(values, dtype=float)
        bad = np.isnan(values) if column in INFINITE_MEANS_NONE else ~np.isfinite(values)
        bad = np.flatnonzero(bad | (np.isneginf(values) if column in INFINITE_MEANS_NONE else False))
        if bad.size:
            first = int(bad[0])
            where = ", ".join(f"{name} = {float(np.asarray(v)[first]):g}" for name, v in points.items())
            raise NonFiniteResult(
                f"{spec.source}: metric column '{column}' is {float(values[first])} for design {first} ({where})"
                f" and {bad.size - 1} more of {len(values)}; nothing was written (check the design's numbers"
                + (", or drop --float32" if not jax.config.jax_enable_x64 else "")
                + ")"
            )


class NonFiniteResult(RunError):
    """A sweep's metric came out NaN or infinite (exit status 1 on the command line)."""


def _flatten(value, prefix: str = "") -> dict[str, str]:
    """Dotted paths of a nested config -> the JSON of each leaf (for naming differing keys)."""
    if isinstance(value, Mapping) and value:
        out: dict[str, str] = {}
        for key, item in value.items():
            out.update(_flatten(item, f"{prefix}.{key}" if prefix else str(key)))
        return out
    return {prefix or "(root)": json.dumps(value, sort_keys=True, default=str)}


def _fingerprint(spec: SweepSpec) -> dict:
    """What must be the same on every process of a distributed sweep: the resolved config
    and the code (versions, git revision, precision)."""
    return {
        "config": spec.config,
        "code": {
            "spacearm": __version__,
            "git_revision": provenance.git_state().get("revision"),
            "jax": jax.__version__,
            "float64": bool(jax.config.jax_enable_x64),
        },
    }


def differing_keys(mine: Mapping, theirs: Mapping) -> list[str]:
    """The dotted keys whose values differ between two fingerprints (or exist in one only)."""
    a, b = _flatten(mine), _flatten(theirs)
    return sorted(key for key in set(a) | set(b) if a.get(key) != b.get(key))


def _shown(keys: Sequence[str]) -> str:
    return ", ".join(keys[:6]) + (f" and {len(keys) - 6} more" if len(keys) > 6 else "")


def agree_with_peers(spec: SweepSpec, *, timeout_s: float = PEER_TIMEOUT_S, refusal: str | None = None) -> None:
    """Refuse to compute unless every process of a distributed sweep has the same resolved
    config and code as process 0.

    Each process publishes its fingerprint in the coordination service's key-value store;
    process 0 compares every peer's with its own and publishes one verdict, which every
    process waits for (at most ``timeout_s``). A mismatch ends every process with a
    `ConfigError` naming the differing keys, before anything is computed or written.
    ``refusal``: process 0's own reason not to run (another run holds the folder's lock),
    passed on in the verdict.
    """
    client = jax_distributed.global_state.client
    if client is None:
        return
    rank, count = jax.process_index(), jax.process_count()
    wait_ms = int(max(1.0, timeout_s) * 1000)
    mine = _fingerprint(spec)
    client.key_value_set(f"spacearm/fingerprint/{rank}", json.dumps(mine, default=str))

    def get(key: str, whom: str) -> str:
        try:
            return client.blocking_key_value_get(key, wait_ms)
        except Exception:  # jaxlib's DEADLINE_EXCEEDED
            raise RunError(
                f"process {rank} of {count}: {whom} did not answer within {timeout_s:g} s "
                "(is it running the same command? wait longer with --peer-timeout)"
            ) from None

    if rank == 0:
        problems = []
        for peer in range(1, count):
            keys = differing_keys(mine, json.loads(get(f"spacearm/fingerprint/{peer}", f"process {peer}")))
            if keys:
                problems.append(f"process {peer} differs from process 0 in {_shown(keys)}")
        verdict = "; ".join(([refusal] if refusal else []) + problems) or "ok"
        client.key_value_set("spacearm/verdict", verdict)
    else:
        theirs = json.loads(get("spacearm/fingerprint/0", "process 0"))
        keys = differing_keys(mine, theirs)
        verdict = get("spacearm/verdict", "process 0")
        if keys:
            verdict = f"this process differs from process 0 in {_shown(keys)}"
    if verdict != "ok":
        # Every process got here: leave the job together (the shutdown barrier), so no
        # process sees its peers vanish and no coordination-service abort follows.
        with contextlib.suppress(Exception):
            jax.distributed.shutdown()
        raise ConfigError(
            f"process {rank} of {count}: refusing to run: {verdict} (every process must run the same "
            "sweep file, --set options and spacearm version)"
        )


def _chunk(spec: SweepSpec, devices: int) -> int:
    """Designs per compiled chunk: ``chunk_size`` (at most the sweep), a multiple of the devices."""
    return max(devices, int(math.ceil(min(spec.chunk_size, spec.n_designs) / devices)) * devices)


def _largest_working_set(spec: SweepSpec) -> tuple[float, str]:
    """The largest per-design working set of the sweep's metrics, in float64 numbers
    (`spacearm._core.memory.working_numbers`), and the advice that makes it smaller."""
    n = np.shape(spec.robot.joint_lower)[-1]
    worst, advice = 0.0, ""
    for metric in spec.metrics:
        numbers, option = working_numbers(metric.name, metric.options, n, joint_average=metric.name in _JOINT_AVERAGES)
        if numbers > worst:
            worst, advice = numbers, f"lower metric '{metric.name}' option {option}" if option else ""
    return worst, advice


def designs_per_step(spec: SweepSpec, devices: int | None = None) -> tuple[int, float]:
    """How many designs each device evaluates side by side, and one design's working set
    in bytes (the largest of its metrics', `spacearm._core.memory.working_numbers`).

    At most `DESIGNS_PER_STEP` (and each metric's own cap) and the designs a device holds
    in a chunk, and few enough that all devices together stay within `STEP_MEMORY_BYTES`:
    a robot with many joints or a metric with large sample blocks runs fewer at once.
    """
    devices = devices or jax.device_count()
    design_bytes = 8.0 * _largest_working_set(spec)[0] * TEMPORARIES
    caps = [METRICS[m.name].designs_per_step for m in spec.metrics if METRICS[m.name].designs_per_step]
    fits = int(STEP_MEMORY_BYTES // (devices * design_bytes)) if design_bytes else DESIGNS_PER_STEP
    return max(1, min([DESIGNS_PER_STEP, _chunk(spec, devices) // devices, fits, *caps])), design_bytes


def memory_estimate(spec: SweepSpec, devices: int | None = None) -> tuple[float, str]:
    """Bytes a sweep holds at once (designs, results, every metric's working set of the
    designs computed side by side, `designs_per_step`) and the advice that makes it smaller."""
    devices = devices or jax.device_count()
    per_step, design_bytes = designs_per_step(spec, devices)
    advice = _largest_working_set(spec)[1]
    columns = len(metric_columns(spec.metrics))
    need = devices * per_step * design_bytes + 8.0 * 2 * spec.n_designs * (columns + len(spec.axes))
    return need, advice or "split the sweep into several files"


def check_sweep_memory(spec: SweepSpec) -> None:
    """Refuse a sweep whose estimated working memory (`memory_estimate`) is over half of this
    machine's memory, with the estimate and the fix; `ConfigError` (exit status 2)."""
    need, advice = memory_estimate(spec)
    check_memory(
        f"{spec.source}: metrics",
        need,
        f"the sweep's metrics ({', '.join(m.name for m in spec.metrics)}) on {spec.n_designs:,} designs",
        advice,
    )


# The joint-box averages: the metrics with a standard-error column.
_JOINT_AVERAGES = frozenset(
    name for name, metric in METRICS.items() if any(column.endswith("_error") for column in metric.columns({}))
)


# The names a sweep writes (see run_sweep, the reports and spacearm.figures.sweep): only these
# are ever removed.
_OWN_FILES = re.compile(r"(table\.csv|grids\.npz|metrics\.png|table\.md|fig10\.png|heatmap_[A-Za-z0-9_.]+\.png)")


def _previous_files(out_dir: Path) -> set[str]:
    """Files an earlier sweep wrote into ``out_dir``, read from its manifest when that is a
    spacearm sweep manifest; limited to the names a sweep writes."""
    try:
        manifest = json.loads((out_dir / "manifest.json").read_text())
        listed = manifest["files"] if "spacearm" in manifest["packages"] and "config_sha256" in manifest else []
    except (OSError, ValueError, KeyError, TypeError):
        return set()
    return {name for name in listed if isinstance(name, str) and _OWN_FILES.fullmatch(name)}


def _kept_line(spans, pieces, total: int, partial: Path) -> str:
    kept = sum(stop - start for n, (start, stop) in enumerate(spans) if n in pieces)
    return f"{kept:,} of {total:,} designs kept in {partial}; run the same command again to resume"


def _check_output_dir(out_dir: Path) -> None:
    """ConfigError unless ``out_dir`` is, or can become, a writable folder of its own (nothing is created)."""
    check_output_folder(out_dir)
