"""The report pipeline: every chapter once per arm, published, and the pages.

``python -m nfarm report`` (``make report``) runs every ``notebooks/NN_*.ipynb`` in order in
the project's Jupyter kernel (:func:`nfarm.infra.notebook_runs.run_notebook`), each into a
staging directory under ``build/stage/``, once per arm (:class:`Edition`, one per study file):
the primary arm's results go to ``figures/``, another's to ``figures/<study>/``
(:mod:`.manifest` publishes them atomically). A chapter whose inputs (:func:`_chapter_key`) and
published files are those of its last run is not run again, so a second ``make report`` with
nothing changed only rewrites the pages (:mod:`.pages`) and the PDF of the whole study
(:mod:`.paper`, ``build/report/nfarm-study.pdf``).

**Explore freely, publish deliberately.** Only a run with the default parameters publishes
into ``figures/``; a smoke run (``--smoke``) publishes into ``build/smoke/figures/`` and its
pages into ``build/smoke/report/``, never into ``figures/``. A chapter run by hand (JupyterLab,
papermill) writes where its ``out_dir`` parameter says, by default ``build/explore/<chapter>/``.

**Editions side by side.** On two or more CPUs each edition's chapters run in a process of
their own, in chapter order, and the chapters that compare the editions after both: a chapter
runs in one kernel, mostly on one core (BLAS has one thread in the report), so one edition
alone leaves a core idle outside chapter 6's sweeps. Publishing takes a lock (``flock`` on the
figures directory's parent), so the editions publish one at a time; the published bytes are
those of a run one edition after the other (``--serial``).

A failing, hanging (``cell_timeout``) or crashing notebook stops the run with one line naming
the notebook and the cell (counted as in the source notebook, without papermill's injected
cell); the executed copy is kept for inspection. Executed notebooks hold no absolute paths of
the checkout and no widget state; their HTML pages load MathJax from ``build/report/mathjax/``
(from the ``jupyter-server-mathjax`` package), so the report reads offline.
"""

from __future__ import annotations

import functools
import hashlib
import json
import multiprocessing
import os
import re
import shutil
import signal
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from ..infra import provenance
from ..infra.notebook_runs import ReportError, chapters, declared_parameters, run_notebook
from ..infra.paths import BUILD, FIGURES, NOTEBOOKS, ROOT, atomic_path, shown_path
from ..infra.provenance import digest_files as _digest_files
from ..presentation.tables import DOCUMENTS
from .editions import PRIMARY_STUDY, RECORDINGS, Edition, editions
from .manifest import chapter_files, publish_chapter, publishing_lock, recover_figures
from .pages import COURSE_TAGS, ReportPages, _git, install_mathjax, machine, write_pages
from .paper import write_paper

__all__ = ["Edition", "editions", "build_report", "ReportRun", "ReportUsageError", "ReportInterrupted",
           "PRIMARY_STUDY", "RECORDINGS"]


def digest_files(h, paths) -> None:
    """Feed each file's project-relative name and SHA-256 to the hash ``h`` (sorted)."""
    _digest_files(h, paths, ROOT)


_NFARM_IMPORT = re.compile(r"^\s*(?:from\s+nfarm\.([\w.]+)\s+import|import\s+nfarm\.([\w.]+)|"
                           r"from\s+nfarm\s+import\s+(\([^)]*\)|[\w ,]+)|import\s+nfarm\s*$)", re.M)


def notebook_modules(notebook: Path) -> list[str]:
    """The package modules (dotted, ``"model.kinematics"``) a notebook's code cells import:
    ``from nfarm.x.y import …``, ``import nfarm.x.y``, and ``from nfarm import name`` (the
    module defining each public name, :data:`nfarm.PUBLIC`, or the subpackage named);
    ``import nfarm`` alone means all of them."""
    import nfarm

    cells = json.loads(notebook.read_text(encoding="utf-8"))["cells"]
    code = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
    root = provenance.PACKAGE
    everything = sorted(".".join(p.relative_to(root).with_suffix("").parts) for p in root.rglob("*.py"))
    found = set()
    for sub, imported, names in _NFARM_IMPORT.findall(code):
        if not (sub or imported or names):
            return everything
        if sub or imported:
            found.add(sub or imported)
            continue
        for name in (n.split()[0] for n in names.strip("()").split(",") if n.split()):
            found.add(nfarm.PUBLIC.get(name, name))
    return sorted(m for m in found if provenance.module_file(m) is not None)


