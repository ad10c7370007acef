"""The course edition of the chapters: exercises, answer checks, a student and a teacher build.

Every chapter ends with a section of exercises, from "change a parameter and explain" to
"implement a variant". Their cells carry tags (nbconvert's tag-based preprocessors do all the
stripping):

* ``exercise`` — the section's statements, its set-up and the student's workspace cells;
* ``solution`` — a worked solution; its metadata ``nfarm.wrong`` holds a deliberately wrong
  answer (code) with which the tests prove that the check below it fails with its message;
* ``check`` — a call of :func:`check`, :func:`check_function` or :func:`check_that`, which shows
  "correct" or what is wrong, and never raises for a wrong answer.

The report (:mod:`nfarm.publishing.report`) runs the chapters without these cells: its numbers and
figures are the study's. :func:`build_course` (``make course``) writes ``build/course/``:

* ``student/`` — the notebooks without their solution cells and without outputs, to open in
  JupyterLab from the checkout (the library and the parameter files are the project's);
* ``teacher/`` — the notebooks executed with their solutions, and their HTML pages; the build
  fails if any check fails on a worked solution;
* ``index.html`` — the chapters with their learning goals, prerequisites and estimated time,
  read from each notebook's metadata ``nfarm.publishing.course`` (``goals``, ``prerequisites``,
  ``minutes``).
"""

from __future__ import annotations

import html
import json
import os
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..infra.paths import BUILD, NOTEBOOKS, atomic_path
from .export import COURSE_TAGS

__all__ = ["check", "check_function", "check_that", "student_notebook", "exercise_notebook",
           "build_course", "check_results", "CHECK_MIME", "TAGS"]

CHECK_MIME = "application/vnd.nfarm.check+json"
TAGS = COURSE_TAGS


# --------------------------------------------------------------------------------------------
# Checks (in the notebooks)


def _show(exercise: str, passed: bool, message: str) -> bool:
    from IPython.display import display

    mark = "✅" if passed else "❌"
    text = f"{mark} Exercise {exercise}: {message}"
    display({CHECK_MIME: {"exercise": exercise, "passed": passed, "message": message},
             "text/markdown": text, "text/plain": text}, raw=True)
    return passed


def _numbers(value: Any) -> np.ndarray | None:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None
    return array


def _compare(answer: Any, expected: Any, rtol: float, atol: float, unit: str) -> str:
    """Empty if ``answer`` matches ``expected``, else what differs (one sentence)."""
    if isinstance(expected, str):
        if not isinstance(answer, str):
            return f"expected a text, got {type(answer).__name__}"
        return "" if answer.strip().lower() == expected.strip().lower() else \
            f"{answer!r} is not the answer"
    if isinstance(expected, bool) or isinstance(answer, bool):
        return "" if answer is expected else f"{answer!r} is not right"
    a, e = _numbers(answer), np.asarray(expected, dtype=float)
    if a is None:
        return f"expected {'a number' if e.ndim == 0 else f'numbers of shape {e.shape}'}, got {type(answer).__name__}"
    if a.shape != e.shape:
        return f"expected shape {e.shape}, got {a.shape}"
    if not np.isfinite(a).all():
        return "the answer holds NaN or infinity"
    if np.allclose(a, e, rtol=rtol, atol=atol):
        return ""
    worst = float(np.max(np.abs(a - e)))
    suffix = f" {unit}" if unit else ""
    if e.ndim == 0:
        return f"{float(a):.6g}{suffix} is off by {worst:.3g}{suffix}"
    return f"off by up to {worst:.3g}{suffix} (element {int(np.argmax(np.abs(a - e).ravel()))})"


def check(exercise: str, answer: Any, expected: Any, *, rtol: float = 1e-6, atol: float = 0.0,
          unit: str = "", hint: str = "") -> bool:
    """Compare a student's ``answer`` (a number, an array, a text or a truth value) with
    ``expected`` (numbers within ``rtol``/``atol``; texts ignoring case); show the verdict
    and return it. ``None`` means "not answered yet"."""
    if answer is None:
        return _show(exercise, False, "not answered yet" + (f" — {hint}" if hint else ""))
    problem = _compare(answer, expected, rtol, atol, unit)
    if problem:
        return _show(exercise, False, f"not yet: {problem}" + (f". Hint: {hint}" if hint else ""))
    return _show(exercise, True, "correct")


