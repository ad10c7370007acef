"""The report as a paper: one PDF of the whole study (numbered figures and tables, a references
list with the dissertation, no code, no unresolved reference), pages with their code folded and
nothing loaded from the internet, and a report folder that holds everything it links."""

from __future__ import annotations

import hashlib
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

from nfarm.infra.paths import ROOT
from nfarm.publishing import paper, report
from nfarm.publishing.manifest import verify_manifest
from nfarm.__main__ import report_command as build_report

pypdf = pytest.importorskip("pypdf")

#: Every test here reads one smoke report (a module fixture, made once per pytest-xdist worker): one worker runs them all.
pytestmark = pytest.mark.xdist_group("paper")

FIGURE_AND_TABLE = """import matplotlib.pyplot as plt
from nfarm.infra.paths import project_path
from nfarm.presentation.plotting import save_figure
from nfarm.presentation.tables import Table
out = project_path(out_dir)
fig, ax = plt.subplots()
ax.plot([0, 1], [0, 1])
save_figure(fig, out, "{p}_line", caption="A line of chapter {p}")
from IPython.display import display
display(Table(["x"], [[1]], caption="Shown, not saved: no number"))
display(Table(["smoke", "value"], [[smoke, 1.5]], caption="Was chapter {p} a smoke run?").save(out, "{p}_params"))
from IPython.display import Markdown, display
display(Markdown("Its parameters are in {{numref}}`{p}_params`."))"""

PROSE = 'from IPython.display import Markdown, display\ndisplay(Markdown(f"The answer is {6 * 7}."))'


def chapter(path: Path, parameters: str, *code: str, prose: str = "") -> None:
    cells = [new_markdown_cell(f"# Chapter {int(path.name[:2])} — A chapter called {path.stem[3:]}\n\n{prose}"),
             new_code_cell(parameters + '\nsmoke = False\nout_dir = "build/explore/x"',
                           metadata={"tags": ["parameters"]})]
    cells += [new_code_cell(c) for c in code]
    cells.append(new_markdown_cell("## 1.1 A section\n\nWith $x^2 + \\tau_5$ and an address, me@example.org."))
    cells.append(new_code_cell(PROSE, metadata={"tags": ["remove-input"]}))
    nbformat.write(new_notebook(cells=cells), path)


@pytest.fixture(scope="module")
def smoke_report(tmp_path_factory):
    """A smoke report of two arms (the primary "a", and "b" whose chapters are numbered "B1", …):
    a chapter per arm, one the same for both, one comparing them; every one draws a figure and
    writes a table."""
    root = tmp_path_factory.mktemp("paper")
    notebooks = root / "notebooks"
    notebooks.mkdir()
    chapter(notebooks / "01_robot.ipynb", 'robot_file = "ra.yaml"', FIGURE_AND_TABLE.format(p="01"),
            prose="This chapter draws a line ({numref}`01_line`),\n\n$$y = x \\label{eq:line}$$\n\n"
                  "and {eq}`line` is its equation.")
    chapter(notebooks / "02_shared.ipynb", "seed = 0", FIGURE_AND_TABLE.format(p="02"))
    chapter(notebooks / "03_compare.ipynb", 'study_files = ["sa.yaml"]', FIGURE_AND_TABLE.format(p="03"))
    arms = [report.Edition("a", "sa.yaml", "ra.yaml", True), report.Edition("b", "sb.yaml", "rb.yaml", False)]
    build = root / "build"
    assert build_report(notebooks_dir=notebooks, figures_dir=root / "figures", build_dir=build, arms=arms,
                        parallel=False, smoke=True) == 0
    return build / "smoke" / "report"


def pdf_text(path: Path) -> str:
    reader = pypdf.PdfReader(path)
    return "\n".join(page.extract_text() for page in reader.pages).replace("\xa0", " ")


