"""The report pipeline: tables, notebook execution with papermill, HTML export, the manifest.

``python -m nfarm report`` (``make report``) runs every ``notebooks/NN_*.ipynb`` in order in
the project's Jupyter kernel, each into a staging directory under ``build/stage/``, once per
arm (:class:`Edition`, one per study file): the primary arm's results go to ``figures/``,
another's to ``figures/<study>/``. A chapter whose inputs (:func:`_chapter_key`) and published
files are those of its last run is not run again, so a second ``make report`` with nothing
changed only rewrites the pages.

**Explore freely, publish deliberately.** Only a run with the default parameters publishes
into ``figures/``; a smoke run (``--smoke``) publishes into ``build/smoke/figures/`` and its
pages into ``build/smoke/report/``, never into ``figures/``. A chapter run by hand (JupyterLab,
papermill) writes where its ``out_dir`` parameter says, by default ``build/explore/<chapter>/``.

**Publishing is atomic.** A chapter that succeeds is published as one step: a copy of
``figures/`` with that chapter's files replaced and ``MANIFEST.sha256`` rewritten is built
beside it (``.figures.new/``) and exchanged with ``figures/`` by one ``renameat2(...,
RENAME_EXCHANGE)`` system call. At every instant ``figures/`` is a complete published state
whose manifest matches it (``python -m nfarm verify``), whenever the run is killed.

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
import csv
import ctypes
import ctypes.util
import datetime
import fcntl
import functools
import hashlib
import html
import io
import json
import logging
import multiprocessing
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .paths import BUILD, FIGURES, NOTEBOOKS, ROOT, atomic_path, shown_path
from . import provenance
from .provenance import digest_files as _digest_files

__all__ = ["Table", "shown", "ReportError", "run_notebook", "build_report", "write_manifest",
           "verify_manifest", "chapters", "KERNEL_NAME"]

KERNEL_NAME = "nfarm"
CHAPTER = re.compile(r"^(\d\d)_\w+\.ipynb$")


# --------------------------------------------------------------------------------------------
# Tables


_NEGATIVE_ZERO = re.compile(r"^-(0(\.0*)?(e[+-]?0+)?)$")


def _cell(value, floatfmt: str) -> str:
    if isinstance(value, (float, np.floating)):
        text = format(float(value), floatfmt)
        return _NEGATIVE_ZERO.sub(r"\1", text)  # -1e-17 shown as 0.0000, not -0.0000
    if isinstance(value, (np.integer, np.bool_)):
        return str(value.item())
    return str(value)


def shown(value: float, fmt: str = ".3g", *, floor: float = 1e-15) -> str:
    """A number for people: ``format(value, fmt)``, or ``"< 1e-15"`` when it is at the level of
    floating-point noise (|value| below ``floor``), which is not data."""
    value = float(value)
    if not np.isfinite(value) or value == 0:
        return str(value) if value else "0"
    if abs(value) < floor:
        return f"< {floor:.0e}".replace("e-0", "e-")
    return _NEGATIVE_ZERO.sub(r"\1", format(value, fmt))


@dataclass
class Table:
    """A small table saved as CSV (for machines) and Markdown (for people), shown in notebooks.

    Floats are written with ``floatfmt`` (one format, or one per column) so the files are
    byte-reproducible.
    """

    columns: Sequence[str]
    rows: Sequence[Sequence]
    floatfmt: str | Sequence[str] = ".6g"
    caption: str = ""
    _text: list[list[str]] = field(init=False, repr=False)

    def __post_init__(self):
        for k, row in enumerate(self.rows):
            if len(row) != len(self.columns):
                raise ValueError(f"table row {k} has {len(row)} cells, expected "
                                 f"{len(self.columns)} ({', '.join(self.columns)})")
        formats = [self.floatfmt] * len(self.columns) if isinstance(self.floatfmt, str) \
            else list(self.floatfmt)
        if len(formats) != len(self.columns):
            raise ValueError(f"floatfmt has {len(formats)} formats for {len(self.columns)} columns")
        self._text = [[_cell(v, f) for v, f in zip(row, formats)] for row in self.rows]

    def to_csv(self) -> str:
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(self.columns)
        writer.writerows(self._text)
        return buffer.getvalue()

    def to_markdown(self) -> str:
        escape = lambda s: s.replace("|", "\\|")  # noqa: E731
        lines = ["| " + " | ".join(map(escape, self.columns)) + " |",
                 "|" + "|".join("---" for _ in self.columns) + "|"]
        lines += ["| " + " | ".join(map(escape, row)) + " |" for row in self._text]
        if self.caption:
            lines = [f"*{self.caption}*", ""] + lines
        return "\n".join(lines) + "\n"

    def _repr_markdown_(self) -> str:
        return self.to_markdown()

    def save(self, out_dir: str | os.PathLike, name: str) -> "Table":
        """Write ``out_dir/tables/name.csv`` and ``.md`` atomically; return ``self`` (for display)."""
        for suffix, text in ((".csv", self.to_csv()), (".md", self.to_markdown())):
            with atomic_path(Path(out_dir) / "tables" / f"{name}{suffix}") as tmp:
                tmp.write_text(text, encoding="utf-8")
        return self


DOCUMENTS = ("docs/STUDY.md",)   # project documents a chapter shows a part of (in every chapter's key)


def markdown_section(path: str | os.PathLike, heading: str) -> str:
    """The text of the section ``## heading`` of a Markdown file (up to the next heading of
    the same or a higher level, without the heading line): a chapter shows a document's table
    from its one source instead of a copy."""
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise ValueError(f"{shown_path(path)}: cannot read it ({exc.strerror})") from None
    starts = [k for k, line in enumerate(lines) if line.strip() == f"## {heading}"]
    if len(starts) != 1:
        raise ValueError(f"{shown_path(path)}: heading '## {heading}': expected once, found {len(starts)} times")
    body = []
    for line in lines[starts[0] + 1:]:
        if re.match(r"#{1,2} ", line):
            break
        body.append(line)
    return "\n".join(body).strip() + "\n"


# --------------------------------------------------------------------------------------------
# Running notebooks


class ReportError(RuntimeError):
    """A chapter could not be built; the message says which and where."""


class _DropMessage(logging.Filter):
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
    started = [k for k, c in enumerate(cells)
               if c.metadata.get("papermill", {}).get("status", "pending") != "pending"]
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
    ``TagRemovePreprocessor``; the report leaves out the exercises, :mod:`nfarm.course`).

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
    quiet = _DropMessage("Kernel died")      # reported below, in one line
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
            logging.getLogger("asyncio").addFilter(_DropMessage("Task exception was never retrieved"))
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


# --------------------------------------------------------------------------------------------
# Publishing


def chapters(notebooks_dir: Path = NOTEBOOKS) -> list[Path]:
    """The chapter notebooks ``NN_name.ipynb``, in order."""
    return sorted(p for p in notebooks_dir.glob("*.ipynb") if CHAPTER.match(p.name))


def _outputs(directory: Path, prefix: str) -> list[Path]:
    return sorted([*directory.glob(f"{prefix}_*.png"), *(directory / "tables").glob(f"{prefix}_*.csv"),
                   *(directory / "tables").glob(f"{prefix}_*.md")])


def _published_files(figures_dir: Path) -> list[Path]:
    return sorted(p for p in figures_dir.rglob("*")
                  if p.is_file() and p.suffix in (".png", ".csv", ".md"))


def _file_sha256(path: Path, chunk: int = 1 << 20) -> str:
    """SHA-256 of a file read in chunks of ``chunk`` bytes (memory bounded whatever its size)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while block := f.read(chunk):
            h.update(block)
    return h.hexdigest()


