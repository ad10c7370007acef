"""The report's index page (:func:`write_index`): what the run was, the verdict and the abstract
(:mod:`.abstract`), how to reproduce it, each edition's chapters with their recordings, the
references (:mod:`.references`), the verdict's history, and an appendix of every chapter's
figures and tables, copied into the report folder with their manifest.
"""

from __future__ import annotations

import csv
import datetime
import html
import shutil
from collections.abc import Mapping, Sequence
from pathlib import Path

from ..infra.paths import FIGURES, ROOT, atomic_path, shown_path
from ..study.contest import SPREAD_SEEDS
from .abstract import (ABSTRACT_FRAMING, ABSTRACT_LIMITS, ABSTRACT_QUESTION, ANSWERS_KIND, DISSERTATION_TITLE,
                       DISSERTATION_TITLE_EN, abstract_answers, verdict_rows, warm_start_rows)
from .build_info import current_commit, machine
from .conclusion import VERDICT_HEAD, conclusion, verdict_display
from .editions import Edition
from .manifest import chapter_files
from .references import references_html

__all__ = ["PAPER_NAME", "write_index"]


#: The whole study as one PDF in the report directory (:mod:`.paper` writes it; the index links it).
PAPER_NAME = "nfarm-study.pdf"


_STYLE = """body{font-family:sans-serif;max-width:70em;margin:2em auto;padding:0 1em;color:#222}
img{max-width:100%;border:1px solid #ddd;margin:.5em 0}
table{border-collapse:collapse;margin:.5em 0 1.5em;font-size:.9em}
td,th{border:1px solid #ccc;padding:.2em .6em;text-align:right}th{background:#f3f3f3}
h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}
figure{margin:1em 0 2em}figcaption{color:#444;margin:.2em 0}.file{color:#888;font-size:.8em}
dl{display:grid;grid-template-columns:max-content auto;gap:.2em 1em}dt{font-weight:bold}
.reproduce{border:1px solid #ccc;background:#fafafa;padding:.5em 1em;margin:1em 0}.reproduce dd{word-break:break-all}"""


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


def _verdict_html(rows: list[dict[str, str]], warm: dict[str, list[dict[str, str]]] | None = None) -> list[str]:
    """The verdict table and the conclusion (:func:`nfarm.publishing.conclusion.conclusion`) as HTML."""
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
            f"a two-level bootstrap over both, coarse over {1 + len(SPREAD_SEEDS)} seeds) and the study's targets met (each arm's <code>tables/07_verdict.csv</code>; the targets in "
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
    """The verdict (:func:`.abstract.verdict_rows`), then the abstract: the study's question, each
    arm's answers (:func:`.abstract.abstract_answers`) and the study's limits."""
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


def write_index(report_dir: Path, figures_dir: Path,
                pages: dict[str, list[tuple[str, str, str]]], arms: list[Edition],
                compared: list[tuple[str, str, str]], *, parameters: dict, smoke: bool,
                recordings_dir: Path | None = None, clean_build: Mapping | None = None) -> None:
    """Write ``report_dir/index.html`` (atomically), with the published figures and tables it shows
    and the recordings it links copied into ``report_dir``.

    ``pages``: per edition name, (prefix, title, page path) of its chapters in order;
    ``compared``: the same for the chapters comparing the editions. Each edition's section
    links the rerun recordings its chapters wrote (:data:`.editions.RECORDINGS`, an edition's in
    its own subdirectory) when ``recordings_dir`` holds any. ``parameters``, ``smoke`` and
    ``clean_build`` are the run's (:class:`nfarm.publishing.website.ReportPages`)."""
    shown = report_dir / "figures"
    if shown.exists():
        shutil.rmtree(shown)
    if (report_dir / "recordings").exists():
        shutil.rmtree(report_dir / "recordings")
    commit = current_commit()
    when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    kind = "smoke run (small parameters: not the published results)" if smoke else \
        "published results (default parameters)" if not parameters else "a run with other parameters"
    robots = "; ".join(f"{e.name}: {e.robot_file or 'the chapters’ default'}"
                       + ("" if e.primary else f" (figures in {e.name}/)") for e in arms)
    facts = {"what": kind, "arms": robots,
             "parameters": ", ".join(f"{k} = {v!r}" for k, v in parameters.items()) or "defaults",
             "commit": commit, "built": when,
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
    parts.append(_reproduce_html(commit, clean_build))
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
