"""Parameter sweeps: a grid of library jobs or notebook runs, one Dask task per cell.

A **sweep file** (:mod:`nfarm.study.sweep_files`) says what runs over which parameters; its
cells are identified by their complete parameters. A cell's results go to ``OUT/<cell key>/``:
``cell.json`` (parameters, metrics, status, seconds, worker), ``log.txt`` (what the job
printed and warned), ``error.txt`` (the traceback of a failed cell) and, for a notebook, the
executed ``notebook.ipynb`` and the files it wrote under ``files/``. A cell whose
``cell.json`` says it succeeded with the same **code** (:func:`code_key`: the sources of the
job's modules and of what they import, transitively — :mod:`nfarm.infra.provenance` — or for a
notebook the whole library and the notebook; the parameter files (not ``params/sweeps/``), the
lock file and the numerics settings) is not run again: an interrupted sweep resumes, and a
widened grid runs only its new cells.

Cells run on Dask's ``distributed``: a :class:`~distributed.LocalCluster` of one
single-threaded worker process per core by default, or any running scheduler
(``tcp://host:8786``: ``dask scheduler`` / ``dask worker``, dask-jobqueue, Kubernetes), given or
named by Dask's configuration (``DASK_SCHEDULER_ADDRESS``; :func:`shared_cluster` starts one local
cluster for several processes, as ``make report`` does for its editions' chapters). The
workers only compute; the client writes every cell's directory as its result arrives
(atomically: a directory renamed into place), so workers need the same checkout and
environment, not the same disk. ``workers=0`` runs the cells one by one in this process.

Every cell runs with one BLAS thread (``threadpoolctl``; ``OPENBLAS_NUM_THREADS=1`` as Dask's
nannies set it), so its results are the same bits in a worker process, on a remote worker with
the same environment and in this process (tested), and a worker's cell does not compete with
its neighbours for the cores. Measured in ``benchmarks/bench_sweep.py``: the machinery's own
cost per cell, and the speed-up of a grid of ANFIS trainings with one and two workers.

A metric is a number, a text or a list of numbers (one per joint, say); ``results.csv``
spreads a list over the columns ``name[1]``, ``name[2]``, …. A notebook records metrics with
:func:`record_metrics` (an output of MIME type :data:`METRICS_MIME`, read back from the
executed notebook).
"""

from __future__ import annotations

import contextlib
import csv
import datetime
import functools
import hashlib
import io
import json
import math
import os
import shutil
import sys
import tempfile
import time
import traceback
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..infra import progress as _progress
from ..infra import provenance
from ..infra.arguments import is_number
from ..infra.limits import time_limit
from ..infra.paths import BUILD, PARAMS, ROOT, atomic_path, project_path, shown_path
from ..infra.provenance import digest_files
from ..infra.reading import ParamsError, json_ready, show
from .jobs import CELL_ENV, JOBS
from .sweep_files import SWEEPS, Cell, Sweep, canonical, load_sweep, sweep_from_dict
from .jobs import cell_threads as _cell_threads

__all__ = ["Sweep", "Cell", "CellResult", "Replicates", "SweepError", "load_sweep", "sweep_from_dict",
           "run_sweep", "run_sweeps", "sweep_results", "sweeps_results", "shared_cluster", "by_configuration", "best_by",
           "code_key", "record_metrics", "write_summary", "METRICS_MIME", "SWEEPS"]

METRICS_MIME = "application/vnd.nfarm.metrics+json"
class SweepError(RuntimeError):
    """A cell a chapter needs failed; the message names it, its parameters and the error."""


@dataclass(frozen=True)
class CellResult:
    """What one cell gave. ``status``: ``"ok"`` or ``"failed"``; ``reused``: read from an
    earlier run's ``cell.json`` rather than run now."""

    cell: Cell
    status: str
    metrics: Mapping[str, Any]
    seconds: float
    worker: str
    error: str = ""
    reused: bool = False

    @property
    def ok(self) -> bool:
        return self.status == "ok"


