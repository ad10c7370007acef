"""The report's HTML pages: each executed chapter exported with nbconvert (captions under its
figures, the arm in its title, navigation within its edition, MathJax from a local copy, no
input of hidden cells), and the index that links every edition's chapters, figures, tables
and recordings.
"""

from __future__ import annotations

import csv
import datetime
import html
import json
import os
import re
import shutil
import subprocess
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from ..infra.notebook_runs import DropMessage, ReportError
from ..infra.paths import FIGURES, ROOT, atomic_path, shown_path
from ..presentation.numbering import anchor
from .editions import Edition
from .manifest import chapter_files

__all__ = ["ABSTRACT_FRAMING", "ANSWERS_KIND", "ReportPages", "machine", "write_pages", "references_html", "pandoc_path", "BIBLIOGRAPHY", "abstract_answers", "verdict_rows", "edition_letter", "DISSERTATION_TITLE", "DISSERTATION_TITLE_EN", "export_html", "chapter_title", "install_mathjax", "COURSE_TAGS",
           "MATHJAX", "PAPER_NAME", "PAGE_TEMPLATE"]


def chapter_title(notebook: Path) -> str:
    cells = json.loads(notebook.read_text(encoding="utf-8"))["cells"]
    for cell in cells:
        if cell["cell_type"] == "markdown":
            for line in "".join(cell["source"]).splitlines():
                if line.startswith("# "):
                    return line[2:].strip()
    return notebook.stem


#: Cells of the course edition (:mod:`nfarm.publishing.course`), left out of the report.
COURSE_TAGS = ("exercise", "solution", "check")

MATHJAX = "mathjax/MathJax.js?config=TeX-AMS-MML_HTMLorMML-full,Safe"

#: The whole study as one PDF in the report directory (:mod:`.paper` writes it; the index links it).
PAPER_NAME = "nfarm-study.pdf"
#: The works the study leans on (BibTeX): the PDF's references list and the index's are made from it.
BIBLIOGRAPHY = ROOT / "docs" / "references.bib"


def pandoc_path() -> str:
    """The pandoc binary the lock ships (the ``pypandoc-binary`` wheel's)."""
    import pypandoc

    return pypandoc.get_pandoc_path()


def references_html(bibliography: Path = BIBLIOGRAPHY) -> str:
    """Every work in ``bibliography`` as an HTML references list, formatted by pandoc's citeproc
    as the PDF's list is (its default style, Chicago author–date), sorted by author.

    Raises:
        ReportError: pandoc failed (one line with its message).
    """
    done = subprocess.run([pandoc_path(), "--from", "markdown", "--to", "html", "--citeproc",
                           "--bibliography", str(bibliography)],
                          input="---\nnocite: |\n  @*\n---\n", capture_output=True, text=True, timeout=120)
    if done.returncode != 0 or 'id="refs"' not in done.stdout:
        raise ReportError(f"the references list: pandoc failed: {' '.join(done.stderr.strip().splitlines()[-1:])}")
    return done.stdout


def install_mathjax(report_dir: Path) -> None:
    """Copy MathJax from the ``jupyter_server_mathjax`` package beside the pages (once)."""
    import jupyter_server_mathjax

    source = Path(jupyter_server_mathjax.__file__).parent / "static"
    target = report_dir / "mathjax"
    if (target / "MathJax.js").is_file():
        return
    tmp = report_dir / ".mathjax.tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    shutil.copytree(source, tmp)
    shutil.rmtree(target, ignore_errors=True)
    os.rename(tmp, target)


def _nav(links: dict[str, tuple[str, str] | None]) -> str:
    parts = [f"<a href='{html.escape(href)}'>{html.escape(label)}: {html.escape(title)}</a>"
             for label, link in links.items() if link for href, title in [link]]
    return ("<nav style='font-family:sans-serif;margin:1em 2em;display:flex;gap:2em'>"
            + "".join(parts) + "</nav>")


def _merge_parameters(nb) -> None:
    """One parameters cell on a page: the values papermill injected written into the chapter's
    own parameters cell (its comments kept), and the injected cell dropped; a first comment
    names the values this run changed. A reader sees the values the page was made with, once."""
    import ast

    tagged = lambda tag: [k for k, c in enumerate(nb.cells) if tag in c.metadata.get("tags", [])]  # noqa: E731
    own, injected = tagged("parameters"), tagged("injected-parameters")
    if len(own) != 1 or len(injected) != 1:
        return
    cell, given = nb.cells[own[0]], nb.cells[injected[0]].source
    try:
        values = {node.targets[0].id: ast.get_source_segment(given, node.value)
                  for node in ast.parse(given).body
                  if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name)}
        tree = ast.parse(cell.source)
    except SyntaxError:
        return
    lines = cell.source.split("\n")
    changed = []
    for node in sorted((n for n in tree.body if isinstance(n, ast.Assign) and len(n.targets) == 1
                        and isinstance(n.targets[0], ast.Name) and n.targets[0].id in values),
                       key=lambda n: n.lineno, reverse=True):
        name = node.targets[0].id
        if ast.get_source_segment(cell.source, node.value) == values[name]:
            values.pop(name)
            continue
        rest = lines[node.end_lineno - 1][node.end_col_offset:]
        lines[node.lineno - 1:node.end_lineno] = [f"{name} = {values.pop(name)}{rest}"]
        changed.append(name)
    lines += [f"{name} = {value}" for name, value in values.items()]
    changed += list(values)
    if changed:
        lines.insert(0, f"# This page's run set: {', '.join(sorted(changed))}")
    cell.source = "\n".join(lines)
    del nb.cells[injected[0]]