def _chapter_key(notebook: Path, parameters: dict, smoke: bool) -> str:
    """SHA-256 of everything a chapter's results depend on: the notebook, its parameters, the
    content of the package modules it imports and of this module (which runs it), with what
    they import, transitively (:func:`nfarm.infra.provenance.code_modules`), every parameter file
    (not the ``.md`` notes beside them), the locked environment and the numerics settings
    (``make report``'s pinned kernels). A change to a module no chapter imports (the course's)
    leaves the chapters as they are."""
    from ..learning.model_cache import NUMERICS_ENV
    from ..infra.paths import PARAMS

    h = hashlib.sha256()
    h.update(notebook.read_bytes())
    h.update(json.dumps({"parameters": parameters, "smoke": smoke,
                         "env": {k: os.environ.get(k) for k in NUMERICS_ENV},
                         "python": sys.version}, sort_keys=True, default=str).encode())
    modules = provenance.code_modules("publishing.report", *notebook_modules(notebook))
    _digest_files(h, [provenance.module_file(m) for m in modules], provenance.PACKAGE)
    digest_files(h, [p for p in PARAMS.rglob("*") if p.is_file() and p.suffix != ".md"])
    digest_files(h, [p for p in (ROOT / "environment.lock", *(ROOT / d for d in DOCUMENTS)) if p.is_file()])
    return h.hexdigest()


def _chained_keys(jobs: Sequence[tuple[Path, "Edition", dict]], comparing: set[str], smoke: bool,
                  extra: dict) -> dict[tuple[str, str], str]:
    """Each chapter run's key (by notebook and edition name): its own inputs
    (:func:`_chapter_key`) and the keys of the chapter runs before it whose results it may read
    — its edition's earlier chapters and the ones run once for every edition (chapter 7 loads
    the models chapter 6 chose; a comparing chapter reads every edition's). A change upstream
    runs every chapter after it again. ``jobs``: every chapter run, in chapter order."""
    once = {name for name in {nb.name for nb, _, _ in jobs}
            if sum(nb.name == name for nb, _, _ in jobs) == 1}
    keys: dict[tuple[str, str], str] = {}
    for nb, arm, own in jobs:
        own_key = _chapter_key(nb, {"smoke": smoke, **own, **extra}, smoke)
        before = sorted(key for (name, edition), key in keys.items()
                        if name < nb.name and (nb.name in comparing or edition == arm.name or name in once))
        keys[nb.name, arm.name] = hashlib.sha256("\n".join([own_key, *before]).encode()).hexdigest()
    return keys


def _published_digests(figures_dir: Path, subdir: str, prefix: str) -> dict[str, str]:
    return {p.relative_to(figures_dir).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in chapter_files(figures_dir / subdir, prefix)}