@dataclass(frozen=True)
class Replicates:
    """One configuration's results over its seeds (:func:`by_configuration`): the cells of a
    sweep whose parameters differ in ``seed`` only.

    ``metrics`` holds each metric's **mean** over the seeds (a list metric per element; a
    metric equal in every seed, or not a number, as it is), so a chapter reads a configuration
    as it reads one cell; :meth:`low` and :meth:`high` give the range over the seeds.
    """

    runs: tuple[CellResult, ...]

    @property
    def cell(self) -> Cell:
        """The first seed's cell (its parameters name the configuration)."""
        return self.runs[0].cell

    @property
    def seeds(self) -> list[int]:
        return [r.cell.params.get("seed", 0) for r in self.runs]

    @property
    def n(self) -> int:
        return len(self.runs)

    @property
    def reused(self) -> bool:
        return all(r.reused for r in self.runs)

    def values(self, name: str) -> Any:
        """``(seeds, ...)`` array of a numeric metric, one row per seed."""
        import numpy as np
        return np.array([r.metrics[name] for r in self.runs], dtype=float)

    @functools.cached_property
    def metrics(self) -> dict[str, Any]:
        out = {}
        for name, first in self.runs[0].metrics.items():
            same = all(canonical(r.metrics.get(name)) == canonical(first) for r in self.runs)
            numeric = is_number(first, numpy=False) or \
                isinstance(first, list) and all(isinstance(v, (int, float)) for v in first)
            out[name] = first if same or not numeric else self.values(name).mean(axis=0).tolist()
        return out

    def low(self, name: str) -> Any:
        """The least value of a numeric metric over the seeds (per element of a list)."""
        return self.values(name).min(axis=0).tolist()

    def high(self, name: str) -> Any:
        """The largest value of a numeric metric over the seeds (per element of a list)."""
        return self.values(name).max(axis=0).tolist()


def by_configuration(results: Iterable[CellResult]) -> list[Replicates]:
    """Group a sweep's results by their parameters other than ``seed``, in the order of each
    configuration's first cell; each group's runs in the order of their seeds."""
    groups: dict[str, list[CellResult]] = {}
    for r in results:
        key = canonical({k: v for k, v in r.cell.params.items() if k != "seed"})
        groups.setdefault(key, []).append(r)
    return [Replicates(tuple(sorted(runs, key=lambda r: r.cell.params.get("seed", 0))))
            for runs in groups.values()]


def best_by(groups: Iterable[Replicates], parameter: str, metric: str, *,
            seed: int | None = None) -> dict[Any, Replicates]:
    """For each value of ``parameter`` (a learner, an input set), the configuration of least
    mean ``metric`` over its seeds — or, given ``seed``, of least ``metric`` on that seed (a
    sweep whose configurations were pruned after seed 0 compares them where all of them ran):
    the choice made on validation results."""
    def value_of(g: Replicates) -> float:
        if seed is None:
            return g.metrics[metric]
        run = next((r for r in g.runs if r.cell.params.get("seed", 0) == seed), None)
        if run is None:
            raise ValueError(f"best_by: a configuration has no cell of seed {seed} (its seeds: {g.seeds})")
        return run.metrics[metric]

    best: dict[Any, Replicates] = {}
    for g in groups:
        value = g.cell.params[parameter]
        if value not in best or value_of(g) < value_of(best[value]):
            best[value] = g
    return best


# --------------------------------------------------------------------------------------------
# Code identity


def code_key(sweep: Sweep) -> str:
    """SHA-256 of the code a cell's results depend on (module docstring): a finished cell with
    another code key runs again.

    For a job: the content of :mod:`nfarm.study.jobs` and of every package module it imports,
    transitively (:func:`nfarm.infra.provenance.code_digest`), and this module's own file (it runs the
    cell); a change to a presentation module (plotting, report) keeps the cells. For a
    notebook: the whole library, which a notebook may import at will, and the notebook."""
    from ..learning.model_cache import NUMERICS_ENV

    h = hashlib.sha256()
    env = {k: os.environ.get(k) for k in NUMERICS_ENV} | CELL_ENV
    h.update(canonical({"env": env, "python": sys.version, "target": sweep.target}).encode())
    if sweep.job:
        modules = {*provenance.code_modules("study.jobs"), "study.sweep"}
        digest_files(h, [provenance.module_file(m) for m in modules], provenance.PACKAGE)
    else:
        digest_files(h, provenance.PACKAGE.rglob("*.py"), provenance.PACKAGE)
        digest_files(h, [project_path(sweep.notebook)], ROOT)
    digest_files(h, [p for p in PARAMS.rglob("*") if p.is_file() and p.suffix != ".md"
                     and not p.is_relative_to(SWEEPS)], ROOT)
    digest_files(h, [p for p in (ROOT / "environment.lock",) if p.is_file()], ROOT)
    return h.hexdigest()


# --------------------------------------------------------------------------------------------
# One cell (runs on a worker)


