"""The documentation site: it builds strictly, every link and image resolves, every formula renders.

The site is built once per session (``mkdocs build --strict``, the command CI runs); the
checks then read the built HTML. Building takes ~15 s on a loaded 2-core machine (~10 s of
CPU: the API reference renders every docstring), hence ``slow``. The build is kept in the
suite's cache folder (``$SPACEARM_CACHE_DIR``, tests/conftest.py) under a digest of
everything it reads: the files git lists in mkdocs.yml, docs/, src/ and results/, and the
versions of Python and of every installed distribution. A later run with the same digest
reads that build; any edit to a page, a docstring, the command line or a result builds
again (``--fresh-cache`` always builds); the folder keeps the three newest builds and any
read within the hour. CI builds the site just before the tests and
names the folder in ``$SPACEARM_TEST_SITE``: the checks read that build instead.
The text checks (no citation of notes that are not shipped) and the formula hook's own
checks are fast.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import io
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from html.parser import HTMLParser
from importlib import metadata
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

ROOT = Path(__file__).resolve().parents[1]

# Notes that live outside the repository: a page or docstring citing them leaves the
# reader with a dead reference.
UNSHIPPED = re.compile(r"DESIGN\.md|SPATIAL\.md|STYLE\.md|\bissue #?\d+|the issue's")


def _load_hooks():
    pytest.importorskip("latex2mathml")
    pytest.importorskip("mkdocs")
    spec = importlib.util.spec_from_file_location("docs_hooks", ROOT / "docs" / "scripts" / "hooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class _Page(HTMLParser):
    """Links, image sources, element ids and the text outside code of one HTML page."""

    def __init__(self):
        super().__init__()
        self.links: list[str] = []
        self.images: list[str] = []
        self.ids: set[str] = set()
        self.text: list[str] = []
        self.maths = 0
        self._code = 0

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if "id" in attrs:
            self.ids.add(attrs["id"])
        if tag == "a" and attrs.get("href"):
            self.links.append(attrs["href"])
        if tag == "img" and attrs.get("src"):
            self.images.append(attrs["src"])
        if tag in ("code", "pre", "script", "style"):
            self._code += 1
        if tag == "math":
            self.maths += 1

    def handle_endtag(self, tag):
        if tag in ("code", "pre", "script", "style"):
            self._code -= 1

    def handle_data(self, data):
        if self._code == 0:
            self.text.append(data)


_SITE_INPUTS = ("mkdocs.yml", "docs", "src", "results")  # what the build reads (mkdocs.yml, docs/scripts)


def _build_site(out: Path) -> None:
    env = dict(os.environ, DISABLE_MKDOCS_2_WARNING="true", NO_MKDOCS_2_WARNING="1")
    run = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr[-4000:]


def _site_inputs_digest() -> str | None:
    """SHA-256 of what the build reads (module docstring); None where git cannot list the files."""
    try:
        listed = subprocess.run(
            ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard", "--", *_SITE_INPUTS],
            cwd=ROOT,
            capture_output=True,
            check=True,
            timeout=60,
        ).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    names = sorted(set(filter(None, listed.split(b"\0"))))
    if b"mkdocs.yml" not in names:  # not this checkout's files (a copy inside another repository)
        return None
    digest = hashlib.sha256()
    for name in names:
        path = ROOT / os.fsdecode(name)
        if not path.is_file():  # listed by git, deleted in the working tree
            continue
        content = path.read_bytes()
        digest.update(b"%d:%s%d:" % (len(name), name, len(content)) + content)
    versions = sorted(f"{d.metadata['Name']}=={d.version}" for d in metadata.distributions() if d.metadata["Name"])
    digest.update("\n".join([sys.version, *versions]).encode())
    return digest.hexdigest()


def _kept_site(tmp_path_factory) -> Path:
    """The site for the current sources: read from the suite's cache folder when built there
    from the same inputs, else built there (into a scratch folder, renamed into place whole).
    Without a cache folder or a digest: built into a scratch folder."""
    cache, key = os.environ.get("SPACEARM_CACHE_DIR", ""), _site_inputs_digest()
    if not cache or key is None:
        out = tmp_path_factory.mktemp("site")
        _build_site(out)
        return out
    kept = Path(cache) / "docs-site"
    out = kept / key
    if (out / "index.html").is_file():
        os.utime(out)  # used now: the clean-up below keeps it
        return out
    kept.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix="building-", dir=kept))
    try:
        _build_site(scratch)
    except BaseException:
        shutil.rmtree(scratch, ignore_errors=True)
        raise
    if out.exists() and not (out / "index.html").is_file():  # a build half removed
        shutil.rmtree(out, ignore_errors=True)
    try:
        scratch.rename(out)
    except OSError:  # another run put the same build in place first, or the old one stayed
        if not (out / "index.html").is_file():
            return scratch  # this run's own build (a scratch folder: removed an hour from now)
        shutil.rmtree(scratch, ignore_errors=True)
    _remove_old_builds(kept, out)
    return out


_KEPT_BUILDS = 3  # the newest builds stay (checkouts and branches side by side), and any used within the hour


def _remove_old_builds(kept: Path, current: Path) -> None:
    """Builds past the newest few that no run used within the hour, and scratch folders of runs
    that died more than an hour ago: another run may still be reading the others."""
    now, entries = time.time(), []
    for entry in kept.iterdir():
        try:
            entries.append((entry.stat().st_mtime, entry))
        except OSError:  # renamed or removed by another run meanwhile
            continue
    builds = sorted((e for e in entries if not e[1].name.startswith("building-")), reverse=True)
    old = [path for mtime, path in builds[_KEPT_BUILDS:] if now - mtime > 3600]
    old += [path for mtime, path in entries if path.name.startswith("building-") and now - mtime > 3600]
    for path in old:
        if path != current:
            shutil.rmtree(path, ignore_errors=True)


@pytest.fixture(scope="session")
def site(tmp_path_factory) -> dict[Path, _Page]:
    """The site built strictly into a scratch folder (or the one CI just built, module
    docstring), each page parsed."""
    _load_hooks()
    built = os.environ.get("SPACEARM_TEST_SITE", "")
    out = Path(built) if built and (Path(built) / "index.html").is_file() else _kept_site(tmp_path_factory)
    pages = {}
    for path in sorted(out.rglob("*.html")):
        parser = _Page()
        parser.feed(path.read_text(encoding="utf-8"))
        pages[path] = parser
    pages["root"] = out
    return pages


def _pages(site):
    """Every page but 404.html, whose links are absolute (it is served from any depth)."""
    return {path: page for path, page in site.items() if path != "root" and path.name != "404.html"}


def _target(page_path: Path, url: str) -> tuple[Path, str] | None:
    parts = urlsplit(url)
    if parts.scheme or parts.netloc or url.startswith(("mailto:", "javascript:")):
        return None
    path = unquote(parts.path)
    target = page_path if not path else (page_path.parent / path).resolve()
    if target.is_dir():
        target = target / "index.html"
    return target, parts.fragment


@pytest.mark.slow
def test_site_has_no_broken_link_and_no_missing_image(site):
    broken = []
    for path, page in _pages(site).items():
        for url in page.links + page.images:
            found = _target(path, url)
            if found is None:
                continue
            target, fragment = found
            if not target.exists():
                broken.append(f"{path.relative_to(site['root'])}: {url} (no file)")
            elif fragment and target.suffix == ".html":
                ids = site[target].ids if target in site else set()
                if fragment not in ids:
                    broken.append(f"{path.relative_to(site['root'])}: {url} (no anchor)")
    assert not broken, "\n".join(broken[:40])
    images = [url for page in _pages(site).values() for url in page.images]
    assert len(images) >= 10, "the pages show the figures of results/"


@pytest.mark.slow
def test_every_formula_is_rendered_as_mathml(site):
    leftovers = []
    for path, page in _pages(site).items():
        raw = path.read_text(encoding="utf-8")
        # J* and w* whose asterisks Markdown paired into emphasis: <em>_v (H</em>, <em>w</em>*
        for em in re.findall(r"<em>(.*?)</em>", raw, flags=re.S):
            if re.search(r"[=^]|^[_)]|\bJ$|<em>", em):
                leftovers.append(f"{path.relative_to(site['root'])}: emphasis made of formula asterisks: {em!r}")
        if 'class="arithmatex"' in raw:
            leftovers.append(f"{path.relative_to(site['root'])}: a formula left to a script")
        text = "".join(page.text)
        patterns = [r"\$\$", r"\\\(", r"\\\[", r"\\frac", r"\\sqrt", r"\\bar", r"\\phi"]
        if "reference" not in path.parts:  # docstrings are plain text (read in terminals too)
            patterns += [r"\^\{", r"_\{"]
        for pattern in patterns:
            if re.search(pattern, text):
                leftovers.append(f"{path.relative_to(site['root'])}: raw TeX {pattern!r} in the text")
    assert not leftovers, "\n".join(leftovers[:40])
    root = site["root"]
    for page, at_least in (
        ("explanation/model/index.html", 10),
        ("tutorials/spatial-arm/index.html", 3),
        ("guide/spatial-robots/index.html", 2),
        ("explanation/wbar-quadrature/index.html", 3),
    ):
        assert site[root / page].maths >= at_least, page


@pytest.mark.slow
def test_site_builds_no_stray_pages_and_loads_nothing_from_the_network(site):
    root = site["root"]
    assert not list(root.rglob("SUMMARY*")), "the literate-nav file is built as a page"
    for path in _pages(site):
        raw = path.read_text(encoding="utf-8")
        for tag in re.findall(r"<(?:script|link|img)\b[^>]*>", raw):
            assert not re.search(r"""(?:src|href)=["']?(?:https?:)?//""", tag), f"{path}: {tag}"


