"""Running a notebook headlessly: papermill in the project's own Jupyter kernel, over Unix
sockets, with a limit on a cell that makes no progress (not on a slow one), its progress told
as it runs, Ctrl-C that stops it, and one line naming the notebook and the cell when it fails
(:func:`run_notebook`); the chapters in order (:func:`chapters`) and the names a notebook's
``parameters`` cell declares (:func:`declared_parameters`).

**Progress, not time.** A chapter's sweep cell runs for as long as its machine needs: on a
slower or shared machine a cell that took 30 minutes takes an hour, and a limit on the cell's
time failed a reproduction that was working (a fresh clone's ``make report``, in the cell that
waited on chapter 6's sweeps). So the limit is on silence: a cell is stopped only when
``cell_timeout`` seconds pass with no progress — no cell started or finished, and no post from
the work inside the cell (:mod:`nfarm.infra.progress`: the sweeps post each finished cell, and
beat while their workers run cells that are within their own time limits). The kernel is then
killed with its process group (its local cluster's workers with it).

Used by the report (:mod:`nfarm.publishing.report`) and by sweeps of notebooks
(:mod:`nfarm.study.sweep`).
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import re
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from . import progress as _progress
from .arguments import check_number
from .paths import NOTEBOOKS, atomic_path, shown_path

__all__ = ["ReportError", "run_notebook", "chapters", "declared_parameters", "KERNEL_NAME", "CHAPTER"]


#: The project's Jupyter kernel (``make setup`` installs it in the environment).
KERNEL_NAME = "nfarm"
#: A chapter notebook's name: two digits, an underscore, a name.
CHAPTER = re.compile(r"^(\d\d)_\w+\.ipynb$")


class ReportError(RuntimeError):
    """A chapter could not be built; the message says which and where."""


class DropMessage(logging.Filter):
    def __init__(self, start: str):
        super().__init__()
        self.start = start

    def filter(self, record: logging.LogRecord) -> bool:
        return not str(record.msg).startswith(self.start)


def _use_project_kernel() -> None:
    """Make Jupyter find this environment's kernel spec first and check that it runs this
    interpreter: the notebooks must never run in a kernel the machine happens to have."""
    from jupyter_client.kernelspec import KernelSpecManager, NoSuchKernel

    share = os.path.join(sys.prefix, "share", "jupyter")
    paths = os.environ.get("JUPYTER_PATH", "").split(os.pathsep)
    if share not in paths:
        os.environ["JUPYTER_PATH"] = os.pathsep.join([share] + [p for p in paths if p])
    try:
        spec = KernelSpecManager().get_kernel_spec(KERNEL_NAME)
    except NoSuchKernel:
        raise ReportError(f"Jupyter kernel {KERNEL_NAME!r} is not installed in {sys.prefix}: "
                          f"run `make setup`") from None
    if Path(spec.argv[0]).resolve() != Path(sys.executable).resolve():
        raise ReportError(f"Jupyter kernel {KERNEL_NAME!r} runs {spec.argv[0]}, not this "
                          f"environment's {sys.executable}: run `make setup`")


def _ipc_kernel_manager(directory: str, watch: "_Watch | None" = None):
    """A kernel manager whose kernel talks over Unix sockets in ``directory``: no open TCP
    ports, and no "running over TCP without encryption" warning from every kernel. The kernel's
    environment names ``directory/progress.json`` for its posts (:mod:`nfarm.infra.progress`),
    and ``watch`` learns its process group."""
    from jupyter_client.manager import AsyncKernelManager

    class IPCKernelManager(AsyncKernelManager):
        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            self.transport = "ipc"
            self.ip = os.path.join(directory, "kernel")

        async def _async_launch_kernel(self, kernel_cmd, **kw):
            # The kernel's own log (not the notebook's outputs, which come by message) goes to
            # a file: an interrupted run's shutdown otherwise prints the kernel's tracebacks
            # into the terminal. ``kernel_log(directory)`` reads it.
            kw["stderr"] = open(os.path.join(directory, "kernel.err"), "ab")   # noqa: SIM115 — the kernel's
            kw["env"] = {**(kw.get("env") or os.environ), _progress.ENV: os.path.join(directory, "progress.json")}
            await super()._async_launch_kernel(kernel_cmd, **kw)
            if watch is not None:
                provisioner = getattr(self, "provisioner", None)
                watch.launched(getattr(provisioner, "pgid", None), getattr(provisioner, "pid", None))

    return IPCKernelManager


class _Watch:
    """A notebook's progress while it runs, and its watchdog: which cell runs (source
    numbering) and for how long, the last post of the work inside it, and the kernel killed
    once ``limit`` seconds pass with neither a cell started or finished nor a new post.
    ``tell`` (if given) receives the state about once a second, from the watchdog's thread."""

    TICK_S = 1.0

    def __init__(self, notebook: str, cells: int, posts: Path, limit: float | None,
                 tell: Callable[[dict], None] | None):
        self.notebook, self.cells, self.posts, self.limit, self.tell = notebook, cells, posts, limit, tell
        self.lock = threading.Lock()
        self.cell, self.source, self.injected = None, "", 0
        self.cell_since = self.last = time.monotonic()
        self.post, self.post_at = None, None
        self.group, self.pid = None, None
        self.stalled = False
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, name="nfarm-notebook-watch", daemon=True)

    def launched(self, group: int | None, pid: int | None) -> None:
        with self.lock:
            self.group, self.pid = group, pid

    def cell_start(self, cell, cell_index: int, **_) -> None:
        if "injected-parameters" in cell.metadata.get("tags", []):
            self.injected += 1
        lines = [line.strip() for line in cell.source.splitlines() if line.strip()] if cell.cell_type == "code" else []
        code = [line for line in lines if not line.startswith("#")] or lines     # what it does, not its comment
        with self.lock:
            self.cell, self.source = cell_index - self.injected, code[0][:80] if code else ""
            self.cell_since = self.last = time.monotonic()
            self.post = None

    def cell_complete(self, **_) -> None:
        with self.lock:
            self.last = time.monotonic()

    def state(self) -> dict:
        with self.lock:
            now = time.monotonic()
            return {"notebook": self.notebook, "cell": self.cell, "cells": self.cells, "source": self.source,
                    "cell_s": now - self.cell_since, "quiet_s": now - self.last,
                    "work": dict(self.post) if self.post else None}

    def _run(self) -> None:
        while not self.stop.wait(self.TICK_S):
            post = _progress.read(self.posts)
            with self.lock:
                if post is not None and post.get("posted") != self.post_at:
                    self.post_at, self.post, self.last = post.get("posted"), post, time.monotonic()
                quiet = time.monotonic() - self.last
                group, pid = self.group, self.pid
            # Counted from the first cell's start: the kernel's start has papermill's own limit.
            if self.limit is not None and self.cell is not None and quiet > self.limit and not self.stalled:
                self.stalled = True
                self._kill(group, pid)
            if self.tell is not None:
                with contextlib.suppress(Exception):     # a display's failure is not the notebook's
                    self.tell(self.state())

    @staticmethod
    def _kill(group: int | None, pid: int | None) -> None:
        """The kernel and the processes it started (a local cluster's workers): its group,
        which it leads (Jupyter starts kernels in a session of their own)."""
        with contextlib.suppress(OSError):
            if group is not None and group > 1 and group != os.getpgrp():
                os.killpg(group, signal.SIGKILL)
            elif pid is not None:
                os.kill(pid, signal.SIGKILL)

    def __enter__(self) -> "_Watch":
        self.thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop.set()
        self.thread.join()


