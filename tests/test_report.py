"""The report pipeline: what is published where, atomic publishing under kills, failure
reports naming the cell, the index, the manifest, reproducibility, offline HTML."""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import numpy as np
import pytest
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

from nfarm.infra import notebook_runs
from nfarm.publishing import manifest, report
from nfarm.infra.paths import ROOT, atomic_path
from nfarm.presentation.tables import Table, markdown_section
from nfarm.publishing.manifest import verify_manifest, write_manifest
from nfarm.__main__ import report_command as build_report   # the command line's: exit status, one line each


def make_notebook(path, *code, tags=None):
    cells = [new_markdown_cell(f"# Chapter {path.stem}"),
             new_code_cell('smoke = False\nseed = 0\nout_dir = "build/explore/x"',
                           metadata={"tags": ["parameters"]})]
    cells += [new_code_cell(c, metadata={"tags": tags} if tags else {}) for c in code]
    nbformat.write(new_notebook(cells=cells), path)


WRITE = """import matplotlib.pyplot as plt
from nfarm.infra.paths import project_path
from nfarm.presentation.plotting import save_figure
from nfarm.presentation.tables import Table
out = project_path(out_dir)
fig, ax = plt.subplots()
ax.plot([0, 1], [0, 1])
save_figure(fig, out, "{p}_line", caption="A line of chapter {p}")
Table(["smoke"], [[smoke]], caption="Was it a smoke run?").save(out, "{p}_params")"""

PROSE = 'from IPython.display import Markdown, display\ndisplay(Markdown(f"The answer is {6 * 7}."))'


@pytest.fixture
def project(tmp_path):
    notebooks = tmp_path / "notebooks"
    notebooks.mkdir()
    make_notebook(notebooks / "01_first.ipynb", WRITE.format(p="01"))
    make_notebook(notebooks / "02_second.ipynb", WRITE.format(p="02"))
    make_notebook(notebooks / "03_third.ipynb", WRITE.format(p="03"))
    nb = nbformat.read(notebooks / "03_third.ipynb", 4)
    nb.cells.append(new_markdown_cell("$$x^2$$"))
    nb.cells.append(new_code_cell(PROSE, metadata={"tags": ["remove-input"]}))
    nbformat.write(nb, notebooks / "03_third.ipynb")
    dirs = dict(notebooks_dir=notebooks, figures_dir=tmp_path / "figures",
                build_dir=tmp_path / "build")
    return tmp_path, dirs


def _head() -> str:
    """The checkout's commit as the index gives it ("" outside a git checkout)."""
    try:
        return subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                              timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""


def digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.mark.notebook
def test_default_run_publishes_atomically_with_index_manifest_and_offline_html(project):
    root, dirs = project
    figures, build = dirs["figures_dir"], dirs["build_dir"]
    stale = figures / "01_removed_since.png"
    stale.parent.mkdir(parents=True)
    stale.write_bytes(b"old")
    heads = {_head()}
    assert build_report(**dirs) == 0
    heads.add(_head())                                  # (another commit may land while the report is built)
    assert not stale.exists(), "a chapter's old outputs are replaced by its new ones"
    assert (figures / "tables" / "01_params.csv").read_text() == "smoke\nFalse\n"
    manifest = (figures / "MANIFEST.sha256").read_text().splitlines()
    assert [line.split("  ")[1] for line in manifest] == [
        f"{p}_line.png" for p in ("01", "02", "03")] + [
        f"tables/{p}_params.{s}" for p in ("01", "02", "03") for s in ("csv", "md")]
    assert verify_manifest(figures) == []
    assert not list(root.glob(".figures.*")), "no publishing leftovers"

    index = (build / "report" / "index.html").read_text()
    assert index.index("Chapter 01_first") < index.index("Chapter 02_second")
    assert index.count("figures/01_line.png") == 1, "each figure once"
    assert "A line of chapter 02" in index and "Was it a smoke run?" in index, "captions shown"
    # The checkout's commit (12 digits, as `git rev-parse --short=12 HEAD`), or "unknown" outside a checkout
    commit = re.search(r"<dt>commit</dt><dd>([^<]*)</dd>", index).group(1)
    assert re.fullmatch(r"(?:[0-9a-f]{12}|unknown)(?: \(with uncommitted changes\))?", commit), commit
    assert commit.split()[0] in {h or "unknown" for h in heads}, (commit, heads)
    page = (build / "report" / "02_second.html").read_text()
    assert "01_first.html" in page and "03_third.html" in page, "navigation between chapters"
    for html in [index] + [p.read_text() for p in (build / "report").glob("*.html")]:
        assert not re.search(r"<(script|link)[^>]+(src|href)=['\"]?https?://", html), \
            "nothing loaded from the internet"
    third = (build / "report" / "03_third.html").read_text()
    assert "mathjax/MathJax.js" in third and (build / "report" / "mathjax" / "MathJax.js").is_file()
    assert "The answer is 42." in third and "display(Markdown" not in third, "remove-input"

    executed = (build / "notebooks" / "01_first.ipynb").read_text()
    assert str(ROOT) not in executed, "no absolute paths of the checkout"

    first = (figures / "MANIFEST.sha256").read_bytes()
    record = (build / "stamps" / "clean_build.json").read_text()
    assert re.search(r"<dt>clean build</dt><dd><code>\d+ min \d+ s for every chapter", index), "the clean build timed"
    # Byte-reproducible: every chapter run again (force, into fresh directories: nothing to reuse) publishes
    # the same bytes, every file of figures/ and its manifest
    again = {**dirs, "figures_dir": root / "again" / "figures", "build_dir": root / "again" / "build"}
    assert build_report(force=True, **again) == 0
    assert sorted(p.name for p in (again["build_dir"] / "notebooks").glob("*.ipynb")) == [
        "01_first.ipynb", "02_second.ipynb", "03_third.ipynb"], "every chapter ran again"
    files = lambda d: {str(p.relative_to(d)): p.read_bytes() for p in sorted(d.rglob("*")) if p.is_file()}  # noqa: E731
    assert (again["figures_dir"] / "MANIFEST.sha256").read_bytes() == first, "figures are byte-reproducible"
    assert files(again["figures_dir"]) == files(figures), "figures are byte-reproducible"
    assert build_report(**dirs) == 0
    assert (figures / "MANIFEST.sha256").read_bytes() == first
    assert (build / "stamps" / "clean_build.json").read_text() == record, "a run that reuses its work is not a clean build"