def write_manifest(figures_dir: Path = FIGURES) -> Path:
    """Write ``MANIFEST.sha256`` (``sha256sum -c`` format, paths relative to ``figures_dir``)."""
    lines = []
    for path in _published_files(figures_dir):
        lines.append(f"{_file_sha256(path)}  {path.relative_to(figures_dir).as_posix()}\n")
    manifest = figures_dir / "MANIFEST.sha256"
    with atomic_path(manifest) as tmp:
        tmp.write_text("".join(lines), encoding="utf-8")
    return manifest


def verify_manifest(figures_dir: Path = FIGURES) -> list[str]:
    """What differs between ``figures_dir`` and its manifest (empty when they agree): files
    whose hash differs, listed files that are missing, files the manifest does not list."""
    manifest = figures_dir / "MANIFEST.sha256"
    if not manifest.is_file():
        return [f"{manifest}: missing"]
    problems, listed = [], set()
    root = figures_dir.resolve()
    for number, line in enumerate(manifest.read_text(encoding="utf-8").splitlines(), 1):
        digest, sep, name = line.partition("  ")
        if not sep or not re.fullmatch(r"[0-9a-f]{64}", digest):
            problems.append(f"{manifest}:{number}: not a 'sha256  path' line")
            continue
        path = figures_dir / name
        if Path(name).is_absolute() or not path.resolve().is_relative_to(root):
            problems.append(f"{manifest}:{number}: {name!r} lies outside the figures directory: not checked")
            continue
        listed.add(name)
        if not path.is_file():
            problems.append(f"{name}: listed but missing")
        elif _file_sha256(path) != digest:
            problems.append(f"{name}: differs from the manifest")
    for path in _published_files(figures_dir):
        if path.relative_to(figures_dir).as_posix() not in listed:
            problems.append(f"{path.relative_to(figures_dir).as_posix()}: not in the manifest")
    return problems


_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def _exchange(a: Path, b: Path) -> bool:
    """Swap two directories atomically (Linux ``renameat2(RENAME_EXCHANGE)``); False where
    the system does not offer it."""
    libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
    renameat2 = getattr(libc, "renameat2", None)
    if renameat2 is None:
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint]
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    errno = ctypes.get_errno()
    if errno in (22, 38, 95):   # EINVAL, ENOSYS, EOPNOTSUPP: this file system cannot
        return False
    raise OSError(errno, f"cannot exchange {a} and {b}: {os.strerror(errno)}")


