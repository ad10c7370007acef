"""The study as one PDF (``build/report/nfarm-study.pdf``): a title page naming the dissertation
reproduced, the abstract, the chapters of every edition from the executed notebooks without
their code (prose, figures, tables and printed results kept), figures and tables numbered per
chapter with their captions, and a references list from ``docs/references.bib``.

The chapters are written as one Markdown document (:func:`paper_markdown`); pandoc (the
``pypandoc-binary`` wheel's binary, with citeproc) turns it into Typst with the references
formatted, and Typst (the ``typst`` wheel's compiler and fonts) sets the PDF. Neither needs the
network. Typst numbers the figures and tables: a chapter's label (``6`` for the primary
edition's chapter 6, ``S6`` for the so101 edition's) followed by the figure's number within it
("Figure 6.2", "Table S7.1"). It numbers what the chapter's page numbers
(:mod:`nfarm.presentation.numbering`): the saved figures and tables, each labelled by its edition
and name; a table the page shows without a number (not saved, or prose's own) is set without a
caption and not counted. A citation in the prose is a Typst reference, which prints the number of
the chapter the figure is in, wherever it is cited.
"""

from __future__ import annotations

import base64
import datetime
import hashlib
import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from ..infra.notebook_runs import ReportError
from ..infra.paths import ROOT, atomic_path
from ..presentation.numbering import citation_keys
from .editions import Edition
from .abstract import (ABSTRACT_FRAMING, ABSTRACT_LIMITS, ABSTRACT_QUESTION, ANSWERS_KIND, DISSERTATION_TITLE,
                       DISSERTATION_TITLE_EN, abstract_answers, verdict_rows, warm_start_rows)
from .build_info import current_commit
from .citations import edition_letter, numbered_equations, numbered_outputs
from .conclusion import VERDICT_HEAD, conclusion, verdict_display
from .export import chapter_title
from .index import PAPER_NAME
from .references import BIBLIOGRAPHY, pandoc_path
from .website import ReportPages

__all__ = ["PAPER_NAME", "BIBLIOGRAPHY", "DISSERTATION", "write_paper", "paper_markdown", "PaperChapter"]

#: The key of the dissertation reproduced in :data:`BIBLIOGRAPHY`.
DISSERTATION = "tu_rain_2023"

#: The dissertation as its title page names it (the Russian title as published; an English rendering).
#: What each part of the study rests on, cited (the front matter's "Sources").
SOURCES = (
    "The arm is described with Denavit–Hartenberg parameters [@denavit_hartenberg_1955], in the standard "
    "or the modified convention [@craig_2005]. Its inverse kinematics is solved by damped least squares, "
    "the Levenberg–Marquardt method [@levenberg_1944; @marquardt_1963] as used for manipulators "
    "[@wampler_1986; @buss_2009; @sugihara_2011]. Its inverse dynamics is the recursive Newton–Euler "
    "algorithm [@luh_walker_paul_1980], checked against Pinocchio [@carpentier_2019]; the dynamics linear "
    "in the inertial parameters is that of @atkeson_an_hollerbach_1986. The learned models are ANFIS "
    "[@jang_1993; @jang_sun_mizutani_1997], trained with Jang's hybrid rule, their rule bases from grid "
    "partitions, fuzzy c-means [@bezdek_1981] or subtractive clustering [@chiu_1994]; the method is "
    "checked on Jang's benchmarks, among them the Mackey–Glass series [@mackey_glass_1977]. Velocities "
    "and accelerations of noisy recordings are estimated with Savitzky–Golay filters "
    "[@savitzky_golay_1964].")