def _parameters_table(nb) -> None:
    """The parameters cell's values as rows (name, value, its comment) in the cell's metadata
    (``nfarm_parameters``), which the study edition's page shows as a small table above the
    folded code: a reader sees the values the page was made with without opening the code. The
    directories the run read and wrote (``…_dir``, ``…_dirs``: the build's, not the study's) are
    left to the folded code."""
    import ast

    for cell in nb.cells:
        if cell.cell_type != "code" or "parameters" not in cell.metadata.get("tags", []):
            continue
        try:
            tree = ast.parse(cell.source)
        except SyntaxError:
            return
        lines = cell.source.split("\n")
        rows = []
        for node in tree.body:
            if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name) \
                    and not node.targets[0].id.endswith(("_dir", "_dirs")):
                rest = lines[node.end_lineno - 1][node.end_col_offset:].strip()
                note = rest[1:].strip() if rest.startswith("#") else ""
                rows.append([node.targets[0].id, ast.get_source_segment(cell.source, node.value), note])
        cell.metadata["nfarm_parameters"] = rows
        return


def _name_the_arm(nb, arm: str) -> None:
    """The chapter's heading names the arm its page is for (an edition's pages look alike)."""
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            lines = cell.source.split("\n")
            for k, line in enumerate(lines):
                if line.startswith("# "):
                    lines[k] = f"{line} · {arm}"
                    cell.source = "\n".join(lines)
                    return


#: The pages' template: JupyterLab's, with no diagram library (nbconvert's lab template imports
#: mermaid from a CDN on every page; no page draws a diagram) and, when the resources ask for it
#: (``nfarm_fold_code``), each code cell's input folded in a ``<details>`` element ("show code"):
#: plain HTML, no script.
PAGE_TEMPLATE = """{%- extends 'lab/index.html.j2' -%}
{%- block html_head_js_mermaidjs -%}{%- endblock html_head_js_mermaidjs -%}
{%- block html_head_js_requirejs -%}{%- endblock html_head_js_requirejs -%}
{% block input_group -%}
{%- if resources.nfarm_fold_code and cell.cell_type == 'code' -%}
{%- if cell.metadata.nfarm_parameters -%}
<table class="nfarm-parameters"><caption>The parameters of this run (the directories it read and wrote: in its code)</caption>
<thead><tr><th>parameter</th><th>value</th><th>what it sets</th></tr></thead><tbody>
{%- for row in cell.metadata.nfarm_parameters -%}
<tr><td><code>{{ row[0] | e }}</code></td><td><code>{{ row[1] | e }}</code></td><td>{{ row[2] | e }}</td></tr>
{%- endfor -%}
</tbody></table>
{%- endif -%}
<details class="nfarm-code"><summary>show code</summary>
{{ super() }}
</details>
{%- else -%}
{{ super() }}
{%- endif -%}
{% endblock input_group %}
{% block extra_css %}
<style>details.nfarm-code>summary{cursor:pointer;color:#666;font:0.85em sans-serif;margin:.2em 0 .2em 1em}
nav.nfarm-toc{font:0.9em sans-serif;margin:1em 0 2em;padding:.5em 1em;border-left:3px solid #ccd}
nav.nfarm-toc ul{list-style:none;margin:.3em 0;padding:0}nav.nfarm-toc li.toc3{margin-left:1.5em}
table.nfarm-parameters{font-size:.85em;margin:.5em 0 .5em 1em;border-collapse:collapse}
table.nfarm-parameters caption{text-align:left;color:#444}
table.nfarm-parameters td,table.nfarm-parameters th{padding:.1em .6em;text-align:left;vertical-align:top}</style>
{% endblock extra_css %}
"""


def edition_letter(edition: Edition) -> str:
    """The letter before an edition's chapter numbers — "" for the primary, the arm's initial for
    the others ("Figure S6.1" in the SO-101's edition) — the same in its HTML pages and the PDF."""
    return "" if edition.primary else edition.name[:1].upper()


_FIGURE_NUMBER = re.compile(r"<b>Figure (\d+\.\d+)\.</b>")
_TABLE_NUMBER = re.compile(r"<strong>Table (\d+\.\d+)\.</strong>")
# A chapter's numbered outputs (nfarm.presentation.numbering): a figure's HTML, a table's Markdown.
_NUMBERED_FIGURE = re.compile(r'<figure class="nfarm-figure" id="fig-(?P<name>[^"]+)".*?<b>Figure (?P<number>\d+\.\d+)\.</b>', re.S)
_NUMBERED_TABLE = re.compile(r'\A<a id="tbl-(?P<name>[^"]+)"></a>\s*\*\*Table (?P<number>\d+\.\d+)\.\*\*')


def numbered_outputs(executed: Path) -> dict[tuple[str, str], str]:
    """The figures and tables an executed chapter numbers, by kind and the name each is saved
    under: ``{("Figure", "06_ik_curves"): "6.2", …}`` (:mod:`nfarm.presentation.numbering`)."""
    import nbformat

    found = {}
    for cell in nbformat.read(executed, 4).cells:
        for output in cell.get("outputs", []) if cell.cell_type == "code" else []:
            data = output.get("data", {})
            for kind, pattern, text in (("Figure", _NUMBERED_FIGURE, data.get("text/html", "")),
                                        ("Table", _NUMBERED_TABLE, data.get("text/markdown", ""))):
                match = pattern.search(text) if isinstance(text, str) else None
                if match:
                    found.setdefault((kind, html.unescape(match.group("name"))), match.group("number"))
    return found


def numbered_equations(executed: Path, letter: str = "") -> dict[str, str]:
    """The display equations a chapter numbers, by name: ``{"lm-step": "(S2.2)", …}``, in the
    order they stand in its Markdown (:func:`nfarm.presentation.numbering.equations`); none for a
    notebook that is not a chapter (``NN_…``)."""
    import nbformat

    from ..presentation.numbering import equations

    if not executed.name[:2].isdigit():
        return {}
    cells = nbformat.read(executed, 4).cells
    try:
        names = equations(c.source for c in cells if c.cell_type == "markdown")
    except ValueError as exc:
        raise ReportError(f"{executed.name}: {exc}") from None
    return {name: f"({letter}{int(executed.name[:2])}.{k})" for k, name in enumerate(names, 1)}


