"""Parameter sweeps on Dask (nfarm.study.sweep): the machinery's own cost per cell, and the speed-up
of a grid of ANFIS trainings with one and two local worker processes, in the same run.

Targets (issue 14): overhead per cell ≤ 0.5 s on a local cluster; speed-up close to the number
of workers. On a shared 2-core machine the second worker competes with whatever else runs, so
the peer is the same grid split over plain Python processes side by side, in the same run: the
target is Dask's speed-up at least 0.9 of theirs. Overhead is measured on a grid of ``idle`` cells (the job returns at once) on one
running cluster: the wall time of 161 cells less that of 1, per cell, times the workers that
shared them — what each cell costs a worker in submitting, running, returning and writing its
directory. The cluster's start is measured apart.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

from common import best_of
from nfarm.presentation.tables import Table
from nfarm.study.sweep import run_sweep, sweep_from_dict

WORKERS = 2
CELLS = 160
TRAININGS = {"name": "bench_anfis", "job": "anfis_benchmark",
             "fixed": {"problem": "mackey_glass", "n_mfs": 2, "epochs": 1500},
             "grid": {"step_size": [0.005, 0.01, 0.02, 0.04], "mf": ["gbell", "gauss"]},
             "metrics": ["check_rmse"]}


def idle(cells: int):
    return sweep_from_dict({"name": "bench_idle", "job": "idle", "grid": {"value": list(range(cells))},
                            "metrics": ["value"]}, "bench")


def timed_run(sweep, workers: int, client=None) -> tuple[float, list]:
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        results = run_sweep(sweep, out, workers=None if client else workers, client=client)
        return time.perf_counter() - start, results


def plain_processes(sweep, processes: int) -> float:
    """Wall time of the grid split over ``processes`` plain Python processes running their
    share in-process, side by side: what the machine allows, without Dask."""
    code = ("import sys, tempfile; from nfarm.study.sweep import run_sweep, sweep_from_dict; "
            "import json; d = json.loads(sys.argv[1]); k, n = int(sys.argv[2]), int(sys.argv[3]); "
            "s = sweep_from_dict(d, 'bench'); s = s.select(lambda p, c=[-1]: (c.__setitem__(0, c[0] + 1) or c[0] % n == k)); "
            "run_sweep(s, tempfile.mkdtemp(), workers=0)")
    import json

    start = time.perf_counter()
    procs = [subprocess.Popen([sys.executable, "-c", code, json.dumps(TRAININGS), str(k), str(processes)])
             for k in range(processes)]
    for proc in procs:
        proc.wait()
    return time.perf_counter() - start


def main() -> None:
    from distributed import Client, LocalCluster

    rows = []
    start = time.perf_counter()
    with LocalCluster(n_workers=WORKERS, threads_per_worker=1, processes=True, silence_logs=40,
                      dashboard_address="127.0.0.1:0") as cluster, Client(cluster) as client:
        started = time.perf_counter() - start
        timed_run(idle(1), WORKERS, client)                      # the workers import nfarm
        one = best_of(lambda: timed_run(idle(1), WORKERS, client)[0], repeat=3)
        many = best_of(lambda: timed_run(idle(CELLS + 1), WORKERS, client)[0], repeat=3)
    per_cell = (many - one) / CELLS * WORKERS
    rows.append([f"overhead per cell, {WORKERS} workers ({CELLS + 1} idle cells less 1, one cluster)",
                 per_cell, "≤ 0.5 s", "met" if per_cell <= 0.5 else "NOT met"])
    here = best_of(lambda: timed_run(idle(CELLS + 1), 0)[0], repeat=2) / (CELLS + 1)
    rows.append(["the same in this process (no Dask), per cell", here, "", ""])
    rows.append([f"local cluster start ({WORKERS} workers)", started, "", ""])
    one = best_of(lambda: timed_run(idle(1), WORKERS)[0], repeat=2)
    rows.append(["a sweep of 1 idle cell, its cluster started and stopped", one, "", ""])

    sweep = sweep_from_dict(TRAININGS, "bench")
    t1, r1 = timed_run(sweep, 1)
    t2, r2 = timed_run(sweep, 2)
    same = [a.metrics for a in r1] == [b.metrics for b in r2]
    work = sum(r.seconds for r in r1)
    rows.append([f"{len(sweep.cells)} ANFIS trainings (Mackey–Glass, {TRAININGS['fixed']['epochs']} epochs), "
                 f"1 worker", t1, f"cells' own time {work:.1f} s", ""])
    rows.append([f"the same, 2 workers (results {'identical' if same else 'DIFFERENT'})", t2,
                 f"speed-up {t1 / t2:.2f}× (ideal 2×)", ""])
    slower = sum(r.seconds for r in r2) / work
    rows.append(["cells' own time with 2 workers, relative to 1", slower, "the machine's contention", ""])
    p1, p2 = plain_processes(sweep, 1), plain_processes(sweep, 2)
    rows.append(["peer: the grid in 1 and in 2 plain processes side by side (no Dask)", p2,
                 f"speed-up {p1 / p2:.2f}× ({p1:.1f} s → {p2:.1f} s)", ""])
    # Without the cluster's start and stop (measured above), which a longer grid amortises.
    cells = (t1 - one) / (t2 - one)
    rows.append(["speed-up of the cells (start and stop left out)", t2 - one, f"{cells:.2f}× (ideal 2×)", ""])
    share = (t1 / t2) / (p1 / p2)
    rows.append(["Dask's speed-up over the machine's (plain processes)", None, f"{share:.2f}",
                 "met" if share >= 0.9 else "NOT met"])
    rows = [[w, "" if t is None else t, r, g] for w, t, r, g in rows]
    print(Table(["what", "seconds", "reference", "target"], rows, floatfmt=["", ".3g", "", ""],
                caption=f"Sweeps on a local Dask cluster, {os.cpu_count()} cores").to_markdown())


if __name__ == "__main__":
    main()