_TYPST_PREAMBLE = r"""
#set document(title: "nfarm — a 5-DOF arm modelled with numerical methods and ANFIS")
#set page(paper: "a4", margin: (x: 2.2cm, y: 2.4cm), numbering: "1")
#set text(size: 10pt, lang: "en")
#set par(justify: true)
#let chap = state("nfarm-chapter", "")
#set figure(numbering: n => context (chap.get() + "." + str(n)))
#show figure.where(kind: table): set block(breakable: true)
#show figure.caption: set text(size: 9pt)
#show table: set text(size: 7pt)
#show raw.where(block: true): set text(size: 7pt)
#show figure.where(kind: table): it => { if it.caption == none { counter(figure.where(kind: table)).update(n => n - 1) }; it }
#show ref: it => {
  let el = it.element
  if el != none and el.func() == figure {
    let loc = el.location()
    link(loc)[#el.supplement~#chap.at(loc).#counter(figure.where(kind: el.kind)).at(loc).first()]
  } else if el != none and el.func() == math.equation {
    let loc = el.location()
    link(loc)[(#chap.at(loc).#counter(math.equation).at(loc).first())]
  } else { it }
}
#show heading.where(level: 1): it => { pagebreak(weak: true); it }
#show heading.where(level: 2): it => { pagebreak(weak: true); it }
"""


@dataclass(frozen=True)
class PaperChapter:
    """One chapter of the PDF: its label (``"6"``, ``"S6"``), title, the edition it belongs to
    and its executed notebook."""

    label: str
    title: str
    edition: str
    executed: Path


def _escape(text: str) -> str:
    """Plain text as Markdown that pandoc reads back as the same text."""
    return re.sub(r"([\\`*_{}\[\]<>#$@|~^])", r"\\\1", text)


def _raw(typst: str) -> str:
    return f"\n```{{=typst}}\n{typst.strip()}\n```\n"


_HEADING = re.compile(r"^(#{1,5})(\s)", re.M)
#: A section's number at the start of its heading ("7.1", "6.2.1"): an edition's letter goes before it.
_SECTION_NUMBER = re.compile(r"^(#{2,6}\s+)(?=\d+(?:\.\d+)+\s)")
_CITATION_LIKE = re.compile(r"(^|[\s\[(;-])@(?=[\w])")


def _prose(markdown: str, labels: dict[str, str] | None = None, where: str = "", letter: str = "") -> str:
    """A notebook's Markdown in the PDF: its headings one level down (a chapter is level 2 in
    its part), their section numbers after the edition's ``letter`` ("S7.1" in a chapter "S7",
    as the outline lists it), no ``@`` read as a bibliography citation (the notebooks cite none), and each
    citation of a figure or table (:data:`nfarm.presentation.numbering.CITATION`) a Typst
    reference to its label in ``labels`` (name -> label).

    Raises:
        ReportError: a citation of a name ``labels`` lacks (``where`` names the chapter).
    """
    from ..presentation.numbering import EQUATION

    def labelled(match: re.Match) -> str:
        key = f"eq:{match.group('name')}"
        if labels is None or key not in labels:
            raise ReportError(f"{where}: equation {match.group('name')} has no label in this edition")
        # Numbered while it is set (an equation without a label is not numbered, as on the page); an
        # empty group before the label: pandoc's TeX reader refuses a label after a bare letter
        return (_raw('#set math.equation(numbering: n => context ("(" + chap.get() + "." + str(n) + ")"))')
                + f"\n$${match.group('before')}{match.group('after')}{{}} \\label{{{labels[key]}}}$$\n"
                + _raw("#set math.equation(numbering: none)"))
    markdown = EQUATION.sub(labelled, markdown)
    out, fenced = [], False
    for line in markdown.split("\n"):
        if line.lstrip().startswith("```"):
            fenced = not fenced
        elif not fenced:
            if letter:
                line = _SECTION_NUMBER.sub(lambda m: m.group(1) + letter, line)
            line = _HEADING.sub(lambda m: "#" + m.group(1) + m.group(2), line)
            line = _CITATION_LIKE.sub(lambda m: m.group(1) + "\\@", line)
            line = _cite(line, labels, where)
        out.append(line)
    return "\n".join(out)


def _cite(text: str, labels: dict[str, str] | None, where: str) -> str:
    """``text`` with each citation of a figure, table or equation a Typst reference to its label
    (:func:`_prose`; an equation's key is ``eq:<name>``)."""
    from ..presentation.numbering import CITATION, EQ_CITATION

    def referrer(prefix: str, missing: str):
        """A citation's Typst reference to ``labels[prefix + name]``; one line naming it where there is none."""
        def reference(match: re.Match) -> str:
            name = match.group("name")
            if labels is None or prefix + name not in labels:
                raise ReportError(f"{where}: cites {missing.format(name=name)}")
            return f"`@{labels[prefix + name]}`{{=typst}}"
        return reference
    text = CITATION.sub(referrer("", "{name}, which no chapter of this edition shows as a numbered figure or table"), text)
    return EQ_CITATION.sub(referrer("eq:", "equation {name}, which no chapter of this edition numbers"), text)