def _tag_equations(nb, numbers: Mapping[str, str]) -> None:
    """Each labelled display equation of ``nb``'s Markdown shown with its number (MathJax's
    ``\\tag``) after an anchor (``eq-<name>``) that citations link to."""
    from ..presentation.numbering import EQUATION

    def tagged(match: re.Match) -> str:
        name = match.group("name")
        return (f'<a id="eq-{name}"></a>\n\n$${match.group("before")}{match.group("after")}'
                f'\\tag{{{numbers[name].strip("()")}}}$$')
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            cell.source = EQUATION.sub(tagged, cell.source)


def citable(numbered: Mapping[tuple[str, str], tuple[str, str]]) -> dict[str, tuple[str, str]]:
    """Each citation key prose may write (:func:`nfarm.presentation.numbering.citation_keys`) ->
    the text and address of what it names, from ``numbered``: ``(kind, name)`` -> (text, address)."""
    from ..presentation.numbering import citation_keys

    return {key: numbered[item] for key, item in citation_keys(numbered).items()}


def resolve_citations(body: str, refs: Mapping[str, tuple[str, str]], where: str) -> str:
    """``body`` (a page) with each citation :data:`nfarm.presentation.numbering.CITATION_HTML` made a
    link: ``refs`` maps a citation key to its text ("Figure S6.2") and address
    ("06_anfis_training.html#fig-06_ik_curves"), as :func:`citable` makes it.

    Raises:
        ReportError: ``"<where>: cites <name>, which no chapter of this edition shows"``.
    """
    from ..presentation.numbering import CITATION_HTML, EQ_CITATION_HTML

    def linker(prefix: str, missing: str):
        """A citation's link: ``refs[prefix + name]``; one line naming the citation where it has none."""
        def link(match: re.Match) -> str:
            name = html.unescape(match.group("name"))
            if prefix + name not in refs:
                raise ReportError(f"{where}: cites {missing.format(name=name)}")
            text, href = refs[prefix + name]
            return f'<a href="{html.escape(href, quote=True)}">{html.escape(text)}</a>'
        return link
    body = CITATION_HTML.sub(linker("", "{name}, which no chapter of this edition shows as a numbered figure or table"),
                             body)
    return EQ_CITATION_HTML.sub(linker("eq:", "equation {name}, which no chapter of this edition numbers"), body)


_SECTION = re.compile(r'<h([23]) id="([^"]+)">(.*?)<a class="anchor-link"', re.S)


def _contents(body: str) -> str:
    """The page with a table of contents under its title: a link to each section (``h2``) and
    subsection (``h3``) nbconvert gave an anchor, in order; the page unchanged if it has none."""
    sections = _SECTION.findall(body)
    if not sections:
        return body
    items = "".join(f'<li class="toc{level}"><a href="#{anchor}">{text.strip()}</a></li>'
                    for level, anchor, text in sections)
    toc = f'<nav class="nfarm-toc" aria-label="contents"><b>Contents</b><ul>{items}</ul></nav>'
    return re.sub(r"(</h1>)", lambda m: m.group(1) + toc, body, count=1)


def export_html(executed: Path, target: Path, nav: str = "", mathjax: str = MATHJAX,
                title: str = "", arm: str = "", fold_code: bool = False, letter: str = "",
                contents: bool = False, refs: Mapping[str, tuple[str, str]] | None = None) -> None:
    """The executed notebook as an HTML page: cells tagged ``remove-input`` show only their
    output (prose computed in code), ``remove-cell`` nothing; MathJax from the report
    directory; a navigation bar between chapters; one parameters cell with the run's values
    (:func:`_merge_parameters`); the heading naming ``arm`` when given; with ``fold_code``,
    every code cell's input folded under "show code" (:data:`PAGE_TEMPLATE`); the figures'
    numbers after ``letter`` (:func:`edition_letter`), as the PDF numbers them; with ``contents``,
    a table of contents under the title (:func:`_contents`); tables numbered after ``letter`` too,
    and citations of figures and tables (:mod:`nfarm.presentation.numbering`) resolved by ``refs``
    (:func:`resolve_citations`; default: this page's own). Nothing is loaded from elsewhere."""
    import nbformat
    from jinja2 import DictLoader
    from nbconvert import HTMLExporter
    from nbconvert.preprocessors import TagRemovePreprocessor
    from traitlets.config import Config

    config = Config()
    config.TagRemovePreprocessor.remove_input_tags = {"remove-input"}
    config.TagRemovePreprocessor.remove_cell_tags = {"remove-cell"}
    config.TagRemovePreprocessor.enabled = True
    exporter = HTMLExporter(template_name="lab", config=config, mathjax_url=mathjax,
                            require_js_url="", jquery_url="", widget_renderer_url="",
                            extra_loaders=[DictLoader({"nfarm-page.html.j2": PAGE_TEMPLATE})],
                            template_file="nfarm-page.html.j2",
                            # the study edition reads as a text: no "In [5]:"/"Out[5]:" prompts
                            exclude_input_prompt=fold_code, exclude_output_prompt=fold_code)
    exporter.register_preprocessor(TagRemovePreprocessor(config=config), enabled=True)
    # Figures carry their captions as alternative text (nfarm.presentation.plotting.save_figure); an image
    # shown without one gets nbconvert's generic text and a warning, which the check of the
    # smoke report (tests/test_pages.py) turns into a failure.
    quiet = DropMessage("Alternative text is missing")
    exporter.log.addFilter(quiet)
    try:
        nb = nbformat.read(executed, 4)
        equations = numbered_equations(executed, letter)
        _tag_equations(nb, equations)
        _merge_parameters(nb)
        if fold_code:
            _parameters_table(nb)
        if arm:
            _name_the_arm(nb, arm)
        body, _ = exporter.from_notebook_node(nb, resources={"metadata": {"name": title or executed.stem},
                                                                 "nfarm_fold_code": fold_code})
    finally:
        exporter.log.removeFilter(quiet)
    body = body.replace('<script src=""></script>', "")       # the URLs switched off above
    if letter:
        body = _FIGURE_NUMBER.sub(lambda m: f"<b>Figure {letter}{m.group(1)}.</b>", body)
        body = _TABLE_NUMBER.sub(lambda m: f"<strong>Table {letter}{m.group(1)}.</strong>", body)
    if refs is None:                 # the page's own figures, tables and equations
        refs = citable({(kind, name): (f"{kind} {letter}{number}", f"#{anchor(kind, name)}")
                        for (kind, name), number in numbered_outputs(executed).items()})
        refs.update({f"eq:{name}": (number, f"#eq-{name}") for name, number in equations.items()})
    body = resolve_citations(body, refs, executed.name)
    if contents:
        body = _contents(body)
    if nav:
        body = re.sub(r"(<body[^>]*>)", lambda m: m.group(1) + nav, body, count=1)
        body = body.replace("</body>", nav + "</body>", 1)
    with atomic_path(target) as tmp:
        tmp.write_text(body, encoding="utf-8")


