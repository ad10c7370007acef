"""Parameter sweeps (nfarm.study.sweep, nfarm.study.jobs): sweep files, cells, resuming, failures, and the
same results in this process, on a local Dask cluster and on a scheduler with two workers
started as separate processes on 127.0.0.1."""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from nfarm.__main__ import main
from nfarm.infra.paths import ROOT
from nfarm.infra.reading import ParamsError
from nfarm.study.contest import SPREAD_SEEDS
from nfarm.study.sweep import SWEEPS, load_sweep, run_sweep, run_sweeps, sweep_from_dict

SMOKE = SWEEPS / "smoke.yaml"
NOTEBOOK = "tests/data/sweep_notebook.ipynb"

#: Tests that start Dask clusters share the two cores with nothing else of theirs.
DASK = pytest.mark.xdist_group("dask")


def write(tmp_path: Path, data: dict, name: str = "sweep.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def small(**changes) -> dict:
    base = {"name": "t", "job": "anfis_benchmark", "fixed": {"problem": "sinc", "epochs": 3},
            "grid": {"n_mfs": [2, 3]}, "seeds": [0, 1], "metrics": ["check_rmse", "rules"]}
    return {**base, **changes}


def metrics(results) -> list:
    return [(r.cell.key, r.status, dict(r.metrics)) for r in results]


# --------------------------------------------------------------------------------------------
# Sweep files


def test_shipped_sweep_files_are_valid():
    files = sorted(SWEEPS.glob("*.yaml"))
    assert SMOKE in files
    for path in files:
        for smoke in (False, True):
            assert load_sweep(path, smoke=smoke).cells


def test_cells_are_the_product_of_grid_cells_and_seeds():
    sweep = sweep_from_dict(small(cells=[{"mf": "gbell"}, {"mf": "gauss"}]))
    assert len(sweep.cells) == 2 * 2 * 2
    assert sweep.varying == ["n_mfs", "mf", "seed"]
    assert {(c.params["mf"], c.params["n_mfs"], c.params["seed"]) for c in sweep.cells} == \
        {(m, n, s) for m in ("gbell", "gauss") for n in (2, 3) for s in (0, 1)}
    assert all(c.params["problem"] == "sinc" and c.params["epochs"] == 3 for c in sweep.cells)


def test_a_default_written_out_is_the_same_cell():
    implicit = sweep_from_dict(small())
    explicit = sweep_from_dict(small(fixed={"problem": "sinc", "epochs": 3, "mf": "gbell"}))
    assert [c.key for c in implicit.cells] == [c.key for c in explicit.cells]
    other = sweep_from_dict(small(fixed={"problem": "sinc", "epochs": 4}))
    assert not {c.key for c in implicit.cells} & {c.key for c in other.cells}


def test_restrict_sets_a_parameter_and_merges_equal_cells():
    sweep = sweep_from_dict(small())
    one = sweep.restrict(seed=1)
    assert len(one.cells) == 2 and all(c.params["seed"] == 1 for c in one.cells)
    assert {c.key for c in one.cells} < {c.key for c in sweep.cells}


def test_paths_are_project_relative():
    data = {"name": "t", "job": "learned_ik", "metrics": ["worst_deg"]}
    a = sweep_from_dict({**data, "fixed": {"study_file": "params/studies/intelbot5.yaml"}})
    b = sweep_from_dict({**data, "fixed": {"study_file": str(ROOT / "params/studies/intelbot5.yaml")}})
    assert a.cells[0].key == b.cells[0].key
    assert a.cells[0].params["study_file"] == "params/studies/intelbot5.yaml"


def test_the_smoke_section_replaces_its_fields():
    data = small(smoke={"grid": {"n_mfs": [2]}, "seeds": [0]})
    assert len(sweep_from_dict(data).cells) == 4
    assert len(sweep_from_dict(data, smoke=True).cells) == 1


def test_a_sweep_file_is_read_whole_by_the_typed_reader():
    """SweepFile (infra.typed) is the schema: the smoke section's fields are read with the
    file's, and a field the smoke version replaces is still the file's, in smoke mode too."""
    from nfarm.infra.typed import section_keys
    from nfarm.study.sweep_files import SmokeSection, SweepFile
    assert list(section_keys(SweepFile)) == ["name", "description", "job", "notebook", "fixed", "grid", "cells",
                                             "seeds", "metrics", "smoke", "cell_timeout_s"]
    assert list(section_keys(SmokeSection)) == ["fixed", "grid", "cells", "seeds"]
    with pytest.raises(ParamsError, match=r"^f.yaml: smoke.seeds\[0\]: must be >= 0, got -1$"):
        sweep_from_dict(small(smoke={"seeds": [-1]}), "f.yaml")
    with pytest.raises(ParamsError, match=r"^f.yaml: grid: must be a mapping of parameters, got \[2\]$"):
        sweep_from_dict(small(grid=[2], smoke={"grid": {"n_mfs": [2]}}), "f.yaml", smoke=True)
    with pytest.raises(ParamsError, match=r"^f.yaml: smoke: must be a mapping of fields, got None$"):
        sweep_from_dict(small(smoke=None), "f.yaml")


@pytest.mark.parametrize("changes, message", [
    ({"colour": 1}, "colour: unknown field"),
    ({"notebook": NOTEBOOK}, "must name either a job or a notebook"),
    ({"job": "train_everything"}, "job: must be one of anfis_benchmark"),
    ({"grid": {"n_mf": [2]}}, "grid.n_mf: unknown parameter of job anfis_benchmark"),
    ({"grid": {"epochs": [2]}}, "grid.epochs: is also in fixed"),
    ({"grid": {"n_mfs": []}}, "grid.n_mfs: must be a list of at least 1 items"),
    ({"grid": {"n_mfs": 2}}, "grid.n_mfs: must be a list"),
    ({"grid": {"seed": [1]}}, "seeds: the grid sets seed too"),
    ({"cells": [{"n_mfs": 2}]}, "cells[0].n_mfs: is also a grid parameter"),
    ({"cells": [{"epoch": 2}]}, "cells[0].epoch: unknown parameter"),
    ({"cells": ["gauss"]}, "cells[0]: must be a mapping of parameters"),
    ({"fixed": [1, 2]}, "fixed: must be a mapping of parameters"),
    ({"fixed": {"epoch": 2}}, "fixed.epoch: unknown parameter"),
    ({"fixed": {"epochs": float("nan")}}, "fixed.epochs: must be a finite number"),
    ({"seeds": [-1]}, "seeds[0]: must be >= 0"),
    ({"metrics": ["accuracy"]}, "metrics[0]: job anfis_benchmark returns no metric 'accuracy'"),
    ({"metrics": []}, "metrics: must be a list of at least 1 items"),
    ({"name": "../elsewhere"}, "name: must be letters, digits"),
    ({"grid": {"n_mfs": list(range(400)), "epochs": list(range(300))}, "fixed": {}},
     "makes 240,000 cells; at most 100,000"),
    ({"smoke": {"grid": {"n_mf": [2]}}}, "smoke.grid.n_mf: unknown parameter"),
    ({"smoke": {"metrics": ["rules"]}}, "smoke.metrics: unknown field"),
    # a value of another kind than its parameter's is refused, not read as something else
    ({"fixed": {"problem": "sinc", "epochs": 3.5}}, "fixed.epochs: must be a whole number, got 3.5"),
    ({"fixed": {"problem": "sinc", "epochs": True}}, "fixed.epochs: must be a whole number, got True"),
    ({"grid": {"step_size": [0.1, "fast"]}}, "grid.step_size: must be a number, got 'fast'"),
    ({"cells": [{"mf": "gauss"}, {"mf": 3}]}, "cells[1].mf: must be a text, got 3"),
    ({"seeds": [0, 1.5]}, "seeds[1]: must be a whole number"),
])
def test_a_bad_sweep_file_gets_one_line(tmp_path, changes, message, capsys):
    path = write(tmp_path, small(**changes))
    with pytest.raises(ParamsError) as caught:
        load_sweep(path)
    text = str(caught.value)
    assert "\n" not in text and text.startswith(str(path)) and message in text, text
    assert main(["sweep", str(path), "--workers", "0", "--out", str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err.strip() == text
    assert not (tmp_path / "out").exists()


def test_a_notebook_sweep_names_only_the_notebooks_parameters(tmp_path):
    data = {"name": "nb", "notebook": NOTEBOOK, "grid": {"y": [1]}, "metrics": ["square"]}
    with pytest.raises(ParamsError, match=r"grid.y: unknown parameter of notebook .*allowed: x, seed, fail\)"):
        sweep_from_dict(data, "f.yaml")
    with pytest.raises(ParamsError, match=r"grid.out_dir: is set by the sweep runner"):
        sweep_from_dict({**data, "grid": {"out_dir": ["x"]}}, "f.yaml")
    with pytest.raises(ParamsError, match=r"notebook: must be an existing .ipynb file"):
        sweep_from_dict({**data, "notebook": "notebooks/99_none.ipynb"}, "f.yaml")


# --------------------------------------------------------------------------------------------
# Running in this process


def test_resume_skips_finished_cells_and_reruns_failed_ones(tmp_path):
    sweep = sweep_from_dict(small(cells=[{}, {"partition": "fcm", "n_rules": 0}]), "t.yaml")
    first = run_sweep(sweep, tmp_path, workers=0)
    assert [r.status for r in first] == ["ok"] * 4 + ["failed"] * 4
    failed = first[-1]
    cell = json.loads((tmp_path / failed.cell.key / "cell.json").read_text())
    assert cell["status"] == "failed" and cell["params"]["n_rules"] == 0
    assert "n_rules" in cell["error"] and "Traceback" in (tmp_path / failed.cell.key / "error.txt").read_text()
    again = run_sweep(sweep, tmp_path, workers=0)
    assert [r.reused for r in again] == [True] * 4 + [False] * 4
    assert metrics(again) == metrics(first)
    rows = list(csv.DictReader((tmp_path / "results.csv").open()))
    assert [r["cell"] for r in rows] == [c.key for c in sweep.cells]
    assert rows[-1]["status"] == "failed" and rows[-1]["n_rules"] == "0" and rows[-1]["error"]
    assert rows[0]["status"] == "ok" and float(rows[0]["check_rmse"]) == first[0].metrics["check_rmse"]
    assert (tmp_path / "summary.md").read_text().count("| failed |") == 4
    assert (tmp_path / "summary.png").stat().st_size > 0


def test_a_change_of_code_runs_the_cells_again(tmp_path, monkeypatch):
    sweep = sweep_from_dict(small(), "t.yaml")
    run_sweep(sweep, tmp_path, workers=0)
    import nfarm.study.sweep

    monkeypatch.setattr(nfarm.study.sweep, "code_key", lambda sweep: "another")
    assert not any(r.reused for r in run_sweep(sweep, tmp_path, workers=0))


def test_a_widened_grid_runs_only_its_new_cells(tmp_path):
    run_sweep(sweep_from_dict(small(), "t.yaml"), tmp_path, workers=0)
    wider = run_sweep(sweep_from_dict(small(grid={"n_mfs": [2, 3, 4]}), "t.yaml"), tmp_path, workers=0)
    assert sum(r.reused for r in wider) == 4 and len(wider) == 6


def test_a_notebook_cell_keeps_its_notebook_files_and_metrics(tmp_path):
    sweep = sweep_from_dict({"name": "nb", "notebook": NOTEBOOK, "grid": {"x": [3.0], "fail": [False, True]},
                             "metrics": ["square", "pair"]}, "nb.yaml")
    ok, failed = run_sweep(sweep, tmp_path, workers=0)
    assert ok.ok and ok.metrics == {"square": 9.0, "pair": [3.0, -3.0]}
    cell = tmp_path / ok.cell.key
    assert (cell / "files" / "square.txt").read_text() == "9.0\n"
    assert json.loads((cell / "notebook.ipynb").read_text())["cells"]
    assert not failed.ok and "asked to fail" in failed.error
    header = (tmp_path / "results.csv").read_text().splitlines()[0].split(",")
    assert header[-7:] == ["square", "pair[1]", "pair[2]", "status", "seconds", "worker", "error"]


def test_a_missing_metric_fails_the_cell(tmp_path):
    sweep = sweep_from_dict({"name": "nb", "notebook": NOTEBOOK, "metrics": ["cube"]}, "nb.yaml")
    (result,) = run_sweep(sweep, tmp_path, workers=0)
    assert not result.ok and "gave no metric 'cube'" in result.error


def test_the_command_line_runs_a_sweep_and_says_what_failed(tmp_path, capsys):
    path = write(tmp_path, small(cells=[{}, {"n_mfs": 0}], grid={}, seeds=[0]))
    assert main(["sweep", str(path), "--workers", "0", "--out", str(tmp_path / "out")]) == 1
    captured = capsys.readouterr()
    assert "2 cells, 1 run, 0 already done, 1 failed" in captured.out
    assert "'n_mfs': 0" in captured.err
    assert main(["sweep", str(path), "--workers", "-1"]) == 2
    assert main(["sweep", str(path), "--workers", "1", "--scheduler", "tcp://127.0.0.1:1"]) == 2


# --------------------------------------------------------------------------------------------
# Dask: a local cluster and a loopback scheduler with two workers


@DASK
def test_a_local_cluster_of_two_processes_gives_the_same_results(tmp_path):
    sweep = load_sweep(SMOKE).restrict(epochs=20)
    here = run_sweep(sweep, tmp_path / "here", workers=0)
    local = run_sweep(sweep, tmp_path / "local", workers=2)
    assert all(r.ok for r in local)
    assert metrics(local) == metrics(here)
    assert {r.worker for r in local} <= {"0", "1"}
    assert json.loads((tmp_path / "local" / local[0].cell.key / "cell.json").read_text())["worker"] in ("0", "1")
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address="127.0.0.1:0") as cluster, \
            Client(cluster) as client:
        given = run_sweep(sweep, tmp_path / "given", client=client)
        assert metrics(given) == metrics(here)
        assert client.status == "running"          # a client of the caller's is left open


def test_cells_a_chapter_makes_take_the_jobs_defaults_its_name_and_every_metric():
    sweep = sweep_from_dict(small(), "t.yaml")
    made = sweep.with_cells([{"problem": "sinc", "n_mfs": 4}, {"problem": "sinc", "n_mfs": 4, "seed": 0}], name="mine")
    assert made.name == "mine" and made.job == sweep.job and len(made.cells) == 1     # the default written out: one cell
    assert made.cells[0].params["epochs"] == 10 and made.metrics == ("train_rmse", "check_rmse", "rules")
    assert sweep.with_cells([{"n_mfs": 4}]).name == "t"
    with pytest.raises(ParamsError, match="unknown"):
        sweep.with_cells([{"n_mfs": 4, "colour": 1}])
    with pytest.raises(ParamsError, match="directory name"):
        sweep.with_cells([{"n_mfs": 4}], name="../up")


def test_several_sweeps_run_together_as_each_alone(tmp_path):
    one = sweep_from_dict(small(), "t.yaml")
    two = sweep_from_dict(small(name="u", grid={"n_mfs": [3, 4]}), "u.yaml")
    alone = [run_sweep(s, tmp_path / "alone" / s.name, workers=0) for s in (one, two)]
    together = run_sweeps([one, two, one], [tmp_path / "t", tmp_path / "u", tmp_path / "t"], workers=0)
    assert [metrics(r) for r in together] == [metrics(r) for r in (alone[0], alone[1], alone[0])]
    assert not any(r.reused for r in together[0])
    assert all(a is b for a, b in zip(together[2], together[0]))     # listed twice, run once
    assert sorted(p.name for p in (tmp_path / "t").iterdir() if p.is_dir()) == sorted(c.key for c in one.cells)
    again = run_sweeps([two, one], [tmp_path / "u", tmp_path / "t"], workers=0)
    assert all(r.reused for runs in again for r in runs)
    with pytest.raises(ValueError, match="one directory per sweep"):
        run_sweeps([one, two], [tmp_path / "t"], workers=0)


@pytest.fixture
def loopback(tmp_path):
    """A ``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1; its address."""
    dask = str(Path(sys.executable).parent / "dask")
    file = tmp_path / "scheduler.json"
    env = {**os.environ, "PYTHONHASHSEED": "0"}
    procs = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", "0",
                               "--no-dashboard", "--scheduler-file", str(file)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        deadline = time.monotonic() + 60
        while not file.is_file() and time.monotonic() < deadline:
            time.sleep(0.2)
        address = json.loads(file.read_text())["address"]
        for name in ("w1", "w2"):
            procs.append(subprocess.Popen([dask, "worker", address, "--nthreads", "1", "--name", name,
                                           "--no-dashboard", "--local-directory", str(tmp_path / name)],
                                          env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        from distributed import Client

        with Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=60)
        yield address
    finally:
        for proc in reversed(procs):
            proc.terminate()
        for proc in procs:
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()


@DASK
def test_a_scheduler_and_two_workers_started_apart_give_the_same_results(tmp_path, loopback):
    sweep = load_sweep(SMOKE).restrict(epochs=20)
    cells = sweep_from_dict(small(cells=[{}, {"n_mfs": 0}], grid={}, seeds=[0]), "t.yaml")
    remote = run_sweep(sweep, tmp_path / "remote", scheduler=loopback)
    here = run_sweep(sweep, tmp_path / "here", workers=0)
    assert metrics(remote) == metrics(here)
    assert {r.worker for r in remote} <= {"w1", "w2"}
    ok, failed = run_sweep(cells, tmp_path / "failing", scheduler=loopback)
    assert ok.ok and not failed.ok and "n_mfs" in failed.error and failed.cell.params["n_mfs"] == 0
    assert all(r.reused for r in run_sweep(sweep, tmp_path / "remote", scheduler=loopback))


@DASK
def test_one_shared_cluster_serves_every_sweep_started_inside_it_and_ends_with_it(tmp_path):
    """nfarm.study.sweep.shared_cluster (issue 63: make report's editions side by side send their cells
    to one cluster of one worker per core, not a cluster each): inside the block, a sweep that names
    neither a scheduler nor workers runs on it, in this process and in a process started inside; its
    workers are the same processes for every sweep (nothing imported twice); afterwards the environment
    is as before and the cluster is gone."""
    from distributed import Client

    from nfarm.study.sweep import shared_cluster
    sweep = load_sweep(SMOKE).restrict(epochs=20)
    here = run_sweep(sweep, tmp_path / "here", workers=0)
    before = os.environ.get("DASK_SCHEDULER_ADDRESS")
    with shared_cluster(1) as address:
        assert os.environ["DASK_SCHEDULER_ADDRESS"] == address
        shared = run_sweep(sweep, tmp_path / "shared")
        assert metrics(shared) == metrics(here) and len({r.worker for r in shared}) == 1
        seen = subprocess.run([sys.executable, "-c", "import os; print(os.environ['DASK_SCHEDULER_ADDRESS'])"],
                              capture_output=True, text=True, check=True).stdout.strip()
        assert seen == address, "a process started inside inherits the address"
        with Client(address, timeout="20s") as client:
            pids = set(client.run(os.getpid).values())
            again = run_sweep(sweep.restrict(epochs=21), tmp_path / "again")
            assert all(r.ok for r in again) and set(client.run(os.getpid).values()) == pids
    assert os.environ.get("DASK_SCHEDULER_ADDRESS") == before
    with pytest.raises(OSError):
        Client(address, timeout="3s")


def _wait_until_cells_run(run: subprocess.Popen, posts: Path, timeout: float = 120) -> dict:
    """The sweep ``run``'s progress state once its cells are under way on the cluster (asserted). Polled, not
    slept: the sweep posts once before its cluster starts, then beats only while it waits on the cluster's
    workers, whose cells sleep for a minute — the second post says the cells are under way."""
    from nfarm.infra import progress

    deadline, first, state = time.monotonic() + timeout, None, None
    while run.poll() is None and time.monotonic() < deadline:
        state = progress.read(posts)
        if state is not None and first is None:
            first = state["posted"]
        if state is not None and state["posted"] != first:
            break
        time.sleep(0.2)
    assert run.poll() is None and state is not None and state["posted"] != first, "the cells run on the cluster"
    return state


@DASK
def test_ctrl_c_inside_a_shared_cluster_stops_its_sweep_and_ends_every_process(tmp_path):
    """SIGINT to the whole process group while a sweep runs on a shared cluster: the sweep stops, the
    cluster's process (which ignores SIGINT) closes its workers as the block is left, no process of the
    group is left behind and nothing but the caller's own line is printed."""
    import signal

    from nfarm.infra import progress
    sweep_file = write(tmp_path, {"name": "slow", "job": "idle", "fixed": {"seconds": 60.0},
                                  "grid": {"value": [1, 2]}, "metrics": ["value"]})
    posts = tmp_path / "progress.json"
    code = f"""
import signal, sys
signal.signal(signal.SIGINT, signal.default_int_handler)
from nfarm.study.sweep import load_sweep, run_sweep, shared_cluster
try:
    with shared_cluster(2):
        run_sweep(load_sweep({str(sweep_file)!r}), {str(tmp_path / "out")!r})
except KeyboardInterrupt:
    print("stopped", file=sys.stderr)
    sys.exit(130)
"""
    run = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           start_new_session=True, cwd=ROOT, env={**os.environ, progress.ENV: str(posts)})
    _wait_until_cells_run(run, posts)
    os.killpg(run.pid, signal.SIGINT)
    _, err = run.communicate(timeout=90)
    assert run.returncode == 130 and err.strip() == "stopped", err
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        try:
            os.killpg(run.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.2)
    else:
        pytest.fail("a process of the shared cluster outlived the block")


def test_a_shared_cluster_that_cannot_start_is_one_line():
    from nfarm.study.sweep import SweepError, shared_cluster
    before = os.environ.get("DASK_SCHEDULER_ADDRESS")
    with pytest.raises(SweepError, match=r"^the local Dask cluster for the chapters' sweep cells did not start: "
                                         r"no address within 0.01 s$"):
        with shared_cluster(1, start_timeout=0.01):
            pass
    assert os.environ.get("DASK_SCHEDULER_ADDRESS") == before
    for bad in (0, -1, 1.5, True, "2"):
        with pytest.raises(ValueError, match="workers must be a whole number >= 1 or None"):
            with shared_cluster(bad):
                pass


# --------------------------------------------------------------------------------------------
# Seeds: a configuration's spread


@pytest.mark.parametrize("name", ["id_comparison", "id_baselines"])
def test_the_pruned_sweeps_run_seed_0_and_their_tier_finalists_two_more(name):
    """Chapter 6 trains every configuration of these with seed 0 and each tier's best on the
    contest's other seeds (nfarm.study.contest.tier_spread_params): three seeds for a finalist, the
    fewest with a spread (issue 63 cut them from five to the clean build's budget)."""
    from nfarm.study import contest
    sweep = load_sweep(SWEEPS / f"{name}.yaml")
    assert {c.params["seed"] for c in sweep.cells} == {0}
    assert 0 not in contest.SPREAD_SEEDS and len(set(contest.SPREAD_SEEDS)) == len(contest.SPREAD_SEEDS) >= 2


@pytest.mark.parametrize(("name", "seeds"), [("id_comparison_large", 5), ("id_baselines_large", 5),
                                             ("id_sizes", 1 + len(SPREAD_SEEDS))])
def test_the_study_sweeps_run_every_configuration_over_its_seeds(name, seeds):
    """Each configuration of a comparison the chapters show has its seeds: chapter 6.6's curve those of
    a contest's finalist (three), the large sweeps run by hand five."""
    sweep = load_sweep(SWEEPS / f"{name}.yaml")
    configurations = {json.dumps({k: v for k, v in c.params.items() if k != "seed"}, sort_keys=True)
                      for c in sweep.cells}
    assert len(sweep.cells) == seeds * len(configurations) and len({c.params["seed"] for c in sweep.cells}) == seeds


def test_results_group_by_configuration_with_the_mean_and_range_over_seeds(tmp_path):
    from nfarm.study.sweep import best_by, by_configuration
    sweep = sweep_from_dict(small(seeds=[0, 1, 2], fixed={"problem": "sinc", "epochs": 2, "partition": "fcm",
                                                         "mf": "gauss"},
                                  grid={"n_rules": [2, 3]}, metrics=["check_rmse", "rules"]))
    results = run_sweep(sweep, tmp_path, workers=0)
    groups = by_configuration(reversed(results))
    assert [g.n for g in groups] == [3, 3] and all(g.seeds == [0, 1, 2] for g in groups)
    for g in groups:
        values = [r.metrics["check_rmse"] for r in g.runs]
        assert len(set(values)) > 1                       # fuzzy c-means starts from the seed
        assert g.metrics["check_rmse"] == pytest.approx(sum(values) / 3)
        assert g.low("check_rmse") == min(values) and g.high("check_rmse") == max(values)
        assert g.metrics["rules"] == g.runs[0].metrics["rules"]          # equal in every seed: as it is
        assert "seed" not in {k for k in g.cell.params if g.cell.params[k] != g.runs[0].cell.params[k]}
    best = best_by(groups, "partition", "check_rmse")
    assert best["fcm"] is min(groups, key=lambda g: g.metrics["check_rmse"])
    # Given a seed, the choice is made on that seed's cells (a sweep pruned after seed 0)
    on_1 = best_by(groups, "partition", "check_rmse", seed=1)
    assert on_1["fcm"] is min(groups, key=lambda g: g.values("check_rmse")[1])
    with pytest.raises(ValueError, match="no cell of seed 7"):
        best_by(groups, "partition", "check_rmse", seed=7)


# --------------------------------------------------------------------------------------------
# The learned jobs' options


@pytest.fixture(scope="module")
def smoke_cell(tmp_path_factory):
    """The parameters of a smoke study's cell with its own data and models directories."""
    base = tmp_path_factory.mktemp("jobs")
    return {"study_file": "params/studies/intelbot5.yaml", "smoke": True,
            "data_dir": str(base / "data"), "models_dir": str(base / "models")}


def test_a_learned_id_cell_trains_on_as_many_states_made_the_seeds_way(smoke_cell):
    from nfarm.study.jobs import JOBS, id_training_data
    import numpy as np
    cell = {**smoke_cell, "inputs": "own", "n_mfs": 2, "epochs": 1, "stride": 2}
    spec = {"duration_s": 6.0, "dt_s": 0.2, "seed": 7}
    own, made = id_training_data(cell), id_training_data({**cell, "seed_like": spec})
    assert len(made["q"]) == len(own["q"])
    # cubics from rest to rest over 6 s sampled every 0.2 s: 31 states each, at rest at both ends
    assert np.allclose(made["qd"][::31], 0) and np.allclose(made["qd"][30::31], 0)
    assert not np.allclose(made["q"][:31], id_training_data({**cell, "seed_like": spec, "seed": 1})["q"][:31])
    result = JOBS["learned_id"].function(JOBS["learned_id"].complete({**cell, "seed_like": spec}))
    assert result["train_samples"] == len(own["q"]) and np.isfinite(result["worst_nrmse"])


@pytest.mark.parametrize("seed_like, more, message", [
    ({"duration_s": 6.0, "dt_s": 0.2}, {}, "seed_like must be null or a mapping of duration_s, dt_s, seed"),
    ({"duration_s": 6.0, "dt_s": 0.0, "seed": 7}, {}, "0 < dt_s <= duration_s <= 600"),
    ({"duration_s": 6.0, "dt_s": 1e-6, "seed": 7}, {}, "at most 10 000 samples"),
    ({"duration_s": 6.0, "dt_s": 0.2, "seed": -1}, {}, r"seed must be an integer in \[0, 2\^32\)"),
    ({"duration_s": 6.0, "dt_s": 0.2, "seed": 7}, {"torques": "measured"}, "rigid-body torques only"),
])
def test_bad_seed_like_trajectories_are_one_line_errors(smoke_cell, seed_like, more, message):
    from nfarm.study.jobs import id_training_data
    with pytest.raises(ParamsError, match=message):
        id_training_data({**smoke_cell, "seed_like": seed_like, **more})


def test_a_learned_ik_cell_trains_on_the_poses_it_names(smoke_cell):
    from nfarm.study.jobs import JOBS
    job = JOBS["learned_ik"]
    cell = {**smoke_cell, "encoding": "quat_xyz", "n_mfs": [2, 2, 1, 1, 1, 1, 1], "epochs": 1}
    region = job.function(job.complete(cell))
    full = job.function(job.complete({**cell, "poses": "full_range"}))
    assert region["worst_deg"] != full["worst_deg"]
    with pytest.raises(ParamsError, match="poses must be one of region, full_range, got 'all'"):
        job.function(job.complete({**cell, "poses": "all"}))


def test_a_chapter_reads_a_cells_model_without_training_it_again(smoke_cell, monkeypatch):
    """The cell trains with one BLAS thread and caches on that environment; a chapter whose
    kernel has the machine's thread count gets the same model, not a second training."""
    from nfarm.study.jobs import JOBS, ik_model
    from nfarm.study.sweep import execute_cell
    cell = {**smoke_cell, "encoding": "arm_plane", "n_mfs": [1, 2, 2, 2, 2, 1], "epochs": 1,
            "max_out_of_plane_deg": 0.5, "seed": 3}
    record = execute_cell("learned_ik", None, JOBS["learned_ik"].complete(cell), ["worst_deg"], None)
    assert record["status"] == "ok", record.get("error")
    stamps = sorted(Path(smoke_cell["models_dir"]).rglob("inputs.sha256"))
    before = {p: p.stat().st_mtime_ns for p in stamps}
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    model = ik_model(cell)
    assert {p: p.stat().st_mtime_ns for p in stamps} == before        # reused, not retrained
    import numpy as np
    assert np.degrees(max(m.val_loss_curve_[m.best_epoch_] for m in model.models_)) == pytest.approx(
        record["metrics"]["worst_deg"], rel=1e-12)


def test_equal_parameters_make_one_cell_whatever_their_spelling():
    sweep = sweep_from_dict(small(grid={"n_mfs": [2, 2.0, 3]}, fixed={"problem": "sinc", "epochs": 3.0}, seeds=[0]))
    assert [c.params["n_mfs"] for c in sweep.cells] == [2, 3]
    assert all(isinstance(c.params["epochs"], int) for c in sweep.cells)
    learned = sweep_from_dict({"name": "l", "job": "learned_id", "metrics": ["worst_nrmse"],
                               "fixed": {"study_file": "params/studies/intelbot5.yaml"},
                               "cells": [{"n_mfs": [1, 2.0, 2]}, {"n_mfs": [1.0, 2, 2]},
                                         {"study_file": "./params/../params/studies/intelbot5.yaml", "n_mfs": [1, 2, 2]}]})
    assert len(learned.cells) == 1 and learned.cells[0].params["n_mfs"] == [1, 2, 2]
    with pytest.raises(ParamsError, match=r"fixed.smoke: must be true or false, got 'no'"):
        sweep_from_dict({"name": "l", "job": "learned_ik", "metrics": ["worst_deg"],
                         "fixed": {"study_file": "params/studies/intelbot5.yaml", "smoke": "no"}})
    with pytest.raises(ParamsError, match=r"fixed.study_file: must be a path \(text\), got 5"):
        sweep_from_dict({"name": "l", "job": "learned_ik", "metrics": ["worst_deg"], "fixed": {"study_file": 5}})


def test_a_cell_whose_shared_preparation_fails_is_recorded_and_the_others_run(tmp_path, monkeypatch):
    """Any exception of the job's shared preparation (not only a ParamsError) fails the cells of
    those parameters, each recorded, and the sweep goes on with the others."""
    from dataclasses import replace

    from nfarm.study.jobs import JOBS

    def prepare(p):
        if p["value"] == 1:
            raise TypeError("unsupported operand type(s)")     # what a bad study value raised

    def function(p):
        prepare(p)
        return {"seconds": 0.0, "value": p["value"]}

    monkeypatch.setitem(JOBS, "idle", replace(JOBS["idle"], function=function, prepare=prepare, shared=("value",)))
    sweep = sweep_from_dict({"name": "p", "job": "idle", "grid": {"value": [0, 1, 2]}, "metrics": ["value"]})
    results = run_sweep(sweep, tmp_path, workers=0)
    assert [r.status for r in results] == ["ok", "failed", "ok"]
    assert "TypeError: unsupported operand" in results[1].error
    assert (tmp_path / "results.csv").is_file()


class EpochClock:
    """A fake ``time`` for :mod:`nfarm.infra.limits`: each reading of the clock moves it on by
    ``tick`` seconds, so a deadline passes after a known number of checks whatever the
    machine's speed (the real speed: ``benchmarks/bench_deadlines.py``)."""

    def __init__(self, tick: float):
        self.now, self.tick = 0.0, tick

    def monotonic(self) -> float:
        self.now += self.tick
        return self.now


def test_a_cell_over_its_time_limit_fails_alone_and_the_others_run(tmp_path, monkeypatch):
    """epochs: 10 000 000 would train for days: the cell stops at its first epoch past the
    sweep file's cell_timeout_s, recorded as failed; its neighbours finish. On a clock that
    moves 0.25 s per reading (one when the limit is set, one per epoch's check), 1.5 s pass
    at the 6th epoch's check and the 7th's is past them."""
    from nfarm.infra import limits

    monkeypatch.setattr(limits, "time", EpochClock(0.25))
    sweep = sweep_from_dict(small(grid={"epochs": [2, 10_000_000]}, fixed={"problem": "sinc"}, seeds=[0],
                                  cell_timeout_s=1.5))
    assert sweep.timeout == 1.5
    results = run_sweep(sweep, tmp_path, workers=0)
    assert [r.status for r in results] == ["ok", "failed"]
    assert results[0].metrics["check_rmse"] > 0
    assert "TimeLimitError: ANFIS training, epoch 7 of 10000000: over the time limit of 1.5 s" in results[1].error


@pytest.mark.parametrize("value, message", [(0, "must be > 0"), (-5, "must be > 0"), ("soon", "must be a number"),
                                            (1e9, "must be <= 604800")])
def test_a_cell_time_limit_is_a_positive_number_of_seconds(value, message):
    with pytest.raises(ParamsError, match=rf"cell_timeout_s: {message}"):
        sweep_from_dict(small(cell_timeout_s=value))


def test_time_limits_nest_and_stay_in_their_thread():
    import threading

    from nfarm.infra.limits import TimeLimitError, check_time, time_limit
    with time_limit(0.05):
        time.sleep(0.08)
        seen = []
        thread = threading.Thread(target=lambda: seen.append(check_time("elsewhere")))
        thread.start()
        thread.join()
        assert seen == [None]                         # another thread: no deadline
        with time_limit(100.0):                      # an inner, later limit does not extend it
            with pytest.raises(TimeLimitError, match=r"here: over the time limit of 0.05 s"):
                check_time("here")
    check_time("after")                              # the block is over
    with pytest.raises(ValueError, match=r"a time limit must be a positive number of seconds"):
        with time_limit(0):
            pass


def test_ctrl_c_stops_a_sweep_on_a_cluster_in_one_line(tmp_path):
    """SIGINT to the terminal's whole process group (the client, the nannies, the workers):
    the client says so in one line and exits 130; no worker prints its traceback."""
    import signal

    sweep_file = write(tmp_path, {"name": "slow", "job": "idle", "fixed": {"seconds": 60.0},
                                  "grid": {"value": [1, 2]}, "metrics": ["value"]})
    from nfarm.infra import progress

    posts = tmp_path / "progress.json"
    run = subprocess.Popen([sys.executable, "-m", "nfarm", "sweep", str(sweep_file), "--workers", "2",
                            "--out", str(tmp_path / "out")], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True, start_new_session=True, cwd=ROOT, env={**os.environ, progress.ENV: str(posts)})
    assert _wait_until_cells_run(run, posts)["done"] == 0
    os.killpg(run.pid, signal.SIGINT)
    _, err = run.communicate(timeout=90)
    assert run.returncode == 130 and err.strip() == "nfarm: interrupted", err


@DASK
def test_the_local_cluster_runs_its_workers_without_the_stack_profiler():
    """The local cluster's workers get nfarm.study.sweep.QUIET_CLUSTER (issue 63: Dask's 10 ms stack
    profiler and fast monitors cost a busy worker 3 % of its CPU): the settings reach the worker
    processes, not only the process that starts them."""
    import dask

    from nfarm.study.sweep import QUIET_CLUSTER, _client
    client = _client(None, 1)
    try:
        seen = next(iter(client.run(lambda: {k: dask.config.get(k) for k in QUIET_CLUSTER}).values()))
    finally:
        cluster = client.cluster
        client.close()
        cluster.close()
    assert seen == QUIET_CLUSTER and seen["distributed.worker.profile.enabled"] is False


@DASK
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's arenas")
def test_the_local_cluster_runs_its_workers_with_one_allocator_arena():
    """The local cluster's worker processes start with Dask's own environment and
    nfarm.study.sweep.WORKER_ENVIRON (issue 63: glibc's one arena, so that a cell's large arrays stay
    in the heap rather than being mapped and unmapped at each free), and the one arena is in force: a
    thread of the worker gets its memory from the main heap, the same arena as the worker's main thread."""
    import dask

    from nfarm.study.sweep import WORKER_ENVIRON, _client
    dasks = dask.config.get("distributed.nanny.pre-spawn-environ")
    expected = {k: str(v) for k, v in {**dasks, **WORKER_ENVIRON}.items()}

    def environ():
        return {k: os.environ.get(k) for k in expected}, _thread_heap()

    client = _client(None, 1)
    try:
        seen, heap = next(iter(client.run(environ).values()))
    finally:
        cluster = client.cluster
        client.close()
        cluster.close()
    assert seen == expected and seen["MALLOC_ARENA_MAX"] == "1"
    assert seen["OPENBLAS_NUM_THREADS"] == "1", "Dask's own settings are kept"
    assert heap == "main", "a new thread of the worker allocates from the main heap"
    if "MALLOC_ARENA_MAX" not in os.environ:
        assert _thread_heap() == "own", "the check can fail: this process's threads have arenas of their own"


def _thread_heap() -> str:
    """Where a new thread's small allocation comes from: ``"main"``, glibc's main heap (below the
    program break), or ``"own"``, an arena of the thread's own (a heap mapped above it)."""
    import ctypes
    import threading

    libc = ctypes.CDLL("libc.so.6")
    libc.malloc.restype = libc.sbrk.restype = ctypes.c_void_p
    libc.malloc.argtypes, libc.sbrk.argtypes, libc.free.argtypes = [ctypes.c_size_t], [ctypes.c_ssize_t], [ctypes.c_void_p]
    out = {}

    def allocate():
        address = libc.malloc(4096)
        out["heap"] = "main" if address < libc.sbrk(0) else "own"
        libc.free(address)

    thread = threading.Thread(target=allocate)
    thread.start()
    thread.join()
    return out["heap"]
