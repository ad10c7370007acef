"""The command line as a user types it, through ``nfarm.__main__.main([...])`` and argparse:
``verify`` on the committed figures and on a tampered copy, every ``report`` option reaching
:func:`nfarm.publishing.report.build_report` (and a real run of a small project through them), the
successful paths of ``datasets``, ``sweep --smoke`` and ``course --smoke``."""

from __future__ import annotations

import csv
import functools
import re
import shutil
from pathlib import Path

import pytest
import yaml

from nfarm.__main__ import main
from nfarm.infra.paths import FIGURES, shown_path
from nfarm.publishing import course, report
from nfarm.publishing.manifest import verify_manifest

from test_report import project  # noqa: F401 — the small project of three notebooks (a fixture)


# --------------------------------------------------------------------------------------------
# verify


def test_verify_passes_on_the_committed_figures(capsys):
    listed = len((FIGURES / "MANIFEST.sha256").read_text().splitlines())
    assert listed > 200
    assert main(["verify"]) == 0
    out, err = capsys.readouterr()
    assert out.strip() == f"{FIGURES}: {listed} files match MANIFEST.sha256" and err == ""


@pytest.mark.parametrize("tamper, message", [
    ("byte", "01_arm_poses.png: differs from the manifest"),
    ("table", "tables/07_verdict.csv: differs from the manifest"),
    ("missing", "tables/01_cross_check.csv: listed but missing"),
    ("extra", "01_extra.png: not in the manifest"),
    ("manifest", "01_workspace.png: differs from the manifest")])