def _csv_to_html(path: Path) -> str:
    rows = list(csv.reader(path.read_text(encoding="utf-8").splitlines()))
    head = "".join(f"<th>{html.escape(c)}</th>" for c in rows[0])
    body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>"
                   for row in rows[1:])
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _caption(path: Path) -> str:
    """A figure's caption (its PNG ``Description``) or a table's (the first line of its .md)."""
    if path.suffix == ".png":
        from PIL import Image

        with Image.open(path) as image:
            return image.text.get("Description", "")
    md = path.with_suffix(".md")
    if md.is_file():
        first = md.read_text(encoding="utf-8").split("\n", 1)[0]
        if first.startswith("*") and first.endswith("*"):
            return first.strip("*")
    return ""


_STYLE = """body{font-family:sans-serif;max-width:70em;margin:2em auto;padding:0 1em;color:#222}
img{max-width:100%;border:1px solid #ddd;margin:.5em 0}
table{border-collapse:collapse;margin:.5em 0 1.5em;font-size:.9em}
td,th{border:1px solid #ccc;padding:.2em .6em;text-align:right}th{background:#f3f3f3}
h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}
figure{margin:1em 0 2em}figcaption{color:#444;margin:.2em 0}.file{color:#888;font-size:.8em}
dl{display:grid;grid-template-columns:max-content auto;gap:.2em 1em}dt{font-weight:bold}
.reproduce{border:1px solid #ccc;background:#fafafa;padding:.5em 1em;margin:1em 0}.reproduce dd{word-break:break-all}"""


def _git(*args: str) -> str:
    try:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                              timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""


# --------------------------------------------------------------------------------------------
# The index


def _figures_html(figures_dir: Path, subdir: str, prefix: str, shown: Path) -> list[str]:
    parts = []
    for path in chapter_files(figures_dir / subdir, prefix):
        if path.suffix == ".md":
            continue
        rel = path.relative_to(figures_dir)
        caption = html.escape(_caption(path))
        label = f"<span class='file'>{html.escape(rel.as_posix())}</span>"
        (shown / rel).parent.mkdir(parents=True, exist_ok=True)
        if not (shown / rel).is_file():
            shutil.copyfile(path, shown / rel)
        if path.suffix == ".png":
            parts.append(f"<figure><img src='figures/{rel.as_posix()}' alt='{caption}'>"
                         f"<figcaption>{caption} {label}</figcaption></figure>")
        else:
            link = f"<a class='file' href='figures/{html.escape(rel.as_posix())}'>{html.escape(rel.as_posix())}</a>"
            parts.append(f"<figure><figcaption>{caption} {link}</figcaption>"
                         f"{_csv_to_html(path)}</figure>")
    return parts


#: The dissertation this study reproduces (``docs/STUDY.md``), its title in Russian and in English.
DISSERTATION_TITLE = ("Модели, алгоритмы и комплекс программ для моделирования манипуляторов на основе "
                      "архитектуры адаптивной нейро-нечеткой системы вывода и обучающих алгоритмов")
DISSERTATION_TITLE_EN = ("Models, algorithms and a software package for modelling manipulators based on "
                         "the architecture of an adaptive neuro-fuzzy inference system and learning "
                         "algorithms")
ABSTRACT_QUESTION = (
    "Can adaptive neuro-fuzzy inference systems (ANFIS), trained with Jang's hybrid rule on data generated "
    "from a 5-DOF arm's models — tool poses from the DH forward kinematics of sampled joint configurations, "
    "torques from recursive Newton–Euler and from a simulated measured arm — compute the arm's inverse "
    "kinematics and inverse dynamics, and how do they compare with the exact solutions (Levenberg–Marquardt, "
    "the closed form, Newton–Euler) and with strong baselines given the same inputs and tuning budget?")
ABSTRACT_LIMITS = (
    "The learned inverse kinematics covers one declared region of each arm, where the inverse map is "
    "single-valued (chapter 5); over the full joint ranges it is many-valued and not learnable as one "
    "function. The data are simulated: the rigid-body torques are exact, and the measured arm is a model — "
    "links off their nominal parameters, friction whose law no learner assumes, torques read from a "
    "simulated motor current — not a real arm. The dissertation's text does not give its robot's numbers, data "
    "settings, rule bases or budgets: those designs are assumed and labelled so (the deviations table of "
    "chapter 5). Comparisons made on validation data are spread over the seeds (draws of the data and of the "
    "initialisation) of every finalist; results on held-out data carry bootstrap intervals over the held-out poses "
    "or trajectories, and the verdict's pool every seed's model, resampled with the held-out units (a two-level "
    "bootstrap).")