def test_formula_hook_renders_tex_and_refuses_a_bad_formula():
    hooks = _load_hooks()
    html = (
        '<p>inline <span class="arithmatex">\\(w^* = \\sqrt{\\det(J^* J^{*T})}\\)</span></p>'
        '<div class="arithmatex">\\[J^* = J_M - J_S I_S^{-1} I_M\\]</div>'
    )
    out = hooks.render_math(html, "page.md")
    assert out.count("<math") == 2 and 'display="block"' in out and 'display="inline"' in out
    assert "<msqrt>" in out and "arithmatex" not in out
    assert "<mo>&#x02212;</mo><mn>1</mn>" in out  # the exponent -1 as MathML, not text
    bad = '<span class="arithmatex">\\(\\frac{1}{\\)</span>'
    with pytest.raises(Exception, match=r"page\.md: cannot render the formula"):
        hooks.render_math(bad, "page.md")


def test_pages_and_docstrings_cite_no_unshipped_notes():
    found = []
    for folder, suffix in ((ROOT / "docs", ".md"), (ROOT / "src", ".py")):
        for path in sorted(folder.rglob(f"*{suffix}")):
            for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                if UNSHIPPED.search(line):
                    found.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert not found, "\n".join(found)


def test_every_page_is_in_the_nav():
    yaml = pytest.importorskip("yaml")
    text = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    # mkdocs.yml has python tags in other setups; this one is plain YAML
    config = yaml.safe_load(text)

    def walk(node):
        if isinstance(node, str):
            yield node
        elif isinstance(node, list):
            for item in node:
                yield from walk(item)
        elif isinstance(node, dict):
            for value in node.values():
                yield from walk(value)

    listed = {entry for entry in walk(config["nav"]) if entry.endswith(".md")}
    pages = {str(p.relative_to(ROOT / "docs")) for p in (ROOT / "docs").rglob("*.md") if "scripts" not in p.parts}
    assert pages - listed == set(), "pages not in the nav"
    assert listed - pages <= {"reference/cli.md", "reference/layout.md", "reference/table2-report.md"}


