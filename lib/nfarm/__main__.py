"""Command line: ``python -m nfarm check-params FILE...`` and ``python -m nfarm report``."""

from __future__ import annotations

import argparse
import sys
import warnings

from .robot import ParamsError, ParamsWarning, load_robot


def check_params(files: list[str]) -> int:
    """Print ``FILE: ok`` or the error for each file; 0 if all are valid, else 2."""
    status = 0
    for path in files:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ParamsWarning)
            try:
                robot = load_robot(path)
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
        print(f"{path}: ok ({robot.name}, {robot.n} joints, {robot.convention} DH)")
    return status


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m nfarm", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    check = sub.add_parser("check-params", help="validate robot parameter files")
    check.add_argument("files", nargs="+", metavar="FILE")
    report = sub.add_parser("report", help="run every chapter notebook and build the report")
    report.add_argument("--smoke", action="store_true", help="small parameter set (for tests)")
    report.add_argument("--only", nargs="*", metavar="NN", help="run only these chapters")
    args = parser.parse_args(argv)
    if args.command == "check-params":
        return check_params(args.files)
    from .report import build_report
    return build_report(smoke=args.smoke, only=args.only)


if __name__ == "__main__":
    sys.exit(main())