def _recover(figures_dir: Path) -> None:
    """Undo what a run killed in the middle of publishing left beside ``figures_dir``."""
    new, old = _sibling(figures_dir, "new"), _sibling(figures_dir, "old")
    if not figures_dir.exists() and old.exists():     # killed between the two fallback renames
        os.rename(old, figures_dir)
    shutil.rmtree(new, ignore_errors=True)
    shutil.rmtree(old, ignore_errors=True)


def _sibling(figures_dir: Path, kind: str) -> Path:
    return figures_dir.with_name(f".{figures_dir.name}.{kind}")


@contextlib.contextmanager
def _publishing(figures_dir: Path):
    """Hold the lock of ``figures_dir``'s publishing: editions run side by side (module
    docstring) publish one at a time. An exclusive ``flock`` on the parent directory, which
    the kernel releases when its holder dies: no lock file, nothing stale."""
    parent = figures_dir.parent
    parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(parent, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)            # releases the lock


def _publish(stage: Path, figures_dir: Path, prefix: str, subdir: str = "") -> list[Path]:
    """Replace chapter ``prefix``'s files in ``figures_dir/subdir`` (an edition's directory,
    ``""`` for the primary arm's) with those in ``stage`` and rewrite the manifest, as one
    atomic step (module docstring)."""
    made = _outputs(stage, prefix)
    strays = sorted(set(p for p in stage.rglob("*") if p.is_file()) - set(made))
    if strays:
        raise ReportError(f"chapter {prefix} wrote files not named {prefix}_*.png or "
                          f"tables/{prefix}_*.{{csv,md}}: {', '.join(map(str, strays))}")
    with _publishing(figures_dir):
        return _publish_locked(stage, made, figures_dir, prefix, subdir)


def _publish_locked(stage: Path, made: list[Path], figures_dir: Path, prefix: str, subdir: str) -> list[Path]:
    _recover(figures_dir)
    new = _sibling(figures_dir, "new")
    if figures_dir.exists():
        shutil.copytree(figures_dir, new)
    else:
        new.mkdir(parents=True)
    for old in _outputs(new / subdir, prefix):
        old.unlink()
    published = []
    for path in made:
        target = new / subdir / path.relative_to(stage)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(path, target)
        published.append(figures_dir / subdir / path.relative_to(stage))
    write_manifest(new)
    if not figures_dir.exists():
        os.rename(new, figures_dir)
    elif _exchange(new, figures_dir):
        shutil.rmtree(new)                      # now the previous state
    else:                                       # two renames; _recover repairs a kill between
        old = _sibling(figures_dir, "old")
        os.rename(figures_dir, old)
        os.rename(new, figures_dir)
        shutil.rmtree(old)
    return published


# --------------------------------------------------------------------------------------------
# HTML


def _title(notebook: Path) -> str:
    cells = json.loads(notebook.read_text(encoding="utf-8"))["cells"]
    for cell in cells:
        if cell["cell_type"] == "markdown":
            for line in "".join(cell["source"]).splitlines():
                if line.startswith("# "):
                    return line[2:].strip()
    return notebook.stem


#: Cells of the course edition (:mod:`nfarm.course`), left out of the report.
COURSE_TAGS = ("exercise", "solution", "check")

MATHJAX = "mathjax/MathJax.js?config=TeX-AMS-MML_HTMLorMML-full,Safe"


def _install_mathjax(report_dir: Path) -> None:
    """Copy MathJax from the ``jupyter_server_mathjax`` package beside the pages (once)."""
    import jupyter_server_mathjax

    source = Path(jupyter_server_mathjax.__file__).parent / "static"
    target = report_dir / "mathjax"
    if (target / "MathJax.js").is_file():
        return
    tmp = report_dir / ".mathjax.tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    shutil.copytree(source, tmp)
    shutil.rmtree(target, ignore_errors=True)
    os.rename(tmp, target)


def _nav(links: dict[str, tuple[str, str] | None]) -> str:
    parts = [f"<a href='{html.escape(href)}'>{label}: {html.escape(title)}</a>"
             for label, link in links.items() if link for href, title in [link]]
    return ("<nav style='font-family:sans-serif;margin:1em 2em;display:flex;gap:2em'>"
            + "".join(parts) + "</nav>")


def _merge_parameters(nb) -> None:
    """One parameters cell on a page: the values papermill injected written into the chapter's
    own parameters cell (its comments kept), and the injected cell dropped; a first comment
    names the values this run changed. A reader sees the values the page was made with, once."""
    import ast

    tagged = lambda tag: [k for k, c in enumerate(nb.cells) if tag in c.metadata.get("tags", [])]  # noqa: E731
    own, injected = tagged("parameters"), tagged("injected-parameters")
    if len(own) != 1 or len(injected) != 1:
        return
    cell, given = nb.cells[own[0]], nb.cells[injected[0]].source
    try:
        values = {node.targets[0].id: ast.get_source_segment(given, node.value)
                  for node in ast.parse(given).body
                  if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name)}
        tree = ast.parse(cell.source)
    except SyntaxError:
        return
    lines = cell.source.split("\n")
    changed = []
    for node in sorted((n for n in tree.body if isinstance(n, ast.Assign) and len(n.targets) == 1
                        and isinstance(n.targets[0], ast.Name) and n.targets[0].id in values),
                       key=lambda n: n.lineno, reverse=True):
        name = node.targets[0].id
        if ast.get_source_segment(cell.source, node.value) == values[name]:
            values.pop(name)
            continue
        rest = lines[node.end_lineno - 1][node.end_col_offset:]
        lines[node.lineno - 1:node.end_lineno] = [f"{name} = {values.pop(name)}{rest}"]
        changed.append(name)
    lines += [f"{name} = {value}" for name, value in values.items()]
    changed += list(values)
    if changed:
        lines.insert(0, f"# This page's run set: {', '.join(sorted(changed))}")
    cell.source = "\n".join(lines)
    del nb.cells[injected[0]]