def check_function(exercise: str, function: Callable | None, reference: Callable,
                   cases: Iterable[tuple], *, rtol: float = 1e-9, atol: float = 1e-12,
                   hint: str = "") -> bool:
    """Call the student's ``function`` and ``reference`` on every case (a tuple of arguments)
    and compare their results; an exception of the student's function is shown, not raised."""
    if function is None:
        return _show(exercise, False, "not answered yet" + (f" — {hint}" if hint else ""))
    for k, args in enumerate(cases):
        try:
            got = function(*args)
        except Exception as exc:  # noqa: BLE001 — the student's code: report, never raise
            return _show(exercise, False, f"not yet: on case {k + 1} your function raised "
                                          f"{type(exc).__name__}: {exc}" + (f". Hint: {hint}" if hint else ""))
        if got is None:
            return _show(exercise, False, "not answered yet: your function returns None"
                         + (f" — {hint}" if hint else ""))
        problem = _compare(got, reference(*args), rtol, atol, "")
        if problem:
            return _show(exercise, False, f"not yet: on case {k + 1}, {problem}"
                         + (f". Hint: {hint}" if hint else ""))
    return _show(exercise, True, "correct")


def check_that(exercise: str, passed: bool | None, *, fail: str, ok: str = "correct") -> bool:
    """Show ``ok`` if ``passed``, else ``fail`` (a property of the answer was tested);
    ``None`` means "not answered yet"."""
    if passed is None:
        return _show(exercise, False, "not answered yet")
    return _show(exercise, bool(passed), ok if passed else f"not yet: {fail}")


def check_results(executed: str | os.PathLike) -> list[dict]:
    """The verdicts of every check in an executed notebook, in order."""
    found = []
    for cell in json.loads(Path(executed).read_text(encoding="utf-8"))["cells"]:
        for output in cell.get("outputs", []):
            verdict = output.get("data", {}).get(CHECK_MIME)
            if verdict:
                found.append(verdict)
    return found


# --------------------------------------------------------------------------------------------
# Builds


def _preprocess(nb, *, remove: Sequence[str] = (), clear: bool = False):
    from nbconvert.preprocessors import ClearOutputPreprocessor, TagRemovePreprocessor

    if remove:
        nb, _ = TagRemovePreprocessor(remove_cell_tags=set(remove), enabled=True).preprocess(nb, {})
    if clear:
        nb, _ = ClearOutputPreprocessor(enabled=True).preprocess(nb, {})
    return nb


def student_notebook(path: str | os.PathLike):
    """The chapter without its solution cells and without outputs."""
    import nbformat

    return _preprocess(nbformat.read(path, 4), remove=("solution",), clear=True)


def exercise_notebook(path: str | os.PathLike, *, wrong: bool = False):
    """The chapter's parameters cell and its exercise section only (its cells are
    self-contained); with ``wrong``, each solution replaced by its deliberately wrong answer."""
    import nbformat

    nb = nbformat.read(path, 4)
    kept = []
    for cell in nb.cells:
        tags = set(cell.metadata.get("tags", []))
        if "parameters" in tags or tags & set(TAGS):
            if wrong and "solution" in tags:
                cell.source = cell.metadata.get("nfarm", {}).get("wrong", "")
            kept.append(cell)
    nb.cells = kept
    return nb


def _course_facts(nb, name: str) -> dict:
    facts = nb.metadata.get("nfarm", {}).get("course")
    if not isinstance(facts, dict) or not {"goals", "prerequisites", "minutes"} <= set(facts):
        raise ValueError(f"{name}: metadata nfarm.publishing.course must give goals, prerequisites and minutes")
    return facts