def record_metrics(**values) -> None:
    """In a notebook run by a sweep: record these metrics of the cell (numbers, texts or lists
    of numbers). Shown as one line of text; the sweep reads them from the executed notebook."""
    from IPython.display import display

    values = json_ready(values)
    text = "metrics: " + ", ".join(f"{k} = {v}" for k, v in values.items())
    display({METRICS_MIME: values, "text/plain": text}, raw=True)


def _notebook_metrics(executed: Path) -> dict:
    found: dict = {}
    for cell in json.loads(executed.read_text(encoding="utf-8"))["cells"]:
        for output in cell.get("outputs", []):
            found.update(output.get("data", {}).get(METRICS_MIME, {}))
    return found


def _run_notebook_cell(notebook: str, params: dict, timeout: float | None) -> tuple[dict, dict]:
    from ..infra.notebook_runs import declared_parameters, run_notebook

    path = project_path(notebook)
    with tempfile.TemporaryDirectory(prefix="nfarm-cell-") as tmp:
        tmp = Path(tmp)
        given = dict(params)
        if "out_dir" in declared_parameters(path):
            given["out_dir"] = str(tmp / "files")
        run_notebook(path, tmp / "notebook.ipynb", given, cell_timeout=timeout)
        files = {"notebook.ipynb": (tmp / "notebook.ipynb").read_bytes()}
        for item in sorted((tmp / "files").rglob("*")):
            if item.is_file():
                files[f"files/{item.relative_to(tmp / 'files').as_posix()}"] = item.read_bytes()
        return _notebook_metrics(tmp / "notebook.ipynb"), files


def _metric(name: str, value: Any) -> Any:
    value = json_ready(value)
    ok = is_number(value, numpy=False) or isinstance(value, str) or \
        isinstance(value, list) and all(is_number(x, numpy=False) for x in value)
    if not ok:
        raise TypeError(f"metric {name!r} must be a number, a text or a list of numbers, "
                        f"got {show(value)}")
    return value


def _worker_name() -> str:
    """The Dask worker's name (tuning its allocator as nfarm does: :mod:`nfarm.infra._allocator`),
    or ``"in-process"``."""
    try:
        from distributed import get_worker

        worker = get_worker()
    except (ImportError, ValueError):
        return "in-process"
    from ..infra._allocator import tune

    tune(worker=True)
    return str(worker.name if worker.name is not None else worker.address)


def execute_cell(job: str | None, notebook: str | None, params: dict, metrics: Sequence[str],
                 timeout: float | None = None) -> dict:
    """Run one cell and return its record (never raises for the cell's own failure): status,
    metrics, seconds, worker, log, error (traceback) and, for a notebook, its files."""
    start, cpu = time.perf_counter(), time.thread_time()   # one thread per cell (its BLAS too)
    log = io.StringIO()
    record: dict = {"worker": _worker_name(), "files": {}, "metrics": {}}
    try:
        with _cell_threads(), contextlib.redirect_stdout(log), contextlib.redirect_stderr(log), \
                warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                if job:
                    with time_limit(timeout):       # the library's long loops check it
                        values = JOBS[job].function(dict(params))
                else:
                    values, record["files"] = _run_notebook_cell(notebook, params, timeout)
            finally:
                for w in caught:
                    log.write(f"{w.category.__name__}: {w.message} ({w.filename}:{w.lineno})\n")
        missing = [m for m in metrics if m not in values]
        if missing:
            raise KeyError(f"the {'job' if job else 'notebook'} gave no metric "
                           f"{', '.join(map(repr, missing))} (it gave {', '.join(values) or 'none'})")
        record.update(status="ok", metrics={m: _metric(m, values[m]) for m in metrics}, error="")
    except BaseException as exc:  # noqa: BLE001 — a cell's failure is its result
        if isinstance(exc, KeyboardInterrupt):
            raise
        record.update(status="failed", error=traceback.format_exc())
    record.update(seconds=time.perf_counter() - start, cpu_seconds=time.thread_time() - cpu, log=log.getvalue())
    return record


# --------------------------------------------------------------------------------------------
# Results on disk


def _error_line(error: str) -> str:
    """The line of a traceback that names the exception (its last), at most 300 characters."""
    lines = [line for line in error.strip().splitlines() if line.strip()]
    return lines[-1].strip()[:300] if lines else ""