@pytest.mark.notebook
def test_smoke_and_custom_runs_never_touch_the_published_figures(project):
    root, dirs = project
    figures, build = dirs["figures_dir"], dirs["build_dir"]
    assert build_report(only=["01"], **dirs) == 0
    before = {p: digest(p) for p in figures.rglob("*") if p.is_file()}
    assert build_report(smoke=True, only=["01"], **dirs) == 0
    assert build_report(only=["01"], extra_parameters={"seed": 3}, **dirs) == 0
    assert {p: digest(p) for p in figures.rglob("*") if p.is_file()} == before
    assert (build / "smoke" / "figures" / "tables" / "01_params.csv").read_text() == "smoke\nTrue\n"
    assert verify_manifest(build / "smoke" / "figures") == []
    assert "smoke run" in (build / "smoke" / "report" / "index.html").read_text()
    assert (build / "custom" / "figures" / "01_line.png").is_file()
    assert not (build / "stamps" / "clean_build.json").exists(), "one chapter, a smoke or a custom run: not a clean build"
    assert "not made in this build directory" in (build / "report" / "index.html").read_text()


@pytest.mark.notebook
def test_a_failing_notebook_stops_the_run_and_names_the_source_cell(project, capsys):
    root, dirs = project
    make_notebook(dirs["notebooks_dir"] / "02_second.ipynb", "x = 1", "raise ValueError('bad joint')")
    assert build_report(**dirs) == 1
    err = capsys.readouterr().err
    # Source cells: 0 title, 1 parameters, 2 "x = 1", 3 the raise (papermill's injected cell
    # is not counted).
    assert "02_second.ipynb failed in cell 3 (\"raise ValueError('bad joint')\"): ValueError: bad joint" in err
    kept = dirs["build_dir"] / "notebooks" / "02_second.ipynb"
    assert f"kept at {kept}" in err and kept.exists()
    assert (dirs["figures_dir"] / "01_line.png").exists(), "earlier chapters are published"
    assert verify_manifest(dirs["figures_dir"]) == [], "figures and manifest agree after a failure"


@pytest.mark.notebook
@pytest.mark.parametrize("code, message", [
    ("import os\nos._exit(3)", r"02_second.ipynb lost its kernel \(it died.*\) in cell 2 \('import os'\)"),
    ("import time\ntime.sleep(60)", r"02_second.ipynb timed out: no progress for 3 s in cell 2 \('import time'\)"),
])
def test_dead_and_hanging_kernels_are_one_line(project, capsys, code, message):
    root, dirs = project
    # a cell after the one that fails: the message names the one that ran, not the last
    make_notebook(dirs["notebooks_dir"] / "02_second.ipynb", code, "after = 1")
    assert build_report(only=["02"], cell_timeout=3, **dirs) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert re.search(message, err[-1]), err
    assert "Traceback" not in "\n".join(err)


def test_bad_notebooks_and_chapter_choices_are_one_line(project, capsys):
    root, dirs = project
    (dirs["notebooks_dir"] / "02_second.ipynb").write_text("{not json")
    assert build_report(only=["02"], **dirs) == 1
    assert "02_second.ipynb: not a valid notebook" in capsys.readouterr().err
    assert build_report(only=["99"], **dirs) == 2
    assert "report: no chapter 99 (chapters: 01, 02, 03)" in capsys.readouterr().err
    assert build_report(only=[], **dirs) == 2
    assert "--only needs chapter numbers" in capsys.readouterr().err


@pytest.mark.parametrize("change, kept", [
    ("nothing but the seconds", True),
    ("the rows' order", True),
    ("a result", False),
    ("a column", False),
    ("the caption", True),
])
def test_a_published_tables_measurements_stay_while_every_other_cell_agrees(tmp_path, change, kept):
    """A table's measured columns (seconds) keep the published values when a chapter publishes the
    same results again, so a build that reproduces the study leaves figures/ byte for byte; any other
    change publishes the new table whole. The Markdown takes the new caption either way."""
    from nfarm.presentation.tables import measured

    figures = tmp_path / "figures"

    def stage(name, fits, seconds, caption, extra=False, swapped=False):
        s = tmp_path / name
        columns = ["learner", "fits", measured("training [s]"), *(["passes"] if extra else [])]
        rows = [["MLP", fits, seconds, *([3] if extra else [])], ["RBF", 2, seconds / 3, *([1] if extra else [])]]
        rows = rows[::-1] if swapped else rows
        Table(columns, rows, floatfmt=".3g", caption=caption).save(s, "01_budget")
        Table(["a"], [[seconds]], caption="no measurements").save(s, "01_plain")
        return s

    manifest.publish_chapter(stage("first", 4, 12.0, "Budget"), figures, "01")
    first = {n: (figures / "tables" / n).read_bytes() for n in ("01_budget.csv", "01_budget.md")}
    again = {"nothing but the seconds": lambda: stage("second", 4, 13.1, "Budget"),
             "the rows' order": lambda: stage("second", 4, 13.1, "Budget", swapped=True),
             "a result": lambda: stage("second", 5, 13.1, "Budget"),
             "a column": lambda: stage("second", 4, 13.1, "Budget", extra=True),
             "the caption": lambda: stage("second", 4, 13.1, "The budget, reworded")}[change]()
    manifest.publish_chapter(again, figures, "01")
    csv_text = (figures / "tables" / "01_budget.csv").read_text()
    md_text = (figures / "tables" / "01_budget.md").read_text()
    assert ("12" in csv_text and "13.1" not in csv_text) is kept
    assert ("| MLP | 4 | 12 |" in md_text) is kept
    if change == "nothing but the seconds":
        assert {n: (figures / "tables" / n).read_bytes() for n in first} == first
    if change == "the caption":
        assert md_text.startswith("*The budget, reworded*\n") and csv_text.encode() == first["01_budget.csv"]
    if change == "the rows' order":           # this build's order, the published seconds
        assert csv_text.splitlines()[1:] == ["RBF,2,4", "MLP,4,12"]
    assert (figures / "tables" / "01_plain.csv").read_text() == "a\n13.1\n"        # no measured column: replaced
    assert verify_manifest(figures) == []


