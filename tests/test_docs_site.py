"""The built documentation site shows its figures and the executed examples.

The site is read from ``DIFFWEAR_SITE`` (a folder ``mkdocs build`` wrote, as
CI passes it); without it the site is built here into a temporary folder
with ``mkdocs build --strict`` (a minute: only under ``--long``; skipped when
mkdocs is not installed).  Counted in the HTML, against counts taken from the
sources:

* the home page, every validation page and every example page hold at least
  one image, and every page at least as many as its markdown source links
  (the links themselves are checked without a site);
* every example page shows as many outputs and output images as its stored
  notebook holds, and no code cell unexecuted ("In [ ]");
* every ``<img src>`` that is not inline data resolves to a file in the site;
* no paragraph holds a line that begins as a list item or a table row does
  (Markdown that Python-Markdown did not read as a list or a table: a list
  straight after a paragraph, or a table or second paragraph indented less
  than four spaces inside a list item).

Without a site, the figure list of ``docs/figures.py`` is checked against
the pages that link its figures (fast, no build).
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
VALIDATION = sorted((DOCS / "validation").glob("*.md"))
FIGURE_LINK = re.compile(r"!\[[^\]]*\]\(([^)\s]+)")


class _Images(HTMLParser):
    """The ``src`` of every ``<img>`` of a page."""

    def __init__(self):
        super().__init__()
        self.sources: list[str] = []

    def handle_starttag(self, tag, attrs):
        if tag == "img":
            self.sources.append(dict(attrs).get("src") or "")


def _images(html: str) -> list[str]:
    parser = _Images()
    parser.feed(html)
    return parser.sources


@pytest.fixture(scope="module")
def site(request, tmp_path_factory) -> Path:
    given = os.environ.get("DIFFWEAR_SITE")
    if given:
        path = Path(given)
        assert (path / "index.html").is_file(), f"DIFFWEAR_SITE={given} holds no built site"
        return path
    if importlib.util.find_spec("mkdocs") is None:
        pytest.skip("mkdocs is not installed (pip install -e .[docs]); or set DIFFWEAR_SITE")
    if not request.config.getoption("--long"):
        pytest.skip("building the site takes a minute: set DIFFWEAR_SITE to a built site, "
                    "or run with --long")
    path = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1",
           "PYTHONPATH": os.pathsep.join([str(ROOT / "src"),
                                          *filter(None, [os.environ.get("PYTHONPATH")])])}
    build = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict",
                            "--site-dir", str(path)], cwd=ROOT, env=env,
                           capture_output=True, text=True)
    assert build.returncode == 0, build.stderr[-3000:]
    return path


def _page(site: Path, source: Path) -> Path:
    """The built HTML of docs source ``source`` (directory URLs)."""
    rel = source.relative_to(DOCS) if source.is_relative_to(DOCS) else \
        Path("examples") / source.name
    if rel.name in ("index.md",):
        return site / rel.parent / "index.html"
    return site / rel.with_suffix("") / "index.html"


def _stored_outputs(notebook: Path) -> list[dict]:
    nb = json.loads(notebook.read_text())
    return [o for c in nb["cells"] if c["cell_type"] == "code" for o in c.get("outputs", [])]


def _stored_images(notebook: Path) -> int:
    return sum("image/png" in o.get("data", {}) for o in _stored_outputs(notebook))


# one rendered output of a code cell (a stream, a result, a figure) in
# mkdocs-jupyter's HTML
OUTPUT_DIV = re.compile(r'<div class="[^"]*\bjp-OutputArea-output\b')


# pages that must show a figure: the home page and every validation page
REQUIRED = [DOCS / "index.md", *VALIDATION]
PAGES = sorted(p for p in DOCS.rglob("*.md") if not p.is_relative_to(DOCS / "examples"))


@pytest.mark.parametrize("source", REQUIRED, ids=[str(p.relative_to(DOCS)) for p in REQUIRED])
def test_page_links_a_figure(source):
    assert FIGURE_LINK.findall(source.read_text()), f"{source.relative_to(ROOT)} links no figure"


@pytest.mark.parametrize("source", PAGES, ids=[str(p.relative_to(DOCS)) for p in PAGES])
def test_page_shows_its_figures(site, source):
    linked = len(FIGURE_LINK.findall(source.read_text()))
    shown = _images(_page(site, source).read_text())
    assert len(shown) >= linked, (f"{source.relative_to(ROOT)}: {linked} figures linked, "
                                  f"{len(shown)} <img> in the page")
    if source in REQUIRED:
        assert shown, f"{source.relative_to(ROOT)}: no <img> in the page"


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_example_page_shows_executed_outputs(site, notebook):
    html = _page(site, notebook).read_text()
    stored = _stored_images(notebook)
    assert stored >= 1, f"{notebook.name} is stored without a figure"
    inline = [s for s in _images(html) if s.startswith("data:image/png")]
    assert len(inline) == stored, (f"{notebook.name}: {stored} figures stored, "
                                   f"{len(inline)} in the page")
    outputs = len(_stored_outputs(notebook))
    shown = len(OUTPUT_DIV.findall(html))
    assert outputs >= 1 and shown == outputs, \
        f"{notebook.name}: {outputs} outputs stored, {shown} shown"
    assert "In [ ]" not in html, f"{notebook.name}: a code cell shown unexecuted"


def test_every_image_resolves_to_a_file(site):
    broken = []
    pages = sorted(site.rglob("*.html"))
    assert len(pages) > 20, f"{site}: only {len(pages)} pages"
    for page in pages:
        for src in _images(page.read_text()):
            if src.startswith("data:"):
                continue
            parts = urlsplit(src)
            if parts.scheme or parts.netloc:
                broken.append(f"{page.relative_to(site)}: external image {src}")
                continue
            target = (page.parent / unquote(parts.path)).resolve()
            if not target.is_file() or target.stat().st_size == 0:
                broken.append(f"{page.relative_to(site)}: {src}")
    assert not broken, "\n".join(broken)


# a line of a paragraph that Markdown should have read as a list item or a
# table row; code is blanked first, as it may hold either legitimately
UNREAD_BLOCK = re.compile(r"^\s*(?:(?:[-*+]|\d+\.)\s.*|\|.*\|\s*)$", re.MULTILINE)
PARAGRAPH = re.compile(r"<p>(.*?)</p>", re.DOTALL)
CODE = re.compile(r"<pre.*?</pre>|<code.*?</code>", re.DOTALL)


def test_no_list_or_table_shown_as_text(site):
    unread = []
    for page in sorted(site.rglob("*.html")):
        html = CODE.sub("code", page.read_text())
        for paragraph in PARAGRAPH.findall(html):
            unread += [f"{page.relative_to(site)}: {line.strip()[:80]!r}"
                       for line in UNREAD_BLOCK.findall(paragraph)]
    assert not unread, "\n".join(unread)


def test_drawn_figures_fit_the_page(site):
    """docs/figures.py's PNGs: figures of 5.5-12 inches at 110-120 dpi are
    about 600-1440 px wide (the theme scales an image down to the text
    column, so wider only costs bytes); a few hundred kB at most each."""
    figures = sorted((site / "figures").glob("*.png"))
    assert len(figures) == len(_figures_module().FIGURES)
    for png in figures:
        head = png.read_bytes()[:24]
        assert head[:8] == b"\x89PNG\r\n\x1a\n", png.name
        width = int.from_bytes(head[16:20], "big")
        assert 500 <= width <= 1440, f"{png.name}: {width} px wide"
        assert png.stat().st_size <= 300_000, f"{png.name}: {png.stat().st_size} bytes"


def _figures_module():
    spec = importlib.util.spec_from_file_location("diffwear_docs_figures", DOCS / "figures.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_linked_figure_is_drawn_and_every_drawn_one_linked():
    """No build: the pages' links under figures/ against docs/figures.py."""
    drawn = set(_figures_module().FIGURES)
    linked = set()
    for page in DOCS.rglob("*.md"):
        for target in FIGURE_LINK.findall(page.read_text()):
            resolved = os.path.normpath(page.parent.relative_to(DOCS) / target)
            if resolved.startswith("figures/"):
                linked.add(resolved)
    assert linked == drawn, (f"linked, not drawn: {sorted(linked - drawn)}; "
                             f"drawn, not linked: {sorted(drawn - linked)}")