def _write_cell(out: Path, sweep: Sweep, cell: Cell, record: dict, code: str) -> None:
    """``out/<key>/`` from ``record``, atomically (a directory renamed into place)."""
    target = out / cell.key
    tmp = Path(tempfile.mkdtemp(prefix=f".{cell.key}.", dir=out))
    try:
        summary = {"sweep": sweep.name, **({"job": sweep.job} if sweep.job else
                                           {"notebook": sweep.notebook}),
                   "params": dict(cell.params), "status": record["status"],
                   "metrics": record["metrics"], "seconds": round(record["seconds"], 3),
                   # the CPU the cell's thread used: its cost on a shared machine, where seconds are not
                   "cpu_seconds": round(record.get("cpu_seconds", 0.0), 3),
                   "worker": record["worker"], "error": _error_line(record.get("error", "")),
                   "code": code,
                   "finished": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}
        (tmp / "log.txt").write_text(record.get("log", ""), encoding="utf-8")
        if record.get("error"):
            (tmp / "error.txt").write_text(record["error"], encoding="utf-8")
        for name, data in record.get("files", {}).items():
            (tmp / name).parent.mkdir(parents=True, exist_ok=True)
            (tmp / name).write_bytes(data)
        (tmp / "cell.json").write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")
        os.chmod(tmp, 0o755)
        old = None
        if target.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{cell.key}.old.", dir=out))
            os.replace(target, old / "cell")
        os.replace(tmp, target)
        if old:
            shutil.rmtree(old, ignore_errors=True)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def _finished(out: Path, cell: Cell, code: str, metrics: Sequence[str]) -> CellResult | None:
    try:
        data = json.loads((out / cell.key / "cell.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not (isinstance(data, dict) and data.get("status") == "ok" and data.get("code") == code
            and isinstance(data.get("metrics"), dict) and all(m in data["metrics"] for m in metrics)
            and canonical(data.get("params")) == canonical(cell.params)):
        return None
    return CellResult(cell, "ok", {m: data["metrics"][m] for m in metrics},
                      float(data.get("seconds", 0.0)), str(data.get("worker", "")), reused=True)


def _csv_value(value: Any) -> Any:
    if isinstance(value, (dict, list)):
        return canonical(value)
    if isinstance(value, float):
        return repr(value)
    return "" if value is None else value


def write_summary(out: Path, sweep: Sweep, results: Sequence[CellResult]) -> list[Path]:
    """``out/results.csv`` (one row per cell), ``out/summary.md`` and ``out/summary.png``."""
    from ..presentation.plotting import plot_sweep, save_figure
    from ..presentation.tables import Table

    names = list(dict.fromkeys(k for r in results for k in r.cell.params))
    columns: list[tuple[str, str, int | None]] = []       # (header, metric, list index)
    for m in sweep.metrics:
        width = max((len(r.metrics[m]) for r in results if isinstance(r.metrics.get(m), list)),
                    default=None)
        columns += [(m, m, None)] if width is None else \
            [(f"{m}[{i + 1}]", m, i) for i in range(width)]
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["cell", *names, *(c[0] for c in columns), "status", "seconds", "worker", "error"])
    for r in results:
        values = []
        for _, m, i in columns:
            value = r.metrics.get(m)
            values.append(value[i] if i is not None and isinstance(value, list) and i < len(value)
                          else value if i is None else None)
        writer.writerow([r.cell.key, *(_csv_value(r.cell.params.get(k)) for k in names),
                         *map(_csv_value, values), r.status, f"{r.seconds:.3f}", r.worker,
                         _error_line(r.error)])
    written = []
    with atomic_path(out / "results.csv") as tmp:
        tmp.write_text(buffer.getvalue(), encoding="utf-8")
    written.append(out / "results.csv")

    varying = sweep.varying
    labels = [", ".join(f"{k}={_csv_value(r.cell.params[k])}" for k in varying) or r.cell.key
              for r in results]
    scalar = [m for m in sweep.metrics
              if any(isinstance(r.metrics.get(m), (int, float)) for r in results)]
    rows = [[label, *(r.metrics.get(m, "") if r.ok else "" for m in scalar), r.status,
             r.seconds] for label, r in zip(labels, results)]
    failed = sum(not r.ok for r in results)
    table = Table(["cell", *scalar, "status", "seconds"], rows, floatfmt=".4g",
                  caption=f"Sweep {sweep.name} ({sweep.target}): {len(results)} cells, "
                          f"{failed} failed; seconds: each cell's run, on its worker")
    with atomic_path(out / "summary.md") as tmp:
        tmp.write_text(table.to_markdown(), encoding="utf-8")
    written.append(out / "summary.md")
    if scalar:
        values = {m: [r.metrics.get(m) if r.ok and isinstance(r.metrics.get(m), (int, float))
                      else math.nan for r in results] for m in scalar}
        fig = plot_sweep(labels, values, title=f"Sweep {sweep.name}: {sweep.target}")
        written.append(Path(save_figure(fig, out, "summary",
                                        caption=f"Metrics of each cell of sweep {sweep.name}")))
        import matplotlib.pyplot as plt
        plt.close(fig)
    return written