def _index(out: Path, chapters: list[tuple[Path, str, dict, bool]]) -> None:
    rows = []
    for notebook, title, facts, executed in chapters:
        stem = notebook.stem
        teacher = (f" · <a href='teacher/{stem}.html'>with solutions</a>"
                   f" (<a href='teacher/{stem}.ipynb'>notebook</a>)" if executed else "")
        goals = "".join(f"<li>{html.escape(g)}</li>" for g in facts["goals"])
        needs = ", ".join(html.escape(p) for p in facts["prerequisites"]) or "none"
        rows.append(f"<section><h2>{html.escape(title)}</h2>"
                    f"<p><a href='student/{notebook.name}'>student notebook</a>{teacher} · "
                    f"about {int(facts['minutes'])} minutes · prerequisites: {needs}</p>"
                    f"<ul>{goals}</ul></section>")
    page = ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>nfarm — course</title>"
            "<style>body{font-family:sans-serif;max-width:52em;margin:2em auto;line-height:1.4}"
            "h2{font-size:1.15em;margin-bottom:0.2em}</style></head><body>"
            "<h1>nfarm — a 5-DOF arm with numerical methods and ANFIS: the course</h1>"
            "<p>Open the student notebooks in JupyterLab from the checkout (<code>make lab</code>; "
            "the library and parameter files are the project's). The teacher's guide is "
            "<code>docs/teaching.md</code>.</p>" + "".join(rows) + "</body></html>")
    with atomic_path(out / "index.html") as tmp:
        tmp.write_text(page, encoding="utf-8")


def build_course(out: str | os.PathLike | None = None, *, smoke: bool = False,
                 only: Sequence[str] | None = None, teacher: bool = True,
                 cell_timeout: float | None = 1800, notebooks_dir: Path = NOTEBOOKS,
                 progress: Callable[[str], None] | None = None) -> Path:
    """Write the student and teacher builds and the index (module docstring) into ``out``
    (default ``build/course/``); ``only``: chapter numbers (``"01"``…); ``teacher=False``
    skips executing the teacher's notebooks. The teacher's notebooks run with ``smoke`` and
    write their figures and recordings under ``out/teacher/files/``, never into ``figures/``;
    they reuse the data sets, models and sweep results of ``build/`` (``make report``'s).

    Raises:
        ValueError: a chapter lacks its course facts, or a check failed on a worked solution
            (one line naming the chapter and the exercise).
        nfarm.infra.notebook_runs.ReportError: a teacher's notebook failed to run.
    """
    import nbformat

    from ..infra.notebook_runs import chapters, declared_parameters, run_notebook
    from .export import chapter_title, export_html, install_mathjax

    out = Path(out) if out is not None else BUILD / "course"
    say = progress or (lambda text: None)
    everything = chapters(notebooks_dir)
    unknown = sorted(set(only or ()) - {nb.name[:2] for nb in everything})
    if unknown or (only is not None and not only):
        raise ValueError(f"no chapter {', '.join(unknown)} (chapters: "
                         f"{', '.join(nb.name[:2] for nb in everything)})" if unknown else
                         "--only names no chapter")
    selected = [nb for nb in everything if not only or nb.name[:2] in only]
    found = []
    for notebook in selected:
        nb = nbformat.read(notebook, 4)
        if not any("exercise" in c.metadata.get("tags", []) for c in nb.cells):
            continue
        facts = _course_facts(nb, notebook.name)
        with atomic_path(out / "student" / notebook.name) as tmp:
            nbformat.write(student_notebook(notebook), tmp)
        executed = False
        if teacher:
            say(f"course: {notebook.name} (teacher) …")
            target = out / "teacher" / notebook.name
            files = out / "teacher" / "files" / notebook.stem
            parameters = {"smoke": smoke, "out_dir": str(files)}
            if "recordings_dir" in declared_parameters(notebook):   # not the report's recordings
                parameters["recordings_dir"] = str(files / "recordings")
            run_notebook(notebook, target, parameters, cell_timeout=cell_timeout)
            failed = [v for v in check_results(target) if not v["passed"]]
            if failed:
                raise ValueError(f"{notebook.name}: exercise {failed[0]['exercise']}'s check fails on "
                                 f"its worked solution: {failed[0]['message']}")
            install_mathjax(out / "teacher")
            export_html(target, target.with_suffix(".html"),
                         title=f"{chapter_title(notebook)} · teacher's edition")
            executed = True
        found.append((notebook, chapter_title(notebook), facts, executed))
    _index(out, found)
    return out