def test_stored_curves_are_thinned_keeping_the_ends(tmp_path):
    """design_studies/docs_figure_data.py: a 3-cycle series cut to its last
    cycle, then to at most MAX_ROWS rows, the first and last kept, values to
    SIGNIFICANT digits."""
    spec = importlib.util.spec_from_file_location(
        "diffwear_docs_figure_data", ROOT / "design_studies" / "docs_figure_data.py")
    data = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(data)
    t = [0.005 * i for i in range(1201)]  # 6 s: three 2 s cycles
    source = tmp_path / "force.csv"
    source.write_text("t_s,force_N\n" + "".join(f"{x!r},{1000 + x / 3!r}\n" for x in t))
    target = tmp_path / "thin.csv"
    data.thin_csv(source, target, last_s=2.0)
    rows = [line.split(",") for line in target.read_text().splitlines()[1:]]
    times = [float(r[0]) for r in rows]
    assert times[0] == pytest.approx(4.0) and times[-1] == pytest.approx(6.0)
    assert len(rows) <= data.MAX_ROWS
    assert len(rows) == 401  # 401 rows of the last cycle: all kept
    data.thin_csv(source, target)
    rows = [line.split(",") for line in target.read_text().splitlines()[1:]]
    assert len(rows) <= data.MAX_ROWS and float(rows[-1][0]) == pytest.approx(6.0)
    assert float(rows[0][0]) == 0.0
    assert rows[-1][1] == f"{1000 + 6.0 / 3:.{data.SIGNIFICANT}g}" == "1002"