def _label(edition: str, kind: str, name: str) -> str:
    """The PDF's label of a numbered figure or table: unique over the editions."""
    return f"{'fig' if kind == 'Figure' else 'tbl'}-{edition}-{name}"


def _image_width(png: Path, *, widest: int = 90, tallest_cm: float = 11.5, text_cm: float = 16.6) -> int:
    """The width (percent of the text's) that shows a figure whole: most of the text's width, or
    less for a tall one, so that it is at most ``tallest_cm`` high and fits a page with its caption."""
    from PIL import Image

    with Image.open(png) as image:
        width, height = image.size
    return max(30, min(widest, int(100 * tallest_cm * width / height / text_cm)))


_TABLE = re.compile(r'\A\s*(?:<a id="tbl-(?P<name>[^"]+)"></a>\s*\*\*Table [^*\n]+\*\*\s*)?'
                    r"\*(?P<caption>[^\n]+)\*\s*\n\s*\n(?P<table>\|.*)\Z", re.S)
_FIGURE_NAME = re.compile(r'<figure class="nfarm-figure" id="fig-(?P<name>[^"]+)"')


def _chapter_markdown(chapter: PaperChapter, assets: Path, labels: dict[str, str] | None = None) -> str:
    """The chapter's prose and outputs, without code: its first level-1 heading replaced by the
    chapter's; the figures and tables the chapter numbers (:mod:`nfarm.presentation.numbering`)
    captioned and labelled for Typst to number them alike, other tables' captions as text; the
    citations of figures and tables resolved by ``labels`` (name -> label, :func:`_prose`)."""
    import nbformat

    nb = nbformat.read(chapter.executed, 4)
    title = re.sub(r"^Chapter\s+\d+\s*[—–-]\s*", "", chapter.title)
    parts = [f"## Chapter {chapter.label} — {_escape(title)}",
             _raw(f'#chap.update("{chapter.label}")\n'
                  "#counter(figure.where(kind: image)).update(0)\n"
                  "#counter(figure.where(kind: table)).update(0)\n"
                  "#counter(math.equation).update(0)")]
    letter = re.sub(r"\d+$", "", chapter.label)      # "S" of chapter "S7"; "" for the primary edition's
    titled, shown = False, set()
    for k, cell in enumerate(nb.cells):
        tags = set(cell.metadata.get("tags", []))
        if "remove-cell" in tags:
            continue
        if cell.cell_type == "markdown":
            text = cell.source
            if not titled:
                text, n = re.subn(r"^# [^\n]*\n?", "", text, count=1, flags=re.M)
                titled = bool(n)
            parts.append(_prose(text, labels, chapter.executed.name, letter))
            continue
        if cell.cell_type != "code":
            continue
        for j, output in enumerate(cell.get("outputs", [])):
            kind = output.get("output_type")
            if kind == "stream" and output.get("name") == "stdout":
                # Printed results (matrices, rule bases); lines naming build files are the run's, not the study's.
                lines = [ln for ln in output.get("text", "").split("\n") if "build/" not in ln]
                text = "\n".join(lines).strip("\n")
                if text.strip():
                    parts.append("~~~~\n" + text.replace("~~~~", "~ ~ ~ ~") + "\n~~~~")
                continue
            if kind not in ("display_data", "execute_result"):
                continue
            data = output.get("data", {})
            if "image/png" in data:
                name = f"{chapter.edition}-{chapter.label}-{k:03d}-{j}.png"
                (assets / name).write_bytes(base64.b64decode(data["image/png"]))
                plain = data.get("text/plain", "")
                caption = plain[len("Figure: "):] if plain.startswith("Figure: ") else ""
                width = _image_width(assets / name)
                figure = _FIGURE_NAME.search(data.get("text/html", "") or "")
                label = f"#{_label(chapter.edition, 'Figure', figure.group('name'))} " if figure else ""
                if label and label in shown:            # shown again: its number once (as on the page)
                    caption = ""
                shown.add(label)
                if caption:
                    parts.append(f"![{_escape(caption.strip())}](assets/{name}){{{label}width={width}%}}")
                else:                                   # no caption: an image, not a numbered figure
                    parts.append(f"![](assets/{name}){{width={width}%}}\\")
            elif "text/markdown" in data:
                text = data["text/markdown"]
                table = _TABLE.match(text)
                if table and table.group("name") and table.group("name") not in shown:   # numbered: labelled
                    shown.add(table.group("name"))
                    parts.append(table.group("table").rstrip() + "\n\n: "
                                 + _cite(table.group("caption").strip(), labels, chapter.executed.name)
                                 + f" {{#{_label(chapter.edition, 'Table', table.group('name'))}}}")
                elif table:                               # not numbered on the page: not in the PDF either
                    parts.append(f"*{_cite(table.group('caption').strip(), labels, chapter.executed.name)}*\n\n"
                                 + table.group("table").rstrip())
                else:
                    parts.append(_prose(text, labels, chapter.executed.name, letter))
    return "\n\n".join(parts) + "\n"