#: What this report can and cannot compare with the dissertation: the index and the PDF say it first.
ABSTRACT_FRAMING = (
    "This is a re-implementation of the dissertation's study under stated assumptions, not a replication of its "
    "numbers. The source we have (docs/STUDY.md) is an OCR text of its introduction, its table of contents, the "
    "first part of its chapter 1, its bibliography and fragments of its program's MATLAB code: it names the methods — "
    "a DH model of a 5-DOF arm, Levenberg–Marquardt IK, recursive Newton–Euler ID, ANFIS trained by Jang's hybrid "
    "rule — but holds none of chapters 2–4: no robot parameters, no data settings or training budgets, and no "
    "tables of results. So what can be compared with a published number is the "
    "ANFIS engine itself, on Jang's three benchmarks beside his results (chapter 4); every result for the arms — "
    "the errors, the comparisons with other learners and the verdict below — is this study's own, on assumed arms "
    "and designs labelled \"(assumed)\" where they are ours, and cannot say whether the dissertation's own figures "
    "would be met.")

#: What the abstract's intervals and comparisons are (:func:`abstract_answers`), as the index and the PDF say it.
ANSWERS_KIND = ("on held-out data; a method chapter 6 trained over several seeds pooled over them, with a two-level 95 % "
                "bootstrap interval over the seeds and the test poses or trajectories; a method trained once, or exact, "
                "with its interval over the test units alone, marked so; every comparison on the paired interval of the two methods' "
                "difference on the same poses or trajectories, seed by seed where either has several (a method with one model "
                "beside each of the other's seeds)")


def abstract_answers(figures_dir: Path, arms: list[Edition]) -> list[str]:
    """Each arm's answers, read from its published ``07_summary.csv`` and its comparisons from
    ``07_paired.csv`` (chapter 07's section 7.7: every method pooled over the seeds chapter 06
    trained it on; every number computed by chapter 07; :func:`nfarm.study.summary.abstract_lines`):
    what the HTML index and the PDF both print. A table an older chapter 07 wrote (or none of
    its paired differences) gives one line saying so, not a failure."""
    from ..study.summary import abstract_lines, read_long_table, read_paired

    answers = []
    for edition in arms:
        tables = figures_dir / edition.subdir / "tables"
        path, paired = tables / "07_summary.csv", tables / "07_paired.csv"
        if path.is_file():
            try:
                answers += abstract_lines(edition.name, read_long_table(path),
                                          read_paired(paired) if paired.is_file() else [])
            except (ValueError, KeyError) as exc:
                answers.append(f"{edition.name}: no answers ({exc}); rerun chapter 7.")
    return answers


def verdict_rows(figures_dir: Path, arms: list[Edition]) -> list[dict[str, str]]:
    """Every arm's verdict rows, read from its published ``07_verdict.csv`` (chapter 07;
    :func:`nfarm.study.summary.verdict_table`), in the arms' order; an arm without one, or with a
    table an older chapter 07 wrote, adds none."""
    from ..study.summary import read_verdicts

    rows = []
    for edition in arms:
        path = figures_dir / edition.subdir / "tables" / "07_verdict.csv"
        if path.is_file():
            try:
                rows += read_verdicts(path)
            except ValueError:
                continue
    return rows


def warm_start_rows(figures_dir: Path, arms: list[Edition]) -> dict[str, list[dict[str, str]]]:
    """Every arm's table of LM from each start (chapter 07's ``07_ik_warm_start.csv``), by the
    arm's name, for :func:`nfarm.study.summary.conclusion`; an arm without one adds none."""
    from ..study.summary import read_warm_starts

    out = {}
    for edition in arms:
        path = figures_dir / edition.subdir / "tables" / "07_ik_warm_start.csv"
        if path.is_file():
            try:
                out[edition.name] = read_warm_starts(path)
            except ValueError:
                continue
    return out


def _verdict_html(rows: list[dict[str, str]], warm: dict[str, list[dict[str, str]]] | None = None) -> list[str]:
    """The verdict table and the conclusion (:func:`nfarm.study.summary.conclusion`) as HTML."""
    from ..study.summary import VERDICT_HEAD, conclusion, verdict_display

    if not rows:
        return ["<p><b>Verdict.</b> Not yet computed: chapter 7 has not published its verdict table.</p>"]
    head, body = VERDICT_HEAD, verdict_display(rows)
    table = ("<table><thead><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr></thead><tbody>"
             + "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>" for row in body)
             + "</tbody></table>")
    return ["<h2 id='verdict'>Verdict</h2>",
            "<p>For each task and arm, on held-out data: the best of the methods compared, the ANFIS's best and its "
            "rank, its difference from the best other method with the paired interval (no difference is shown where the "
            "interval holds 0, or where Holm's correction over the arm's comparisons leaves the difference's bootstrap "
            "p-value at 0.05 or above; each value pooled over the seeds of its training and the test units, the interval "
            "a two-level bootstrap over both, coarse over five seeds) and the study's targets met (each arm's <code>tables/07_verdict.csv</code>; the targets in "
            "<code>docs/STUDY.md</code>).</p>", table,
            "<p>" + " ".join(html.escape(sentence) for sentence in conclusion(rows, warm)) + "</p>"]


