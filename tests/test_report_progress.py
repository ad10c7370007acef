"""A report that finishes on a slow machine and says where it is: a cell is stopped for silence,
never for being slow; the sweep cells' progress reaches the terminal; an interrupted run resumes
from the sweep cells it finished."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

from nfarm.infra import progress
from nfarm.infra.notebook_runs import ReportError, run_notebook
from nfarm.infra.paths import ROOT
from nfarm.publishing.console import Console, duration, status_line


def make_notebook(path: Path, *code: str) -> Path:
    cells = [new_markdown_cell(f"# {path.stem}"),
             new_code_cell('smoke = False\nseed = 0\nout_dir = "build/explore/x"\nsweeps_dir = None',
                           metadata={"tags": ["parameters"]})]
    cells += [new_code_cell(c) for c in code]
    nbformat.write(new_notebook(cells=cells), path)
    return path


POSTING = """import time
from nfarm.infra import progress
for k in range(8):
    progress.post("work", k, 8)
    time.sleep(0.5)"""

SWEEP = """from nfarm.study.sweep import sweeps_results
from nfarm.study.sweep_files import sweep_from_dict
sweep = sweep_from_dict({{"name": "tiny", "job": "idle", "fixed": {{"seconds": {seconds}}},
                          "grid": {{"value": list(range({cells}))}}, "metrics": ["value"]}})