@pytest.mark.notebook
def test_the_smoke_report_builds_one_pdf_of_the_whole_study(smoke_report):
    pdf = smoke_report / paper.PAPER_NAME
    assert pdf.is_file() and pdf.read_bytes()[:5] == b"%PDF-"
    text = pdf_text(pdf)
    flat = " ".join(text.split())
    assert "Figure 1.1:" in flat and "A line of chapter 01" in flat, "figures numbered per chapter, captioned"
    assert "Table 1.1:" in flat and "Table 2.1:" in flat and "Table 3.1:" in flat, "tables numbered per chapter"
    assert "Figure B1.1:" in flat, "the other arm's chapters numbered apart"
    assert "Was chapter 02 a smoke run?" in flat
    assert "Table 1.1: Was chapter 01 a smoke run?" in flat, "numbered as its page numbers it: a table not saved is not"
    assert "Shown, not saved: no number" in flat and "Table 1.2" not in flat
    assert "draws a line (Figure 1.1)" in flat and "draws a line (Figure B1.1)" in flat, "citations resolved per edition"
    assert "Its parameters are in Table 1.1." in flat and "Its parameters are in Table B1.1." in flat
    assert "Its parameters are in Table 2.1." in flat and "numref" not in flat
    assert "and (1.1) is its equation" in flat and "and (B1.1) is its equation" in flat, "equations numbered per edition"
    assert "\\label" not in flat and "{eq}" not in flat
    assert "??" not in text and not re.search(r"\(\w+\?\)", text), "no unresolved reference"
    assert "References" in text
    refs = flat[flat.rindex("References"):]
    assert "Tu Rain" in refs and "Belgorod State National Research University" in refs, "the dissertation cited"
    assert "Jang" in refs and "Levenberg" in refs and "Pinocchio" in refs
    assert "Tu Rain" in flat[:flat.index("Contents")], "the title page names the dissertation"
    assert "The answer is 42." in flat and "me@example.org" in flat, "outputs and prose kept"
    for code in ("save_figure(", "import matplotlib", "out_dir", "display(Markdown"):
        assert code not in text, f"code left in the PDF: {code}"
    assert "smoke run" in flat.lower()
    outline = []

    def walk(items):
        for item in items:
            walk(item) if isinstance(item, list) else outline.append(" ".join(item.title.split()))
    walk(pypdf.PdfReader(pdf).outline)
    # every chapter writes a section "1.1": the b edition's chapter B1 numbers it B1.1, the shared chapters do not
    assert outline.count("1.1 A section") == 3 and outline.count("B1.1 A section") == 1, outline


class _Refs(HTMLParser):
    def __init__(self):
        super().__init__()
        self.links: list[str] = []
        self.scripts: list[str] = []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        for name in ("href", "src"):
            if attrs.get(name):
                self.links.append(attrs[name])
        if tag == "script" and attrs.get("src"):
            self.scripts.append(attrs["src"])


def _pages(report_dir: Path) -> list[Path]:
    return sorted(p for p in report_dir.rglob("*.html") if "mathjax" not in p.relative_to(report_dir).parts)


@pytest.mark.notebook
def test_pages_fold_their_code_and_load_nothing_from_the_internet(smoke_report):
    pages = _pages(smoke_report)
    assert len(pages) >= 5
    for page in pages:
        html = page.read_text(encoding="utf-8")
        refs = _Refs()
        refs.feed(html)
        assert not [s for s in refs.scripts if re.match(r"(https?:)?//", s)], f"{page.name}: a script from the internet"
        assert not re.search(r"cdn\.|cdnjs|jsdelivr|unpkg|mermaid", html, re.I), f"{page.name}: a CDN reference"
        assert not re.search(r"import\(\s*['\"]https?:", html), f"{page.name}: a module from the internet"
        if page.name != "index.html":
            assert "<details class=\"nfarm-code\"><summary>show code</summary>" in html, page.name
            assert "The answer is 42." in html and "display(Markdown" not in html, "remove-input still hidden"
            assert not re.search(r"<div class=\"jp-(In|Out)putPrompt", html), f"{page.name}: In/Out prompts"
    first = (smoke_report / "01_robot.html").read_text(encoding="utf-8")
    folded = re.findall(r"<details class=\"nfarm-code\">.*?</details>", first, re.S)
    assert any("save_figure" in block for block in folded), "the code is there, folded"
    assert "save_figure" not in re.sub(r"<details class=\"nfarm-code\">.*?</details>", "", first, flags=re.S)
    # The parameters the page was made with, as a small table above the folded code (the smoke run's own values)
    table = re.search(r'<table class="nfarm-parameters">.*?</table>', first, re.S)
    import html as html_
    assert table and '<code>robot_file</code></td><td><code>"ra.yaml"</code>' in html_.unescape(table.group(0)), table
    assert "<code>smoke</code></td><td><code>True</code>" in table.group(0), "the run's value, not the default"
    assert "out_dir" not in table.group(0) and "build/" not in table.group(0), "no build path among the study's values"