def test_publishing_is_atomic_at_every_step(tmp_path, monkeypatch):
    """A crash after any file operation of a publish leaves figures/ as it was before or as
    it is after, its manifest matching; the next publish cleans up."""
    figures = tmp_path / "figures"

    def stage(version):
        s = tmp_path / f"stage{version}"
        (s / "tables").mkdir(parents=True, exist_ok=True)
        for k in range(3):
            (s / f"01_f{k}.png").write_bytes(f"v{version} {k}".encode())
        (s / "tables" / "01_t.csv").write_text(f"v{version}\n")
        (s / "tables" / "01_t.md").write_text(f"v{version}\n")
        return s

    def state(directory):
        return tuple(sorted((p.relative_to(directory).as_posix(), digest(p))
                            for p in directory.rglob("*") if p.is_file()))

    def published(version, before):
        """figures/ after an uninterrupted publish of ``version`` onto the state ``before``."""
        copy = tmp_path / "reference" / f"{len(seen)}"
        shutil.copytree(figures, copy)
        assert state(copy) == before
        manifest.publish_chapter(stage(version), copy, "01")
        return state(copy)

    manifest.publish_chapter(stage(1), figures, "01")
    seen = []                                        # (crash point, "before" or "after")
    step, crash_at = [0], [0]

    def counting(fn):
        def wrapper(*args, **kwargs):
            step[0] += 1
            if step[0] == crash_at[0]:
                raise KeyboardInterrupt("killed")
            return fn(*args, **kwargs)
        return wrapper

    real_ops = {name: getattr(shutil, name) for name in ("copyfile", "copytree", "rmtree")}
    for crash in range(1, 40):
        version = 2 + crash % 2
        manifest.recover_figures(figures)
        before = state(figures)
        after = published(version, before)
        assert after != before
        step[0], crash_at[0] = 0, crash
        for name, fn in real_ops.items():
            monkeypatch.setattr(shutil, name, counting(fn))
        monkeypatch.setattr(manifest, "_exchange", counting(manifest._exchange))
        try:
            manifest.publish_chapter(stage(version), figures, "01")
            finished = True
        except KeyboardInterrupt:
            finished = False
        monkeypatch.undo()
        assert verify_manifest(figures) == [], f"crash at step {crash}"
        now = state(figures)
        assert now in (before, after), f"crash at step {crash}: figures/ is neither as before nor as after"
        seen.append((crash, "before" if now == before else "after"))
        if finished:
            break
    else:
        pytest.fail("the publish never finished")
    assert crash > 3, "the crash points covered the publish"
    outcomes = {outcome for _, outcome in seen[:-1]}
    assert outcomes == {"before", "after"}, f"the crashes left only {outcomes}: {seen}"
    manifest.recover_figures(figures)
    assert not list(tmp_path.glob(".figures.*"))


#: A run of the command line's report that stops, alive, in the middle of publishing chapter ``pause``: the
#: chapter's new figures staged beside figures/ with their manifest, not yet swapped in. It says so by
#: creating ``marker``, then sleeps until it is killed.
PAUSED_REPORT = """
import sys, time
from pathlib import Path
from nfarm.publishing import manifest
from nfarm.__main__ import report_command
write, publish, chapter = manifest.write_manifest, manifest._publish_locked, []

def publishing(stage, made, figures_dir, prefix, subdir):
    chapter[:] = [prefix]
    return publish(stage, made, figures_dir, prefix, subdir)

def pausing(directory, *args, **kwargs):
    written = write(directory, *args, **kwargs)
    if Path(directory).name.endswith(".new") and chapter == [{pause!r}]:     # the chapter's publish, staged
        Path({marker!r}).write_text(str(directory))
        time.sleep(600)
    return written

manifest.write_manifest, manifest._publish_locked = pausing, publishing
sys.exit(report_command(notebooks_dir=Path({notebooks!r}), figures_dir=Path({figures!r}), build_dir=Path({build!r})))
"""


@pytest.mark.notebook
def test_killing_a_real_run_in_the_middle_of_publishing_keeps_figures_consistent(project, tmp_path):
    """``python -m nfarm report`` killed with SIGKILL at chosen moments, each observed before the kill
    (the run paused in a chapter's publish, its new files staged): the first chapter's first publish
    (nothing published: no figures/), the second chapter's (the first's published, the second's not),
    the third's (two published); figures/ and its manifest agree after every kill, and a run after
    them publishes everything."""
    root, dirs = project
    figures = dirs["figures_dir"]
    published = lambda: sorted(p.name for p in (figures / "tables").glob("*_params.csv"))  # noqa: E731
    # (kill in the publish of this chapter, the chapters published before it)
    for k, (pause, before) in enumerate([("01", None), ("02", ["01_params.csv"]), ("03", ["01_params.csv", "02_params.csv"])]):
        marker = tmp_path / f"paused_{k}"
        script = PAUSED_REPORT.format(pause=pause, marker=str(marker), notebooks=str(dirs["notebooks_dir"]),
                                      figures=str(figures), build=str(dirs["build_dir"]))
        process = subprocess.Popen([sys.executable, "-c", script], stderr=subprocess.DEVNULL, start_new_session=True)
        try:
            deadline = time.monotonic() + 300
            while not marker.exists():
                assert process.poll() is None, f"the run ended (status {process.returncode}) before chapter {pause}'s publish"
                assert time.monotonic() < deadline, f"the run never reached chapter {pause}'s publish"
                time.sleep(0.05)
            assert process.poll() is None, "alive, in the middle of its publish"
        finally:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
        assert Path(marker.read_text()).is_dir(), "the chapter's files were staged when it was killed"
        if before is None:
            assert not figures.exists(), "killed before its first publish: nothing published"
        else:
            assert verify_manifest(figures) == [], f"kill {k}"
            assert published() == before, f"kill {k}"
    assert build_report(**dirs) == 0
    assert verify_manifest(figures) == []
    assert published() == ["01_params.csv", "02_params.csv", "03_params.csv"]
    assert not list(root.glob(".figures.*")), "the staged files of the killed runs cleared"


