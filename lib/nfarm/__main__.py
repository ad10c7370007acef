"""Command line: ``python -m nfarm check-params FILE...``, ``add-arm``, ``report``, ``datasets``,
``sweep``, ``course``, ``verify`` and ``panel``."""

from __future__ import annotations

import argparse
import os
import sys
import warnings

# Nothing of the library is imported here, only in the commands: a Ctrl-C while the library
# loads then meets _main's one line, not a traceback through the imports.


def _check_one(path: str) -> str:
    """Validate one robot, study or sweep file (told apart by their required fields); the
    summary."""
    from .infra.reading import load_yaml
    from .model.robot import load_robot

    if path.lower().endswith(".urdf"):
        robot = load_robot(path)
        return f"{robot.name}, {robot.n} joints converted from the URDF to {robot.convention} DH"
    data = load_yaml(path)
    if isinstance(data, dict) and "metrics" in data and ("job" in data or "notebook" in data):
        from .study.sweep import sweep_from_dict

        sweep = sweep_from_dict(data, source=path)
        return f"sweep {sweep.name!r}: {len(sweep.cells)} cells of {sweep.target}"
    if isinstance(data, dict) and "robot_file" in data and "joints" not in data:
        from .study.study_files import study_from_dict

        study = study_from_dict(data, source=path)
        return (f"study {study.name!r} of {study.robot.name}, IK sizes "
                f"{'/'.join(str(study.ik_sizes[k]) for k in ('train', 'val', 'test'))}, ID "
                f"trajectories {'/'.join(str(study.id.trajectories[k]) for k in ('train', 'val', 'test'))}")
    robot = load_robot(path)
    via = " (from its URDF)" if isinstance(data, dict) and "urdf" in data else ""
    return f"{robot.name}, {robot.n} joints, {robot.convention} DH{via}"