def _last_line(path: Path) -> str:
    """The last non-empty line of a kernel's log (at most 200 characters), or ""."""
    try:
        with open(path, "rb") as f:
            f.seek(max(0, f.seek(0, os.SEEK_END) - 4096))
            lines = [line.strip() for line in f.read().decode("utf-8", "replace").splitlines() if line.strip()]
    except OSError:
        return ""
    return lines[-1][:200] if lines else ""


def _source_cell(executed: Path, index: int) -> int:
    """The index in the source notebook of the executed notebook's cell ``index`` (papermill's
    injected parameters cell is not in the source)."""
    import nbformat

    try:
        cells = nbformat.read(executed, 4).cells
    except Exception:  # noqa: BLE001 — unreadable output: keep papermill's count
        return index
    injected = sum("injected-parameters" in c.metadata.get("tags", []) for c in cells[:index])
    return index - injected


def _running_cell(executed: Path) -> tuple[int, str] | None:
    """The cell that was running when the kernel died or the time ran out — the last one
    papermill started — as (source index, first line)."""
    import nbformat

    try:
        cells = nbformat.read(executed, 4).cells
    except Exception:  # noqa: BLE001
        return None
    # A cell started has its start time; on a time-out papermill marks the cells after the running
    # one "completed" too, without a start time (seen: the report named the last cell, not the one
    # that ran out of time).
    started = [k for k, c in enumerate(cells) if c.metadata.get("papermill", {}).get("start_time")]
    if not started:
        return None
    k = started[-1]
    injected = sum("injected-parameters" in c.metadata.get("tags", []) for c in cells[:k])
    lines = cells[k].source.strip().splitlines()
    return k - injected, lines[0] if lines else ""


