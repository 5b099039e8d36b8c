"""The run manifest: everything needed to rerun a result (config and its hash, versions,
git state, float64 flag, devices, timings, and a hash of every input file).

Provenance of inputs: every file named on the command line (a sweep file, a design
problem, a robot file), the robot file a sweep or problem names, and the URDF a spatial
robot reads, each with its SHA-256; a URDF taken from an installed package also records
the package and its version. The git state is that of spacearm's own checkout, with the
result folders (``results/``, ``build/``) left out: rerunning a committed result rewrites
its files, and that must not mark the code as modified in the next manifest.
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import subprocess
import time
from collections.abc import Mapping, Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

import jax
import yaml

from .._version import __version__
from .files import json_default

__all__ = [
    "build_manifest",
    "config_hash",
    "device_info",
    "file_sha256",
    "git_state",
    "input_files",
    "package_versions",
]

# Folders of a checkout that hold results, not code or inputs: their changes do not make the
# code "dirty" (a rerun of a committed result rewrites them).
RESULT_FOLDERS = ("results", "build")

_PACKAGES = ("spacearm", "jax", "jaxlib", "numpy", "optax", "matplotlib", "pyyaml", "scipy")


def config_hash(config: Any) -> str:
    """SHA-256 of the compact JSON of a resolved config (built in a fixed key order by the loaders)."""
    # Key order is kept: in a sweep the order of the axes decides which design is which row.
    text = json.dumps(config, separators=(",", ":"), default=json_default)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def package_versions() -> dict[str, str | None]:
    """Installed versions of spacearm and the packages a result depends on (None if absent)."""
    versions: dict[str, str | None] = {}
    for name in _PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return versions


def git_state(start: str | os.PathLike | None = None) -> dict[str, Any]:
    """The git revision of the checkout holding ``start`` (spacearm's own by default), and
    whether its tracked files outside the result folders differ from it (None outside git).

    ``dirty_files`` names up to 20 of them; ``excluded`` the folders left out (`RESULT_FOLDERS`).
    """
    where = Path(start) if start else Path(__file__).resolve().parent
    excluded = [f":(top,exclude){folder}" for folder in RESULT_FOLDERS]
    try:
        revision = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=where, capture_output=True, text=True, timeout=10, check=True
        ).stdout.strip()
        status = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no", "--", ":(top)", *excluded],
            cwd=where,
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        ).stdout
        changed = [line[3:] for line in status.splitlines() if line.strip()]
        return {
            "revision": revision,
            "dirty": bool(changed),
            "dirty_files": changed[:20],
            "excluded": list(RESULT_FOLDERS),
        }
    except (OSError, subprocess.SubprocessError):
        return {"revision": None, "dirty": None}


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _package_file(package: str, path: str) -> tuple[Path, str | None] | None:
    """A file inside an installed distribution (as robot files name URDFs) and its version."""
    try:
        distribution = metadata.distribution(package)
    except metadata.PackageNotFoundError:
        return None
    for record in distribution.files or ():
        if str(record).replace("\\", "/").endswith("/" + path.lstrip("/")) or str(record) == path:
            return Path(distribution.locate_file(record)), distribution.version
    return None


def _read_mapping(path: Path) -> Mapping | None:
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return None
    return data if isinstance(data, Mapping) else None


def input_files(command: Sequence[str] | None, config: Any = None) -> list[dict[str, Any]]:
    """Every input file of a run with its SHA-256: the files named on the command line, the
    robot file a sweep or design problem names, the URDF a spatial robot reads (with the
    package and version it came from, when it came from one). Meshes are not read by
    spacearm and are not listed. A file that cannot be read is listed with ``sha256: None``.
    """
    found: dict[str, dict[str, Any]] = {}

    def add(path: Path, role: str, **more: Any) -> None:
        key = os.fspath(path.resolve())
        if key in found:
            return
        try:
            digest = file_sha256(path)
        except OSError:
            digest = None
        found[key] = {"role": role, "path": os.path.normpath(path), "sha256": digest, **more}

    def add_urdf(entry: Any, base: Path) -> None:
        if isinstance(entry, Mapping) and isinstance(entry.get("package"), str) and isinstance(entry.get("path"), str):
            located = _package_file(entry["package"], entry["path"])
            if located is not None:
                add(
                    located[0], "urdf", package=entry["package"], package_version=located[1], package_path=entry["path"]
                )
        elif isinstance(entry, str):
            candidate = Path(entry) if Path(entry).is_absolute() else base / entry
            if candidate.is_file():
                add(candidate, "urdf")

    def add_robot_mapping(robot: Mapping, base: Path) -> None:
        arm = robot.get("arm")
        if isinstance(arm, Mapping):
            add_urdf(arm.get("urdf"), base)

    for argument in list(command or [])[1:]:
        path = Path(argument)
        if path.suffix.lower() not in (".yaml", ".yml", ".urdf") or not path.is_file():
            continue
        add(path, "command line")
        data = _read_mapping(path) if path.suffix.lower() != ".urdf" else None
        if data is None:
            continue
        add_robot_mapping(data, path.parent)
        robot = data.get("robot")
        if isinstance(robot, str):
            robot_path = Path(robot) if Path(robot).is_absolute() else path.parent / robot
            if robot_path.is_file():
                add(robot_path, "robot file")
                robot_data = _read_mapping(robot_path)
                if robot_data is not None:
                    add_robot_mapping(robot_data, robot_path.parent)
        elif isinstance(robot, Mapping):
            add_robot_mapping(robot, path.parent)
    # The resolved config: a URDF given as a package file or a path from here.
    robot = config.get("robot") if isinstance(config, Mapping) else None
    if isinstance(robot, Mapping):
        add_robot_mapping(robot, Path.cwd())
    return list(found.values())


def device_info() -> dict[str, Any]:
    """The JAX backend, device and process counts, and the devices."""
    return {
        "backend": jax.default_backend(),
        "device_count": jax.device_count(),
        "process_count": jax.process_count(),
        "devices": [str(device) for device in jax.devices()],
    }


def build_manifest(
    config: Any,
    *,
    command: Sequence[str] | None = None,
    timings: Mapping[str, float] | None = None,
    extra: Mapping[str, Any] | None = None,
    git: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Everything needed to rerun a result: the resolved config and its hash, versions,
    git state, float64 flag, devices and timings.

    ``git``: the state taken before the run wrote anything (default: now). Regenerating
    results that are committed changes tracked files, which must not mark the code dirty.
    """
    data = {
        "config": config,
        "config_sha256": config_hash(config),
        "command": list(command) if command is not None else None,
        "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "packages": package_versions(),
        "spacearm_version": __version__,  # the imported code's own version (packages: the installed one)
        "git": dict(git) if git is not None else git_state(),
        "inputs": input_files(command, config),
        "float64": bool(jax.config.jax_enable_x64),
        **device_info(),
        "timings_s": dict(timings or {}),
    }
    if extra:
        data.update(extra)
    return data