def _verdict(figures_dir: Path, arms: list[Edition]) -> str:
    """The verdict table and the conclusion, as on the index (:func:`nfarm.publishing.abstract.verdict_rows`)."""
    rows = verdict_rows(figures_dir, arms)
    if not rows:
        return "# Verdict {.unnumbered}\n\nNot yet computed: chapter 7 has not published its verdict table."
    lines = ["| " + " | ".join(VERDICT_HEAD) + " |", "|" + "---|" * len(VERDICT_HEAD)]
    lines += ["| " + " | ".join(_escape(cell) for cell in row) + " |" for row in verdict_display(rows)]
    # Before the chapters: not numbered (a number would have no chapter to belong to), its caption above it
    return ("# Verdict {.unnumbered}\n\n*The verdict on held-out data, per task and arm (each arm's verdict table, "
            "chapter 7)*\n\n" + "\n".join(lines) + "\n\n"
            + " ".join(_escape(sentence) for sentence in conclusion(rows, warm_start_rows(figures_dir, arms))))


#: The long tables, every row of a chapter's results for machines (:func:`nfarm.study.rows.long_table`),
#: whose reading copies the chapters show: the PDF sets them whole in its appendix.
LONG_TABLES = ("07_summary", "08_learned")


def _appendix(figures_dir: Path, arms: list[Edition]) -> str:
    """The PDF's appendix: each of :data:`LONG_TABLES` an edition published, whole, numbered "Table A.k"
    (``""`` where none is published)."""
    tables = []
    for arm in arms:
        for name in LONG_TABLES:
            path = figures_dir / arm.subdir / "tables" / f"{name}.md"
            found = _TABLE.match(path.read_text(encoding="utf-8")) if path.is_file() else None
            if found:
                tables.append(found.group("table").rstrip() + "\n\n: " + _escape(found.group("caption").strip())
                              + f" ({_escape(arm.name)}) {{#tbl-appendix-{arm.name}-{name}}}")
    if not tables:
        return ""
    return "\n\n".join(["# Appendix: the long tables {.unnumbered}",
                         _raw('#chap.update("A")\n#counter(figure.where(kind: table)).update(0)'), *tables])


def _abstract(figures_dir: Path, arms: list[Edition]) -> str:
    answers = abstract_answers(figures_dir, arms)
    parts = [f"**What this is.** {_escape(ABSTRACT_FRAMING)}", _verdict(figures_dir, arms), "# Abstract {.unnumbered}",
             f"**Question.** {_escape(ABSTRACT_QUESTION)}"]
    if answers:
        parts.append(f"**Answers** ({_escape(ANSWERS_KIND)}):")
        parts.append("\n".join(f"- {_escape(line)}" for line in answers))
    parts.append(f"**Limits.** {_escape(ABSTRACT_LIMITS)}")
    parts.append(f"**Sources.** {SOURCES}")
    return "\n\n".join(parts)