def check_params(files: list[str]) -> int:
    """Print ``FILE: ok`` or the error for each file; 0 if all are valid, else 2."""
    from .model.robot import ParamsError, ParamsWarning

    status = 0
    for path in files:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ParamsWarning)
            try:
                summary = _check_one(path)
            except ParamsError as exc:
                print(exc, file=sys.stderr)
                status = 2
                continue
            except Exception as exc:  # noqa: BLE001 — a bug of ours: report it, check the rest
                print(f"{path}: internal error while checking ({type(exc).__name__}: {exc}); "
                      f"please report it", file=sys.stderr)
                status = 2
                continue
        for warning in caught:
            print(f"warning: {warning.message}", file=sys.stderr)
        print(f"{path}: ok ({summary})")
    return status


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m nfarm", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    check = sub.add_parser("check-params", help="validate robot, study and sweep parameter files")
    check.add_argument("files", nargs="+", metavar="FILE")
    arm = sub.add_parser("add-arm", help="a new arm from its URDF: robot and study files with derived defaults")
    arm.add_argument("urdf", metavar="PATH.urdf")
    arm.add_argument("--name", default=None, metavar="N", help="the robot's name (default the file's)")
    arm.add_argument("--tip", default=None, metavar="LINK",
                     help="the chain's last link (default the URDF's only leaf)")
    arm.add_argument("--lock", action="append", default=[], metavar="JOINT=VALUE",
                     help="the position [rad or m] of a joint off the chain (repeatable; default 0 "
                          "within its limits)")
    arm.add_argument("--params", default=None, metavar="DIR",
                     help="the parameter directory written to (default the project's params/)")
    arm.add_argument("--force", action="store_true", help="replace an arm of the same name")
    report = sub.add_parser("report", help="run every chapter notebook and build the report")
    report.add_argument("--smoke", action="store_true", help="small parameter set (for tests)")
    report.add_argument("--only", nargs="*", metavar="NN", help="run only these chapters")
    report.add_argument("--arm", default=None, metavar="NAME",
                        help="run one arm's edition (params/studies/NAME.yaml) and the chapters comparing the "
                             "arms, not the other arms' chapters")
    report.add_argument("--force", action="store_true",
                        help="run chapters whose inputs are unchanged since their last run too")
    report.add_argument("--serial", action="store_true",
                        help="run the editions one after the other (default: side by side on 2+ CPUs)")
    report.add_argument("--cell-timeout", type=_seconds, default=1800, metavar="SECONDS",
                        help="stop a cell that makes no progress for this long (default 1800; a cell "
                             "that makes progress runs as long as it needs; a positive number of "
                             "seconds, or 'none' for no limit)")
    report.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="a running Dask scheduler (tcp://host:8786) for chapter 6's missing sweep "
                             "cells (default: a local cluster); the published files are the same")
    datasets = sub.add_parser("datasets", help="build a study's training and test data sets")
    datasets.add_argument("study", metavar="STUDY", help="params/studies/<robot>.yaml")
    datasets.add_argument("--out", default=None, metavar="DIR",
                          help="output directory (default build/datasets/<robot>/)")
    datasets.add_argument("--force", action="store_true", help="rebuild files that are up to date")
    sweep = sub.add_parser("sweep", help="run a sweep file's cells on Dask (local cluster by default)")
    sweep.add_argument("file", metavar="FILE", help="params/sweeps/<name>.yaml")
    sweep.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="a running Dask scheduler (tcp://host:8786); default: a local cluster")
    sweep.add_argument("--workers", type=_whole_option("--workers", None), default=None, metavar="N",
                       help="local cluster's worker processes (default: one per core; 0: run the "
                            "cells one by one in this process)")
    sweep.add_argument("--out", default=None, metavar="DIR",
                       help="results directory (default build/sweeps/<name>/)")
    sweep.add_argument("--smoke", action="store_true", help="the sweep file's smaller version")
    course = sub.add_parser("course", help="build the course: student and teacher notebooks")
    course.add_argument("--out", default=None, metavar="DIR", help="default build/course/")
    course.add_argument("--smoke", action="store_true", help="teacher's notebooks with small parameters")
    course.add_argument("--only", nargs="*", metavar="NN", help="only these chapters")
    course.add_argument("--no-teacher", action="store_true",
                        help="the student build and the index only (nothing executed)")
    verify = sub.add_parser("verify", help="check figures/ against figures/MANIFEST.sha256")
    verify.add_argument("--figures", default=None, metavar="DIR")
    panel = sub.add_parser("panel", help="serve the arm panel as a local web page (Voilà)")
    panel.add_argument("--port", type=_whole_option("--port", 1, 65535), default=8866, metavar="PORT",
                       help="default 8866")
    args = parser.parse_args(argv)
    if args.command == "panel":
        return panel_command(args.port)
    if args.command == "check-params":
        return check_params(args.files)
    if args.command == "add-arm":
        return add_arm_command(args.urdf, args.name, args.tip, args.lock, args.params, args.force)
    if args.command == "verify":
        return verify_figures(args.figures)
    if args.command == "datasets":
        return make_datasets(args.study, args.out, args.force)
    if args.command == "course":
        return course_command(args.out, args.smoke, args.only, not args.no_teacher)
    if args.command == "sweep":
        return run_sweep_file(args.file, args.scheduler, args.workers, args.out, args.smoke)
    return report_command(smoke=args.smoke, only=args.only, cell_timeout=args.cell_timeout,
                          force=args.force, parallel=False if args.serial else None,
                          scheduler=args.scheduler, arm=args.arm)


def add_arm_command(urdf: str, name: str | None, tip: str | None, locks: list[str],
                    params: str | None, force: bool) -> int:
    """``python -m nfarm add-arm``: what it chose and why on standard output; 0, or 2 with one
    line on standard error for a refused arm (nothing written)."""
    from .infra.paths import PARAMS, project_path
    from .infra.reading import ParamsError
    from .study.add_arm import add_arm

    from .infra.typed import parse_number

    lock = {}
    for item in locks:
        joint, sep, value = item.partition("=")
        if not sep or not joint:
            print(f"{urdf}: --lock {item!r}: must be JOINT=VALUE, VALUE a number [rad or m]", file=sys.stderr)
            return 2
        try:
            number = parse_number(value, f"--lock {joint}", integer=False)
        except ParamsError as exc:
            print(f"{urdf}: {exc} [rad or m]", file=sys.stderr)
            return 2
        if joint in lock:
            print(f"{urdf}: --lock {joint}: given twice ({lock[joint]:g} and {number:g}): give each joint "
                  f"one lock", file=sys.stderr)
            return 2
        lock[joint] = number
    problem = _output_directory("--params", params)
    if problem:
        print(problem, file=sys.stderr)
        return 2
    try:
        add_arm(urdf, name=name, tip=tip, lock=lock, params=project_path(params) if params else PARAMS,
                force=force, say=print)
    except ParamsError as exc:
        print(str(exc).splitlines()[0], file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"{exc.filename or urdf}: {exc.strerror or type(exc).__name__}", file=sys.stderr)
        return 2
    return 0


