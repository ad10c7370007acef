"""The report pipeline: tables, notebook execution with papermill, HTML export, the manifest.

``python -m nfarm report`` (``make report``) runs every ``notebooks/NN_*.ipynb`` in order in
the project's Jupyter kernel, each into a staging directory; when a chapter succeeds its
figures and tables replace that chapter's files in ``figures/`` (so ``figures/`` always holds
complete runs), the executed notebook is exported to HTML, and at the end
``build/report/index.html`` and ``figures/MANIFEST.sha256`` are rewritten. A failing notebook
stops the run, names the notebook and the cell, and keeps the executed copy for inspection.
"""

from __future__ import annotations

import csv
import hashlib
import html
import io
import json
import os
import re
import shutil
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .paths import BUILD, FIGURES, NOTEBOOKS, atomic_path

__all__ = ["Table", "ReportError", "run_notebook", "build_report", "write_manifest",
           "KERNEL_NAME"]

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


# --------------------------------------------------------------------------------------------
# Running notebooks


class ReportError(RuntimeError):
    """A chapter could not be built; the message says which and where."""


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


def run_notebook(notebook: str | os.PathLike, output: str | os.PathLike, parameters: dict,
                 *, progress: bool = False) -> None:
    """Execute ``notebook`` with papermill in the project kernel, writing ``output``.

    Raises:
        ReportError: a cell failed; names the notebook, the cell and the error. ``output``
            holds the executed notebook up to the failure.
    """
    import papermill
    from papermill.exceptions import PapermillExecutionError

    _use_project_kernel()
    notebook, output = Path(notebook), Path(output)
    output.parent.mkdir(parents=True, exist_ok=True)
    try:
        papermill.execute_notebook(str(notebook), str(output), parameters=parameters,
                                   kernel_name=KERNEL_NAME, language="python", cwd=str(notebook.parent),
                                   progress_bar=progress, log_output=False)
    except PapermillExecutionError as exc:
        source = exc.source.strip().splitlines()
        first = source[0] if source else ""
        raise ReportError(
            f"{notebook.name} failed in cell {exc.cell_index} (execution count "
            f"{exc.exec_count}: {first!r}): {exc.ename}: {exc.evalue}\n"
            f"the executed notebook is kept at {output}") from None


# --------------------------------------------------------------------------------------------
# The whole report


def chapters(notebooks_dir: Path = NOTEBOOKS) -> list[Path]:
    """The chapter notebooks ``NN_name.ipynb``, in order."""
    return sorted(p for p in notebooks_dir.glob("*.ipynb") if CHAPTER.match(p.name))


def _outputs(directory: Path, prefix: str) -> list[Path]:
    return sorted([*directory.glob(f"{prefix}_*.png"), *(directory / "tables").glob(f"{prefix}_*.csv"),
                   *(directory / "tables").glob(f"{prefix}_*.md")])


def _publish(stage: Path, figures_dir: Path, prefix: str) -> list[Path]:
    """Replace chapter ``prefix``'s files in ``figures_dir`` with those in ``stage``."""
    made = _outputs(stage, prefix)
    strays = sorted(set(p for p in stage.rglob("*") if p.is_file()) - set(made))
    if strays:
        raise ReportError(f"chapter {prefix} wrote files not named {prefix}_*.png or "
                          f"tables/{prefix}_*.{{csv,md}}: {', '.join(map(str, strays))}")
    for old in _outputs(figures_dir, prefix):
        old.unlink()
    published = []
    for path in made:
        target = figures_dir / path.relative_to(stage)
        target.parent.mkdir(parents=True, exist_ok=True)
        os.replace(path, target)
        published.append(target)
    return published


def write_manifest(figures_dir: Path = FIGURES) -> Path:
    """Write ``MANIFEST.sha256`` (``sha256sum -c`` format, paths relative to ``figures_dir``)."""
    lines = []
    for path in sorted(p for p in figures_dir.rglob("*")
                       if p.is_file() and p.suffix in (".png", ".csv", ".md")):
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
        lines.append(f"{digest}  {path.relative_to(figures_dir).as_posix()}\n")
    manifest = figures_dir / "MANIFEST.sha256"
    with atomic_path(manifest) as tmp:
        tmp.write_text("".join(lines), encoding="utf-8")
    return manifest


def _title(notebook: Path) -> str:
    cells = json.loads(notebook.read_text(encoding="utf-8"))["cells"]
    for cell in cells:
        if cell["cell_type"] == "markdown":
            for line in "".join(cell["source"]).splitlines():
                if line.startswith("# "):
                    return line[2:].strip()
    return notebook.stem


