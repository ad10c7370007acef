"""What an executed chapter numbers — its figures and tables (:func:`numbered_outputs`) and its
display equations (:func:`numbered_equations`) — and the links its citations of them become
(:func:`citable`, :func:`resolve_citations`), each number after its edition's letter
(:func:`edition_letter`): the same in the HTML pages (:mod:`.export`, :mod:`.website`) and in
the PDF (:mod:`.paper`). The markup a chapter numbers and cites with is
:mod:`nfarm.presentation.numbering`'s.
"""

from __future__ import annotations

import html
import re
from collections.abc import Mapping
from pathlib import Path

from ..infra.notebook_runs import ReportError
from .editions import Edition

__all__ = ["edition_letter", "numbered_outputs", "numbered_equations", "citable", "resolve_citations"]


def edition_letter(edition: Edition) -> str:
    """The letter before an edition's chapter numbers — "" for the primary, the arm's initial for
    the others ("Figure S6.1" in the SO-101's edition) — the same in its HTML pages and the PDF."""
    return "" if edition.primary else edition.name[:1].upper()


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