def paper_chapters(report: ReportPages) -> list[tuple[str, str, list[PaperChapter]]]:
    """The PDF's parts in order: each edition's chapters (a chapter the same for every arm only
    in the primary's), then the chapters comparing the editions; as (part title, a note, chapters)."""
    parts = []
    primary = [nb for nb in report.chapters if report.arms and report.arms[0] in report.runs.get(nb.name, ())]
    for arm in report.arms:
        letter = edition_letter(arm)
        chapters = []
        for nb in report.chapters:
            if nb.name in report.comparing or arm not in report.runs.get(nb.name, ()):
                continue
            executed = report.executed_dir / arm.subdir / nb.name
            if executed.is_file():
                chapters.append(PaperChapter(f"{letter}{int(nb.name[:2])}", chapter_title(nb), arm.name, executed))
        if chapters:
            what = "the dissertation's arm" if arm.primary else \
                f"its chapters numbered {chapters[0].label}–{chapters[-1].label}"
            shared = [str(int(nb.name[:2])) for nb in primary
                      if nb.name not in report.comparing and arm not in report.runs.get(nb.name, ())]
            note = "" if arm.primary or not shared else (
                f"Chapter{'s' if len(shared) > 1 else ''} {', '.join(shared)}, the same for every arm, "
                f"{'are' if len(shared) > 1 else 'is'} in the {report.arms[0].name} edition.")
            parts.append((f"The {arm.name} edition ({what})", note, chapters))
    compared = [PaperChapter(str(int(nb.name[:2])), chapter_title(nb), "compared", report.executed_dir / nb.name)
                for nb in report.chapters if nb.name in report.comparing
                and (report.executed_dir / nb.name).is_file()]
    if compared:
        parts.append(("The arms compared", "", compared))
    return parts


def paper_markdown(report: ReportPages, assets: Path, *, commit: str = "", built: str = "") -> str:
    """The whole PDF as pandoc Markdown (raw Typst for the title page and the numbering); the
    figures' PNGs are written into ``assets``."""
    kind = "A smoke run (small parameters): not the published results." if report.smoke else \
        "The published results (default parameters)." if not report.parameters else \
        "A run with other parameters: " + ", ".join(f"{k} = {v!r}" for k, v in report.parameters.items()) + "."
    title = _raw(f"""
#align(center)[
  #v(3cm)
  #text(size: 22pt, weight: "bold")[nfarm — a 5-DOF arm modelled with numerical methods and ANFIS]
  #v(1cm)
  #text(size: 13pt)[A reproducible study reproducing the dissertation]
  #v(0.4cm)
  #text(size: 12pt)[Tu Rain (Ту Раин), _{DISSERTATION_TITLE}_]
  #v(0.2cm)
  #text(size: 11pt)[({DISSERTATION_TITLE_EN})]
  #v(0.2cm)
  #text(size: 11pt)[Candidate of Sciences dissertation, Belgorod State National Research University, 2023]
  #v(2cm)
  #text(size: 10pt)[{kind}]
  #v(0.2cm)
  #text(size: 10pt)[Commit {commit or "unknown"} · built {built}]
]
#pagebreak()
#outline(depth: 2)
""")
    body = [title, f"This study reproduces the dissertation of @{DISSERTATION} and extends it with a second arm.",
            _abstract(report.figures_dir, list(report.arms))]
    parts = paper_chapters(report)
    # What each edition's prose may cite: its own chapters' figures and tables, then the shared chapters'
    numbered: dict[str, list[tuple[str, str]]] = {}
    for _, _, chapters in parts:
        for c in chapters:
            numbered.setdefault(c.edition, []).extend(numbered_outputs(c.executed))
    labels = {edition: {key: _label(edition, kind, name) for key, (kind, name) in citation_keys(items).items()}
              for edition, items in numbered.items()}
    for _, _, chapters in parts:                 # and its equations
        for c in chapters:
            labels.setdefault(c.edition, {}).update(
                {f"eq:{name}": f"eq-{c.edition}-{name}" for name in numbered_equations(c.executed)})
    primary = report.arms[0].name if report.arms else ""
    for part, note, chapters in parts:
        body.append(f"# {_escape(part)}")
        if note:
            body.append(_escape(note))
        body += [_chapter_markdown(c, assets, {**labels.get(primary, {}), **labels.get(c.edition, {})})
                 for c in chapters]
    appendix = _appendix(report.figures_dir, list(report.arms))
    if appendix:
        body.append(appendix)
    body.append("# References {.unnumbered}\n\n::: {#refs}\n:::")
    return "\n\n".join(body) + "\n"


