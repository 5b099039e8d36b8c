"""Results on disk: atomic writes, tables, grids and the run manifest."""

from .files import (
    atomic_path as atomic_path,
    json_default as json_default,
    read_csv as read_csv,
    save_figure as save_figure,
    write_csv as write_csv,
    write_json as write_json,
    write_npz as write_npz,
    write_text as write_text,
)
from .grids import open_results as open_results
from .manifest import (
    build_manifest as build_manifest,
    config_hash as config_hash,
    device_info as device_info,
    git_state as git_state,
    package_versions as package_versions,
)
