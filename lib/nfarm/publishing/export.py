"""One executed notebook as an HTML page (:func:`export_html`, with nbconvert), as the report's
pages (:mod:`.website`) and the course's teacher edition (:mod:`.course`) show it: the notebook
rewritten for its reader — one parameters cell with the run's values, their table above the
folded code, the heading naming the arm, the display equations numbered — then exported with
captions under its figures, MathJax from a local copy (:func:`install_mathjax`), no input of
hidden cells, the report's with a table of contents, and its numbers and citations resolved
(:mod:`.citations`).
"""

from __future__ import annotations

import json
import os
import re
import shutil
from collections.abc import Mapping
from pathlib import Path

from ..infra.notebook_runs import DropMessage
from ..infra.paths import atomic_path
from ..presentation.numbering import anchor
from .citations import citable, numbered_equations, numbered_outputs, resolve_citations

__all__ = ["COURSE_TAGS", "MATHJAX", "PAGE_TEMPLATE", "chapter_title", "export_html", "install_mathjax"]


def chapter_title(notebook: Path) -> str:
    """The notebook's title: its first Markdown heading ``# …``, or its file's stem if it has none."""
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


_FIGURE_NUMBER = re.compile(r"<b>Figure (\d+\.\d+)\.</b>")
_TABLE_NUMBER = re.compile(r"<strong>Table (\d+\.\d+)\.</strong>")


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
    numbers after ``letter`` (:func:`.citations.edition_letter`), as the PDF numbers them; with ``contents``,
    a table of contents under the title (:func:`_contents`); tables numbered after ``letter`` too,
    and citations of figures and tables (:mod:`nfarm.presentation.numbering`) resolved by ``refs``
    (:func:`.citations.resolve_citations`; default: this page's own). Nothing is loaded from elsewhere."""
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