@pytest.mark.notebook
def test_each_chapter_page_opens_with_its_contents_and_links_the_other_edition(smoke_report):
    """A chapter page lists its sections under its title, each a link to the section's anchor; a
    chapter run for every arm links to the same chapter of the other edition."""
    for page in (smoke_report / "01_robot.html", smoke_report / "b" / "01_robot.html"):
        html = page.read_text(encoding="utf-8")
        toc = re.search(r'<nav class="nfarm-toc"[^>]*>(.*?)</nav>', html, re.S)
        assert toc and html.index("</h1>") < toc.start(), f"{page}: contents under the title"
        (anchor,) = re.findall(r'<a href="#([^"]+)">1.1 A section</a>', toc.group(1))
        assert f'<h2 id="{anchor}">' in html
    first_a = (smoke_report / "01_robot.html").read_text(encoding="utf-8")
    first_b = (smoke_report / "b" / "01_robot.html").read_text(encoding="utf-8")
    assert "href='b/01_robot.html'>b edition:" in first_a and "href='../01_robot.html'>a edition:" in first_b
    shared = (smoke_report / "02_shared.html").read_text(encoding="utf-8")
    assert " edition:" not in shared, "a chapter the same for every arm has no other edition"


@pytest.mark.notebook
def test_the_report_folder_holds_what_it_links_and_says_how_to_reproduce_it(smoke_report, tmp_path):
    copy = tmp_path / "elsewhere"                 # the folder copied: its links still resolve
    shutil.copytree(smoke_report, copy)
    broken = []
    for page in _pages(copy):
        refs = _Refs()
        refs.feed(page.read_text(encoding="utf-8"))
        for link in refs.links:
            parts = urlsplit(link)
            if parts.scheme or link.startswith(("#", "//")):
                assert parts.scheme in ("", "data", "mailto"), f"{page.name}: {link}"
                continue
            target = (page.parent / unquote(parts.path)).resolve()
            if not target.exists() or copy.resolve() not in target.parents:
                broken.append(f"{page.relative_to(copy)}: {link}")
    assert not broken, broken
    index = (copy / "index.html").read_text(encoding="utf-8")
    assert f"href='{paper.PAPER_NAME}'" in index
    assert "href='figures/tables/01_params.csv'" in index and "href='figures/b/tables/01_params.csv'" in index
    assert verify_manifest(copy / "figures") == [], "figures/MANIFEST.sha256 checks the copies"
    lock = hashlib.sha256((ROOT / "environment.lock").read_bytes()).hexdigest()
    box = index[index.index("<div class='reproduce'>"):]
    box = box[:box.index("</div>")]
    assert lock in box and "make report" in box and re.search(r"\d+ cores?", box)
    assert re.search(r"<dt>commit</dt><dd><code>([0-9a-f]{7,}|unknown)", box)


@pytest.mark.notebook
def test_the_index_lists_the_references_as_the_pdf_does(smoke_report):
    """The HTML edition has its references list too: every work of the bibliography, formatted by the
    same citeproc as the PDF's, the dissertation among them."""
    index = (smoke_report / "index.html").read_text(encoding="utf-8")
    assert "<h2 id='references'>References</h2>" in index and 'id="refs"' in index
    keys = re.findall(r"^@\w+\{([\w-]+),", paper.BIBLIOGRAPHY.read_text(encoding="utf-8"), re.M)
    assert {k for k in keys if f'id="ref-{k}"' in index} == set(keys), "every work listed"
    listed = re.sub(r"<[^>]+>|\s+", " ", index[index.index('id="refs"'):])
    assert "Tu Rain" in listed and "Belgorod State National Research University" in listed and "Jang" in listed


def test_the_pdf_s_appendix_holds_every_long_table_each_edition_published(tmp_path):
    arms = [report.Edition("a", "sa.yaml", "ra.yaml", True), report.Edition("b", "sb.yaml", "rb.yaml", False)]
    for where, name in (("", "07_summary"), ("", "08_learned"), ("b", "07_summary")):
        (tmp_path / where / "tables").mkdir(parents=True, exist_ok=True)
        (tmp_path / where / "tables" / f"{name}.md").write_text(f"*Every row of {name}*\n\n| x |\n|---|\n| < 1e-6 |\n")
    appendix = paper._appendix(tmp_path, arms)
    assert appendix.startswith("# Appendix: the long tables") and '#chap.update("A")' in appendix
    assert [m for m in re.findall(r"\{#(tbl-appendix-[\w-]+)\}", appendix)] == \
        ["tbl-appendix-a-07_summary", "tbl-appendix-a-08_learned", "tbl-appendix-b-07_summary"]
    assert ": Every row of 07\\_summary (b)" in appendix and "| < 1e-6 |" in appendix
    assert paper._appendix(tmp_path / "none", arms) == ""