def panel_command(port: int) -> int:
    """``python -m nfarm panel``: the server prepared (port, directories), the address with its
    token printed, then the process becomes the Voilà server; 2 with one line for a port or a
    directory that cannot be used."""
    from .publishing.panel_server import new_token, panel_url, prepare, serve

    try:
        prepare(port)
    except ValueError as error:
        print(f"panel: {error}", file=sys.stderr)
        return 2
    token = new_token()
    print(f"panel: {panel_url(port, token)} (the page takes a few seconds to start its kernel; "
          f"Ctrl-C stops the server)", flush=True)
    try:
        serve(port, token)
    except (ValueError, OSError) as error:
        print(f"panel: cannot start the server: {error}", file=sys.stderr)
        return 2
    return 0   # not reached: serve replaces the process


def course_command(out: str | None, smoke: bool, only, teacher: bool) -> int:
    """``python -m nfarm course``: 0; 2 with one line for an ``--out`` that cannot be the
    course's directory; 1 with one line on standard error for a failed build."""
    from .infra.notebook_runs import ReportError
    from .infra.paths import shown_path
    from .publishing.course import build_course

    problem = _output_directory("--out", out)
    if problem:
        print(f"course: {problem}", file=sys.stderr)
        return 2
    try:
        where = build_course(out, smoke=smoke, only=only, teacher=teacher,
                             progress=lambda text: print(text, file=sys.stderr))
    except (ValueError, ReportError) as exc:
        print(f"course: {str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__}",
              file=sys.stderr)
        return 1
    except OSError as exc:           # a directory that turned unwritable while the course was built
        print(f"course: cannot write {exc.filename or out}: {exc.strerror or type(exc).__name__}", file=sys.stderr)
        return 1
    print(f"{shown_path(where)}: student/, teacher/ and index.html")
    return 0


def report_command(**options) -> int:
    """``python -m nfarm report``: :func:`nfarm.publishing.report.build_report` with its progress
    and its failure on stderr, one line each; the exit status (0; 1 for a failure; 2 for a bad
    choice of chapters; 130 when interrupted)."""
    from .infra.notebook_runs import ReportError
    from .infra.paths import shown_path
    from .infra.reading import ParamsError
    from .publishing import report
    from .publishing.console import Console

    console = Console(sys.stderr)      # the chapters as they run: cells, sweep cells, time left
    say = console.say
    try:
        try:
            run = report.build_report(say=say, tell=console.tell, **options)
        finally:
            console.close()
    except report.ReportUsageError as exc:
        say(str(exc))
        return 2
    except report.ReportInterrupted as exc:
        say(str(exc))
        return 130
    except ReportError as exc:
        say(str(exc))
        return 1
    except ParamsError as exc:       # a parameter file the report reads breaks a rule
        say(str(exc).splitlines()[0])
        return 2
    say(f"{shown_path(run.index)}; figures in {shown_path(run.figures_dir)}")
    return 0


def _seconds(text: str) -> float | None:
    """``--cell-timeout``: a positive number of seconds (a fraction such as ``2.5`` too; at most a
    week, :data:`nfarm.infra.typed.CELL_TIMEOUT_S`), or ``none`` (no limit), read by the one
    parser of typed numbers (:func:`nfarm.infra.typed.parse_number`); else argparse's usage
    error with the rule."""
    from .infra.reading import ParamsError
    from .infra.typed import CELL_TIMEOUT_S, parse_number

    try:
        return parse_number(text, "--cell-timeout", CELL_TIMEOUT_S, none="none")
    except ParamsError:
        try:
            float(text)
        except ValueError:          # no number at all
            raise argparse.ArgumentTypeError(f"must be a number of seconds or 'none', got {text!r}") from None
        raise argparse.ArgumentTypeError(
            f"must be a positive number of seconds in plain decimal, at most {CELL_TIMEOUT_S.hi:g} (a week), "
            f"or 'none' for no limit, got {text!r}") from None


def _whole_option(option: str, lo: int | None, hi: int | None = None):
    """An argparse type for a whole-number option (``--workers``, ``--port``): plain decimal
    digits within ``[lo, hi]`` by :func:`nfarm.infra.typed.parse_number` (``1_0`` and ``٣`` are no
    numbers here, though Python's ``int`` reads them)."""
    def parse(text: str) -> int:
        from .infra.reading import ParamsError
        from .infra.typed import Range, parse_number

        try:
            return parse_number(text, option, Range(lo=lo, hi=hi), integer=True)
        except ParamsError as exc:
            raise argparse.ArgumentTypeError(str(exc).split(": ", 1)[1]) from None
    parse.__name__ = option.lstrip("-")
    return parse