def _history_html(arms: Sequence[Edition], figures_dir: Path) -> list[str]:
    """The verdict's history (:func:`nfarm.publishing.history.verdict_history`): per arm and task,
    its verdict and gap on every test split the study has read, oldest first."""
    from .history import verdict_history

    if Path(figures_dir).resolve() != FIGURES.resolve():   # a smoke or custom run's verdict is not a split read
        return []
    rows = verdict_history(arms, figures_dir)
    if not rows:
        return []
    splits = list(dict.fromkeys(r.split for r in rows))
    cells: dict[tuple[str, str], dict[str, str]] = {}
    for r in rows:
        cells.setdefault((r.arm, r.task), {})[r.split] = f"{r.verdict}, {r.gap} {r.unit} ({r.commit})"
    head = ["arm", "task"] + [f"test_seed {split}" if split[:1].isdigit() else split for split in splits]
    body = [[arm, task] + [by.get(split, "—") for split in splits] for (arm, task), by in cells.items()]
    table = ("<table><thead><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr></thead><tbody>"
             + "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>" for row in body)
             + "</tbody></table>")
    return ["<h2 id='history'>Appendix: the verdict on every test split read</h2>",
            f"<p>The study drew its test split {len(splits)} times and changed choices after each read "
            "(<code>docs/STUDY.md</code>, \"the final test set\", says what changed after each): each task's verdict "
            "and gap (ANFIS − best other, with its interval) on every split, as the last commit that published it "
            "(in parentheses; \"now\": this report's) wrote them, read from the repository's history. A task's "
            "metric changed where its unit did.</p>", table]


def _abstract_html(figures_dir: Path, arms: list[Edition]) -> list[str]:
    """The verdict (:func:`verdict_rows`), then the abstract: the study's question, each arm's
    answers (:func:`abstract_answers`) and the study's limits."""
    parts = [f"<p><b>What this is.</b> {html.escape(ABSTRACT_FRAMING)}</p>"]
    parts += _verdict_html(verdict_rows(figures_dir, arms), warm_start_rows(figures_dir, arms))
    parts += ["<h2 id='abstract'>Abstract</h2>", f"<p><b>Question.</b> {html.escape(ABSTRACT_QUESTION)}</p>"]
    answers = abstract_answers(figures_dir, arms)
    if answers:
        parts.append(f"<p><b>Answers</b> ({html.escape(ANSWERS_KIND)}; from each arm's "
                     "<code>tables/07_summary.csv</code> and <code>tables/07_paired.csv</code>):</p><ul>")
        parts += [f"<li>{html.escape(line)}</li>" for line in answers]
        parts.append("</ul>")
    else:
        parts.append("<p><b>Answers.</b> Not yet computed: chapter 7 has not published its summary table.</p>")
    parts.append(f"<p><b>Limits.</b> {html.escape(ABSTRACT_LIMITS)}</p>")
    return parts