# --------------------------------------------------------------------------------------------
# Running


#: The local cluster's Dask settings: no statistical profiler sampling each worker's stack every 10 ms,
#: the event loops' watchdog tick and the memory and system monitors once a second or five, not every
#: 20-500 ms. Dask's defaults cost a cluster of two workers 3.6 CPU-s a minute idle and 3 % of a busy
#: worker's CPU; these 0.5 s and 0.7 % (measured on 2 cores, 2026-12-03). Nothing a cell computes
#: depends on them; the dashboard's profile page stays empty.
QUIET_CLUSTER = {"distributed.worker.profile.enabled": False,
                 "distributed.admin.tick.interval": "1s",
                 "distributed.worker.memory.monitor-interval": "1s",
                 "distributed.admin.system-monitor.interval": "5s"}

#: What the local cluster's workers' environment adds to Dask's own (``distributed.nanny.pre-spawn-environ``:
#: one BLAS and OpenMP thread, its trim threshold, which :func:`nfarm.infra._allocator.tune` then
#: replaces): glibc's allocator with one arena (``MALLOC_ARENA_MAX=1``). A Dask worker runs each
#: cell in a thread of its pool, and a thread's arena is a heap of at most 64 MB, so every larger
#: array (the ridge cells' 3 213-column designs, the kernels' feature maps) was mapped and
#: unmapped again at each free whatever the thresholds, and faulted in afresh by the next (36 µs a
#: page fault on this project's 2-core VMs): on 12 of the measured arm's cells the workers' system
#: time fell from 9.9 to 5.8 s with one arena (2026-12-03). A worker runs one cell at a time, so the
#: one arena is not contended. Nothing a cell computes depends on it.
WORKER_ENVIRON = {"MALLOC_ARENA_MAX": 1}


def _client(scheduler: str | None, workers: int | None):
    """A client of the scheduler at ``scheduler``; else, with ``workers`` not given, of the one Dask's
    configuration names (``DASK_SCHEDULER_ADDRESS``: :func:`shared_cluster`'s, or the user's); else of a
    local cluster of ``workers`` processes (:func:`_local_cluster`), closed with the client."""
    from distributed import Client

    if scheduler is None and workers is None:
        import dask

        # the environment first: Dask reads it into its configuration once, when it is imported
        scheduler = os.environ.get("DASK_SCHEDULER_ADDRESS") or dask.config.get("scheduler-address", None)
    if scheduler:
        try:
            return Client(scheduler, timeout="20s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise ParamsError(f"cannot reach the Dask scheduler at {scheduler}: "
                              f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}") from None
    return Client(_local_cluster(workers))


def _local_cluster(workers: int | None):
    """A :class:`~distributed.LocalCluster` of ``workers`` single-threaded worker processes (default one
    per core), with :data:`QUIET_CLUSTER`'s settings and :data:`WORKER_ENVIRON`'s environment."""
    from distributed import LocalCluster

    # silence_logs=CRITICAL: a worker whose scheduler is shutting down logs an ERROR with a
    # traceback from its heartbeat (seen once in a make report, printed into a chapter's
    # output with the machine's paths); a cell's own failure is in its cell.json, not the log.
    import dask

    environ = {**dask.config.get("distributed.nanny.pre-spawn-environ", default={}), **WORKER_ENVIRON}
    with dask.config.set({**QUIET_CLUSTER, "distributed.nanny.pre-spawn-environ": environ}):
        return LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                            processes=True, silence_logs=50,
                            # no fixed port (its HTTP server starts anyway; clusters side by side)
                            dashboard_address="127.0.0.1:0")


#: How long :func:`shared_cluster` waits for its cluster to start [s].
SHARED_CLUSTER_START_S = 120.0


