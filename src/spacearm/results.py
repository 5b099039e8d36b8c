"""Deprecated path (one release): use :mod:`spacearm.io`."""

from .io import (
    atomic_path as atomic_path,
    build_manifest as manifest,
    config_hash as config_hash,
    device_info as device_info,
    git_state as git_state,
    package_versions as package_versions,
    read_csv as read_csv,
    save_figure as save_figure,
    write_csv as write_csv,
    write_json as write_json,
    write_npz as write_npz,
    write_text as write_text,
)

__all__ = [
    "atomic_path", "manifest", "config_hash", "device_info", "git_state", "package_versions", "read_csv",
    "save_figure", "write_csv", "write_json", "write_npz", "write_text",
]