def _copy_published(figures_dir: Path, shown: Path) -> bool:
    """Copy the published files ``MANIFEST.sha256`` lists, and the manifest, into ``shown`` (the
    report's own ``figures/``): the report folder holds every figure and table it names, and
    ``sha256sum -c MANIFEST.sha256`` checks them there. Whether there was a manifest."""
    manifest = figures_dir / "MANIFEST.sha256"
    if not manifest.is_file():
        return False
    for line in manifest.read_text(encoding="utf-8").splitlines():
        _, sep, name = line.partition("  ")
        source = figures_dir / name
        if not sep or not source.is_file() or ".." in Path(name).parts:
            continue
        (shown / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(source, shown / name)
    shutil.copyfile(manifest, shown / "MANIFEST.sha256")
    return True


def machine() -> str:
    """The machine's CPU model and the cores this process may use."""
    model = ""
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace").splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import platform

    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    return f"{model or platform.processor() or platform.machine() or 'unknown CPU'}, {cores} core{'s' if cores != 1 else ''}"


def _reproduce_html(commit: str, clean_build: Mapping | None = None) -> str:
    """The index's "reproduce" box: the commit, the command, the lock's SHA-256, the machine and
    the time of the last clean build in this build directory (``clean_build``, as
    :func:`nfarm.publishing.report.build_report` records it), if one was made here."""
    import hashlib

    lock = ROOT / "environment.lock"
    lock_hash = hashlib.sha256(lock.read_bytes()).hexdigest() if lock.is_file() else "no environment.lock"
    rows = {"commit": commit, "command": "make setup && make report",
            "environment.lock SHA-256": lock_hash, "machine": machine()}
    if clean_build:
        minutes, seconds = divmod(round(float(clean_build["seconds"])), 60)
        rows["clean build"] = (f"{minutes} min {seconds} s for every chapter, every data set, model and sweep cell "
                               f"made (set-up excluded), on {clean_build['machine']}, commit {clean_build['commit']}, "
                               f"{clean_build['finished']}")
    else:
        rows["clean build"] = "not made in this build directory (docs/performance.md: the times measured)"
    return ("<div class='reproduce'><b>Reproduce</b><dl>"
            + "".join(f"<dt>{html.escape(k)}</dt><dd><code>{html.escape(v)}</code></dd>" for k, v in rows.items())
            + "</dl><p>Every chapter reads its inputs from this commit; <code>make report</code> reruns them "
              "with the locked environment and writes this folder (<code>build/report/</code>). The machine "
              "above built this folder; the timings a page quotes were measured where its chapter ran.</p></div>")


def _write_index(report_dir: Path, figures_dir: Path,
                 pages: dict[str, list[tuple[str, str, str]]], arms: list[Edition],
                 compared: list[tuple[str, str, str]], *, parameters: dict, smoke: bool,
                 recordings_dir: Path | None = None, clean_build: Mapping | None = None) -> None:
    """``pages``: per edition name, (prefix, title, page path) of its chapters in order;
    ``compared``: the same for the chapters comparing the editions. Each edition's section
    links the rerun recordings its chapters wrote (:data:`RECORDINGS`, an edition's in its own
    subdirectory) when ``recordings_dir`` holds any."""
    shown = report_dir / "figures"
    if shown.exists():
        shutil.rmtree(shown)
    if (report_dir / "recordings").exists():
        shutil.rmtree(report_dir / "recordings")
    commit = _git("rev-parse", "--short=12", "HEAD") or "unknown"
    dirty = " (with uncommitted changes)" if _git("status", "--porcelain") else ""
    when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    kind = "smoke run (small parameters: not the published results)" if smoke else \
        "published results (default parameters)" if not parameters else "a run with other parameters"
    robots = "; ".join(f"{e.name}: {e.robot_file or 'the chapters’ default'}"
                       + ("" if e.primary else f" (figures in {e.name}/)") for e in arms)
    facts = {"what": kind, "arms": robots,
             "parameters": ", ".join(f"{k} = {v!r}" for k, v in parameters.items()) or "defaults",
             "commit": commit + dirty, "built": when,
             "figures": shown_path(figures_dir) + " (checked by MANIFEST.sha256)"}
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>nfarm — study report"
             f"</title><style>{_STYLE}</style></head><body><h1>nfarm — a 5-DOF arm modelled with "
             "numerical methods and ANFIS</h1>",
             f"<p>A reproduction, as software, of Tu Rain (Ту Раин), <i>{html.escape(DISSERTATION_TITLE_EN)}</i> "
             f"(«{html.escape(DISSERTATION_TITLE)}»), Candidate of Sciences dissertation, Belgorod State National "
             "Research University, 2023 — and a test of its answer.</p>"]
    if (report_dir / PAPER_NAME).is_file():
        parts.append(f"<p><a href='{PAPER_NAME}'>The whole study as one PDF</a> (every chapter of both "
                     "editions, without code, with a references list)</p>")
    parts += _abstract_html(figures_dir, arms)
    parts.append(_reproduce_html(commit + dirty, clean_build))
    has_manifest = _copy_published(figures_dir, shown)
    if has_manifest:
        facts["figures"] = (shown_path(figures_dir) + ", copied into this folder's figures/ "
                            "(checked by figures/MANIFEST.sha256)")
    parts.append("<dl>")
    parts += [f"<dt>{html.escape(k)}</dt><dd>{html.escape(v)}</dd>" for k, v in facts.items()]
    parts.append("</dl>")

    def own(edition: Edition, page: str) -> bool:
        return page.startswith(edition.subdir + "/") if edition.subdir else "/" not in page

    def anchor(edition: Edition, entry: tuple[str, str, str]) -> str:
        if entry in compared:
            return f"ch{entry[0]}"
        return f"{(edition if own(edition, entry[2]) else arms[0]).name}-ch{entry[0]}"

    def read_at(edition: Edition, entry: tuple[str, str, str]) -> str:
        """A shared chapter is read in the edition's copy, whose navigation stays in the edition."""
        if entry in compared or not edition.subdir or own(edition, entry[2]):
            return entry[2]
        return f"{edition.subdir}/{Path(entry[2]).name}"

    for edition in arms:
        entries = pages.get(edition.name, [])
        if entries:
            parts.append(f"<h2 id='{html.escape(edition.name)}'>Chapters for {html.escape(edition.name)}"
                         f"{' (the dissertation’s arm)' if edition.primary else ''}</h2><ol>")
            parts += [f"<li value='{int(e[0])}'><a href='{html.escape(str(read_at(edition, e)))}'>{html.escape(e[1])}</a> · <a "
                      f"href='#{anchor(edition, e)}'>its figures and tables</a>"
                      f"{'' if own(edition, e[2]) or e in compared else ' (the same for every arm)'}"
                      f"</li>" for e in entries]
            parts.append("</ol>")
            found = sorted((recordings_dir / edition.subdir).glob("*.rrd")) if recordings_dir else []
            copied = []
            for f in found:                          # inside the report folder, linked relatively
                inside = report_dir / "recordings" / edition.subdir / f.name
                inside.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(f, inside)
                copied.append(inside)
            if copied:
                parts.append("<p>Rerun recordings: " + ", ".join(
                    f"<a href='{html.escape(f.relative_to(report_dir).as_posix())}'>{html.escape(f.name)}</a>"
                    for f in copied) + f" (open one with <code>.venv/bin/rerun "
                    f"{html.escape(copied[0].relative_to(report_dir).as_posix())}</code> in this folder)</p>")
    # The works the chapters cite ("Jang 1993", "Sugihara 2011", …), the dissertation among them
    parts.append("<h2 id='references'>References</h2>")
    parts.append(references_html())
    # The appendix: every chapter's figures and tables, the arms side by side first
    parts += _history_html(arms, figures_dir)
    parts.append("<h2 id='appendix'>Appendix: every chapter's figures and tables</h2>")
    for prefix, title, page in compared:
        parts.append(f"<h3 id='ch{prefix}'>{html.escape(title)}</h3>"
                     f"<p><a href='{html.escape(str(page))}'>The chapter in full</a></p>")
        parts += _figures_html(figures_dir, "", prefix, shown)
    for edition in arms:
        for entry in pages.get(edition.name, []):
            prefix, title, page = entry
            if entry in compared or not own(edition, page):
                continue
            parts.append(f"<h3 id='{html.escape(edition.name)}-ch{prefix}'>{html.escape(edition.name)} · "
                         f"{html.escape(title)}</h3><p><a href='{html.escape(str(page))}'>The chapter in full "
                         f"(prose, code and results)</a></p>")
            parts += _figures_html(figures_dir, edition.subdir, prefix, shown)
    parts.append("</body></html>\n")
    with atomic_path(report_dir / "index.html") as tmp:
        tmp.write_text("\n".join(parts), encoding="utf-8")