def _yaml_blocks(page: Path) -> list[str]:
    return re.findall(r"```yaml\n(.*?)```", page.read_text(encoding="utf-8"), flags=re.S)


def test_the_spatial_tutorial_shows_the_files_it_ships():
    """The robot file, sweep and design problem of the spatial tutorial are the shipped ones
    (configs/baxter-smallsat.yaml, sweeps/baxter-mount.yaml, sweeps/baxter-pareto.yaml), up to
    the robot path, which is one folder shorter in the tutorial's working folder."""
    yaml = pytest.importorskip("yaml")
    blocks = [yaml.safe_load(block) for block in _yaml_blocks(ROOT / "docs" / "tutorials" / "spatial-arm.md")]
    robot, as_written, locks, sweep, problem = blocks
    shipped_robot = yaml.safe_load((ROOT / "configs" / "baxter-smallsat.yaml").read_text())
    robot["arm"].update(as_written)  # the two fixes the tutorial adds, one at a time
    robot["arm"].update(locks)
    assert robot == shipped_robot
    for block, name in ((sweep, "baxter-mount.yaml"), (problem, "baxter-pareto.yaml")):
        shipped = yaml.safe_load((ROOT / "sweeps" / name).read_text())
        assert (
            shipped.pop("robot") == "../configs/baxter-smallsat.yaml" and block.pop("robot") == "baxter-smallsat.yaml"
        )
        assert block == shipped, name