def _name_the_arm(nb, arm: str) -> None:
    """The chapter's heading names the arm its page is for (an edition's pages look alike)."""
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            lines = cell.source.split("\n")
            for k, line in enumerate(lines):
                if line.startswith("# "):
                    lines[k] = f"{line} · {arm}"
                    cell.source = "\n".join(lines)
                    return


def _export_html(executed: Path, target: Path, nav: str = "", mathjax: str = MATHJAX,
                 title: str = "", arm: str = "") -> None:
    """The executed notebook as an HTML page: cells tagged ``remove-input`` show only their
    output (prose computed in code), ``remove-cell`` nothing; MathJax from the report
    directory; a navigation bar between chapters; one parameters cell with the run's values
    (:func:`_merge_parameters`); the heading naming ``arm`` when given."""
    import nbformat
    from nbconvert import HTMLExporter
    from nbconvert.preprocessors import TagRemovePreprocessor
    from traitlets.config import Config

    config = Config()
    config.TagRemovePreprocessor.remove_input_tags = {"remove-input"}
    config.TagRemovePreprocessor.remove_cell_tags = {"remove-cell"}
    config.TagRemovePreprocessor.enabled = True
    exporter = HTMLExporter(template_name="lab", config=config, mathjax_url=mathjax,
                            require_js_url="", jquery_url="", widget_renderer_url="")
    exporter.register_preprocessor(TagRemovePreprocessor(config=config), enabled=True)
    # Figures carry their captions as alternative text (nfarm.plotting.save_figure); an image
    # shown without one gets nbconvert's generic text and a warning, which the check of the
    # smoke report (tests/test_pages.py) turns into a failure.
    quiet = _DropMessage("Alternative text is missing")
    exporter.log.addFilter(quiet)
    try:
        nb = nbformat.read(executed, 4)
        _merge_parameters(nb)
        if arm:
            _name_the_arm(nb, arm)
        body, _ = exporter.from_notebook_node(nb, resources={"metadata": {"name": title or executed.stem}})
    finally:
        exporter.log.removeFilter(quiet)
    body = body.replace('<script src=""></script>', "")       # the URLs switched off above
    if nav:
        body = re.sub(r"(<body[^>]*>)", lambda m: m.group(1) + nav, body, count=1)
        body = body.replace("</body>", nav + "</body>", 1)
    with atomic_path(target) as tmp:
        tmp.write_text(body, encoding="utf-8")


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


_STYLE = """body{font-family:sans-serif;max-width:70em;margin:2em auto;padding:0 1em;color:#222}
img{max-width:100%;border:1px solid #ddd;margin:.5em 0}
table{border-collapse:collapse;margin:.5em 0 1.5em;font-size:.9em}
td,th{border:1px solid #ccc;padding:.2em .6em;text-align:right}th{background:#f3f3f3}
h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}
figure{margin:1em 0 2em}figcaption{color:#444;margin:.2em 0}.file{color:#888;font-size:.8em}
dl{display:grid;grid-template-columns:max-content auto;gap:.2em 1em}dt{font-weight:bold}"""


def _git(*args: str) -> str:
    try:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                              timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""


# --------------------------------------------------------------------------------------------
# Editions: the chapters once per arm


PRIMARY_STUDY = "intelbot5"      # the dissertation's arm: its edition publishes into figures/
#: Where the chapters write their rerun recordings (their ``recordings_dir`` default); another
#: edition's go to ``RECORDINGS/<name>/``.
RECORDINGS = "build/recordings"


@dataclass(frozen=True)
class Edition:
    """One arm's run of the chapters: a study file and its robot file (as the reader names
    them). The primary edition runs every chapter with its default parameters and publishes
    into ``figures/``; another runs the chapters that take a ``robot_file`` or ``study_file``
    with its own and publishes into ``figures/<name>/``. A chapter that takes neither (04, on
    Jang's benchmarks) is the same for every arm and runs once; a chapter that takes
    ``study_files`` (08) compares the editions and runs once, after them."""

    name: str
    study_file: str
    robot_file: str
    primary: bool

    @property
    def subdir(self) -> str:
        return "" if self.primary else self.name

    def parameters(self, declared: Sequence[str]) -> dict | None:
        """The parameters of this edition's run of a chapter declaring ``declared``, or None
        when the chapter is not run for it."""
        if self.primary:
            return {}
        chosen = {k: v for k, v in (("robot_file", self.robot_file),
                                    ("study_file", self.study_file)) if k in declared}
        if chosen and "recordings_dir" in declared:   # its recordings beside, not over, the primary's
            chosen["recordings_dir"] = f"{RECORDINGS}/{self.name}"
        return chosen or None