def test_the_verdict_before_the_chapters_is_not_numbered():
    """A numbered table before any chapter would print "Table .1": the verdict's caption stands above it, as an
    unnumbered table's does (read from the published verdicts)."""
    from nfarm.infra.paths import FIGURES
    from nfarm.publishing.editions import editions

    text = paper._verdict(FIGURES, editions())
    assert text.startswith("# Verdict {.unnumbered}\n\n*The verdict on held-out data")
    assert not re.search(r"^: ", text, re.M), "no numbered caption"


def test_the_bibliography_has_every_work_the_pdf_cites():
    bib = paper.BIBLIOGRAPHY.read_text(encoding="utf-8")
    keys = re.findall(r"^@\w+\{([\w-]+),", bib, re.M)
    assert len(keys) == len(set(keys)) >= 17
    cited = set(re.findall(r"@([a-z][\w]+)", paper.SOURCES)) | {paper.DISSERTATION}
    assert cited <= set(keys), sorted(cited - set(keys))
    for entry in re.split(r"\n(?=@)", bib.strip())[1:]:
        assert re.search(r"^\s*title\s*=", entry, re.M) and re.search(r"^\s*year\s*=\s*\{\d{4}\}", entry, re.M), entry
        assert re.search(r"^\s*author\s*=", entry, re.M), entry
    thesis = bib[bib.index("@phdthesis{" + paper.DISSERTATION):]
    assert paper.DISSERTATION_TITLE in thesis and "Belgorod State National Research University" in thesis
    assert not re.search(r"^\s*doi\s*=", bib, re.M | re.I), "no DOI written from memory"


def test_a_notebook_s_prose_keeps_its_at_signs_and_its_headings_go_one_level_down():
    assert paper._prose("# A\n\nmail me@x.org or @someone\n\n```\n# kept\n```") == \
        "## A\n\nmail me@x.org or \\@someone\n\n```\n# kept\n```"


@pytest.mark.notebook
def test_the_pdf_is_built_again_only_when_what_it_is_made_of_changes(smoke_report, monkeypatch):
    """A second build with the same inputs keeps the PDF (no pandoc, no Typst); a changed input
    makes it again."""
    import typst

    pages = report.ReportPages(chapters=(), runs={}, comparing=frozenset(), arms=(), executed_dir=smoke_report,
                               report_dir=smoke_report / "again", figures_dir=smoke_report, parameters={}, smoke=True,
                               recordings_dir=None)
    compiled = []
    real = typst.compile
    monkeypatch.setattr(typst, "compile", lambda *a, **k: compiled.append(1) or real(*a, **k))
    first = paper.write_paper(pages, commit="abc")
    made = first.read_bytes()
    assert paper.write_paper(pages, commit="abc").read_bytes() == made and len(compiled) == 1
    paper.write_paper(pages, commit="abd")                      # the commit it states changed
    assert len(compiled) == 2
    (smoke_report / "again" / ".paper.sha256").write_text("0" * 64 + "\n")   # a stamp that does not match
    paper.write_paper(pages, commit="abd")
    assert len(compiled) == 3


@pytest.mark.notebook
def test_a_citation_of_a_figure_or_table_no_chapter_shows_stops_the_pdf_in_one_line():
    from nfarm.infra.notebook_runs import ReportError

    assert paper._prose("as {numref}`01_line` shows", {"01_line": "fig-a-01_line"}, "01_robot.ipynb") == \
        "as `@fig-a-01_line`{=typst} shows"
    with pytest.raises(ReportError, match=r"^01_robot.ipynb: cites 01_lnie, which no chapter of this edition shows"):
        paper._prose("as {numref}`01_lnie` shows", {"01_line": "fig-a-01_line"}, "01_robot.ipynb")


def test_equations_are_numbered_in_order_and_each_carries_a_label():
    from nfarm.infra.notebook_runs import ReportError
    from nfarm.presentation.numbering import equations

    assert equations(["$$a = b \\label{eq:first}$$ and $$x^2$$", "$$c \\label{eq:second} = d$$"]) == ["first", "second"]
    assert equations(["$$a = b$$"]) == [], "an equation without a label is not numbered"
    with pytest.raises(ValueError, match="given twice"):
        equations(["$$a \\label{eq:x}$$", "$$b \\label{eq:x}$$"])
    with pytest.raises(ValueError, match="must stand on one line"):
        equations(["$$a =\nb \\label{eq:x}$$"])
    # In the PDF: numbered while Typst's numbering is set around it, the label unique to the edition, after an
    # empty group (pandoc refuses a label after a bare letter); an equation without a label is left as it is
    pdf = paper._prose("$$y = x \\label{eq:line}$$\n\nas {eq}`line`; $$x^2$$", {"eq:line": "eq-a-line"}, "01.ipynb")
    assert "$$y = x {} \\label{eq-a-line}$$" in pdf and "as `@eq-a-line`{=typst}; $$x^2$$" in pdf
    assert pdf.index("#set math.equation(numbering: n =>") < pdf.index("$$y") < pdf.index("numbering: none)")
    with pytest.raises(ReportError, match=r"^01.ipynb: cites equation lnie, which no chapter of this edition numbers"):
        paper._prose("as {eq}`lnie`", {"eq:line": "eq-a-line"}, "01.ipynb")


