"""One self-contained HTML page: plotly.js, the forward kinematics, the data and the page script inlined.

Every page opens from disk in any browser with no server and no network: nothing is
fetched (tests/test_views.py loads each page in headless Chromium with every host name
unresolvable and counts the network requests it made: none). plotly.js (Plotly, MIT) comes
from the ``plotly`` Python package, the optional ``view`` extra; without it every writer
raises `MissingViewExtra` naming the extra.
"""

from __future__ import annotations

import html
import importlib
import importlib.util
import json
import math
from pathlib import Path

import numpy as np

from ..._core.errors import ConfigError
from ...io import write_text
from .model import FK_SCRIPT

__all__ = ["VIEW_EXTRA_MESSAGE", "MissingViewExtra", "plotly_bundle", "view_extra_available", "write_page"]

VIEW_EXTRA_MESSAGE = (
    "interactive HTML views need Plotly, the optional 'view' extra: "
    "pip install -e \".[view]\" (or pip install 'spacearm[view]', or pip install plotly)"
)

APP_SCRIPT = Path(__file__).with_name("app.js")

_STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; margin: 0; display: flex; height: 100vh; }
#plot { flex: 1; min-width: 0; }
#panel { width: 320px; padding: 10px 14px; overflow-y: auto; border-left: 1px solid #ddd; font-size: 13px; }
#panel h1 { font-size: 16px; margin: 4px 0 6px; }
#panel p { color: #444; margin: 4px 0 10px; }
.control { margin: 6px 0; }
.control label { display: flex; justify-content: space-between; }
.control input[type=range] { width: 100%; }
#readout { font-family: ui-monospace, monospace; white-space: pre-wrap; background: #f6f6f6; padding: 6px; margin-top: 10px; }
button { margin: 4px 4px 4px 0; }
"""


class MissingViewExtra(ConfigError):
    """Plotly (the ``view`` extra) is not installed; the message says how to install it."""


def view_extra_available() -> bool:
    """Whether plotly (the ``view`` extra) is importable."""
    try:
        return importlib.util.find_spec("plotly") is not None
    except (ImportError, ValueError):
        return False


def plotly_bundle() -> str:
    """The plotly.js bundle (about 4.8 MB) from the installed ``plotly`` package."""
    try:
        offline = importlib.import_module("plotly.offline")
    except ImportError:
        raise MissingViewExtra(VIEW_EXTRA_MESSAGE) from None
    return offline.get_plotlyjs()


def _json(value) -> str:
    """JSON for a ``<script>`` block: finite numbers, NaN/inf as null, and ``<``, ``>`` and
    ``&`` as ``\\u`` escapes, so no name can close the block or open an HTML comment
    (``</script>``, ``<!--<script>``) in it."""

    def clean(x):
        if isinstance(x, dict):
            return {str(k): clean(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [clean(v) for v in x]
        if isinstance(x, np.ndarray):
            return clean(x.tolist())
        if isinstance(x, (np.floating, float)):
            return float(x) if math.isfinite(x) else None
        if isinstance(x, np.integer):
            return int(x)
        return x

    text = json.dumps(clean(value), separators=(",", ":"), allow_nan=False)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def write_page(path: str | Path, *, title: str, note: str, data: dict) -> Path:
    """Write one page: ``data`` (``mode``: ``"arm"``, ``"replay"`` or ``"front"``, and what
    that mode reads; see app.js beside this file) becomes ``window.SPACEARM``.

    Raises:
        MissingViewExtra: plotly is not installed (nothing is written).
    """
    bundle = plotly_bundle()
    page = "\n".join(
        [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>{html.escape(title)}</title>",
            f"<style>{_STYLE}</style></head><body>",
            '<div id="plot"></div>',
            f'<div id="panel"><h1>{html.escape(title)}</h1><p>{html.escape(note)}</p>'
            '<div id="controls"></div><div id="readout"></div></div>',
            # Any script error is kept on the page (data-error), where a test or a reader can see it.
            "<script>window.addEventListener('error', function (e) { document.body.dataset.error = e.message; });</script>",
            f"<script>{bundle}</script>",
            f"<script>{FK_SCRIPT.read_text()}</script>",
            f"<script>window.SPACEARM = {_json(data)};</script>",
            f"<script>{APP_SCRIPT.read_text()}</script>",
            "</body></html>",
        ]
    )
    return write_text(path, page)