def test_verify_reports_every_kind_of_difference(tmp_path):
    (tmp_path / "tables").mkdir()
    (tmp_path / "a.png").write_bytes(b"a")
    (tmp_path / "tables" / "b.csv").write_text("b\n")
    write_manifest(tmp_path)
    assert verify_manifest(tmp_path) == []
    (tmp_path / "a.png").write_bytes(b"changed")
    (tmp_path / "tables" / "b.csv").unlink()
    (tmp_path / "c.png").write_bytes(b"c")
    assert verify_manifest(tmp_path) == ["a.png: differs from the manifest",
                                         "tables/b.csv: listed but missing",
                                         "c.png: not in the manifest"]


def test_table_formats_and_files(tmp_path):
    table = Table(["name", "value", "n"], [["a|b", -1e-17, np.int64(3)], ["c", 2.5, 4]],
                  floatfmt=["", ".3f", ""], caption="cap")
    assert table.to_csv() == "name,value,n\na|b,0.000,3\nc,2.500,4\n"
    assert table.to_markdown().splitlines()[2:] == [
        "| name | value | n |", "|---|---|---|", "| a\\|b | 0.000 | 3 |", "| c | 2.500 | 4 |"]
    table.save(tmp_path, "01_x")
    assert (tmp_path / "tables" / "01_x.csv").read_text() == table.to_csv()
    with pytest.raises(ValueError, match="table row 0 has 2 cells, expected 3"):
        Table(["a", "b", "c"], [[1, 2]])