def editions(params_dir: Path | None = None) -> list[Edition]:
    """One edition per study file ``params/studies/*.yaml``, the primary (intelbot5) first;
    a single primary edition with the chapters' defaults if there is no study file."""
    from .datasets import load_study          # the study's robot file, validated
    from .paths import PARAMS

    files = sorted(((params_dir or PARAMS) / "studies").glob("*.yaml"))
    found = [Edition(f.stem, shown_path(f), load_study(f).robot_file, f.stem == PRIMARY_STUDY)
             for f in files]
    if not any(e.primary for e in found):
        return [Edition(PRIMARY_STUDY, "", "", True)]
    return sorted(found, key=lambda e: (not e.primary, e.name))


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


def digest_files(h, paths) -> None:
    """Feed each file's project-relative name and SHA-256 to the hash ``h`` (sorted)."""
    _digest_files(h, paths, ROOT)


_NFARM_IMPORT = re.compile(r"^\s*(?:from\s+nfarm\.(\w+)\s+import|import\s+nfarm\.(\w+)|"
                           r"from\s+nfarm\s+import\s+(\([^)]*\)|[\w ,]+)|import\s+nfarm\s*$)", re.M)


def notebook_modules(notebook: Path) -> list[str]:
    """The package modules a notebook's code cells import (``from nfarm.x import …``,
    ``from nfarm import x``, ``import nfarm.x``); ``import nfarm`` alone means all of them."""
    cells = json.loads(notebook.read_text(encoding="utf-8"))["cells"]
    code = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
    everything = sorted(p.stem for p in provenance.PACKAGE.glob("*.py"))
    found = set()
    for sub, imported, names in _NFARM_IMPORT.findall(code):
        if not (sub or imported or names):
            return everything
        found.update(n.split()[0] for n in (sub or imported or names).strip("()").split(",") if n.split())
    return sorted(m for m in found if m in everything)


def _chapter_key(notebook: Path, parameters: dict, smoke: bool) -> str:
    """SHA-256 of everything a chapter's results depend on: the notebook, its parameters, the
    content of the package modules it imports and of this module (which runs it), with what
    they import, transitively (:func:`nfarm.provenance.code_modules`), every parameter file
    (not the ``.md`` notes beside them), the locked environment and the numerics settings
    (``make report``'s pinned kernels). A change to a module no chapter imports (the course's)
    leaves the chapters as they are."""
    from .learned import NUMERICS_ENV
    from .paths import PARAMS

    h = hashlib.sha256()
    h.update(notebook.read_bytes())
    h.update(json.dumps({"parameters": parameters, "smoke": smoke,
                         "env": {k: os.environ.get(k) for k in NUMERICS_ENV},
                         "python": sys.version}, sort_keys=True, default=str).encode())
    modules = provenance.code_modules("report", *notebook_modules(notebook))
    _digest_files(h, [provenance.PACKAGE / f"{m}.py" for m in modules], provenance.PACKAGE)
    digest_files(h, [p for p in PARAMS.rglob("*") if p.is_file() and p.suffix != ".md"])
    digest_files(h, [p for p in (ROOT / "environment.lock", *(ROOT / d for d in DOCUMENTS)) if p.is_file()])
    return h.hexdigest()


def _published_digests(figures_dir: Path, subdir: str, prefix: str) -> dict[str, str]:
    return {p.relative_to(figures_dir).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in _outputs(figures_dir / subdir, prefix)}


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
# The index


