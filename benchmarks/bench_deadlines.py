"""How soon the library gives up or stops: the speeds the unit tests used to assert (issue 47).

The tests check the behaviour with a fake clock or a bound no machine misses (a cell that
would train for days stops at a counted epoch; a Ctrl-C'd run ends long before the hour its
work would take; a refusal counts the draws it made). The seconds are measured here, each
against the bound the test used to hold:

* a study region too narrow for its size is refused after about a million draws (< 60 s);
* a sweep cell with ``epochs: 10 000 000`` stops past its 1.5-s limit while a 2-epoch cell
  beside it finishes within it (the sweep < 60 s);
* Ctrl-C stops a notebook running in the project kernel, and two editions of the report
  running side by side, each in one line (< 30 s from the signal).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import nbformat

from common import seconds_per_call  # noqa: F401 — sets the benchmark environment
from nfarm.infra.paths import PARAMS
from nfarm.presentation.tables import Table
from nfarm.study.study_files import load_study
from nfarm.study.sweep import run_sweep, sweep_from_dict


def narrow_region() -> float:
    region = load_study(PARAMS / "studies" / "intelbot5.yaml").ik_region
    start = time.perf_counter()
    try:
        region.sample(50_000_000, 0)
    except ValueError:
        return time.perf_counter() - start
    raise AssertionError("the region was not refused")


def cell_over_its_limit() -> tuple[float, float, list[str]]:
    sweep = sweep_from_dict({"name": "t", "job": "anfis_benchmark", "fixed": {"problem": "sinc"},
                             "grid": {"epochs": [2, 10_000_000]}, "seeds": [0],
                             "metrics": ["check_rmse"], "cell_timeout_s": 1.5})
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        results = run_sweep(sweep, out, workers=0)
        return time.perf_counter() - start, results[0].seconds, [r.status for r in results]


def _interrupted(code: list[str], started) -> float:
    """Seconds from SIGINT to the end of the process ``code`` once ``started()`` says its work runs."""
    run = subprocess.Popen(code, stderr=subprocess.PIPE, text=True)
    for _ in range(1200):
        if started():
            break
        time.sleep(0.1)
    time.sleep(2.0)
    start = time.perf_counter()
    run.send_signal(signal.SIGINT)
    run.communicate(timeout=600)
    if run.returncode != 130:
        raise AssertionError(f"exit status {run.returncode}, not 130")
    return time.perf_counter() - start


def ctrl_c_notebook(tmp: Path) -> float:
    notebook, out = tmp / "slow.ipynb", tmp / "out.ipynb"
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell("seconds = 3600", metadata={"tags": ["parameters"]}),
                nbformat.v4.new_code_cell("import time\ntime.sleep(seconds)")]
    nbformat.write(nb, notebook)
    code = ("import sys\nfrom nfarm.infra.notebook_runs import run_notebook\n"
            "try:\n    run_notebook(sys.argv[1], sys.argv[2], {})\nexcept KeyboardInterrupt:\n    sys.exit(130)\n")
    return _interrupted([sys.executable, "-c", code, str(notebook), str(out)],
                        lambda: out.exists() and '"time.sleep' in out.read_text())


def ctrl_c_editions(tmp: Path) -> float:
    notebooks = tmp / "notebooks"
    notebooks.mkdir()
    for name, parameter in (("01_robot", 'robot_file = "ra.yaml"'), ("02_compare", 'study_files = ["sa.yaml"]')):
        cells = [nbformat.v4.new_markdown_cell(f"# Chapter {name}"),
                 nbformat.v4.new_code_cell(parameter + '\nsmoke = False\nout_dir = "build/explore/x"',
                                           metadata={"tags": ["parameters"]})]
        nbformat.write(nbformat.v4.new_notebook(cells=cells), notebooks / f"{name}.ipynb")
    code = f"""
import sys, time
from pathlib import Path
from nfarm.infra import notebook_runs
from nfarm.publishing import report
root = Path({str(tmp)!r})
def slow(notebook, output, parameters, **options):
    with notebook_runs._interruptible():
        (root / f"started-{{parameters.get('robot_file', 'a')}}").touch()
        time.sleep(3600)
report.run_notebook = slow
arms = [report.Edition("a", "sa.yaml", "ra.yaml", True), report.Edition("b", "sb.yaml", "rb.yaml", False)]
from nfarm.__main__ import report_command
sys.exit(report_command(notebooks_dir=root / "notebooks", figures_dir=root / "figures", build_dir=root / "build",
                        arms=arms, parallel=True))
"""
    return _interrupted([sys.executable, "-c", code], lambda: len(list(tmp.glob("started-*"))) == 2)


def main() -> None:
    rows = []
    refused = narrow_region()
    rows.append(["a region too narrow for 50,000,000 poses refused", refused, "< 60 s",
                 "met" if refused < 60 else "NOT met"])
    whole, small, statuses = cell_over_its_limit()
    rows.append([f"a sweep: a cell of 10,000,000 epochs past its 1.5-s limit beside one of 2 ({', '.join(statuses)})",
                 whole, "< 60 s", "met" if whole < 60 and statuses == ["ok", "failed"] else "NOT met"])
    rows.append(["the 2-epoch cell's recorded time (with the job's first imports)", small,
                 "its status: within the limit at each epoch's check", statuses[0]])
    with tempfile.TemporaryDirectory() as tmp:
        stopped = ctrl_c_notebook(Path(tmp))
    rows.append(["Ctrl-C to the end of a run of a notebook in its kernel", stopped, "< 30 s",
                 "met" if stopped < 30 else "NOT met"])
    with tempfile.TemporaryDirectory() as tmp:
        stopped = ctrl_c_editions(Path(tmp))
    rows.append(["Ctrl-C to the end of a report's two editions side by side", stopped, "< 30 s",
                 "met" if stopped < 30 else "NOT met"])
    print(Table(["what", "seconds", "bound", "target"], rows, floatfmt=["", ".3g", "", ""],
                caption=f"How soon nfarm gives up or stops, {os.cpu_count()} cores").to_markdown())


if __name__ == "__main__":
    main()
