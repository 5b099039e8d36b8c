"""Build-time hooks of the documentation site (``hooks:`` in mkdocs.yml).

* Formulas: ``pymdownx.arithmatex`` (generic mode) marks ``$...$`` and ``$$...$$`` in the
  pages; :func:`on_page_content` turns each into MathML with ``latex2mathml``, so the
  built pages need no script, no font download and no network to show their math
  (every current browser renders MathML Core). A formula latex2mathml cannot read fails
  the build, naming the page and the formula.
* The API reference's ``SUMMARY.md`` feeds mkdocs-literate-nav its navigation and is
  then dropped, so it is not built as a page of its own.
"""

from __future__ import annotations

import html
import re

from latex2mathml.converter import convert
from mkdocs.exceptions import PluginError
from mkdocs.plugins import event_priority

NAV_FILE = "reference/api/SUMMARY.md"

# arithmatex's generic output: \( .. \) in a span, \[ .. \] in a div.
_INLINE = re.compile(r'<span class="arithmatex">\\\((.*?)\\\)</span>', re.S)
_BLOCK = re.compile(r'<div class="arithmatex">\\\[(.*?)\\\]</div>', re.S)


def to_mathml(tex: str, display: str, where: str) -> str:
    """One TeX formula (HTML-escaped, as arithmatex leaves it) as a MathML element."""
    source = html.unescape(tex).strip()
    try:
        return convert(source, display=display)
    except Exception as error:  # latex2mathml raises many types; any of them is a bad formula
        raise PluginError(f"{where}: cannot render the formula {source!r}: {error}") from None


def render_math(text: str, where: str = "page") -> str:
    """Replace arithmatex's marked formulas in an HTML page by MathML."""
    text = _BLOCK.sub(lambda m: f'<div class="math-block">{to_mathml(m.group(1), "block", where)}</div>', text)
    return _INLINE.sub(lambda m: to_mathml(m.group(1), "inline", where), text)


@event_priority(-200)  # after mkdocs-literate-nav (-100) has read the nav file
def on_files(files, config):
    nav_file = files.get_file_from_path(NAV_FILE)
    if nav_file is not None:
        files.remove(nav_file)
    return files


def on_page_content(html_text, page, config, files):
    return render_math(html_text, page.file.src_uri)