(runs,) = sweeps_results([sweep], sweeps_dir, workers=0)
assert [r.metrics["value"] for r in runs] == list(range({cells}))
from nfarm.infra.paths import project_path
from nfarm.presentation.tables import Table
Table(["value"], [[r.metrics["value"]] for r in runs], caption="The sweep's values").save(project_path(out_dir), "01_values")"""


@pytest.mark.notebook
def test_a_cell_that_makes_progress_runs_past_the_limit(tmp_path):
    """Four seconds of work that posts every half second, under a limit of 2 s of silence."""
    nb = make_notebook(tmp_path / "01_slow.ipynb", POSTING, "after = 1")
    states = []
    run_notebook(nb, tmp_path / "out.ipynb", {}, cell_timeout=2, tell=states.append)
    assert any((s["work"] or {}).get("step") == "work" and s["cell"] == 2 for s in states), states[-3:]
    assert max(s["cell_s"] for s in states if s["cell"] == 2) > 2, "the cell ran past the limit"


@pytest.mark.notebook
def test_a_silent_cell_is_stopped_after_the_limit_with_its_kernel(tmp_path):
    marker = tmp_path / "the cell ended"
    nb = make_notebook(tmp_path / "01_stuck.ipynb", f"import time\ntime.sleep(120)\nopen({str(marker)!r}, 'w').close()",
                       "after = 1")
    with pytest.raises(ReportError, match=r"01_stuck.ipynb timed out: no progress for 2 s in cell 2 "
                                          r"\('import time'\); the executed notebook is kept"):
        run_notebook(nb, tmp_path / "out.ipynb", {}, cell_timeout=2)
    assert not marker.exists(), "stopped with its kernel at the limit, not at the cell's end"


@pytest.mark.parametrize("bad", [0, -1, float("nan"), float("inf"), True, "10"])
def test_the_limit_is_a_positive_finite_number_of_seconds(tmp_path, bad):
    nb = make_notebook(tmp_path / "01_x.ipynb", "x = 1")
    with pytest.raises(ValueError, match="cell_timeout must be a positive, finite number of seconds"):
        run_notebook(nb, tmp_path / "out.ipynb", {}, cell_timeout=bad)


def test_posts_are_atomic_and_absent_without_a_runner(tmp_path, monkeypatch):
    monkeypatch.delenv(progress.ENV, raising=False)
    progress.post("nowhere", 1, 2)                      # nothing to write to: nothing happens
    where = tmp_path / "p.json"
    monkeypatch.setenv(progress.ENV, str(where))
    progress.post("step", 2, 5, reused=1, eta_s=float("nan"))
    assert progress.read(where) | {"posted": 0, "pid": 0} == {
        "step": "step", "done": 2, "total": 5, "reused": 1, "eta_s": None, "posted": 0, "pid": 0}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.json"], "no temporary file left"
    where.write_text("{not json")
    assert progress.read(where) is None
    where.write_text(json.dumps({"step": "s", "done": "2", "total": 5, "reused": 0, "posted": 1.0}))
    assert progress.read(where) is None, "a post of the wrong shape is no post"


def test_heartbeats_stop_when_the_counts_stay_still_for_too_long(tmp_path, monkeypatch):
    where = tmp_path / "p.json"
    monkeypatch.setenv(progress.ENV, str(where))
    with progress.heartbeat(lambda: ("s", 1, 3, 0, None), every_s=0.05, alive_for_s=0.3):
        time.sleep(0.2)
        first = progress.read(where)
        assert first is not None, "beats while the counts are fresh"
        time.sleep(0.6)
        stale = progress.read(where)["posted"]
        time.sleep(0.3)
        assert progress.read(where)["posted"] == stale, "no beat once alive_for_s has passed unchanged"


def test_the_estimate_of_time_left():
    assert progress.eta(4, 6, 120.0) == pytest.approx(180.0)
    assert progress.eta(0, 6, 120.0) is None
    assert progress.eta(1, 61, 540.0) is None, "one of 62 cells says nothing of the rest"
    assert progress.eta(7, 55, 600.0) == pytest.approx(55 * 600 / 7)
    assert duration(30) == "30 s" and duration(61) == "1 min" and duration(7260) == "2 h 01 min"


def test_a_log_is_told_of_long_cells_only_and_a_terminal_redraws_one_line_per_chapter(monkeypatch):
    log = io.StringIO()
    console = Console(log, terminal=False)
    short = {"label": "01_dh_model.ipynb", "cell": 3, "cells": 20, "source": "x = 1", "cell_s": 2.0, "work": None}
    console.tell(short)
    assert log.getvalue() == "", "a short cell prints nothing into a log"
    long = {**short, "label": "06_anfis_training.ipynb (so101)", "cell": 7, "cell_s": 300.0,
            "work": {"step": "ik_contest", "done": 37, "total": 120, "reused": 20, "eta_s": 650.0}}
    console.tell(long)
    console.tell({**long, "cell_s": 301.0})             # within EVERY_S: not repeated
    lines = log.getvalue().splitlines()
    assert lines == ["report: 06_anfis_training.ipynb (so101): 20 of 120 sweep cells of ik_contest already finished "
                     "(by an earlier chapter, or a run that stopped), reused", f"report: {status_line(long)}"]
    assert "cell 7 of 20 for 5 min (x = 1): sweep cells of ik_contest 37 of 120 done (20 found done), " \
           "about 11 min left" in lines[1]
    screen = io.StringIO()
    terminal = Console(screen, terminal=True)
    terminal.tell(long)
    terminal.tell({**short, "cell_s": 40.0})
    assert set(terminal.bars) == {long["label"], short["label"]}, "one line per chapter under way"
    terminal.say("a line between the bars")
    terminal.tell({"label": long["label"], "finished": True})
    assert set(terminal.bars) == {short["label"]}
    terminal.close()
    assert "ik_contest 37 of 120" in screen.getvalue() and "a line between the bars" in screen.getvalue()


def _report(notebooks: Path, figures: Path, build: Path, cell_timeout: float = 1800) -> list[str]:
    code = ("import sys\nfrom pathlib import Path\nfrom nfarm.__main__ import report_command\n"
            f"sys.exit(report_command(notebooks_dir=Path({str(notebooks)!r}), figures_dir=Path({str(figures)!r}), "
            f"build_dir=Path({str(build)!r}), cell_timeout={cell_timeout!r}, parallel=False))")
    return [sys.executable, "-c", code]


@pytest.mark.notebook
def test_an_interrupted_report_resumes_from_the_sweep_cells_it_finished(tmp_path):
    """Killed (Ctrl-C) once two of six sweep cells are finished — seen on disk, not guessed by
    a clock — the run stops; run again, it reuses those cells, says so, and publishes."""
    notebooks, sweeps = tmp_path / "notebooks", tmp_path / "sweeps"
    notebooks.mkdir()
    make_notebook(notebooks / "01_sweeps.ipynb", f"sweeps_dir = {str(sweeps)!r}", SWEEP.format(seconds=1.5, cells=6))
    figures, build = tmp_path / "figures", tmp_path / "build"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    run = subprocess.Popen(_report(notebooks, figures, build), cwd=ROOT, env=env, stderr=subprocess.PIPE,
                           text=True, start_new_session=True)
    finished = lambda: sorted(sweeps.glob("tiny/*/cell.json"))     # noqa: E731
    deadline = time.monotonic() + 240
    while len(finished()) < 2 and run.poll() is None and time.monotonic() < deadline:
        time.sleep(0.1)
    assert len(finished()) >= 2 and run.poll() is None, "two cells finished while the report ran"
    os.killpg(run.pid, signal.SIGINT)
    _, err = run.communicate(timeout=120)
    assert run.returncode == 130, err
    assert "interrupted" in err.splitlines()[-1]
    kept = {p: p.stat().st_mtime_ns for p in finished()}
    assert 2 <= len(kept) < 6, "stopped in the middle of the sweep"
    # the second run: the finished cells reused (not run again), the others run, the chapter published
    again = subprocess.run(_report(notebooks, figures, build), cwd=ROOT, env=env, stderr=subprocess.PIPE,
                           text=True, timeout=240)
    assert again.returncode == 0, again.stderr
    assert {p: p.stat().st_mtime_ns for p in kept} == kept, "the finished cells were not run again"
    assert len(finished()) == 6
    assert (figures / "tables" / "01_values.csv").read_text() == "value\n" + "".join(f"{k}\n" for k in range(6))
    assert f"01_sweeps.ipynb: {len(kept)} of 6 sweep cells of tiny already finished (by an earlier " \
           f"chapter, or a run that stopped), reused" in again.stderr, again.stderr


def test_a_chapters_sweep_cells_are_bounded_for_hangs_not_for_slowness(monkeypatch):
    """The chapters' cells get the chapter limit (hours), not the 1 800 s of a sweep run by hand."""
    from nfarm.study import sweep as sweep_module

    seen = {}
    monkeypatch.setattr(sweep_module, "run_sweeps", lambda sweeps, outs, **kw: seen.update(kw) or [[] for _ in sweeps])
    tiny = sweep_module.sweep_from_dict({"name": "tiny", "job": "idle", "grid": {"value": [0]}, "metrics": ["value"]})
    sweep_module.sweeps_results([tiny], workers=0)
    assert seen["timeout"] == sweep_module.CHAPTER_CELL_LIMIT_S >= 4 * 3600
    assert sweep_module.run_sweep.__kwdefaults__["timeout"] == 1800, "a sweep run by hand keeps its limit"
