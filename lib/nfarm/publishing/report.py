"""The report pipeline: every chapter once per arm, published, and the pages.

``python -m nfarm report`` (``make report``) runs every ``notebooks/NN_*.ipynb`` in order in
the project's Jupyter kernel (:func:`nfarm.infra.notebook_runs.run_notebook`), each into a
staging directory under ``build/stage/``, once per arm (:class:`Edition`, one per study file):
the primary arm's results go to ``figures/``, another's to ``figures/<study>/``
(:mod:`.manifest` publishes them atomically). A chapter whose inputs (:func:`_chapter_key`) and
published files are those of its last run is not run again, so a second ``make report`` with
nothing changed only rewrites the pages (:mod:`.website`) and the PDF of the whole study
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

import contextlib
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
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from ..infra import provenance
from ..infra.notebook_runs import ReportError, chapters, declared_parameters, run_notebook
from ..infra.paths import BUILD, FIGURES, NOTEBOOKS, ROOT, atomic_path, shown_path
from ..infra.provenance import digest_files as _digest_files
from ..presentation.tables import DOCUMENTS
from .editions import PRIMARY_STUDY, RECORDINGS, Edition, editions
from .manifest import chapter_files, publish_chapter, publishing_lock, recover_figures
from .build_info import current_commit, machine
from .export import COURSE_TAGS, install_mathjax
from .paper import write_paper
from .website import ReportPages, write_pages

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
    """Run the chapters for every arm (:func:`editions`), publish their figures and tables, write
    the PDF of the whole study, export HTML and write the index; return where the index and the
    figures are (:class:`ReportRun`).

    Its stages, in order: plan the run (:func:`_plan`), recover the figures directory and copy
    MathJax (:func:`_prepare`), run and publish the editions' chapters (:func:`_run_editions`),
    then those comparing the editions (:func:`_run_comparing_chapters`), record a clean build's
    time (:func:`_stamp_clean_build`), write the PDF and the pages (:func:`_write_pdf_and_pages`).

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
    plan = _plan(smoke=smoke, only=only, notebooks_dir=notebooks_dir, figures_dir=figures_dir, build_dir=build_dir,
                 extra_parameters=extra_parameters, cell_timeout=cell_timeout, arms=arms, force=force,
                 parallel=parallel, scheduler=scheduler, arm=arm)
    relay = _Relay(say, tell)                     # an edition's process sends its lines here
    try:
        _prepare(plan)
        with _sweep_cluster(plan):
            _run_editions(plan, relay)
        _run_comparing_chapters(plan, relay)
        _stamp_clean_build(plan)
        _write_pdf_and_pages(plan, say)
    except KeyboardInterrupt:
        raise ReportInterrupted(f"interrupted; {shown_path(plan.figures_dir)} holds the chapters published "
                                f"before (its manifest matches)") from None
    except OSError as exc:                        # a read-only or full build directory, …
        raise ReportError(_cannot_write(exc)) from None
    return ReportRun(plan.report_dir / "index.html", plan.figures_dir)


#: One chapter run: the notebook, the edition it runs for and that edition's own parameters.
_Job = tuple[Path, Edition, dict]


@dataclass(frozen=True)
class _Plan:
    """What one :func:`build_report` run does, decided before any chapter runs (:func:`_plan`).

    Attributes:
        everything: every chapter notebook, in order (the pages and the PDF list them all).
        runs: per notebook file name, its runs for every edition (:func:`_runs`), in order.
        comparing: the file names of the chapters that compare the editions (they declare
            ``study_files``).
        jobs: the chapter runs this run makes, in chapter order (``only`` and ``arm`` applied).
        sequences: per edition that has any, its jobs but the comparing chapters', in order.
        keys: every chapter run's key, by notebook file name and edition name
            (:func:`_chained_keys`).
        declared: per notebook file name, the parameters it declares.
        arms: the run's editions, the primary first.
        extra: the run's parameters other than the defaults.
        smoke, force, scheduler, cell_timeout: as :func:`build_report` was given them.
        variant: ``"smoke"``, ``"custom"`` (other parameters) or ``None`` (the published run).
        build_dir: the build directory; ``base``: this variant's part of it (``build_dir/<variant>``,
            or ``build_dir`` itself), which holds the executed notebooks and the chapters' stamps.
        figures_dir: where the chapters publish.
        report_dir: where the pages and the PDF go.
        side_by_side: each edition's chapters run in a process of their own.
        clean: a clean build, whose time is recorded (:data:`CLEAN_BUILD`).
        started: :func:`time.monotonic` when the run was planned.
        commit: the checkout's commit then (:func:`nfarm.publishing.build_info.current_commit`).
    """

    everything: tuple[Path, ...]
    runs: Mapping[str, tuple[tuple[Edition, dict], ...]]
    comparing: frozenset[str]
    jobs: tuple[_Job, ...]
    sequences: tuple[tuple[_Job, ...], ...]
    keys: Mapping[tuple[str, str], str]
    declared: Mapping[str, Sequence[str]]
    arms: tuple[Edition, ...]
    extra: Mapping[str, object]
    smoke: bool
    force: bool
    scheduler: str | None
    cell_timeout: float | None
    variant: str | None
    build_dir: Path
    base: Path
    figures_dir: Path
    report_dir: Path
    side_by_side: bool
    clean: bool
    started: float
    commit: str