def _export_html(executed: Path, target: Path) -> None:
    import nbformat
    from nbconvert import HTMLExporter

    body, _ = HTMLExporter(template_name="lab").from_notebook_node(nbformat.read(executed, 4))
    with atomic_path(target) as tmp:
        tmp.write_text(body, encoding="utf-8")


def _csv_to_html(path: Path) -> str:
    rows = list(csv.reader(path.read_text(encoding="utf-8").splitlines()))
    head = "".join(f"<th>{html.escape(c)}</th>" for c in rows[0])
    body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>"
                   for row in rows[1:])
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


_STYLE = """body{font-family:sans-serif;max-width:70em;margin:2em auto;padding:0 1em;color:#222}
img{max-width:100%;border:1px solid #ddd;margin:.5em 0}
table{border-collapse:collapse;margin:.5em 0 1.5em;font-size:.9em}
td,th{border:1px solid #ccc;padding:.2em .6em;text-align:right}th{background:#f3f3f3}
h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}"""


def _write_index(report_dir: Path, figures_dir: Path, entries: list[tuple[str, str, str]]) -> None:
    """``entries``: (prefix, title, html file name) per chapter, in order."""
    shown = report_dir / "figures"
    if shown.exists():
        shutil.rmtree(shown)
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>nfarm — study report"
             f"</title><style>{_STYLE}</style></head><body><h1>nfarm — study report</h1><ol>"]
    parts += [f"<li><a href='#ch{p}'>{html.escape(t)}</a></li>" for p, t, _ in entries]
    parts.append("</ol>")
    for prefix, title, page in entries:
        parts.append(f"<h2 id='ch{prefix}'>{html.escape(title)}</h2>"
                     f"<p><a href='{page}'>The chapter in full (code and prose)</a></p>")
        for path in _outputs(figures_dir, prefix):
            rel = path.relative_to(figures_dir)
            if path.suffix == ".png":
                (shown / rel).parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(path, shown / rel)
                parts.append(f"<h3>{html.escape(path.stem)}</h3><img src='figures/{rel.as_posix()}'>")
            elif path.suffix == ".csv":
                parts.append(f"<h3>{html.escape(path.stem)}</h3>{_csv_to_html(path)}")
    parts.append("</body></html>\n")
    with atomic_path(report_dir / "index.html") as tmp:
        tmp.write_text("\n".join(parts), encoding="utf-8")


def build_report(*, smoke: bool = False, only: Sequence[str] | None = None,
                 notebooks_dir: Path = NOTEBOOKS, figures_dir: Path = FIGURES,
                 build_dir: Path = BUILD, extra_parameters: dict | None = None) -> int:
    """Run the chapters, publish their figures and tables, export HTML, write the index and
    the manifest. Returns the process exit status (0, or 1 with the failure on stderr)."""
    notebooks = chapters(notebooks_dir)
    if only:
        notebooks = [nb for nb in notebooks if nb.name[:2] in set(only)]
    if not notebooks:
        print(f"report: no chapter notebooks NN_*.ipynb in {notebooks_dir}", file=sys.stderr)
        return 1
    report_dir = build_dir / "report"
    for nb in notebooks:
        prefix = nb.name[:2]
        stage = build_dir / "stage" / nb.stem
        shutil.rmtree(stage, ignore_errors=True)
        stage.mkdir(parents=True)
        executed = build_dir / "notebooks" / nb.name
        parameters = {"smoke": smoke, "out_dir": str(stage), **(extra_parameters or {})}
        print(f"report: {nb.name} …", file=sys.stderr, flush=True)
        try:
            run_notebook(nb, executed, parameters, progress=sys.stderr.isatty())
            published = _publish(stage, figures_dir, prefix)
        except ReportError as exc:
            print(f"report: {exc}", file=sys.stderr)
            return 1
        _export_html(executed, report_dir / f"{nb.stem}.html")
        print(f"report: {nb.name}: {len(published)} figures and tables", file=sys.stderr)
    entries = [(nb.name[:2], _title(nb), f"{nb.stem}.html") for nb in chapters(notebooks_dir)
               if (report_dir / f"{nb.stem}.html").exists()]
    _write_index(report_dir, figures_dir, entries)
    manifest = write_manifest(figures_dir)
    print(f"report: {report_dir / 'index.html'}; {manifest}", file=sys.stderr)
    return 0
