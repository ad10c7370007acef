"""Running a notebook headlessly: papermill in the project's own Jupyter kernel, over Unix
sockets, with a time limit per cell, Ctrl-C that stops it, and one line naming the notebook
and the cell when it fails (:func:`run_notebook`); the chapters in order (:func:`chapters`) and
the names a notebook's ``parameters`` cell declares (:func:`declared_parameters`).

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
from collections.abc import Sequence
from pathlib import Path

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


def _ipc_kernel_manager(directory: str):
    """A kernel manager whose kernel talks over Unix sockets in ``directory``: no open TCP
    ports, and no "running over TCP without encryption" warning from every kernel."""
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
            await super()._async_launch_kernel(kernel_cmd, **kw)

    return IPCKernelManager


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
                 remove_tags: Sequence[str] = ()) -> None:
    """Execute ``notebook`` with papermill in the project kernel, writing ``output``.

    ``cell_timeout``: seconds a cell may run before the run fails (``None``: no limit).
    ``remove_tags``: cells with any of these tags are left out (nbconvert's
    ``TagRemovePreprocessor``; the report leaves out the exercises, :mod:`nfarm.publishing.course`).

    Raises:
        ReportError: the notebook is not valid, a cell failed, timed out or killed the
            kernel; one line naming the notebook and the cell (source numbering). ``output``
            holds the executed notebook up to the failure.
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
    quiet = DropMessage("Kernel died")      # reported below, in one line
    logging.getLogger("papermill").addFilter(quiet)
    with tempfile.TemporaryDirectory(prefix="nfarm-kernel-") as sockets, _interruptible():
        try:
            papermill.execute_notebook(
                str(to_run), str(output), parameters=parameters, kernel_name=KERNEL_NAME,
                language="python", cwd=str(notebook.parent), progress_bar=progress,
                log_output=False, execution_timeout=cell_timeout,
                kernel_manager_class=_ipc_kernel_manager(sockets))
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
            what = f"timed out after {cell_timeout:g} s" if isinstance(exc, CellTimeoutError) \
                or "timed out" in str(exc).lower() else \
                "lost its kernel (it died: a crash, os._exit or out of memory)" \
                if isinstance(exc, DeadKernelError) or "dead" in str(exc).lower() else \
                f"failed: {type(exc).__name__}: {str(exc).strip().splitlines()[0][:200]}"
            said = _last_line(Path(sockets) / "kernel.err") if isinstance(exc, DeadKernelError) else ""
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