def _plan(*, smoke: bool, only: Sequence[str] | None, notebooks_dir: Path, figures_dir: Path, build_dir: Path,
          extra_parameters: dict | None, cell_timeout: float | None, arms: Sequence[Edition] | None,
          force: bool, parallel: bool | None, scheduler: str | None, arm: str | None) -> _Plan:
    """The plan of a :func:`build_report` run made from its arguments (the same names): the
    chapters, the editions each runs for and with what key, where they publish, and whether the
    editions run side by side.

    Raises:
        ReportUsageError: ``only`` names no chapter, or one that does not exist; ``arm`` names no
            edition.
        ReportError: no chapter notebook, or a study file is not valid.
    """
    everything, notebooks = _select(notebooks_dir, only)
    if not notebooks:
        raise ReportError(f"no chapter notebooks NN_*.ipynb in {shown_path(notebooks_dir)}")
    extra = dict(extra_parameters or {})
    variant = "smoke" if smoke else "custom" if extra else None
    base = build_dir / variant if variant else build_dir
    if variant:
        figures_dir = base / "figures"
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
    started, commit = time.monotonic(), current_commit()
    runs = {nb.name: tuple(_runs(declared[nb.name], arms, extra)) for nb in everything}
    comparing = frozenset(nb.name for nb in everything if "study_files" in declared[nb.name])
    jobs = tuple((nb, edition, own) for nb in notebooks for edition, own in runs[nb.name]
                 if arm is None or nb.name in comparing or edition.name == arm)
    keys = _chained_keys([(nb, edition, own) for nb in everything for edition, own in runs[nb.name]],
                         comparing, smoke, extra)
    sequences = [tuple(j for j in jobs if j[1] is edition and j[0].name not in comparing) for edition in arms]
    sequences = tuple(seq for seq in sequences if seq)
    if parallel is None:
        parallel = _cpus() >= 2
    return _Plan(everything=tuple(everything), runs=runs, comparing=comparing, jobs=jobs, sequences=sequences,
                 keys=keys, declared=declared, arms=tuple(arms), extra=extra, smoke=smoke, force=force,
                 scheduler=scheduler, cell_timeout=cell_timeout, variant=variant, build_dir=build_dir, base=base,
                 figures_dir=figures_dir, report_dir=base / "report", side_by_side=parallel and len(sequences) > 1,
                 clean=clean, started=started, commit=commit)


def _runs(declared: Sequence[str], arms: Sequence[Edition], extra: dict) -> list[tuple[Edition, dict]]:
    """The runs of a chapter declaring the parameters ``declared``: (edition, its own parameters)
    for each edition it runs for (:meth:`Edition.parameters`). A chapter comparing the editions
    (it declares ``study_files``) runs once, for the first, with every edition's study file (none
    where a run with ``extra`` parameters does not give ``study_files``)."""
    if "study_files" in declared:                 # compares the arms: once, after them
        if extra and "study_files" not in extra:
            return []
        files = {} if extra or len(arms) < 2 else \
            {"study_files": [a.study_file for a in arms]}
        return [(arms[0], files)]
    return [(a, p) for a in arms if (p := a.parameters(declared)) is not None]


def _prepare(plan: _Plan) -> None:
    """Before any chapter runs: undo what a killed run left half published beside the figures
    directory (under the publishing lock), and copy MathJax beside the pages."""
    with publishing_lock(plan.figures_dir):
        recover_figures(plan.figures_dir)
    install_mathjax(plan.report_dir)


def _run_editions(plan: _Plan, relay: _Relay) -> None:
    """Run and publish every edition's chapters but those comparing the editions: side by side, each
    edition's in a process of its own (:func:`_side_by_side`), or all in chapter order."""
    if plan.side_by_side:
        _side_by_side([functools.partial(_run_in_order, plan, relay, seq) for seq in plan.sequences], relay=relay)
    else:
        _run_in_order(plan, relay, [j for j in plan.jobs if j[0].name not in plan.comparing])


def _sweep_cluster(plan: _Plan):
    """The one local Dask cluster that every edition's chapters send their missing sweep cells to
    (:func:`nfarm.study.sweep.shared_cluster`, one worker per CPU this process may use), or nothing:
    in a smoke run (its cells run in the chapter's own process), where the user named a scheduler
    (``scheduler``, ``DASK_SCHEDULER_ADDRESS``) or the chapters' workers (a parameter), and where no
    chapter that runs sweep cells is out of date. Side by side, each edition's chapter would
    otherwise start a cluster of one worker per core, twice as many worker processes as cores
    (issue 63)."""
    sweeping = [(nb, arm) for nb, arm, _ in plan.jobs if "sweep_workers" in plan.declared[nb.name]]
    if plan.smoke or plan.scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS") or \
            {"sweep_workers", "sweep_scheduler"} & set(plan.extra) or \
            (not plan.force and all(_up_to_date(*_stamped(plan, nb, arm)) for nb, arm in sweeping)):
        return contextlib.nullcontext()
    from ..study.sweep import shared_cluster

    return shared_cluster(_cpus())