def test_verify_fails_on_a_tampered_copy(tmp_path, capsys, tamper, message):
    copy = tmp_path / "figures"
    shutil.copytree(FIGURES, copy)
    assert main(["verify", "--figures", str(copy)]) == 0
    capsys.readouterr()
    if tamper == "byte":                     # one byte of a figure flipped
        path = copy / "01_arm_poses.png"
        data = bytearray(path.read_bytes())
        data[len(data) // 2] ^= 1
        path.write_bytes(bytes(data))
    elif tamper == "table":                  # a published number changed
        path = copy / "tables" / "07_verdict.csv"
        path.write_text(path.read_text(encoding="utf-8").replace("ANFIS better", "rival better", 1), encoding="utf-8")
    elif tamper == "missing":
        (copy / "tables" / "01_cross_check.csv").unlink()
    elif tamper == "extra":
        (copy / "01_extra.png").write_bytes(b"\x89PNG")
    else:                                    # the manifest's line of a figure edited
        path = copy / "MANIFEST.sha256"
        lines = path.read_text().splitlines(keepends=True)
        k = next(i for i, line in enumerate(lines) if line.endswith("  01_workspace.png\n"))
        lines[k] = ("0" if lines[k][0] != "0" else "1") + lines[k][1:]
        path.write_text("".join(lines))
    assert main(["verify", "--figures", str(copy)]) == 1
    out, err = capsys.readouterr()
    assert out == "" and err.splitlines() == [f"{copy}: {message}"]


# --------------------------------------------------------------------------------------------
# report: each option, as parsed, reaches build_report


@pytest.fixture
def recorded(monkeypatch, tmp_path):
    """build_report replaced by a recorder of its keyword arguments (the run's work patched out)."""
    calls = []

    def build(**options):
        calls.append(options)
        return report.ReportRun(tmp_path / "build" / "report" / "index.html", tmp_path / "figures")
    monkeypatch.setattr(report, "build_report", build)
    return calls


DEFAULTS = {"smoke": False, "only": None, "cell_timeout": 1800, "force": False, "parallel": None,
            "scheduler": None, "arm": None}


@pytest.mark.parametrize("arguments, changed", [
    ([], {}),
    (["--smoke"], {"smoke": True}),
    (["--only", "01", "07"], {"only": ["01", "07"]}),
    (["--only"], {"only": []}),
    (["--arm", "so101"], {"arm": "so101"}),
    (["--force"], {"force": True}),
    (["--serial"], {"parallel": False}),
    (["--scheduler", "tcp://cluster:8786"], {"scheduler": "tcp://cluster:8786"}),
    (["--cell-timeout", "90"], {"cell_timeout": 90.0}),
    (["--cell-timeout", "none"], {"cell_timeout": None}),
    (["--smoke", "--only", "02", "--arm", "intelbot5", "--force", "--serial", "--scheduler", "tcp://h:1",
      "--cell-timeout", "5.5"],
     {"smoke": True, "only": ["02"], "arm": "intelbot5", "force": True, "parallel": False,
      "scheduler": "tcp://h:1", "cell_timeout": 5.5})],
    ids=["defaults", "smoke", "only", "only-none", "arm", "force", "serial", "scheduler", "cell-timeout",
         "cell-timeout-none", "all"])
def test_every_report_option_reaches_build_report(recorded, capsys, arguments, changed):
    assert main(["report", *arguments]) == 0
    (options,) = recorded
    say = options.pop("say")
    # the options parsed; beside them only the progress display's callbacks (say, tell, …)
    assert {k: v for k, v in options.items() if k in DEFAULTS} == {**DEFAULTS, **changed}
    assert set(DEFAULTS) <= set(options) and all(callable(options[k]) for k in set(options) - set(DEFAULTS))
    say("a line")
    run = report.build_report()
    assert capsys.readouterr().err.splitlines() == [
        f"report: {shown_path(run.index)}; figures in {shown_path(run.figures_dir)}", "report: a line"]


@pytest.mark.parametrize("error, status", [("ReportUsageError", 2), ("ReportInterrupted", 130), ("ReportError", 1)])
def test_report_failures_are_an_exit_status_and_one_line(monkeypatch, capsys, error, status):
    from nfarm.infra.notebook_runs import ReportError
    kind = ReportError if error == "ReportError" else getattr(report, error)

    def fail(**options):
        raise kind("chapter 02 failed in cell 3")
    monkeypatch.setattr(report, "build_report", fail)
    assert main(["report", "--only", "02"]) == status
    assert capsys.readouterr().err == "report: chapter 02 failed in cell 3\n"


@pytest.mark.parametrize("arguments", [["--only", "1x"], ["--arm"], ["--cell-timeout"], ["--serial", "x"]])
def test_a_malformed_report_option_is_a_usage_error(recorded, capsys, arguments):
    """(``--only 1x`` is argparse's to accept: build_report refuses an unknown chapter, test_report.)"""
    if arguments == ["--only", "1x"]:
        assert main(["report", *arguments]) == 0 and recorded[0]["only"] == ["1x"]
        return
    with pytest.raises(SystemExit) as exit_:
        main(["report", *arguments])
    assert exit_.value.code == 2 and not recorded
    assert "usage:" in capsys.readouterr().err


#: What the report says when it has run and published a chapter of the small project.
PUBLISHED = re.compile(r"01_first\S*: \d+ figures and tables published")


@pytest.mark.notebook
def test_report_options_on_a_real_run_of_a_small_project(project, monkeypatch, capsys):  # noqa: F811
    """The parsed options drive a real build (test_report's three small notebooks): ``--smoke`` into
    build/smoke, never figures/; ``--only`` one chapter; a second run reuses it, ``--force`` runs it
    again; ``--serial``, ``--cell-timeout`` and ``--scheduler`` taken."""
    _, dirs = project
    figures, build = dirs["figures_dir"], dirs["build_dir"]
    monkeypatch.setattr(report, "build_report", functools.partial(report.build_report, **dirs))
    assert main(["report", "--smoke", "--only", "01", "--serial", "--cell-timeout", "120"]) == 0
    assert (build / "smoke" / "figures" / "tables" / "01_params.csv").read_text() == "smoke\nTrue\n"
    assert not (build / "smoke" / "figures" / "02_line.png").exists(), "--only 01: chapter 02 not run"
    assert not figures.exists(), "a smoke run publishes nothing into figures/"
    capsys.readouterr()
    assert main(["report", "--only", "01", "--serial", "--scheduler", "tcp://127.0.0.1:1"]) == 0
    assert (figures / "tables" / "01_params.csv").read_text() == "smoke\nFalse\n"
    assert verify_manifest(figures) == [] and not (figures / "02_line.png").exists()
    assert PUBLISHED.search(capsys.readouterr().err)
    published = (figures / "01_line.png").stat().st_mtime_ns
    assert main(["report", "--only", "01"]) == 0
    err = capsys.readouterr().err
    assert re.search(r"01_first\S*: up to date", err) and not PUBLISHED.search(err)
    assert (figures / "01_line.png").stat().st_mtime_ns == published
    assert main(["report", "--only", "01", "--force"]) == 0
    err = capsys.readouterr().err
    assert "up to date" not in err and PUBLISHED.search(err)
    assert (figures / "01_line.png").stat().st_mtime_ns != published
    assert main(["report", "--only", "04"]) == 2
    assert capsys.readouterr().err.startswith("report: no chapter 04 (chapters: 01, 02, 03")


# --------------------------------------------------------------------------------------------
# datasets, sweep --smoke, course --smoke


def test_datasets_builds_reuses_and_forces(tmp_path, capsys):
    """``datasets`` on a small study (test_datasets' sizes): every file made, then reused, then
    made again with ``--force``; each a line on standard output, the data sets readable."""
    import numpy as np
    from test_datasets import small_study

    data = small_study()
    data["id"]["trajectories"] = {"train": 2, "val": 2, "test": 2}
    study = tmp_path / "small.yaml"
    study.write_text(yaml.safe_dump(data, sort_keys=False))
    out = tmp_path / "data"
    names = sorted(f"{kind}_{split}.npz" for kind in ("ik", "ik_full", "id") for split in ("train", "val", "test"))
    for arguments, status in (([], "made"), ([], "reused"), (["--force"], "made")):
        assert main(["datasets", str(study), "--out", str(out), *arguments]) == 0
        lines = capsys.readouterr().out.splitlines()
        assert sorted(lines) == sorted(f"{out / name}: {status}" for name in names)
    with np.load(out / "ik_train.npz") as ik:
        assert len(next(iter(ik.values()))) == data["ik"]["sizes"]["train"]


def test_sweep_smoke_runs_the_smaller_version(tmp_path, capsys):
    """``sweep --smoke`` runs the file's ``smoke`` section (here one epoch, one seed) and says so."""
    path = tmp_path / "sweep.yaml"
    path.write_text(yaml.safe_dump({
        "name": "cli", "job": "anfis_benchmark", "fixed": {"problem": "sinc", "epochs": 50},
        "grid": {"n_mfs": [2, 3]}, "seeds": [0, 1], "metrics": ["check_rmse", "rules"],
        "smoke": {"fixed": {"problem": "sinc", "epochs": 1}, "seeds": [0]}}, sort_keys=False))
    out = tmp_path / "out"
    assert main(["sweep", str(path), "--smoke", "--workers", "0", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.out.splitlines()[-1].endswith(
        ": 2 cells, 2 run, 0 already done, 0 failed; results.csv, summary.md, summary.png")
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert sorted((r["n_mfs"], r["epochs"], r["seed"], r["status"]) for r in rows) == \
        [("2", "1", "0", "ok"), ("3", "1", "0", "ok")]
    assert sorted(float(r["rules"]) for r in rows) == [4.0, 9.0]
    assert (out / "summary.md").stat().st_size > 0 and (out / "summary.png").stat().st_size > 0
    assert main(["sweep", str(path), "--smoke", "--workers", "0", "--out", str(out)]) == 0
    assert ": 2 cells, 0 run, 2 already done, 0 failed" in capsys.readouterr().out


def test_course_smoke_builds_the_teachers_notebooks_with_small_parameters(tmp_path, monkeypatch, capsys):
    """``course --smoke --only 04`` reaches build_course with its options (its teacher run patched
    out: test_course runs it) and prints where the course is."""
    seen = []

    def build(out, **options):
        seen.append((out, options))
        return Path(out)
    monkeypatch.setattr(course, "build_course", build)
    out = tmp_path / "course"
    assert main(["course", "--smoke", "--only", "04", "--out", str(out)]) == 0
    ((where, options),) = seen
    progress = options.pop("progress")
    assert where == str(out) and options == {"smoke": True, "only": ["04"], "teacher": True}
    assert capsys.readouterr().out == f"{out}: student/, teacher/ and index.html\n"
    progress("chapter 04 …")
    assert capsys.readouterr().err == "chapter 04 …\n"
    assert main(["course", "--no-teacher", "--out", str(out)]) == 0
    assert seen[-1][1]["smoke"] is False and seen[-1][1]["teacher"] is False and seen[-1][1]["only"] is None


def test_course_smoke_through_the_command_line_for_real(tmp_path, capsys):
    """The student build of one chapter with ``--smoke --no-teacher``: nothing executed, the index written."""
    out = tmp_path / "course"
    assert main(["course", "--smoke", "--only", "01", "--no-teacher", "--out", str(out)]) == 0
    assert [p.name for p in (out / "student").iterdir()] == ["01_dh_model.ipynb"]
    assert (out / "index.html").stat().st_size > 0
    assert capsys.readouterr().out.strip().endswith("student/, teacher/ and index.html")