def _figures_html(figures_dir: Path, subdir: str, prefix: str, shown: Path) -> list[str]:
    parts = []
    for path in _outputs(figures_dir / subdir, prefix):
        if path.suffix == ".md":
            continue
        rel = path.relative_to(figures_dir)
        caption = html.escape(_caption(path))
        label = f"<span class='file'>{html.escape(rel.as_posix())}</span>"
        if path.suffix == ".png":
            (shown / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(path, shown / rel)
            parts.append(f"<figure><img src='figures/{rel.as_posix()}' alt='{caption}'>"
                         f"<figcaption>{caption} {label}</figcaption></figure>")
        else:
            parts.append(f"<figure><figcaption>{caption} {label}</figcaption>"
                         f"{_csv_to_html(path)}</figure>")
    return parts


ABSTRACT_QUESTION = (
    "Can adaptive neuro-fuzzy inference systems (ANFIS), trained with Jang's hybrid rule on data generated "
    "from a 5-DOF arm's numerical models — the DH forward kinematics, Levenberg–Marquardt inverse "
    "kinematics and recursive Newton–Euler inverse dynamics — compute the arm's inverse kinematics and "
    "inverse dynamics, and how do they compare with the exact solutions and with strong baselines?")
ABSTRACT_LIMITS = (
    "The learned inverse kinematics covers one declared region of each arm, where the inverse map is "
    "single-valued (chapter 05); over the full joint ranges it is many-valued and not learnable as one "
    "function. The data are simulated: the rigid-body torques are exact, and the arm with friction is a "
    "model whose law no learner assumes. The dissertation's text does not give its robot's numbers, data "
    "settings, rule bases or budgets: those designs are assumed and labelled so (the deviations table of "
    "chapter 05). The spreads are over the sweep files' seeds (data draws) for the comparisons made on "
    "validation data and bootstrap intervals over the held-out poses or trajectories for the results.")


def _abstract_html(figures_dir: Path, arms: list[Edition]) -> list[str]:
    """The abstract: the study's question, each arm's answers read from its published
    ``07_summary.csv`` (every number computed by chapter 07; :func:`nfarm.summary.abstract_lines`),
    and the study's limits."""
    from .summary import abstract_lines, read_long_table

    parts = ["<h2 id='abstract'>Abstract</h2>", f"<p><b>Question.</b> {html.escape(ABSTRACT_QUESTION)}</p>"]
    answers = []
    for edition in arms:
        path = figures_dir / edition.subdir / "tables" / "07_summary.csv"
        if path.is_file():
            try:
                answers += abstract_lines(edition.name, read_long_table(path))
            except (ValueError, KeyError) as exc:      # an older chapter 07's table: say so, not fail
                answers.append(f"{edition.name}: no answers ({exc}); rerun chapter 07.")
    if answers:
        parts.append("<p><b>Answers</b> (on held-out data, with 95 % bootstrap intervals; from each arm's "
                     "<code>tables/07_summary.csv</code>):</p><ul>")
        parts += [f"<li>{html.escape(line)}</li>" for line in answers]
        parts.append("</ul>")
    else:
        parts.append("<p><b>Answers.</b> Not yet computed: chapter 07 has not published its summary table.</p>")
    parts.append(f"<p><b>Limits.</b> {html.escape(ABSTRACT_LIMITS)}</p>")
    return parts


def _write_index(report_dir: Path, figures_dir: Path,
                 pages: dict[str, list[tuple[str, str, str]]], arms: list[Edition],
                 compared: list[tuple[str, str, str]], *, parameters: dict, smoke: bool,
                 recordings_dir: Path | None = None) -> None:
    """``pages``: per edition name, (prefix, title, page path) of its chapters in order;
    ``compared``: the same for the chapters comparing the editions. Each edition's section
    links the rerun recordings its chapters wrote (:data:`RECORDINGS`, an edition's in its own
    subdirectory) when ``recordings_dir`` holds any."""
    shown = report_dir / "figures"
    if shown.exists():
        shutil.rmtree(shown)
    commit = _git("rev-parse", "--short=12", "HEAD") or "unknown"
    dirty = " (with uncommitted changes)" if _git("status", "--porcelain") else ""
    when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    kind = "smoke run (small parameters: not the published results)" if smoke else \
        "published results (default parameters)" if not parameters else "a run with other parameters"
    robots = "; ".join(f"{e.name}: {e.robot_file or 'the chapters’ default'}"
                       + ("" if e.primary else f" (figures in {e.name}/)") for e in arms)
    facts = {"what": kind, "arms": robots,
             "parameters": ", ".join(f"{k} = {v!r}" for k, v in parameters.items()) or "defaults",
             "commit": commit + dirty, "built": when,
             "figures": shown_path(figures_dir) + " (checked by MANIFEST.sha256)"}
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>nfarm — study report"
             f"</title><style>{_STYLE}</style></head><body><h1>nfarm — a 5-DOF arm modelled with "
             "numerical methods and ANFIS</h1>"]
    parts += _abstract_html(figures_dir, arms)
    parts.append("<dl>")
    parts += [f"<dt>{html.escape(k)}</dt><dd>{html.escape(v)}</dd>" for k, v in facts.items()]
    parts.append("</dl>")
    for prefix, title, page in compared:           # the arms side by side, first
        parts.append(f"<h2 id='ch{prefix}'>{html.escape(title)}</h2>"
                     f"<p><a href='{page}'>The chapter in full</a></p>")
        parts += _figures_html(figures_dir, "", prefix, shown)

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
            parts.append(f"<h2 id='{edition.name}'>Chapters for {html.escape(edition.name)}"
                         f"{' (the dissertation’s arm)' if edition.primary else ''}</h2><ol>")
            parts += [f"<li value='{int(e[0])}'><a href='{read_at(edition, e)}'>{html.escape(e[1])}</a> · <a "
                      f"href='#{anchor(edition, e)}'>its figures and tables</a>"
                      f"{'' if own(edition, e[2]) or e in compared else ' (the same for every arm)'}"
                      f"</li>" for e in entries]
            parts.append("</ol>")
            found = sorted((recordings_dir / edition.subdir).glob("*.rrd")) if recordings_dir else []
            if found:
                parts.append("<p>Rerun recordings: " + ", ".join(
                    f"<a href='{html.escape(os.path.relpath(f, report_dir))}'>{html.escape(f.name)}</a>"
                    for f in found) + f" (open one with <code>.venv/bin/rerun "
                    f"{html.escape(shown_path(found[0]))}</code>)</p>")
    for edition in arms:
        for entry in pages.get(edition.name, []):
            prefix, title, page = entry
            if entry in compared or not own(edition, page):
                continue
            parts.append(f"<h3 id='{edition.name}-ch{prefix}'>{html.escape(edition.name)} · "
                         f"{html.escape(title)}</h3><p><a href='{page}'>The chapter in full "
                         f"(prose, code and results)</a></p>")
            parts += _figures_html(figures_dir, edition.subdir, prefix, shown)
    parts.append("</body></html>\n")
    with atomic_path(report_dir / "index.html") as tmp:
        tmp.write_text("\n".join(parts), encoding="utf-8")