def _clean_executed(executed: Path, source: Path) -> None:
    """Remove what must not be published from an executed notebook: widget state (a progress
    bar frozen at 0 %) and the checkout's absolute paths in papermill's metadata (the input is
    the chapter's notebook, also when a copy without some cells ran)."""
    import nbformat

    nb = nbformat.read(executed, 4)
    nb.metadata.pop("widgets", None)
    meta = nb.metadata.get("papermill", {})
    for key in ("input_path", "output_path"):
        if key in meta:
            meta[key] = shown_path(source if key == "input_path" else Path(meta[key]))
    for cell in nb.cells:
        for output in cell.get("outputs", []):
            output.get("data", {}).pop("application/vnd.jupyter.widget-view+json", None)
    with atomic_path(executed) as tmp:
        nbformat.write(nb, tmp)


@contextlib.contextmanager
def _interruptible():
    """SIGINT (Ctrl-C) raises ``KeyboardInterrupt`` while a notebook runs, so that the run stops
    and its caller says so in one line. Measured: with Python's own handler the interrupt was
    lost inside the execution's event loop and the report ran on to its end; a handler that
    raises it reaches the caller, and papermill's clean-up shuts the kernel down."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupted(signum, frame):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, interrupted)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def run_notebook(notebook: str | os.PathLike, output: str | os.PathLike, parameters: dict,
                 *, progress: bool = False, cell_timeout: float | None = 1800,
                 remove_tags: Sequence[str] = (), tell: Callable[[dict], None] | None = None) -> None:
    """Execute ``notebook`` with papermill in the project kernel, writing ``output``.

    ``cell_timeout``: seconds a cell may go without progress before the run fails (module
    docstring; ``None``: no limit). A cell that makes progress is never stopped, however long
    it runs. ``progress``: papermill's bar of cells. ``tell``: receives the run's state about
    once a second (a dict: ``notebook``, ``cell`` and ``cells`` in source numbering, the cell's
    first line ``source``, ``cell_s`` seconds in it, ``quiet_s`` seconds since the last
    progress, and ``work``: the last post of the work inside the cell, or ``None``).
    ``remove_tags``: cells with any of these tags are left out (nbconvert's
    ``TagRemovePreprocessor``; the report leaves out the exercises, :mod:`nfarm.publishing.course`).

    Raises:
        ReportError: the notebook is not valid, a cell failed, made no progress for
            ``cell_timeout`` seconds or killed the kernel; one line naming the notebook and the
            cell (source numbering). ``output`` holds the executed notebook up to the failure.
    """
    import nbformat
    import papermill
    from nbclient.exceptions import CellTimeoutError, DeadKernelError
    from papermill.exceptions import PapermillExecutionError

    _use_project_kernel()
    notebook, output = Path(notebook), Path(output)
    try:
        nbformat.validate(nbformat.read(notebook, 4))
    except FileNotFoundError:
        raise ReportError(f"{notebook}: notebook not found") from None
    except Exception as exc:  # noqa: BLE001 — NotJSONError, ValidationError, …
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ReportError(f"{notebook.name}: not a valid notebook: {first[:200]}") from None
    output.parent.mkdir(parents=True, exist_ok=True)
    to_run = notebook
    if remove_tags:
        from nbconvert.preprocessors import TagRemovePreprocessor

        nb, _ = TagRemovePreprocessor(remove_cell_tags=set(remove_tags), enabled=True).preprocess(
            nbformat.read(notebook, 4), {})
        to_run = output.with_name(f".{output.stem}.source.ipynb")
        with atomic_path(to_run) as tmp:
            nbformat.write(nb, tmp)
    check_number("cell_timeout", cell_timeout, 0, float("inf"), open_lo=True, finite=False, numpy=False, or_none=True,
                 message=f"cell_timeout must be a positive, finite number of seconds or None, got {cell_timeout!r}")
    quiet = DropMessage("Kernel died")      # reported below, in one line
    logging.getLogger("papermill").addFilter(quiet)
    cells = len(nbformat.read(to_run, 4).cells)
    with tempfile.TemporaryDirectory(prefix="nfarm-kernel-") as sockets, _interruptible(), \
            _Watch(notebook.name, cells, Path(sockets) / "progress.json", cell_timeout, tell) as watch:
        try:
            papermill.execute_notebook(
                str(to_run), str(output), parameters=parameters, kernel_name=KERNEL_NAME,
                language="python", cwd=str(notebook.parent), progress_bar=progress,
                log_output=False, execution_timeout=None,
                kernel_manager_class=_ipc_kernel_manager(sockets, watch),
                on_cell_start=watch.cell_start, on_cell_complete=watch.cell_complete)
        except PapermillExecutionError as exc:
            source = exc.source.strip().splitlines()
            first = source[0] if source else ""
            cell = _source_cell(output, exc.cell_index)
            raise ReportError(
                f"{notebook.name} failed in cell {cell} ({first!r}): {exc.ename}: "
                f"{exc.evalue.strip().splitlines()[0] if exc.evalue.strip() else ''}; "
                f"the executed notebook is kept at {output}") from None
        except KeyboardInterrupt:
            # The running cell's task ends with its kernel and is collected later, when asyncio
            # would log its DeadKernelError ("Task exception was never retrieved", seen when a
            # report runs the editions side by side): the caller says the interrupt in one line.
            logging.getLogger("asyncio").addFilter(DropMessage("Task exception was never retrieved"))
            raise
        except (DeadKernelError, CellTimeoutError, RuntimeError) as exc:
            where = _running_cell(output)
            at = f" in cell {where[0]} ({where[1]!r})" if where else ""
            what = f"timed out: no progress for {cell_timeout:g} s" if watch.stalled \
                or isinstance(exc, CellTimeoutError) or "timed out" in str(exc).lower() else \
                "lost its kernel (it died: a crash, os._exit or out of memory)" \
                if isinstance(exc, DeadKernelError) or "dead" in str(exc).lower() else \
                f"failed: {type(exc).__name__}: {str(exc).strip().splitlines()[0][:200]}"
            said = _last_line(Path(sockets) / "kernel.err") if isinstance(exc, DeadKernelError) \
                and not watch.stalled else ""
            raise ReportError(f"{notebook.name} {what}{at}{f' (its last words: {said!r})' if said else ''}; "
                              f"the executed notebook is kept at {output}") from None
        finally:
            logging.getLogger("papermill").removeFilter(quiet)
            if to_run != notebook:
                to_run.unlink(missing_ok=True)
    _clean_executed(output, notebook)


def chapters(notebooks_dir: Path = NOTEBOOKS) -> list[Path]:
    """The chapter notebooks ``NN_name.ipynb``, in order."""
    return sorted(p for p in notebooks_dir.glob("*.ipynb") if CHAPTER.match(p.name))


def declared_parameters(notebook: Path) -> list[str]:
    """The names its cell tagged ``parameters`` assigns (what papermill may override)."""
    import ast

    try:
        cells = json.loads(notebook.read_text(encoding="utf-8"))["cells"]
        for cell in cells:
            if "parameters" in cell.get("metadata", {}).get("tags", []):
                tree = ast.parse("".join(cell["source"]))
                return [t.id for node in tree.body if isinstance(node, (ast.Assign, ast.AnnAssign))
                        for t in (node.targets if isinstance(node, ast.Assign) else [node.target])
                        if isinstance(t, ast.Name)]
        return []
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ReportError(f"{notebook.name}: not a valid notebook "
                          f"({type(exc).__name__}: {str(exc).splitlines()[0][:200]})") from None
    except SyntaxError as exc:
        raise ReportError(f"{notebook.name}: cannot read its parameters cell "
                          f"({type(exc).__name__}: {str(exc).splitlines()[0][:200]})") from None