def _output_directory(option: str, out: str | None) -> str | None:
    """The one line owed for an ``--out`` that cannot be a results directory, or None."""
    if out is None:
        return None
    from pathlib import Path

    path = Path(out).resolve()
    if path.exists() and not path.is_dir():
        return f"{option}: {out} exists and is not a directory"
    system = next((root for root in ("/proc", "/sys", "/dev") if path == Path(root) or Path(root) in path.parents), None)
    if system:
        return f"{option}: {out} lies in {system}, a system directory: give a directory of your own"
    parent = next((p for p in (path, *path.parents) if p.exists()), None)
    if parent is not None and not parent.is_dir():
        return f"{option}: {out} lies under {parent}, a file, not a directory"
    if parent is None or not os.access(parent, os.W_OK | os.X_OK):
        return f"{option}: {out} cannot be written (no permission in {parent})"
    return None


def make_datasets(study_file: str, out: str | None, force: bool) -> int:
    """Build (or reuse) every data set of a study; one line per file."""
    from .infra.reading import ParamsError
    from .study.datasets import build_datasets
    from .study.study_files import load_study

    problem = _output_directory("--out", out)
    if problem:
        print(problem, file=sys.stderr)
        return 2
    try:
        study = load_study(study_file)
    except ParamsError as exc:
        print(exc, file=sys.stderr)
        return 2
    command = " ".join(["python -m nfarm datasets", study_file] + (["--out", out] if out else []))
    try:
        for path, status in build_datasets(study, out, force=force, progress=sys.stderr.isatty(),
                                           command=command):
            print(f"{path}: {status}")
    except ValueError as exc:          # e.g. a region whose filters accept too few poses
        print(f"{study_file}: {str(exc).splitlines()[0]}", file=sys.stderr)
        return 2
    return 0


def run_sweep_file(path: str, scheduler: str | None, workers: int | None, out: str | None,
                   smoke: bool) -> int:
    """Run a sweep; one line per failed cell and a closing line. 0 if every cell succeeded,
    1 if some failed, 2 for a bad sweep file or an unreachable scheduler."""
    from .infra.paths import BUILD, project_path, shown_path
    from .infra.reading import ParamsError
    from .study.sweep import load_sweep, run_sweep

    if workers is not None and workers < 0:
        print(f"--workers: must be >= 0, got {workers}", file=sys.stderr)
        return 2
    cores = os.cpu_count() or 1
    if workers is not None and workers > cores:
        print(f"--workers: {workers} asked for, {cores} cores here: running {cores} (one cell per core; a "
              f"cluster of more machines takes --scheduler)", file=sys.stderr)
        workers = cores
    problem = _output_directory("--out", out)
    if problem:
        print(problem, file=sys.stderr)
        return 2
    if scheduler and workers is not None:
        print("--workers: the scheduler's cluster has its own workers; give one or the other",
              file=sys.stderr)
        return 2
    try:
        sweep = load_sweep(path, smoke=smoke)
        directory = project_path(out) if out else BUILD / "sweeps" / sweep.name
        results = run_sweep(sweep, directory, scheduler=scheduler, workers=workers,
                            progress=sys.stderr.isatty())
    except ParamsError as exc:
        print(exc, file=sys.stderr)
        return 2
    failed = [r for r in results if not r.ok]
    reused = sum(r.reused for r in results)
    print(f"{shown_path(directory)}: {len(results)} cells, {len(results) - reused - len(failed)} "
          f"run, {reused} already done, {len(failed)} failed; results.csv, summary.md, summary.png")
    for r in failed:
        print(f"  failed {r.cell.key} {dict(r.cell.params)}: {r.error.strip().splitlines()[-1]}",
              file=sys.stderr)
    return 1 if failed else 0


def verify_figures(figures: str | None) -> int:
    """Print what differs from the manifest; 0 when nothing does, else 1."""
    from pathlib import Path

    from .infra.paths import FIGURES
    from .publishing.manifest import manifest_entries, verify_manifest

    directory = Path(figures) if figures else FIGURES
    problems = verify_manifest(directory)
    for line in problems:
        print(f"{directory}: {line}", file=sys.stderr)
    if not problems:
        count = manifest_entries(directory)
        print(f"{directory}: {count} files match MANIFEST.sha256")
    return 1 if problems else 0


def _main() -> int:
    try:
        return main()
    except KeyboardInterrupt:
        print("nfarm: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(_main())
