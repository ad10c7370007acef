"""The report's HTML pages (:func:`write_pages`): every executed chapter's page
(:func:`nfarm.publishing.export.export_html`), linked to the chapters before and after it within
its edition, to the same chapter in the other editions and to the index; a chapter the same for
every arm copied into each edition's directory; its citations resolved within its edition
(:mod:`.citations`); then the index (:mod:`.index`).
"""

from __future__ import annotations

import html
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from ..presentation.numbering import anchor
from .citations import citable, edition_letter, numbered_equations, numbered_outputs
from .editions import Edition
from .export import MATHJAX, chapter_title, export_html
from .index import write_index

__all__ = ["ReportPages", "write_pages"]


def _nav(links: dict[str, tuple[str, str] | None]) -> str:
    """A page's navigation bar: a link for each of ``links`` (label -> (address, title)) that has one."""
    parts = [f"<a href='{html.escape(href)}'>{html.escape(label)}: {html.escape(title)}</a>"
             for label, link in links.items() if link for href, title in [link]]
    return ("<nav style='font-family:sans-serif;margin:1em 2em;display:flex;gap:2em'>"
            + "".join(parts) + "</nav>")


@dataclass(frozen=True)
class ReportPages:
    """What :func:`write_pages` writes the pages of a report run from (and
    :func:`nfarm.publishing.paper.write_paper` its PDF).

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
    write_index(report_dir, report.figures_dir, {a.name: pages.get(a.name, []) for a in arms}, list(arms),
                compared, parameters=dict(report.parameters), smoke=report.smoke,
                recordings_dir=report.recordings_dir, clean_build=report.clean_build)