@contextlib.contextmanager
def shared_cluster(workers: int | None = None, *, start_timeout: float = SHARED_CLUSTER_START_S):
    """One local cluster (:func:`_local_cluster`, ``workers`` processes) for every process this one
    starts while the ``with`` block runs; yields its scheduler's address.

    The cluster runs in a child process of its own, and the address is put in this process's
    environment as ``DASK_SCHEDULER_ADDRESS`` (Dask's ``scheduler-address``), which the processes
    started inside the block inherit: every :func:`run_sweeps` there that names neither a
    scheduler nor ``workers`` sends its cells to it (:func:`_client`). ``make report`` runs its two
    editions' chapters side by side (issue 63): with a local cluster of one worker per core each,
    four worker processes shared two cores, and a cell cost 8-14 % more CPU than with two
    (an MLP of the learned-IK contest 5.5 → 6.2 CPU-s, boosted trees on the regressor 19.0 →
    21.7; measured 2026-12-08, ``docs/performance.md``); and every chapter's call started, and
    imported into, workers of its own.

    The child ignores Ctrl-C (the processes that send it cells stop theirs) and closes the cluster
    when this process leaves the block or dies (its standard input ends); the environment is then
    restored. Raises :class:`SweepError` when the cluster does not start within ``start_timeout``
    seconds (the child's last line of error)."""
    import select
    import subprocess

    if workers is not None and (not isinstance(workers, int) or isinstance(workers, bool) or workers < 1):
        raise ValueError(f"workers must be a whole number >= 1 or None, got {workers!r}")
    code = ("import signal, sys; signal.signal(signal.SIGINT, signal.SIG_IGN); "
            "from nfarm.study.sweep import _serve_cluster; _serve_cluster(%r)" % (workers,))
    with tempfile.TemporaryFile(mode="w+", encoding="utf-8") as errors:
        child = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                 stderr=errors, text=True, cwd=ROOT)
        try:
            ready, _, _ = select.select([child.stdout], [], [], start_timeout)
            address = child.stdout.readline().strip() if ready else ""
            if not address.startswith("tcp://"):
                child.kill()
                child.wait()
                errors.seek(0)
                lines = [line.strip() for line in errors.read().splitlines() if line.strip()]
                why = lines[-1][:300] if lines else (f"no address within {start_timeout:g} s" if not ready
                                                     else f"it ended with status {child.returncode}")
                raise SweepError(f"the local Dask cluster for the chapters' sweep cells did not start: {why}")
            before = os.environ.get("DASK_SCHEDULER_ADDRESS")
            os.environ["DASK_SCHEDULER_ADDRESS"] = address
            try:
                yield address
            finally:
                if before is None:
                    os.environ.pop("DASK_SCHEDULER_ADDRESS", None)
                else:
                    os.environ["DASK_SCHEDULER_ADDRESS"] = before
        finally:
            if child.poll() is None:
                with contextlib.suppress(OSError):
                    child.stdin.close()             # the child closes its cluster and ends
                try:
                    child.wait(timeout=60)
                except subprocess.TimeoutExpired:
                    child.kill()
                    child.wait()


def _serve_cluster(workers: int | None) -> None:
    """:func:`shared_cluster`'s child: start the cluster, print its address, hold it until standard
    input ends, close it."""
    cluster = _local_cluster(workers)
    try:
        print(cluster.scheduler_address, flush=True)
        sys.stdin.read()
    finally:
        cluster.close()


def run_sweep(sweep: Sweep, out: str | os.PathLike | None = None, *, scheduler: str | None = None,
              workers: int | None = None, client=None, progress: bool = False,
              summary: bool = True, timeout: float | None = 1800,
              prepare: bool = True) -> list[CellResult]:
    """Run every cell of ``sweep`` not finished in ``out`` (default ``build/sweeps/<name>/``),
    and return every cell's result in the sweep's order.

    Args:
        scheduler: address of a running Dask scheduler; ``None`` starts a local cluster of
            ``workers`` processes (default: one per core); ``workers=0`` runs the cells one by
            one in this process, without Dask.
        client: a ``distributed.Client`` of your own (a ``SLURMCluster``'s, say), used as it
            is and left open; instead of ``scheduler`` and ``workers``.
        progress: a progress bar of finished cells on standard error.
        summary: write ``results.csv``, ``summary.md`` and ``summary.png`` (a chapter that runs
            part of a sweep skips them: the files describe the whole sweep's run).
        timeout: seconds a cell may run: a job's whole cell (its training stops at the next
            epoch past it, :mod:`nfarm.infra.limits`), each code cell of a notebook's; ``None``: no
            limit. A sweep file's ``cell_timeout_s`` takes its place for that sweep's cells.
        prepare: do the job's shared work once, here, before the workers start
            (:attr:`nfarm.study.jobs.Job.prepare`: the data sets of the learned jobs).
    """
    return run_sweeps([sweep], [out], scheduler=scheduler, workers=workers, client=client,
                      progress=progress, summary=summary, timeout=timeout, prepare=prepare)[0]