def test_atomic_path_leaves_no_half_written_file(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("disk full")
    assert target.read_text() == "old"
    assert list(tmp_path.iterdir()) == [target]


def test_a_killed_writers_temporary_file_is_removed_by_the_next_write(tmp_path):
    """SIGKILL runs no clean-up: the next write of the same path removes what a dead writer
    left, and leaves a live writer's file and other paths' files alone."""
    import signal
    import subprocess
    import sys

    target = tmp_path / "id_val.npz"
    code = ("import sys, time; from nfarm.infra.paths import atomic_path\n"
            "with atomic_path(sys.argv[1]) as tmp:\n"
            "    tmp.write_bytes(b'x' * 1000); print(tmp, flush=True); time.sleep(60)")
    writer = subprocess.Popen([sys.executable, "-c", code, str(target)], stdout=subprocess.PIPE, text=True)
    left = tmp_path / os.path.basename(writer.stdout.readline().strip())
    assert left.is_file() and left.name.startswith(f".id_val.npz.{writer.pid}.")
    alive = tmp_path / f".id_val.npz.{os.getppid()}.abc.tmp"          # a live process's write
    other = tmp_path / ".other.npz.999999999.abc.tmp"
    alive.write_text("a")
    other.write_text("o")
    with atomic_path(target) as tmp:          # while the writer lives, its file stays
        tmp.write_text("first")
    assert left.is_file()
    writer.send_signal(signal.SIGKILL)
    writer.wait()
    with atomic_path(target) as tmp:
        tmp.write_text("second")
    assert target.read_text() == "second" and not left.exists() and alive.exists() and other.exists()


def communicate_or_kill(run, seconds):
    """The process's output once it ends; a process still running after ``seconds`` (a bound
    no working machine misses: the work it would still be doing takes an hour) is killed with
    and the test fails. Speed is measured in ``benchmarks/bench_deadlines.py``."""
    try:
        return run.communicate(timeout=seconds)
    except subprocess.TimeoutExpired:
        run.kill()
        run.communicate()
        pytest.fail(f"still running {seconds} s after Ctrl-C")


def test_ctrl_c_stops_a_running_notebook_in_one_line(tmp_path):
    """SIGINT while a cell runs: run_notebook raises KeyboardInterrupt (the caller's one line),
    the kernel is shut down, and nothing else reaches the terminal."""
    import signal
    import subprocess
    import sys

    notebook = tmp_path / "slow.ipynb"
    nb = nbformat.v4.new_notebook()
    # The cell would sleep an hour: a run that ends within the generous wait below was stopped.
    nb.cells = [nbformat.v4.new_code_cell("seconds = 3600", metadata={"tags": ["parameters"]}),
                nbformat.v4.new_code_cell("import time\ntime.sleep(seconds)")]
    nbformat.write(nb, notebook)
    out = tmp_path / "out.ipynb"
    code = ("import sys\nfrom nfarm.infra.notebook_runs import run_notebook\n"
            "try:\n    run_notebook(sys.argv[1], sys.argv[2], {})\n    print('finished', file=sys.stderr)\n"
            "except KeyboardInterrupt:\n    print('interrupted', file=sys.stderr)\n    sys.exit(130)\n")
    run = subprocess.Popen([sys.executable, "-c", code, str(notebook), str(out)], stderr=subprocess.PIPE, text=True)
    for _ in range(600):                      # until the sleeping cell runs
        if out.exists() and '"time.sleep' in out.read_text():
            break
        time.sleep(0.1)
    time.sleep(2.0)
    run.send_signal(signal.SIGINT)
    _, err = communicate_or_kill(run, 600)           # far below the cell's hour
    assert run.returncode == 130
    assert err.strip() == "interrupted", err


def test_executed_notebook_json_is_plain(tmp_path):
    """The helper that cleans executed notebooks drops widget state and absolute paths."""
    nb = new_notebook(cells=[new_code_cell("1")])
    nb.metadata["widgets"] = {"application/vnd.jupyter.widget-state+json": {"state": {}}}
    nb.metadata["papermill"] = {"input_path": str(ROOT / "notebooks" / "x.ipynb"),
                                "output_path": str(ROOT / "build" / "x.ipynb")}
    path = tmp_path / "x.ipynb"
    nbformat.write(nb, path)
    notebook_runs._clean_executed(path, ROOT / "notebooks" / "x.ipynb")
    data = json.loads(path.read_text())
    assert "widgets" not in data["metadata"]
    assert data["metadata"]["papermill"]["input_path"] == "notebooks/x.ipynb"



def make_chapter(path, parameters: str):
    cells = [new_markdown_cell(f"# Chapter {path.stem}"),
             new_code_cell(parameters + '\nsmoke = False\nout_dir = "build/explore/x"',
                           metadata={"tags": ["parameters"]})]
    nbformat.write(new_notebook(cells=cells), path)


def fake_run(runs, log=None):
    """Stands in for papermill: records the run (in ``runs``, and as a line of ``log`` from
    whichever process runs it) and writes what the chapter was given."""
    def run(notebook, output, parameters, **_):
        runs.append((notebook.name, {k: v for k, v in parameters.items() if k != "out_dir"}))
        if log is not None:
            with open(log, "a") as f:
                f.write(f"{os.getpid()} {notebook.name} {parameters.get('study_file', parameters.get('robot_file', '-'))}\n")
        given_ = {k: v for k, v in parameters.items() if k not in ("out_dir", "smoke")}
        Table(["value"], [[repr(given_)]], caption="What the chapter was given").save(
            ROOT / parameters["out_dir"] if not os.path.isabs(parameters["out_dir"])
            else parameters["out_dir"], f"{notebook.name[:2]}_given")
        output.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(notebook, output)
    return run


@pytest.fixture
def two_arms(tmp_path, monkeypatch):
    notebooks = tmp_path / "notebooks"
    notebooks.mkdir()
    make_chapter(notebooks / "01_robot.ipynb", 'robot_file = "ra.yaml"')
    make_chapter(notebooks / "02_shared.ipynb", "seed = 0")
    make_chapter(notebooks / "03_study.ipynb", 'study_file = "sa.yaml"')
    make_chapter(notebooks / "04_compare.ipynb", 'study_files = ["sa.yaml"]')
    runs = []
    monkeypatch.setattr(report, "run_notebook", fake_run(runs))
    arms = [report.Edition("a", "sa.yaml", "ra.yaml", True), report.Edition("b", "sb.yaml", "rb.yaml", False)]
    return runs, dict(notebooks_dir=notebooks, figures_dir=tmp_path / "figures",
                      build_dir=tmp_path / "build", arms=arms, parallel=False)


def test_editions_side_by_side_publish_what_one_after_the_other_does(two_arms, tmp_path, monkeypatch):
    """Each edition's chapters in a process of their own, in order; the comparing chapter after
    both, in this process; the published bytes those of the serial run."""
    runs, dirs = two_arms
    assert build_report(**dirs) == 0
    serial = {p.relative_to(dirs["figures_dir"]): p.read_bytes() for p in dirs["figures_dir"].rglob("*") if p.is_file()}
    log = tmp_path / "runs.log"
    monkeypatch.setattr(report, "run_notebook", fake_run([], log))
    side = dict(dirs, figures_dir=tmp_path / "figures2", build_dir=tmp_path / "build2", parallel=True)
    assert build_report(**side) == 0
    assert {p.relative_to(side["figures_dir"]): p.read_bytes() for p in side["figures_dir"].rglob("*")
            if p.is_file()} == serial
    lines = [line.split() for line in log.read_text().splitlines()]
    by_process = {}
    for pid, name, given_ in lines:
        by_process.setdefault(pid, []).append(name)
    assert sorted(by_process.values()) == [["01_robot.ipynb", "02_shared.ipynb", "03_study.ipynb"],
                                           ["01_robot.ipynb", "03_study.ipynb"], ["04_compare.ipynb"]]
    assert lines[-1][:2] == [str(os.getpid()), "04_compare.ipynb"]          # after both, here
    assert not list(tmp_path.glob(".figures2.*")), "no publishing leftovers"


def test_the_editions_side_by_side_send_their_sweep_cells_to_one_cluster(tmp_path, monkeypatch):
    """Issue 63: each edition's chapter 6 started a local cluster of one worker per core, so two editions side by
    side ran four worker processes on two cores (a cell 8-14 % dearer in CPU). The report starts one
    (nfarm.study.sweep.shared_cluster) for every chapter that runs sweep cells (it declares sweep_workers), and
    none in a smoke run, where the user chose the workers, or where those chapters are up to date."""
    import contextlib

    from nfarm.study import sweep as sweep_module
    notebooks = tmp_path / "notebooks"
    notebooks.mkdir()
    make_chapter(notebooks / "01_robot.ipynb", 'robot_file = "ra.yaml"')
    make_chapter(notebooks / "02_sweeps.ipynb", 'study_file = "sa.yaml"\nsweep_workers = None')
    make_chapter(notebooks / "03_compare.ipynb", 'study_files = ["sa.yaml"]')
    started = []

    @contextlib.contextmanager
    def fake_cluster(workers=None):
        started.append(workers)
        monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", f"tcp://127.0.0.1:{len(started)}")
        try:
            yield os.environ["DASK_SCHEDULER_ADDRESS"]
        finally:
            monkeypatch.delenv("DASK_SCHEDULER_ADDRESS")

    monkeypatch.setattr(sweep_module, "shared_cluster", fake_cluster)
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    log = tmp_path / "seen.log"

    def run(notebook, output, parameters, **options):
        with open(log, "a") as f:
            f.write(f"{notebook.name} {parameters.get('study_file', '-')} {os.environ.get('DASK_SCHEDULER_ADDRESS', '-')}\n")
        return fake_run([])(notebook, output, parameters, **options)

    monkeypatch.setattr(report, "run_notebook", run)
    arms = [report.Edition("a", "sa.yaml", "ra.yaml", True), report.Edition("b", "sb.yaml", "rb.yaml", False)]
    dirs = dict(notebooks_dir=notebooks, figures_dir=tmp_path / "figures", build_dir=tmp_path / "build", arms=arms,
                parallel=True)
    assert build_report(**dirs) == 0
    seen = sorted(line.split() for line in log.read_text().splitlines())
    # the primary edition runs on the chapter's own study_file (not given), the other on its own
    assert [s for s in seen if s[0] == "02_sweeps.ipynb"] == [["02_sweeps.ipynb", "-", "tcp://127.0.0.1:1"],
                                                              ["02_sweeps.ipynb", "sb.yaml", "tcp://127.0.0.1:1"]]
    assert started == [report._cpus()] and "DASK_SCHEDULER_ADDRESS" not in os.environ
    assert build_report(**dirs) == 0 and started == [report._cpus()], "nothing to run: no cluster"
    assert build_report(smoke=True, **dirs) == 0 and started == [report._cpus()], "smoke cells run in the chapter"
    assert build_report(extra_parameters={"sweep_workers": 1}, **dirs) == 0 and len(started) == 1
    assert build_report(force=True, **dirs) == 0 and len(started) == 2


def test_a_failing_edition_side_by_side_stops_the_run_in_one_line(two_arms, tmp_path, monkeypatch, capfd):
    runs, dirs = two_arms

    def failing(notebook, output, parameters, **options):
        if parameters.get("study_file") == "sb.yaml":
            raise report.ReportError(f"{notebook.name} failed in cell 2 ('x'): ValueError: bad")
        return fake_run([])(notebook, output, parameters, **options)

    monkeypatch.setattr(report, "run_notebook", failing)
    assert build_report(**dict(dirs, parallel=True)) == 1
    err = capfd.readouterr().err
    assert "report: 03_study.ipynb failed in cell 2 ('x'): ValueError: bad" in err
    assert "04_compare" not in err and "Traceback" not in err
    assert verify_manifest(dirs["figures_dir"]) == []


def given(path):
    return path.read_text().splitlines()[-1]


def test_each_arm_is_published_in_its_own_directory_and_compared_once(two_arms):
    runs, dirs = two_arms
    figures, build = dirs["figures_dir"], dirs["build_dir"]
    assert build_report(**dirs) == 0
    assert [name for name, _ in runs] == ["01_robot.ipynb", "01_robot.ipynb", "02_shared.ipynb",
                                          "03_study.ipynb", "03_study.ipynb", "04_compare.ipynb"]
    tables = figures / "tables"
    assert given(tables / "01_given.csv") == "{}"                       # the primary: defaults
    assert "'robot_file': 'rb.yaml'" in given(figures / "b" / "tables" / "01_given.csv")
    assert "'study_file': 'sb.yaml'" in given(figures / "b" / "tables" / "03_given.csv")
    assert not (figures / "b" / "tables" / "02_given.csv").exists()     # the same for every arm
    assert "'study_files': ['sa.yaml', 'sb.yaml']" in given(tables / "04_given.csv")
    assert not (figures / "b" / "tables" / "04_given.csv").exists()
    assert verify_manifest(figures) == []
    assert "b/tables/01_given.csv" in (figures / "MANIFEST.sha256").read_text()
    page = (build / "report" / "b" / "01_robot.html").read_text()
    assert "../mathjax/MathJax.js" in page and "../b/02_shared.html" in page   # the shared 02, in b's pages
    shared_b = (build / "report" / "b" / "02_shared.html").read_text()          # its navigation stays in b
    assert "../b/01_robot.html" in shared_b and "../b/03_study.html" in shared_b and "../01_robot.html" not in shared_b
    last_b = (build / "report" / "b" / "03_study.html").read_text()          # b's last leads on to the comparison
    assert "../04_compare.html" in last_b
    assert "<title>Chapter 01_robot · b</title>" in page                      # not "Notebook"
    index = (build / "report" / "index.html").read_text()
    assert "href='b/02_shared.html'" in index and "href='02_shared.html'" in index   # each edition's copy
    assert "<title>Chapter 01_robot · a</title>" in (build / "report" / "01_robot.html").read_text()
    assert "<title>Chapter 02_shared · the same for every arm</title>" in (build / "report" / "02_shared.html").read_text()
    assert "<title>Chapter 02_shared · the same for every arm</title>" in shared_b
    compare = (build / "report" / "04_compare.html").read_text()     # back to each edition's last chapter
    assert "href='03_study.html'>previous (a):" in compare and "href='b/03_study.html'>previous (b):" in compare
    index = (build / "report" / "index.html").read_text()
    # The index: the verdict, then the chapter lists, then the appendix of every figure and table (the comparison's first)
    assert index.index("Chapters for a") < index.index("id='appendix'") < index.index("id='ch04'") \
        < index.index("id='a-ch01'")
    assert "Chapters for b" in index and "b/tables/01_given.csv" in index
    assert "(the same for every arm)" in index


def test_one_arm_s_edition_runs_alone_with_the_comparison(two_arms, capsys):
    """``make report ARM=b``: b's chapters and the comparing chapter run, a's are neither run nor
    checked, and the index still lists both editions."""
    runs, dirs = two_arms
    assert build_report(arm="b", **dirs) == 0
    assert runs == [("01_robot.ipynb", {"smoke": False, "robot_file": "rb.yaml"}),
                    ("03_study.ipynb", {"smoke": False, "study_file": "sb.yaml"}),
                    ("04_compare.ipynb", {"smoke": False, "study_files": ["sa.yaml", "sb.yaml"]})]
    assert "Chapters for a" in (dirs["build_dir"] / "report" / "index.html").read_text()
    assert build_report(arm="c", **dirs) == 2
    assert "--arm: no edition 'c'; the editions are a, b (params/studies/*.yaml)" in capsys.readouterr().err


def test_chapters_whose_inputs_are_unchanged_are_not_run_again(two_arms, capsys):
    runs, dirs = two_arms
    figures = dirs["figures_dir"]
    assert build_report(only=["01", "02"], **dirs) == 0 and len(runs) == 3
    assert build_report(only=["01", "02"], **dirs) == 0 and len(runs) == 3   # nothing rerun
    assert capsys.readouterr().err.count("up to date") == 3
    (figures / "b" / "tables" / "01_given.csv").write_text("edited\n")  # a published file changed
    nb = dirs["notebooks_dir"] / "02_shared.ipynb"
    nb.write_text(nb.read_text().replace("seed = 0", "seed = 1"))      # a chapter changed
    assert build_report(only=["01", "02"], **dirs) == 0
    assert runs[3:] == [("01_robot.ipynb", {"smoke": False, "robot_file": "rb.yaml"}),
                        ("02_shared.ipynb", {"smoke": False})]
    assert "'robot_file': 'rb.yaml'" in given(figures / "b" / "tables" / "01_given.csv")
    assert build_report(only=["01"], force=True, **dirs) == 0 and len(runs) == 7
    assert build_report(only=["01"], smoke=True, **dirs) == 0 and len(runs) == 9  # other inputs
    assert verify_manifest(figures) == []

def test_a_changed_chapter_runs_every_chapter_that_reads_its_results_again(two_arms, capsys):
    """Chapter 7 loads the models chapter 6 chose: a chapter whose own inputs are unchanged runs
    again when a chapter before it did — its edition's, one run for every edition, and for the
    comparing chapter every edition's; the other edition's earlier chapters stay as they are."""
    runs, dirs = two_arms
    assert build_report(**dirs) == 0 and len(runs) == 6
    nb = dirs["notebooks_dir"] / "02_shared.ipynb"
    nb.write_text(nb.read_text().replace("seed = 0", "seed = 1"))          # the chapter run once for both
    assert build_report(**dirs) == 0
    assert [name for name, _ in runs[6:]] == ["02_shared.ipynb", "03_study.ipynb", "03_study.ipynb", "04_compare.ipynb"]
    capsys.readouterr()
    edited = dirs["notebooks_dir"] / "03_study.ipynb"
    edited.write_text(edited.read_text().replace("# Chapter", "# The chapter"))   # both editions' 03
    assert build_report(**dirs) == 0
    assert [name for name, _ in runs[10:]] == ["03_study.ipynb", "03_study.ipynb", "04_compare.ipynb"]
    assert capsys.readouterr().err.count("up to date") == 3              # 01 (a, b) and 02: upstream only
    assert build_report(**dirs) == 0 and len(runs) == 13                  # and then nothing
    assert verify_manifest(dirs["figures_dir"]) == []


def test_editions_come_from_the_study_files():
    arms = report.editions()
    assert [a.name for a in arms][:1] == ["intelbot5"] and arms[0].primary
    so101 = next(a for a in arms if a.name == "so101")
    assert (so101.robot_file, so101.subdir) == ("params/robots/so101.yaml", "so101")
    assert so101.parameters(["robot_file", "seed"]) == {"robot_file": "params/robots/so101.yaml"}
    assert so101.parameters(["seed"]) is None and arms[0].parameters(["robot_file"]) == {}
    # Its rerun recordings go beside the primary's, never over them.
    assert so101.parameters(["study_file", "recordings_dir"]) == {
        "study_file": "params/studies/so101.yaml", "recordings_dir": "build/recordings/so101"}
    assert arms[0].parameters(["study_file", "recordings_dir"]) == {}
    assert so101.parameters(["recordings_dir"]) is None      # a chapter that is not its own


def test_the_index_links_each_arm_s_recordings(two_arms):
    runs, dirs = two_arms
    recordings = dirs["build_dir"] / "recordings"
    (recordings / "b").mkdir(parents=True)
    (recordings / "03_motion.rrd").write_bytes(b"a")
    (recordings / "b" / "03_motion.rrd").write_bytes(b"b")
    assert build_report(**dirs) == 0
    index = (dirs["build_dir"] / "report" / "index.html").read_text()
    a, b = index.index("Chapters for a"), index.index("Chapters for b")
    # copied into the report folder and linked relatively: the folder reads anywhere it is copied
    assert index.index("href='recordings/03_motion.rrd'", a) < b
    assert index.index("href='recordings/b/03_motion.rrd'", b) > b
    report_dir = dirs["build_dir"] / "report"
    assert (report_dir / "recordings" / "b" / "03_motion.rrd").read_bytes() == b"b"


def test_markdown_section_returns_one_sections_text(tmp_path):
    doc = tmp_path / "doc.md"
    doc.write_text("# Title\n\n## A\n\nfirst\n### sub\ntext\n## B\n\nsecond\n", encoding="utf-8")
    assert markdown_section(doc, "A") == "first\n### sub\ntext\n"
    assert markdown_section(doc, "B") == "second\n"
    with pytest.raises(ValueError, match=r"doc.md: heading '## C': expected once, found 0"):
        markdown_section(doc, "C")
    with pytest.raises(ValueError, match="cannot read"):
        markdown_section(tmp_path / "missing.md", "A")


def test_the_deviations_table_chapter_05_shows_is_in_the_study_document():
    text = markdown_section(ROOT / "docs" / "STUDY.md", "Deviations from the dissertation")
    rows = [line for line in text.splitlines() if line.startswith("| ") and not line.startswith("| element")]
    assert len(rows) >= 10 and all(line.count(" | ") == 3 for line in rows)
    assert any("(seed, line" in line for line in rows) and any("not in the seed" in line for line in rows)


@pytest.mark.parametrize("name", ["../outside.png", "../../../etc/hostname", "/etc/hostname", "tables/../../x.csv"])
def test_verify_refuses_manifest_entries_outside_the_figures_directory(tmp_path, name):
    figures = tmp_path / "figures"
    figures.mkdir()
    (tmp_path / "outside.png").write_bytes(b"o")
    (figures / "a.png").write_bytes(b"a")
    write_manifest(figures)
    digest = "0" * 64
    with (figures / "MANIFEST.sha256").open("a") as f:
        f.write(f"{digest}  {name}\n")
    problems = verify_manifest(figures)
    assert len(problems) == 1 and "lies outside the figures directory: not checked" in problems[0]


def test_verify_hashes_in_chunks(tmp_path, monkeypatch):
    (tmp_path / "big.png").write_bytes(bytes(range(256)) * 9000)      # 2.3 MB: three chunks of 1 MiB
    write_manifest(tmp_path)
    monkeypatch.setattr(manifest.Path, "read_bytes", lambda self: pytest.fail("read whole"))
    assert verify_manifest(tmp_path) == []


@pytest.mark.parametrize("value, message", [("0", "positive number"), ("-1", "positive number"),
                                            ("nan", "positive number"), ("inf", "positive number"),
                                            ("soon", "a number of seconds or 'none'")])
def test_cell_timeout_takes_a_positive_number_of_seconds(value, message, capsys):
    from nfarm.__main__ import main
    with pytest.raises(SystemExit) as exit_:
        main(["report", "--cell-timeout", value])
    assert exit_.value.code == 2 and message in capsys.readouterr().err


def test_cell_timeout_none_is_no_limit(monkeypatch):
    from nfarm import __main__
    from nfarm.publishing import report
    seen = {}
    monkeypatch.setattr(report, "build_report", lambda **kw: seen.update(kw) or report.ReportRun(Path("i"), Path("f")))
    assert __main__.main(["report", "--cell-timeout", "none"]) == 0 and seen["cell_timeout"] is None
    assert __main__.main(["report", "--cell-timeout", "600.5"]) == 0 and seen["cell_timeout"] == 600.5


@pytest.mark.parametrize("out, message", [("FILE", "exists and is not a directory"), ("/proc/x", "system directory"),
                                          ("/dev/null", "exists and is not a directory")])
@pytest.mark.parametrize("command", [["sweep", "params/sweeps/smoke.yaml"], ["datasets", "params/studies/intelbot5.yaml"]])
def test_an_out_directory_that_cannot_be_one_is_one_line(tmp_path, capsys, out, message, command):
    from nfarm.__main__ import main
    if out == "FILE":
        out = str(tmp_path / "file")
        (tmp_path / "file").write_text("x")
    assert main([*command, "--out", out]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and "Traceback" not in err[0]


def test_a_read_only_build_directory_is_one_line(project, capsys, monkeypatch):
    """(Simulated: the tests may run as a user who may write anywhere.)"""
    from nfarm.publishing import report
    _, dirs = project

    def refuse(report_dir):
        raise PermissionError(13, "Permission denied", str(report_dir / "mathjax"))
    monkeypatch.setattr(report, "install_mathjax", refuse)
    assert build_report(only=["01"], **dirs) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"report: cannot write {dirs['build_dir'] / 'report' / 'mathjax'}: Permission denied"]


def test_ctrl_c_stops_editions_running_side_by_side(tmp_path):
    """SIGINT to the report alone (not its process group): it passes the interrupt on to the
    editions still running after its grace period, and ends with one line."""
    import signal
    import subprocess
    import sys

    # Ctrl-C's own handler, whatever this test run inherited: a run started in the background (`make test &`, nohup)
    # ignores SIGINT, as the shell asks, and the report would rightly ignore it too
    code = f"""
import signal, sys, time
signal.signal(signal.SIGINT, signal.default_int_handler)
sys.path.insert(0, {os.path.dirname(__file__)!r})
from pathlib import Path
from nfarm.infra import notebook_runs
from nfarm.publishing import report
from test_report import make_chapter, fake_run
root = Path({str(tmp_path)!r})
notebooks = root / "notebooks"
notebooks.mkdir()
make_chapter(notebooks / "01_robot.ipynb", 'robot_file = "ra.yaml"')
make_chapter(notebooks / "02_compare.ipynb", 'study_files = ["sa.yaml"]')
def slow(notebook, output, parameters, **options):
    with notebook_runs._interruptible():
        (root / f"started-{{parameters.get('robot_file', 'a')}}").touch()
        time.sleep(3600)          # an hour: a run that ends within the wait below was stopped
report.run_notebook = slow
arms = [report.Edition("a", "sa.yaml", "ra.yaml", True), report.Edition("b", "sb.yaml", "rb.yaml", False)]
from nfarm.__main__ import report_command
sys.exit(report_command(notebooks_dir=notebooks, figures_dir=root / "figures", build_dir=root / "build",
                             arms=arms, parallel=True))
"""
    run = subprocess.Popen([sys.executable, "-c", code], stderr=subprocess.PIPE, text=True)
    for _ in range(600):
        if len(list(tmp_path.glob("started-*"))) == 2:
            break
        time.sleep(0.1)
    run.send_signal(signal.SIGINT)
    _, err = communicate_or_kill(run, 600)           # far below the chapters' hour
    assert run.returncode == 130
    assert err.strip().splitlines()[-1].startswith("report: interrupted;"), err
    assert "Traceback" not in err, err


@pytest.mark.notebook
def test_the_library_reports_by_return_and_exception_and_prints_nothing(project, capsys):
    """build_report returns what it wrote and raises what went wrong; the command line prints
    (report_command) — the library itself says nothing unless given ``say``."""
    from nfarm.infra.notebook_runs import ReportError
    from nfarm.publishing.report import ReportUsageError, build_report as library_build

    root, dirs = project
    said = []
    run = library_build(only=["01"], say=said.append, **dirs)
    assert run.index == dirs["build_dir"] / "report" / "index.html" and run.index.exists()
    assert said[0] == "01_first.ipynb …" and said[1].startswith("01_first.ipynb: ") and "published in" in said[1]
    with pytest.raises(ReportUsageError, match=r"^no chapter 99 \(chapters: 01"):
        library_build(only=["99"], **dirs)
    make_notebook(dirs["notebooks_dir"] / "02_second.ipynb", "raise ValueError('bad joint')")
    with pytest.raises(ReportError, match="02_second.ipynb failed in cell 3"):
        library_build(only=["02"], **dirs)
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""


def test_a_scheduler_reaches_only_the_chapters_that_run_sweep_cells_and_is_no_input(tmp_path, monkeypatch, capsys):
    """`make report SCHEDULER=…`: the address goes to the chapters declaring ``sweep_scheduler``
    (chapter 6) and nowhere else; where cells run is not part of a chapter's key, so a report
    made without it is up to date with it, and both publish into figures/."""
    notebooks = tmp_path / "notebooks"
    notebooks.mkdir()
    make_chapter(notebooks / "01_robot.ipynb", 'robot_file = "ra.yaml"')
    make_chapter(notebooks / "06_training.ipynb", 'study_file = "sa.yaml"\nsweep_scheduler = None')
    runs = []
    monkeypatch.setattr(report, "run_notebook", fake_run(runs))
    dirs = dict(notebooks_dir=notebooks, figures_dir=tmp_path / "figures", build_dir=tmp_path / "build",
                arms=[report.Edition("a", "sa.yaml", "ra.yaml", True)], parallel=False)
    assert build_report(**dirs) == 0 and len(runs) == 2
    assert build_report(scheduler="tcp://127.0.0.1:8786", **dirs) == 0 and len(runs) == 2   # up to date
    assert capsys.readouterr().err.count("up to date") == 2
    assert build_report(scheduler="tcp://127.0.0.1:8786", force=True, **dirs) == 0
    assert runs[2:] == [("01_robot.ipynb", {"smoke": False}),
                        ("06_training.ipynb", {"smoke": False, "sweep_scheduler": "tcp://127.0.0.1:8786"})]
    assert (tmp_path / "figures" / "tables" / "06_given.csv").exists()          # published, not a variant