def _stamped(plan: _Plan, nb: Path, arm: Edition) -> tuple[Path, str, Path, Path, str, str]:
    """What :func:`_up_to_date` compares for one chapter run: its stamp, key, executed notebook,
    the figures directory, the edition's part of it and the chapter's prefix."""
    return (plan.base / "stamps" / arm.name / f"{nb.stem}.json", plan.keys[nb.name, arm.name],
            plan.base / "notebooks" / arm.subdir / nb.name, plan.figures_dir, arm.subdir, nb.name[:2])


def _run_comparing_chapters(plan: _Plan, relay: _Relay) -> None:
    """Run and publish the chapters that compare the editions, after the editions' own."""
    _run_in_order(plan, relay, [j for j in plan.jobs if j[0].name in plan.comparing])


def _run_in_order(plan: _Plan, relay: _Relay, jobs: Sequence[_Job]) -> None:
    """Run and publish each of ``jobs`` (:func:`_run_chapter`), one after the other."""
    for job in jobs:
        _run_chapter(plan, relay, *job)


def _run_chapter(plan: _Plan, relay: _Relay, nb: Path, arm: Edition, own: dict) -> None:
    """Run and publish one chapter of one edition, and stamp it with its key and its published
    files; nothing when it is up to date (:func:`_up_to_date`) and the run is not forced (raises
    :class:`ReportError`)."""
    label = nb.name if arm.primary else f"{nb.name} ({arm.name})"
    stage = plan.build_dir / "stage" / (nb.stem if arm.primary else f"{arm.name}-{nb.stem}")
    stamp, key, executed, _, _, prefix = stamped = _stamped(plan, nb, arm)
    parameters = {"smoke": plan.smoke, **own, **plan.extra}
    if not plan.force and _up_to_date(*stamped):
        relay.say(f"{label}: up to date (its inputs are unchanged)")
        return
    shutil.rmtree(stage, ignore_errors=True)
    stage.mkdir(parents=True)
    relay.say(f"{label} …")
    try:
        where = {"sweep_scheduler": plan.scheduler} \
            if plan.scheduler and "sweep_scheduler" in plan.declared[nb.name] else {}
        run_notebook(nb, executed, {**parameters, **where, "out_dir": shown_path(stage)},
                     progress=sys.stderr.isatty() and not plan.side_by_side and not relay.telling,
                     cell_timeout=plan.cell_timeout, remove_tags=COURSE_TAGS,
                     tell=(lambda state: relay.tell({**state, "label": label})) if relay.telling else None)
        published = publish_chapter(stage, plan.figures_dir, prefix, arm.subdir)
    except ReportError:
        stamp.unlink(missing_ok=True)
        raise
    finally:
        if relay.telling:
            relay.tell({"label": label, "finished": True})
    shutil.rmtree(stage, ignore_errors=True)
    stamp.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(stamp) as tmp:
        tmp.write_text(json.dumps({"key": key, "outputs": _published_digests(
            plan.figures_dir, arm.subdir, prefix)}, indent=1), encoding="utf-8")
    relay.say(f"{label}: {len(published)} figures and tables published in "
              f"{shown_path(plan.figures_dir / arm.subdir)}")


def _stamp_clean_build(plan: _Plan) -> None:
    """Record a clean build's time (:data:`CLEAN_BUILD`), once its chapters have run."""
    if plan.clean:
        _record_clean_build(plan.build_dir / "stamps" / CLEAN_BUILD, time.monotonic() - plan.started, plan.commit)


def _write_pdf_and_pages(plan: _Plan, say: Callable[[str], None]) -> None:
    """The PDF of the whole study (:func:`nfarm.publishing.paper.write_paper`), then every executed
    chapter's HTML page and the index, which links the PDF (:func:`nfarm.publishing.website.write_pages`)."""
    pages = ReportPages(
        chapters=plan.everything, runs={name: tuple(arm for arm, _ in runs) for name, runs in plan.runs.items()},
        comparing=plan.comparing, arms=plan.arms, executed_dir=plan.base / "notebooks",
        report_dir=plan.report_dir, figures_dir=plan.figures_dir, parameters=plan.extra, smoke=plan.smoke,
        recordings_dir=None if plan.smoke or plan.extra else plan.build_dir / "recordings",
        clean_build=None if plan.variant else _read_clean_build(plan.build_dir / "stamps" / CLEAN_BUILD))
    say("the PDF of the whole study …")
    write_paper(pages)                            # before the index, which links it
    write_pages(pages)


#: Where a clean build records its time (under ``build/stamps/``): the index's "reproduce" box reads it.
CLEAN_BUILD = "clean_build.json"


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

    @property
    def telling(self) -> bool:
        """Whether the report was given a ``tell``, to which a running chapter's state goes."""
        return self._tell is not None

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