# --------------------------------------------------------------------------------------------
# The whole report


def _select(notebooks_dir: Path, only: Sequence[str] | None) -> tuple[list[Path], list[Path]] | str:
    everything = chapters(notebooks_dir)
    if only is None:
        return everything, everything
    wanted = set(only)
    if not wanted:
        return "report: --only needs chapter numbers (e.g. --only 01 03)"
    unknown = sorted(wanted - {nb.name[:2] for nb in everything})
    if unknown:
        return (f"report: no chapter {', '.join(unknown)} (chapters: "
                f"{', '.join(nb.name[:2] for nb in everything)})")
    return everything, [nb for nb in everything if nb.name[:2] in wanted]


def build_report(*, smoke: bool = False, only: Sequence[str] | None = None,
                 notebooks_dir: Path = NOTEBOOKS, figures_dir: Path = FIGURES,
                 build_dir: Path = BUILD, extra_parameters: dict | None = None,
                 cell_timeout: float | None = 1800, arms: Sequence[Edition] | None = None,
                 force: bool = False, parallel: bool | None = None) -> int:
    """Run the chapters for every arm (:func:`editions`), publish their figures and tables,
    export HTML and write the index.

    Only a run with the default parameters (not ``smoke``, no ``extra_parameters``)
    publishes into ``figures_dir``; others publish into ``build_dir/<variant>/figures``. A run
    with ``extra_parameters`` is one edition (the primary's, with those parameters). A chapter
    whose inputs (:func:`_chapter_key`) are those of its last run, and whose published files
    are still that run's, is not run again unless ``force``.

    ``parallel`` (default: when this process may use two CPUs or more): the editions' chapters
    run side by side, one process per edition, each in chapter order (module docstring); the
    chapters that compare the editions run after them. Otherwise one after the other.

    Returns the process exit status (0; 1 with the failure on stderr; 2 for a bad choice of
    chapters; 130 when interrupted).
    """
    selected = _select(notebooks_dir, only)
    if isinstance(selected, str):
        print(selected, file=sys.stderr)
        return 2
    everything, notebooks = selected
    if not notebooks:
        print(f"report: no chapter notebooks NN_*.ipynb in {notebooks_dir}", file=sys.stderr)
        return 1
    extra = dict(extra_parameters or {})
    variant = "smoke" if smoke else "custom" if extra else None
    base = build_dir / variant if variant else build_dir
    if variant:
        figures_dir = base / "figures"
    report_dir = base / "report"
    try:
        arms = list(arms) if arms is not None else editions()
        if extra:
            arms = [a for a in arms if a.primary]
        declared = {nb.name: declared_parameters(nb) for nb in everything}
    except (ReportError, ValueError) as exc:      # a bad notebook, or study file (ParamsError)
        print(f"report: {exc}", file=sys.stderr)
        return 1

    def runs(nb: Path) -> list[tuple[Edition, dict]]:
        names = declared[nb.name]
        if "study_files" in names:                # compares the arms: once, after them
            if extra and "study_files" not in extra:
                return []
            files = {} if extra or len(arms) < 2 else \
                {"study_files": [a.study_file for a in arms]}
            return [(arms[0], files)]
        return [(a, p) for a in arms if (p := a.parameters(names)) is not None]

    with _publishing(figures_dir):
        _recover(figures_dir)
    comparing = {nb.name for nb in everything if "study_files" in declared[nb.name]}
    jobs = [(nb, arm, own) for nb in notebooks for arm, own in runs(nb)]
    sequences = [[j for j in jobs if j[1] is arm and j[0].name not in comparing] for arm in arms]
    sequences = [seq for seq in sequences if seq]
    if parallel is None:
        parallel = _cpus() >= 2
    side_by_side = parallel and len(sequences) > 1

    def chapter(nb: Path, arm: Edition, own: dict) -> bool:
        """Run and publish one chapter of one edition; False (said on stderr) if it failed."""
        prefix = nb.name[:2]
        label = nb.name if arm.primary else f"{nb.name} ({arm.name})"
        stage = build_dir / "stage" / (nb.stem if arm.primary else f"{arm.name}-{nb.stem}")
        executed = base / "notebooks" / arm.subdir / nb.name
        stamp = base / "stamps" / arm.name / f"{nb.stem}.json"
        parameters = {"smoke": smoke, **own, **extra}
        key = _chapter_key(nb, parameters, smoke)
        if not force and _up_to_date(stamp, key, executed, figures_dir, arm.subdir, prefix):
            print(f"report: {label}: up to date (its inputs are unchanged)", file=sys.stderr, flush=True)
            return True
        shutil.rmtree(stage, ignore_errors=True)
        stage.mkdir(parents=True)
        print(f"report: {label} …", file=sys.stderr, flush=True)
        try:
            run_notebook(nb, executed, {**parameters, "out_dir": shown_path(stage)},
                         progress=sys.stderr.isatty() and not side_by_side, cell_timeout=cell_timeout,
                         remove_tags=COURSE_TAGS)
            published = _publish(stage, figures_dir, prefix, arm.subdir)
        except ReportError as exc:
            stamp.unlink(missing_ok=True)
            print(f"report: {exc}", file=sys.stderr, flush=True)
            return False
        shutil.rmtree(stage, ignore_errors=True)
        stamp.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(stamp) as tmp:
            tmp.write_text(json.dumps({"key": key, "outputs": _published_digests(
                figures_dir, arm.subdir, prefix)}, indent=1), encoding="utf-8")
        print(f"report: {label}: {len(published)} figures and tables published in "
              f"{shown_path(figures_dir / arm.subdir)}", file=sys.stderr, flush=True)
        return True

    def in_order(sequence) -> int:
        return 0 if all(chapter(*job) for job in sequence) else 1

    try:
        _install_mathjax(report_dir)
        if side_by_side:
            status = _side_by_side([functools.partial(in_order, seq) for seq in sequences])
        else:
            status = in_order([j for j in jobs if j[0].name not in comparing])
        if status == 0:
            status = in_order([j for j in jobs if j[0].name in comparing])
        if status == 130:
            raise KeyboardInterrupt
        if status:
            return status
        _write_pages(everything, runs, comparing, arms, base, report_dir, figures_dir, extra, smoke,
                     None if smoke or extra else build_dir / "recordings")
    except KeyboardInterrupt:
        print(f"report: interrupted; {shown_path(figures_dir)} holds the chapters published "
              f"before (its manifest matches)", file=sys.stderr)
        return 130
    except OSError as exc:                        # a read-only or full build directory, …
        return _cannot_write(exc)
    print(f"report: {shown_path(report_dir / 'index.html')}; figures in "
          f"{shown_path(figures_dir)}", file=sys.stderr)
    return 0


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


