"""Results on disk: atomic writes, tables, grids and the run manifest."""

from .files import (
    atomic_path as atomic_path,
)
from .files import (
    json_default as json_default,
)
from .files import (
    read_csv as read_csv,
)
from .files import (
    save_figure as save_figure,
)
from .files import (
    write_csv as write_csv,
)
from .files import (
    write_json as write_json,
)
from .files import (
    write_npz as write_npz,
)
from .files import (
    write_text as write_text,
)
from .grids import open_results as open_results
from .manifest import (
    build_manifest as build_manifest,
)
from .manifest import (
    config_hash as config_hash,
)
from .manifest import (
    device_info as device_info,
)
from .manifest import (
    git_state as git_state,
)
from .manifest import (
    package_versions as package_versions,
)