def run_sweeps(sweeps: Sequence[Sweep], outs: Sequence[str | os.PathLike | None] | None = None, *,
               scheduler: str | None = None, workers: int | None = None, client=None,
               progress: bool = False, summary: bool = True, timeout: float | None = 1800,
               prepare: bool = True) -> list[list[CellResult]]:
    """:func:`run_sweep` for several sweeps at once: the unfinished cells of all of them go to
    one cluster, in the order given (Dask starts earlier submissions first), and each sweep's
    results come back in its own order. One cluster for a chapter's sweeps keeps every worker
    busy until the last cell instead of idling at the tail of each sweep, and starts once. A
    cell listed twice (the same directory and key) runs once. ``outs``: one directory per
    sweep (``None``: ``build/sweeps/<name>/``); the other arguments as :func:`run_sweep`'s."""
    from tqdm.auto import tqdm

    outs = [None] * len(sweeps) if outs is None else list(outs)
    if len(outs) != len(sweeps):
        raise ValueError(f"give one directory per sweep: {len(sweeps)} sweeps, {len(outs)} directories")
    if workers is not None and workers < 0:
        raise ValueError(f"workers must be >= 0, got {workers}")
    dirs = [project_path(o) if o is not None else BUILD / "sweeps" / s.name for s, o in zip(sweeps, outs)]
    codes = [code_key(s) for s in sweeps]
    results: dict[tuple[Path, str], CellResult] = {}
    pending: dict[tuple[Path, str], tuple[int, Cell]] = {}
    for i, (sweep, out) in enumerate(zip(sweeps, dirs)):
        out.mkdir(parents=True, exist_ok=True)
        for cell in sweep.cells:
            where = (out, cell.key)
            if where in results or where in pending:
                continue
            done = _finished(out, cell, codes[i], sweep.metrics)
            if done:
                results[where] = done
            else:
                pending[where] = (i, cell)
    step = ", ".join(dict.fromkeys(s.name for s in sweeps))
    bar = tqdm(total=len(results) + len(pending), initial=len(results), unit="cell",
               disable=not progress, desc=step, file=sys.stderr, dynamic_ncols=True)
    # Whoever runs this (make report's chapter) is told the cells done and the time left
    # (nfarm.infra.progress); the cells found finished are the run being resumed.
    reused, total, started = len(results), len(results) + len(pending), time.monotonic()
    told = {"eta_s": None, "at": started}

    def state() -> tuple:
        eta_s = told["eta_s"]
        left = None if eta_s is None else max(0.0, eta_s - (time.monotonic() - told["at"]))
        return step, len(results), total, reused, left

    def finish(i: int, cell: Cell, record: dict) -> None:
        sweep = sweeps[i]
        _write_cell(dirs[i], sweep, cell, record, codes[i])
        results[(dirs[i], cell.key)] = CellResult(cell, record["status"], record["metrics"],
                                                  record["seconds"], record["worker"],
                                                  record.get("error", ""))
        bar.update()
        now = time.monotonic()
        told.update(eta_s=_progress.eta(len(results) - reused, total - len(results), now - started), at=now)
        _progress.post(*state()[:3], reused=reused, eta_s=state()[4])
        if record["status"] != "ok":
            bar.write(f"{sweep.name}: cell {cell.key} failed: {_error_line(record['error'])}",
                      file=sys.stderr)

    todo = list(pending.values())
    limits = [_timeout(sweeps[i], timeout) for i, _ in todo]
    # While the cells run elsewhere (a cluster's workers), this process waits; its beats say so,
    # until every cell under way should have ended by its own time limit.
    alive_for = None if any(t is None for t in limits) else max(limits, default=0.0) + 60.0
    _progress.post(step, reused, total, reused=reused)
    try:
        if todo and prepare:
            for job in dict.fromkeys(sweeps[i].job for i, _ in todo):
                if job and JOBS[job].prepare:
                    _prepare(JOBS[job], [c for i, c in todo if sweeps[i].job == job])
        if todo and workers == 0 and not scheduler and client is None:
            for i, cell in todo:
                finish(i, cell, execute_cell(sweeps[i].job, sweeps[i].notebook, dict(cell.params),
                                             sweeps[i].metrics, _timeout(sweeps[i], timeout)))
        elif todo:
            with _progress.heartbeat(state, alive_for_s=alive_for):
                _run_on_dask(sweeps, todo, scheduler, workers, client, timeout, finish)
    finally:
        bar.close()
    every = []
    for sweep, out in zip(sweeps, dirs):
        ordered = [results[(out, c.key)] for c in sweep.cells if (out, c.key) in results]
        if summary and len(ordered) == len(sweep.cells):
            write_summary(out, sweep, ordered)
        every.append(ordered)
    return every