def _side_by_side(tasks, grace: float = 10.0) -> int:
    """Run each task (a callable returning an exit status) in a forked process of its own, all
    at once; the first non-zero status (130 when interrupted). Ctrl-C reaches every process of
    the terminal's group: each child stops its notebook (:func:`_interruptible`) and exits 130,
    and this process waits for them."""
    context = multiprocessing.get_context("fork")
    sys.stdout.flush()
    sys.stderr.flush()
    children = [context.Process(target=_child, args=(task,), daemon=False) for task in tasks]
    for child in children:
        child.start()
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
    codes = [child.exitcode for child in children]
    if interrupted or 130 in codes or any(c is not None and c < 0 for c in codes):
        return 130
    return next((c for c in codes if c), 0)


def _cannot_write(exc: OSError) -> int:
    where = f" {shown_path(Path(exc.filename))}" if exc.filename else ""
    print(f"report: cannot write{where}: {exc.strerror or exc}", file=sys.stderr)
    return 1


def _child(task) -> None:
    try:
        code = task()
    except KeyboardInterrupt:
        code = 130
    except OSError as exc:
        code = _cannot_write(exc)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def _write_pages(everything, runs, comparing: set[str], arms, base: Path, report_dir: Path,
                 figures_dir: Path, extra: dict, smoke: bool,
                 recordings_dir: Path | None = None) -> None:
    """HTML pages of every executed chapter, with navigation within each arm's chapters, and
    the index."""
    pages: dict[str, list[tuple[str, str, str]]] = {}
    compared = []
    per_arm = set()              # chapters run for more than one arm: their titles name it
    for nb in everything:
        if len(list(runs(nb))) > 1:
            per_arm.add(nb.name[:2])
        for arm, _ in runs(nb):
            executed = base / "notebooks" / arm.subdir / nb.name
            if not executed.exists():
                continue
            entry = (nb.name[:2], _title(nb), f"{arm.subdir}/{nb.stem}.html".lstrip("/"))
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
        up = "../" if arm.subdir else ""      # an edition's pages are one directory down
        # A shared chapter is copied into the edition's directory with the edition's navigation,
        # so that "previous" and "next" never leave the edition.
        here = [f"{arm.subdir}/{Path(page).name}" if arm.subdir else page for _, _, page in own]
        for k, (prefix, title, page) in enumerate(own):
            # An edition's last chapter leads on to the chapter that compares the arms (one page,
            # the primary's), which the reader of every edition meets last.
            last = (up + compared[0][2], compared[0][1]) if compared and not arm.primary else None
            links = {"index": (up + "index.html", "all chapters"),
                     "previous": (up + here[k - 1], own[k - 1][1]) if k > 0 else None,
                     "next": (up + here[k + 1], own[k + 1][1]) if k + 1 < len(own) else last}
            executed = base / "notebooks" / page.replace(".html", ".ipynb")
            page = here[k]
            _export_html(executed, report_dir / page, _nav(links), mathjax=up + MATHJAX,
                         title=f"{title} · {arm.name}" if prefix in per_arm else title,
                         arm=arm.name if prefix in per_arm else "")
    _write_index(report_dir, figures_dir, {a.name: pages.get(a.name, []) for a in arms}, arms,
                 compared, parameters=extra, smoke=smoke, recordings_dir=recordings_dir)
