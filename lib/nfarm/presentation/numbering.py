r"""Figures and tables numbered by chapter, and prose that cites them by number.

A chapter's saved figures and tables (:func:`nfarm.presentation.plotting.save_figure`,
:meth:`nfarm.presentation.tables.Table.save`) are numbered in the order a reader first meets
them, figures and tables apart: the third figure chapter 6 shows is "Figure 6.3", its second
table "Table 6.2"; an edition's letter goes before the chapter's number in its pages and in
the PDF ("Figure S6.3", :func:`nfarm.publishing.pages.edition_letter`). A figure or table shown
again keeps its number.

Prose cites one by the name it is saved under, in MyST's role syntax; a name saved both as a
figure and as a table is cited with its kind, ``fig:`` or ``tbl:``::

    The contest's ranking ({numref}`tbl:06_ik_contest`) puts the ANFIS first.

The report resolves the citation to "Table 6.2", linked to the table, in the HTML pages
(:func:`nfarm.publishing.pages.export_html`) and as a Typst reference in the PDF
(:mod:`nfarm.publishing.paper`); a citation of a name no chapter of the edition shows stops the
report with a one-line error. A chapter run by hand shows the citation as written.

**Equations.** A display equation of a chapter's Markdown (``$$ … $$``, on one line) that carries
a label, ``\label{eq:<name>}``, is numbered in the order it stands in the chapter: "(2.1)",
"(S2.1)" in another edition; prose cites it as {eq}`<name>`, resolved to "(2.1)", linked, in
the pages and the PDF alike (:func:`equations`). One without a label is not numbered.

Example:
    >>> clear()
    >>> number("Figure", "06_ik_curves"), number("Figure", "06_ik_rules"), number("Table", "06_ik_models")
    ('6.1', '6.2', '6.1')
    >>> number("Figure", "06_ik_curves"), number("Figure", "arm")      # shown again; no chapter
    ('6.1', None)
    >>> [m.group("name") for m in CITATION.finditer("as {numref}`06_ik_rules` shows")]
    ['06_ik_rules']
    >>> sorted(citation_keys([("Figure", "06_ik_contest"), ("Table", "06_ik_contest"), ("Figure", "06_ik_rules")]))
    ['06_ik_rules', 'fig:06_ik_contest', 'fig:06_ik_rules', 'tbl:06_ik_contest']
    >>> equations(["$$\\Delta q = J^+ e \\label{eq:step}$$", "as {eq}`step` says; $$E = e^2 \\label{eq:error}$$ $$x^2$$"])
    ['step', 'error']
"""

from __future__ import annotations

import re

from ..infra.arguments import check_choice

__all__ = ["number", "clear", "chapter_of", "citation_keys", "anchor", "equations", "CITATION", "CITATION_HTML", "KINDS", "DISPLAY",
           "EQUATION", "EQ_CITATION", "EQ_CITATION_HTML"]

#: What is numbered: figures and tables, each counted apart within a chapter; the prefix of each
#: kind's anchors and citations.
KINDS = {"Figure": "fig", "Table": "tbl"}
#: A citation in Markdown: {numref}`<name>`.
CITATION = re.compile(r"\{numref\}`(?P<name>[^`\s]+)`")
#: The same citation as nbconvert renders it in a page.
CITATION_HTML = re.compile(r"\{numref\}<code>(?P<name>[^<\s]+)</code>")

#: A labelled display equation in Markdown, on one line: ``$$ … \label{eq:<name>} … $$``.
EQUATION = re.compile(r"\$\$(?P<before>[^$\n]*?)\\label\{eq:(?P<name>[\w-]+)\}(?P<after>[^$\n]*)\$\$")
#: Any display equation in Markdown (labelled or not).
DISPLAY = re.compile(r"\$\$.*?\$\$", re.S)
#: A citation of an equation in Markdown, {eq}`<name>`, and as nbconvert renders it in a page.
EQ_CITATION = re.compile(r"\{eq\}`(?P<name>[^`\s]+)`")
EQ_CITATION_HTML = re.compile(r"\{eq\}<code>(?P<name>[^<\s]+)</code>")

_SEEN: dict[tuple[str, str], list[str]] = {}       # (kind, chapter) → names, in the order first shown


def chapter_of(name: str) -> str | None:
    """The chapter a saved name belongs to (``"06"`` for ``"06_ik_curves"``), or ``None``."""
    return name[:2] if name[:2].isdigit() and name[2:3] == "_" else None


def number(kind: str, name: str) -> str | None:
    """The number (``"6.3"``) of the figure or table ``name`` in its chapter, in the order first
    shown in this process (an IPython kernel runs one chapter); ``None`` for a name that is not
    a chapter's (``"NN_…"``)."""
    check_choice("kind", kind, KINDS)
    chapter = chapter_of(name)
    if chapter is None:
        return None
    names = _SEEN.setdefault((kind, chapter), [])
    if name not in names:
        names.append(name)
    return f"{int(chapter)}.{names.index(name) + 1}"


def clear() -> None:
    """Forget every number given (a new chapter in the same process)."""
    _SEEN.clear()


def anchor(kind: str, name: str) -> str:
    """The anchor of a numbered figure or table on its page: ``"fig-06_ik_curves"``."""
    return f"{KINDS[kind]}-{name}"


def citation_keys(items) -> dict[str, tuple[str, str]]:
    """What prose may write in a citation for each ``(kind, name)`` of ``items``: ``"fig:<name>"``
    or ``"tbl:<name>"``, and the bare name where one kind alone has it."""
    items = list(dict.fromkeys(items))
    keys = {f"{KINDS[kind]}:{name}": (kind, name) for kind, name in items}
    bare = [name for _, name in items]
    keys.update({name: (kind, name) for kind, name in items if bare.count(name) == 1})
    return keys


def equations(markdowns) -> list[str]:
    """The names of the labelled display equations in ``markdowns`` (a chapter's Markdown cells,
    in order), in the order they stand: equation ``k`` (from 1) of chapter ``c`` is "(c.k)".

    Raises:
        ValueError: a labelled display equation on more than one line, or a name given twice.
    """
    names: list[str] = []
    for text in markdowns:
        for display in DISPLAY.finditer(text):
            found = EQUATION.fullmatch(display.group(0))
            if not found:
                if "\\label{eq:" in display.group(0):
                    raise ValueError(f"a labelled display equation must stand on one line: {display.group(0)[:80]!r}")
                continue
            if found.group("name") in names:
                raise ValueError(f"equation name {found.group('name')!r} given twice")
            names.append(found.group("name"))
    return names