_BUILT = "@@built@@"      # the build time's place in the Markdown while its key is taken


def _paper_key(markdown: str, assets: Path, bibliography: Path) -> str:
    """SHA-256 of what the PDF is made of: its Markdown (the build time left out), every figure
    copied beside it, the bibliography, this module (the preamble, the pandoc call) and the
    locked environment (pandoc's and Typst's versions)."""
    h = hashlib.sha256(markdown.encode())
    for path in [*sorted(assets.rglob("*")), bibliography, Path(__file__), ROOT / "environment.lock"]:
        if path.is_file():
            h.update(path.name.encode())
            h.update(path.read_bytes())
    return h.hexdigest()


def write_paper(report: ReportPages, *, commit: str = "", bibliography: Path = BIBLIOGRAPHY) -> Path:
    """Write ``report.report_dir / PAPER_NAME`` (atomically) and return its path. A PDF whose
    inputs (:func:`_paper_key`, stored beside it as ``.paper.sha256``) are unchanged is kept as it
    is, with the build time it states.

    Raises:
        ReportError: pandoc or Typst failed (one line with the tool's message).
    """
    import typst

    target = report.report_dir / PAPER_NAME
    stamp = report.report_dir / ".paper.sha256"
    report.report_dir.mkdir(parents=True, exist_ok=True)
    for stale in report.report_dir.glob(".paper-*"):    # a killed build's work directory
        shutil.rmtree(stale, ignore_errors=True)
    if not commit:
        commit = current_commit()
    built = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    with tempfile.TemporaryDirectory(prefix=".paper-", dir=report.report_dir) as tmp:
        work = Path(tmp)
        (work / "assets").mkdir()
        markdown = paper_markdown(report, work / "assets", commit=commit, built=_BUILT)
        key = _paper_key(markdown, work / "assets", bibliography)
        if target.is_file() and stamp.is_file() and stamp.read_text(encoding="utf-8").strip() == key:
            return target
        markdown = markdown.replace(_BUILT, built)
        (work / "paper.md").write_text(markdown, encoding="utf-8")
        done = subprocess.run(
            [pandoc_path(), "paper.md", "--from", "markdown-auto_identifiers",
             # --columns: no pipe table is "wider than the page" to pandoc, so Typst sizes the columns to their cells
             "--to", "typst", "--columns", "100000", "--citeproc", "--bibliography", str(bibliography),
             "--metadata", "link-citations=true", "--output", "body.typ"],
            cwd=work, capture_output=True, text=True, timeout=600)
        if done.returncode != 0:
            raise ReportError(f"the PDF: pandoc failed: {' '.join(done.stderr.strip().splitlines()[-1:])}")
        unconverted = re.search(r"Could not convert TeX math (.{0,80})", done.stderr)
        if unconverted:                              # never raw TeX in print
            raise ReportError(f"the PDF: pandoc could not convert an equation: {unconverted.group(1)}")
        unresolved = re.findall(r"citation (\S+) not found", done.stderr)
        if unresolved:                               # a citation the bibliography lacks: never "(key?)" in print
            raise ReportError(f"the PDF cites what {BIBLIOGRAPHY.name} lacks: {', '.join(sorted(set(unresolved)))}")
        (work / "paper.typ").write_text(_TYPST_PREAMBLE + (work / "body.typ").read_text(encoding="utf-8"),
                                        encoding="utf-8")
        try:
            pdf = typst.compile(str(work / "paper.typ"), root=str(work))
        except Exception as exc:                     # typst.TypstError: the compiler's diagnostics
            first = str(exc).strip().splitlines()[:3]
            raise ReportError(f"the PDF: Typst failed: {' '.join(first)}") from None
        stamp.unlink(missing_ok=True)               # a PDF without its stamp is never kept
        with atomic_path(target) as out:
            out.write_bytes(pdf)
        with atomic_path(stamp) as out:
            out.write_text(key + "\n", encoding="utf-8")
    return target