def sweep_results(sweep: Sweep, sweeps_dir: str | os.PathLike | None = None, *,
                  workers: int | None = None) -> list[CellResult]:
    """The results of every cell of ``sweep`` for a chapter: read from
    ``<sweeps_dir>/<name>/`` (default ``build/sweeps/``) where finished, the others run now on
    a local cluster of ``workers`` processes (``0``: in this process).

    Raises:
        SweepError: a cell failed (its record is kept in its directory).
    """
    return sweeps_results([sweep], sweeps_dir, workers=workers)[0]


#: The time limit of a chapter's sweep cell [s] (:func:`sweeps_results`): a bound on a cell that
#: hangs, not on a slow one. The chapters' cells come from the committed sweep files, whose epochs
#: are capped; the longest measured took 830 s on a 2-core machine shared by six processes (180 s
#: of CPU), and 1 800 s, the limit of a sweep run by hand, left a slower or busier machine too
#: little room (issue 63).
CHAPTER_CELL_LIMIT_S = 6 * 3600.0


def sweeps_results(sweeps: Sequence[Sweep], sweeps_dir: str | os.PathLike | None = None, *,
                   workers: int | None = None, scheduler: str | None = None,
                   timeout: float | None = CHAPTER_CELL_LIMIT_S) -> list[list[CellResult]]:
    """:func:`sweep_results` of several sweeps, their unfinished cells run on one cluster
    (:func:`run_sweeps`: a local one of ``workers`` processes, or the running Dask scheduler at
    ``scheduler``): a chapter runs everything it will show first, then reads it back. ``timeout``:
    each cell's limit (:data:`CHAPTER_CELL_LIMIT_S`; a sweep file's ``cell_timeout_s`` first)."""
    base = project_path(sweeps_dir) if sweeps_dir is not None else BUILD / "sweeps"
    every = run_sweeps(sweeps, [base / s.name for s in sweeps], workers=workers, scheduler=scheduler,
                       summary=False, timeout=timeout)
    for sweep, results in zip(sweeps, every):
        for r in results:
            if not r.ok:
                raise SweepError(f"sweep {sweep.name}: cell {r.cell.key} {dict(r.cell.params)} "
                                 f"failed: {_error_line(r.error)} (see "
                                 f"{shown_path(base / sweep.name / r.cell.key / 'error.txt')})")
    return every


def _timeout(sweep: Sweep, given: float | None) -> float | None:
    """A cell's time limit: its sweep file's ``cell_timeout_s``, else the runner's."""
    return sweep.timeout if sweep.timeout is not None else given


def _prepare(job, cells: Sequence[Cell]) -> None:
    """The job's shared work, once per distinct value of its ``shared`` parameters; a cell whose
    parameters it fails on (any exception) fails later with that error, recorded with its
    parameters, and the other cells go on."""
    seen = set()
    for cell in cells:
        key = canonical([cell.params[k] for k in job.shared])
        if key not in seen:
            seen.add(key)
            # Whatever it raises (a path that is no study file, a region the arm cannot reach):
            # the cells of these parameters fail with it, recorded, and the others run.
            with contextlib.suppress(Exception):
                job.prepare(dict(cell.params))


def _run_on_dask(sweeps: Sequence[Sweep], pending: Sequence[tuple[int, Cell]], scheduler: str | None,
                 workers: int | None, given, timeout: float | None,
                 finish: Callable[[int, Cell, dict], None]) -> None:
    from distributed import as_completed

    client = given if given is not None else _client(scheduler, workers)
    try:
        futures = {}
        for i, cell in pending:
            sweep = sweeps[i]
            future = client.submit(execute_cell, sweep.job, sweep.notebook, dict(cell.params),
                                   list(sweep.metrics), _timeout(sweep, timeout),
                                   key=f"nfarm-{sweep.name}-{cell.key}", pure=False, retries=0)
            futures[future] = (i, cell)
        for future in as_completed(futures):
            i, cell = futures[future]
            try:
                record = future.result()
            except Exception as exc:  # noqa: BLE001 — a worker died, or the task was lost
                record = {"status": "failed", "metrics": {}, "seconds": 0.0, "worker": "",
                          "log": "", "files": {},
                          "error": f"{type(exc).__name__}: the cell's worker failed ({exc})"}
            finish(i, cell, record)
    finally:
        if given is None:
            cluster = getattr(client, "cluster", None)
            client.close()
            if cluster is not None and not scheduler:
                cluster.close()