def _up_to_date(stamp: Path, key: str, executed: Path, figures_dir: Path, subdir: str,
                prefix: str) -> bool:
    """Whether the chapter ran with these inputs (``key``) and its published files and
    executed notebook are still what that run left."""
    try:
        record = json.loads(stamp.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return (isinstance(record, dict) and record.get("key") == key and executed.is_file()
            and record.get("outputs") == _published_digests(figures_dir, subdir, prefix))


# --------------------------------------------------------------------------------------------
# The whole report


class ReportUsageError(ReportError):
    """A choice of chapters that names none (the command line's exit status 2)."""


class ReportInterrupted(ReportError):
    """The run was stopped by Ctrl-C; the figures directory holds what was published before."""


@dataclass(frozen=True)
class ReportRun:
    """What a finished report wrote: its index page and the figures directory it published into."""

    index: Path
    figures_dir: Path


def _select(notebooks_dir: Path, only: Sequence[str] | None) -> tuple[list[Path], list[Path]]:
    everything = chapters(notebooks_dir)
    if only is None:
        return everything, everything
    wanted = set(only)
    if not wanted:
        raise ReportUsageError("--only needs chapter numbers (e.g. --only 01 03)")
    unknown = sorted(wanted - {nb.name[:2] for nb in everything})
    if unknown:
        raise ReportUsageError(f"no chapter {', '.join(unknown)} (chapters: "
                               f"{', '.join(nb.name[:2] for nb in everything)})")
    return everything, [nb for nb in everything if nb.name[:2] in wanted]


def _quiet(text: str) -> None:
    """The default progress sink: the library says nothing; the command line prints."""


def build_report(*, smoke: bool = False, only: Sequence[str] | None = None,
                 notebooks_dir: Path = NOTEBOOKS, figures_dir: Path = FIGURES,
                 build_dir: Path = BUILD, extra_parameters: dict | None = None,
                 cell_timeout: float | None = 1800, arms: Sequence[Edition] | None = None,
                 force: bool = False, parallel: bool | None = None, scheduler: str | None = None,
                 arm: str | None = None, say: Callable[[str], None] = _quiet,
                 tell: Callable[[dict], None] | None = None) -> ReportRun:
    """Run the chapters for every arm (:func:`editions`), publish their figures and tables,
    export HTML and write the index.

    Only a run with the default parameters (not ``smoke``, no ``extra_parameters``)
    publishes into ``figures_dir``; others publish into ``build_dir/<variant>/figures``. A run
    with ``extra_parameters`` is one edition (the primary's, with those parameters). A chapter
    whose inputs (:func:`_chapter_key`, and those of the chapters before it whose results it
    reads: :func:`_chained_keys`) are those of its last run, and whose published files are still
    that run's, is not run again unless ``force``.

    ``parallel`` (default: when this process may use two CPUs or more): the editions' chapters
    run side by side, one process per edition, each in chapter order (module docstring); the
    chapters that compare the editions run after them. Otherwise one after the other.

    ``scheduler``: the address of a running Dask scheduler (``tcp://host:8786``) to which the
    chapters that run sweep cells (those declaring ``sweep_scheduler``: chapter 6) send the cells
    they miss. Where a cell runs changes none of its results, so it is neither part of a
    chapter's key nor a reason to publish elsewhere.

    ``arm``: the name of one edition (``params/studies/<arm>.yaml``) whose chapters run, with
    the chapters comparing the editions; the other editions' chapters are neither run nor
    checked (their published files stay as they are), and the index still lists every edition.

    ``say`` receives a line per chapter as it starts, is found up to date, or is published
    (``python -m nfarm report`` prints them). ``tell`` receives a running chapter's state about
    once a second (:func:`nfarm.infra.notebook_runs.run_notebook`'s, with the chapter's
    ``label``; ``{"label": …, "finished": True}`` when it ends), from every edition's process
    (:class:`nfarm.publishing.console.Console` shows them). ``cell_timeout``: the seconds a cell
    may go without progress (a slow cell that makes progress is never stopped).

    A failed or interrupted run resumes from what it finished: the chapters published are up to
    date, and chapter 6's sweep cells each finished are kept (``build/sweeps/``) and not run again.

    Raises:
        ReportUsageError: ``only`` names no chapter, or one that does not exist; ``arm`` names no
            edition.
        ReportInterrupted: Ctrl-C; the figures directory holds the chapters published before.
        ReportError: a chapter failed (one line naming it and its cell), a notebook or study
            file is not valid, or a directory cannot be written.
    """
    everything, notebooks = _select(notebooks_dir, only)
    if not notebooks:
        raise ReportError(f"no chapter notebooks NN_*.ipynb in {shown_path(notebooks_dir)}")
    extra = dict(extra_parameters or {})
    variant = "smoke" if smoke else "custom" if extra else None
    base = build_dir / variant if variant else build_dir
    if variant:
        figures_dir = base / "figures"
    report_dir = base / "report"
    try:
        arms = list(arms) if arms is not None else editions()
    except ValueError as exc:                     # a study file (ParamsError)
        raise ReportError(str(exc)) from None
    if extra:
        arms = [a for a in arms if a.primary]
    if arm is not None and arm not in [a.name for a in arms]:
        raise ReportUsageError(f"--arm: no edition {arm!r}; the editions are {', '.join(a.name for a in arms)} "
                               f"(params/studies/*.yaml)")
    declared = {nb.name: declared_parameters(nb) for nb in everything}
    # A clean build: the published run of every chapter of every edition with nothing made before it
    # (its sweep cells on this machine: a cluster's workers would make the time another machine's)
    clean = variant is None and only is None and arm is None and not force and scheduler is None and \
        not any((build_dir / made).exists() for made in ("datasets", "models", "sweeps", "stamps"))
    started, commit = time.monotonic(), _commit()

    def runs(nb: Path) -> list[tuple[Edition, dict]]:
        names = declared[nb.name]
        if "study_files" in names:                # compares the arms: once, after them
            if extra and "study_files" not in extra:
                return []
            files = {} if extra or len(arms) < 2 else \
                {"study_files": [a.study_file for a in arms]}
            return [(arms[0], files)]
        return [(a, p) for a in arms if (p := a.parameters(names)) is not None]

    comparing = {nb.name for nb in everything if "study_files" in declared[nb.name]}
    jobs = [(nb, edition, own) for nb in notebooks for edition, own in runs(nb)
            if arm is None or nb.name in comparing or edition.name == arm]
    keys = _chained_keys([(nb, edition, own) for nb in everything for edition, own in runs(nb)], comparing, smoke, extra)
    sequences = [[j for j in jobs if j[1] is edition and j[0].name not in comparing] for edition in arms]
    sequences = [seq for seq in sequences if seq]
    if parallel is None:
        parallel = _cpus() >= 2
    side_by_side = parallel and len(sequences) > 1

    def chapter(nb: Path, arm: Edition, own: dict) -> None:
        """Run and publish one chapter of one edition (raises :class:`ReportError`)."""
        prefix = nb.name[:2]
        label = nb.name if arm.primary else f"{nb.name} ({arm.name})"
        stage = build_dir / "stage" / (nb.stem if arm.primary else f"{arm.name}-{nb.stem}")
        executed = base / "notebooks" / arm.subdir / nb.name
        stamp = base / "stamps" / arm.name / f"{nb.stem}.json"
        parameters = {"smoke": smoke, **own, **extra}
        key = keys[nb.name, arm.name]
        if not force and _up_to_date(stamp, key, executed, figures_dir, arm.subdir, prefix):
            relay.say(f"{label}: up to date (its inputs are unchanged)")
            return
        shutil.rmtree(stage, ignore_errors=True)
        stage.mkdir(parents=True)
        relay.say(f"{label} …")
        try:
            where = {"sweep_scheduler": scheduler} if scheduler and "sweep_scheduler" in declared[nb.name] else {}
            run_notebook(nb, executed, {**parameters, **where, "out_dir": shown_path(stage)},
                         progress=sys.stderr.isatty() and not side_by_side and tell is None,
                         cell_timeout=cell_timeout, remove_tags=COURSE_TAGS,
                         tell=None if tell is None else lambda state: relay.tell({**state, "label": label}))
            published = publish_chapter(stage, figures_dir, prefix, arm.subdir)
        except ReportError:
            stamp.unlink(missing_ok=True)
            raise
        finally:
            if tell is not None:
                relay.tell({"label": label, "finished": True})
        shutil.rmtree(stage, ignore_errors=True)
        stamp.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(stamp) as tmp:
            tmp.write_text(json.dumps({"key": key, "outputs": _published_digests(
                figures_dir, arm.subdir, prefix)}, indent=1), encoding="utf-8")
        relay.say(f"{label}: {len(published)} figures and tables published in "
            f"{shown_path(figures_dir / arm.subdir)}")

    def in_order(sequence) -> None:
        for job in sequence:
            chapter(*job)

    relay = _Relay(say, tell)                     # an edition's process sends its lines here

    try:
        with publishing_lock(figures_dir):
            recover_figures(figures_dir)
        install_mathjax(report_dir)
        if side_by_side:
            _side_by_side([functools.partial(in_order, seq) for seq in sequences], relay=relay)
        else:
            in_order([j for j in jobs if j[0].name not in comparing])
        in_order([j for j in jobs if j[0].name in comparing])
        record = build_dir / "stamps" / CLEAN_BUILD
        if clean:
            _record_clean_build(record, time.monotonic() - started, commit)
        pages = ReportPages(
            chapters=tuple(everything), runs={nb.name: tuple(arm for arm, _ in runs(nb)) for nb in everything},
            comparing=frozenset(comparing), arms=tuple(arms), executed_dir=base / "notebooks",
            report_dir=report_dir, figures_dir=figures_dir, parameters=extra, smoke=smoke,
            recordings_dir=None if smoke or extra else build_dir / "recordings",
            clean_build=None if variant else _read_clean_build(record))
        say("the PDF of the whole study …")
        write_paper(pages)                        # before the index, which links it
        write_pages(pages)
    except KeyboardInterrupt:
        raise ReportInterrupted(f"interrupted; {shown_path(figures_dir)} holds the chapters published "
                                f"before (its manifest matches)") from None
    except OSError as exc:                        # a read-only or full build directory, …
        raise ReportError(_cannot_write(exc)) from None
    return ReportRun(report_dir / "index.html", figures_dir)


#: Where a clean build records its time (under ``build/stamps/``): the index's "reproduce" box reads it.
CLEAN_BUILD = "clean_build.json"


def _commit() -> str:
    """The checkout's commit, and whether it had uncommitted changes (when a build starts)."""
    return (_git("rev-parse", "--short=12", "HEAD") or "unknown") + \
        (" (with uncommitted changes)" if _git("status", "--porcelain") else "")


def _record_clean_build(path: Path, seconds: float, commit: str) -> None:
    """Record a clean build's time (its chapters, from nothing made), the machine and the commit."""
    import datetime

    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps({
            "seconds": round(seconds, 1), "machine": machine(), "commit": commit,
            "finished": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")}, indent=1),
            encoding="utf-8")


def _read_clean_build(path: Path) -> dict | None:
    """The clean build recorded at ``path``, or ``None`` (none, or a file this code did not write)."""
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
        float(record["seconds"]), str(record["machine"]), str(record["commit"]), str(record["finished"])
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return record


def _cpus() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def _wait(children, seconds: float) -> None:
    """Join ``children`` for at most ``seconds`` in all, ignoring further Ctrl-C meanwhile."""
    deadline = time.monotonic() + seconds
    for child in children:
        while child.is_alive() and time.monotonic() < deadline:
            try:
                child.join(max(0.0, min(0.5, deadline - time.monotonic())))
            except KeyboardInterrupt:
                pass


class _Relay:
    """The report's ``say`` and ``tell``, called from the process that runs a chapter: in the
    report's own process directly; in an edition's forked process (:func:`_side_by_side`) sent
    through a queue to the report's, which shows every edition's progress in one place."""

    def __init__(self, say: Callable[[str], None], tell: Callable[[dict], None] | None):
        self._say, self._tell, self.queue = say, tell, None

    def say(self, text: str) -> None:
        if self.queue is not None:
            self.queue.put(("say", text))
        else:
            self._say(text)

    def tell(self, state: dict) -> None:
        if self._tell is None:
            return
        if self.queue is not None:
            self.queue.put(("tell", state))
        else:
            self._tell(state)

    def serve(self, queue) -> None:
        """Show what the editions' processes send, until ``None`` arrives (the report's thread)."""
        while (item := queue.get()) is not None:
            kind, what = item
            try:
                (self._say if kind == "say" else self._tell or (lambda _: None))(what)
            except Exception:  # noqa: BLE001 — a display's failure must not stop the report
                pass


def _side_by_side(tasks, grace: float = 10.0, relay: _Relay | None = None) -> None:
    """Run each task (a callable) in a forked process of its own, all at once; raise
    ``KeyboardInterrupt`` when one was interrupted (:func:`build_report` says it as
    :class:`ReportInterrupted`), else a :class:`ReportError` with every failed task's line. Ctrl-C
    reaches every process of the terminal's group: each child stops its notebook
    (:func:`nfarm.infra.notebook_runs._interruptible`) and says so, and this process waits for
    them. A child tells its end through a pipe, as (``"ok"``, ``""``), (``"failed"``,
    message) or (``"interrupted"``, ``""``)."""
    context = multiprocessing.get_context("fork")
    sys.stdout.flush()
    sys.stderr.flush()
    pipes = [context.Pipe(duplex=False) for _ in tasks]
    queue = context.SimpleQueue() if relay is not None else None
    children = [context.Process(target=_child, args=(task, sender, relay, queue), daemon=False)
                for task, (_, sender) in zip(tasks, pipes)]
    for child in children:
        child.start()
    for _, sender in pipes:
        sender.close()                              # the children hold their ends
    shower = None
    if queue is not None:                           # started after the forks: no thread is copied
        import threading

        shower = threading.Thread(target=relay.serve, args=(queue,), name="nfarm-report-relay", daemon=True)
        shower.start()
    interrupted = False
    while True:
        try:
            for child in children:
                child.join()
            break
        except KeyboardInterrupt:
            # From the terminal, the children got it too and are stopping; one still running
            # after a grace period was not (the signal went to this process alone): pass it on,
            # once (a second one would land in its kernel's shut-down).
            interrupted = True
            _wait(children, grace)
            for child in children:
                if child.is_alive():
                    os.kill(child.pid, signal.SIGINT)
    if shower is not None:
        # The end marker from a thread of its own: a child killed while writing would hold the queue's
        # lock, and the report must not wait on it; what the children sent before is shown first.
        import threading

        threading.Thread(target=queue.put, args=(None,), daemon=True).start()
        shower.join(timeout=10.0)
    ends = []
    for (receiver, _), child in zip(pipes, children):
        try:
            end = receiver.recv() if receiver.poll() else None
        except (EOFError, OSError):
            end = None
        receiver.close()
        if end is None:                             # it ended before it could tell
            end = ("interrupted", "") if child.exitcode is None or child.exitcode < 0 else \
                ("failed", f"an edition's process ended with status {child.exitcode} (its error is above)")
        ends.append(end)
    if interrupted or any(how == "interrupted" for how, _ in ends):
        raise KeyboardInterrupt
    failed = [message for how, message in ends if how == "failed"]
    if failed:
        raise ReportError("; ".join(failed))


def _cannot_write(exc: OSError) -> str:
    where = f" {shown_path(Path(exc.filename))}" if exc.filename else ""
    return f"cannot write{where}: {exc.strerror or exc}"


def _child(task, sender, relay: _Relay | None = None, queue=None) -> None:
    if relay is not None:
        relay.queue = queue                         # this process's lines go to the report's
    try:
        task()
        end = ("ok", "")
    except KeyboardInterrupt:
        end = ("interrupted", "")
    except ReportError as exc:
        end = ("failed", str(exc))
    except OSError as exc:
        end = ("failed", _cannot_write(exc))
    try:
        sender.send(end)
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)