def test_the_two_arm_tutorial_shows_the_file_it_ships():
    yaml = pytest.importorskip("yaml")
    [robot] = [yaml.safe_load(block) for block in _yaml_blocks(ROOT / "docs" / "tutorials" / "two-arms.md")]
    assert robot == yaml.safe_load((ROOT / "configs" / "dual-ur5-servicer.yaml").read_text())


# Pages whose numbers come from running them ----------------------------------------------------

# Each ```python block of these pages runs, in order, in one namespace from the repository's
# root; a ```text block right after a python block is what that block prints, character for
# character. (Printed numbers are rounded so that they do not depend on the last bits.)
EXECUTED_PAGES = (
    "tutorials/two-arms.md",
    "explanation/trees.md",
    "tutorials/dynamics.md",
    "tutorials/wheel-sizing.md",
    "tutorials/capture-mount.md",
)

_BLOCK = re.compile(r"```(python|text)\n(.*?)```", flags=re.S)


def page_blocks(page: Path) -> list[tuple[str, str | None]]:
    """``(code, printed or None)`` for every python block of ``page``, in order."""
    blocks = [(m.group(1), m.group(2), m.start(), m.end()) for m in _BLOCK.finditer(page.read_text(encoding="utf-8"))]
    out = []
    for i, (kind, body, _, end) in enumerate(blocks):
        if kind != "python":
            continue
        following = blocks[i + 1] if i + 1 < len(blocks) else None
        adjacent = following is not None and following[0] == "text"
        adjacent = adjacent and page.read_text(encoding="utf-8")[end : following[2]].strip() == ""
        out.append((body, following[1] if adjacent else None))
    return out


def run_page(page: Path) -> list[tuple[str, str | None, str]]:
    """Run a page's python blocks (from the repository root): ``(code, shown, printed)`` each."""
    namespace: dict = {"__name__": "__docs__"}
    results = []
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        for code, shown in page_blocks(page):
            buffer = io.StringIO()
            with contextlib.redirect_stdout(buffer):
                exec(compile(code, str(page), "exec"), namespace)
            results.append((code, shown, buffer.getvalue()))
    finally:
        os.chdir(cwd)
    return results


@pytest.mark.slow
@pytest.mark.parametrize("name", EXECUTED_PAGES)
def test_pages_print_what_they_show(name):
    """(~20 s each on a loaded 2-core machine: the dual UR5 kernels compile.) Every output block
    of the page is what its code prints."""
    try:
        metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        pytest.skip("the pages use the dual UR5 of example-robot-data (the test extra)")
    import matplotlib

    matplotlib.use("Agg")
    page = ROOT / "docs" / name
    runs = run_page(page)
    assert sum(shown is not None for _, shown, _ in runs) >= 3, "the page shows what its code prints"
    for code, shown, printed in runs:
        if shown is not None:
            assert printed == shown, f"{name}: the block\n{code}\nprints\n{printed}\nbut the page shows\n{shown}"