def test_the_chapters_equations_are_labelled_and_their_citations_resolve_within_the_chapter():
    """Every display equation of the study's chapters carries a label (numbered, as a paper numbers its
    equations), and prose cites only its own chapter's equations (the course's teacher pages are
    exported one by one)."""
    from nfarm.infra.notebook_runs import chapters
    from nfarm.infra.paths import NOTEBOOKS
    from nfarm.presentation.numbering import DISPLAY, EQ_CITATION, equations

    cited = 0
    for notebook in chapters(NOTEBOOKS):
        markdown = [c.source for c in nbformat.read(notebook, 4).cells if c.cell_type == "markdown"]
        names = equations(markdown)
        assert len(names) == sum(len(DISPLAY.findall(text)) for text in markdown), f"{notebook.name}: every equation numbered"
        for text in markdown:
            for found in EQ_CITATION.finditer(text):
                assert found.group("name") in names, f"{notebook.name} cites {found.group('name')}"
                cited += 1
    assert cited >= 4


def test_a_page_citing_what_its_edition_does_not_show_is_refused_in_one_line():
    from nfarm.infra.notebook_runs import ReportError
    from nfarm.publishing.citations import resolve_citations

    refs = {"06_ik_curves": ("Figure S6.2", "06_anfis_training.html#06_ik_curves")}
    assert resolve_citations("as {numref}<code>06_ik_curves</code> shows", refs, "06.ipynb") == \
        'as <a href="06_anfis_training.html#06_ik_curves">Figure S6.2</a> shows'
    with pytest.raises(ReportError, match=r"^06.ipynb: cites 06_ik_curvse, which no chapter of this edition shows"):
        resolve_citations("as {numref}<code>06_ik_curvse</code> shows", refs, "06.ipynb")
    with pytest.raises(ReportError, match=r"^06.ipynb: cites equation lm-stpe, which no chapter"):
        resolve_citations("by {eq}<code>lm-stpe</code>", {"eq:lm-step": ("(2.2)", "#eq-lm-step")}, "06.ipynb")


@pytest.mark.notebook
def test_each_edition_s_html_cites_its_figures_and_tables_by_number_and_links_them(smoke_report):
    page = (smoke_report / "01_robot.html").read_text()
    assert '<figure class="nfarm-figure" id="fig-01_line"' in page and '<a id="tbl-01_params"></a>' in page
    assert '(<a href="01_robot.html#fig-01_line">Figure 1.1</a>)' in page
    assert '<a href="01_robot.html#tbl-01_params">Table 1.1</a>' in page and "<strong>Table 1.1.</strong>" in page
    other = (smoke_report / "b" / "01_robot.html").read_text()
    assert '<a href="01_robot.html#fig-01_line">Figure B1.1</a>' in other and "<strong>Table B1.1.</strong>" in other
    unfolded = lambda text: re.sub(r'<details class="nfarm-code">.*?</details>', "", text, flags=re.S)   # noqa: E731
    assert "numref" not in unfolded(page) and "numref" not in unfolded(other), "every citation resolved"
    # Equations: numbered for MathJax, anchored, cited by number and linked, per edition
    assert '<a id="eq-line"></a>' in page and r"\tag{1.1}" in page and r"\label" not in page
    assert '<a href="01_robot.html#eq-line">(1.1)</a> is its equation' in page
    assert r"\tag{B1.1}" in other and '<a href="01_robot.html#eq-line">(B1.1)</a> is its equation' in other
    assert "{eq}" not in unfolded(page) and "{eq}" not in unfolded(other)


@pytest.mark.notebook
def test_each_edition_s_html_numbers_its_figures_as_the_pdf_does(smoke_report):
    assert "<b>Figure 1.1.</b>" in (smoke_report / "01_robot.html").read_text()
    other = (smoke_report / "b" / "01_robot.html").read_text()
    assert "<b>Figure B1.1.</b>" in other and "<b>Figure 1.1.</b>" not in other
    assert "<b>Figure 2.1.</b>" in (smoke_report / "b" / "02_shared.html").read_text()   # the same for every arm