@dataclass(frozen=True)
class ReportPages:
    """What :func:`write_pages` writes the pages of a report run from.

    Attributes:
        chapters: every chapter notebook (the sources ``NN_*.ipynb``), in order.
        runs: per notebook file name, the editions it was run for, in order (none: not run).
        comparing: the notebook file names of the chapters that compare the editions.
        arms: the run's editions, the primary first.
        executed_dir: where the executed notebooks are (an edition's under its ``subdir``).
        report_dir: where the pages go.
        figures_dir: the published figures and tables the index shows.
        parameters: the run's parameters other than the defaults (the index names them).
        smoke: a smoke run (the index says so).
        recordings_dir: the rerun recordings the index links, or ``None``.
        clean_build: the last clean build in this build directory (its seconds, machine, commit
            and when it finished), or ``None``.
    """

    chapters: tuple[Path, ...]
    runs: Mapping[str, tuple[Edition, ...]]
    comparing: frozenset[str]
    arms: tuple[Edition, ...]
    executed_dir: Path
    report_dir: Path
    figures_dir: Path
    parameters: Mapping[str, object]
    smoke: bool
    recordings_dir: Path | None = None
    clean_build: Mapping | None = None


def write_pages(report: ReportPages) -> None:
    """HTML pages of every executed chapter, with navigation within each arm's chapters, and
    the index."""
    arms, comparing, report_dir = report.arms, report.comparing, report.report_dir
    pages: dict[str, list[tuple[str, str, str]]] = {}
    compared = []
    per_arm = set()              # chapters run for more than one arm: their titles name it
    for nb in report.chapters:
        runs = report.runs.get(nb.name, ())
        if len(runs) > 1:
            per_arm.add(nb.name[:2])
        for arm in runs:
            executed = report.executed_dir / arm.subdir / nb.name
            if not executed.exists():
                continue
            entry = (nb.name[:2], chapter_title(nb), f"{arm.subdir}/{nb.stem}.html".lstrip("/"))
            if arm.primary and nb.name in comparing:
                compared.append(entry)
            pages.setdefault(arm.name, []).append(entry)
    primary = pages.get(arms[0].name, []) if arms else []
    for arm in arms:
        own = pages.get(arm.name, [])
        if not arm.primary:                   # the shared chapters, read in the primary's pages
            shared = [e for e in primary if e[0] not in {o[0] for o in own} and e not in compared]
            own = sorted(own + shared)
        pages[arm.name] = own

    def copies(arm) -> list[str]:
        """The edition's pages as its reader opens them: a shared chapter is copied into the
        edition's directory with the edition's navigation, so "previous" and "next" never leave it."""
        return [f"{arm.subdir}/{Path(page).name}" if arm.subdir else page for _, _, page in pages[arm.name]]

    for arm in arms:
        own, here = pages[arm.name], copies(arm)
        up = "../" if arm.subdir else ""      # an edition's pages are one directory down
        numbered = {}                         # what the edition's prose may cite, and where it is
        for (prefix, _, source), shown_at in zip(own, here):
            executed = report.executed_dir / source.replace(".html", ".ipynb")
            letter = edition_letter(arm) if prefix in per_arm else ""
            for (kind, name), number in (numbered_outputs(executed) if executed.exists() else {}).items():
                numbered.setdefault((kind, name), (f"{kind} {letter}{number}",
                                                   f"{Path(shown_at).name}#{anchor(kind, name)}"))
        refs = citable(numbered)
        for (prefix, _, source), shown_at in zip(own, here):
            executed = report.executed_dir / source.replace(".html", ".ipynb")
            letter = edition_letter(arm) if prefix in per_arm else ""
            for name, number in (numbered_equations(executed, letter) if executed.exists() else {}).items():
                refs.setdefault(f"eq:{name}", (number, f"{Path(shown_at).name}#eq-{name}"))
        for k, (prefix, title, page) in enumerate(own):
            # An edition's last chapter leads on to the chapter that compares the arms (one page,
            # the primary's), which the reader of every edition meets last; that page leads back
            # to each edition's last chapter.
            last = (up + compared[0][2], compared[0][1]) if compared and not arm.primary else None
            links = {"index": (up + "index.html", "all chapters"),
                     "previous": (up + here[k - 1], own[k - 1][1]) if k > 0 else None,
                     "next": (up + here[k + 1], own[k + 1][1]) if k + 1 < len(own) else last}
            if (prefix, title, page) in compared and k > 0 and len(arms) > 1:
                del links["previous"]
                for other in arms:
                    theirs = [e for e in pages[other.name] if e not in compared]
                    if theirs:
                        links[f"previous ({other.name})"] = (copies(other)[pages[other.name].index(theirs[-1])],
                                                             theirs[-1][1])
                links["next"] = links.pop("next")
            if prefix in per_arm:       # the same chapter in the other editions
                for other in arms:
                    if other is not arm and any(e[0] == prefix for e in pages[other.name]):
                        j = next(i for i, e in enumerate(pages[other.name]) if e[0] == prefix)
                        links[f"{other.name} edition"] = (up + copies(other)[j], title)
            executed = report.executed_dir / page.replace(".html", ".ipynb")
            page = here[k]
            same_for_all = prefix not in per_arm and (prefix, title, own[k][2]) not in compared and len(arms) > 1
            export_html(executed, report_dir / page, _nav(links), mathjax=up + MATHJAX, fold_code=True, contents=True,
                        title=f"{title} · {arm.name}" if prefix in per_arm else
                        f"{title} · the same for every arm" if same_for_all else title,
                        arm=arm.name if prefix in per_arm else "",
                        letter=edition_letter(arm) if prefix in per_arm else "", refs=refs)
    _write_index(report_dir, report.figures_dir, {a.name: pages.get(a.name, []) for a in arms}, list(arms),
                 compared, parameters=dict(report.parameters), smoke=report.smoke,
                 recordings_dir=report.recordings_dir, clean_build=report.clean_build)
