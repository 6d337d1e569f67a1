"""The `quadcog` command: tour, scenarios, run, paper, analyze."""
import argparse
from pathlib import Path
import sys

from .errors import QuadcogError


def main(argv=None):
    ap = argparse.ArgumentParser(prog="quadcog", description="quadrotor with a moving CoG")
    sub = ap.add_subparsers(dest="command", required=True)
    sub.add_parser("tour", help="evaluate the generated functions at hover and print them")
    sub.add_parser("scenarios", help="list the shipped scenarios with their descriptions")
    run = sub.add_parser("run", help="run one scenario: a file (TOML) or a shipped name")
    run.add_argument("scenario", help="scenario file (see README 'Scenario files') or the name "
                                      "of a shipped one (`quadcog scenarios` lists them)")
    run.add_argument("--out", type=Path, required=True, help="folder for metrics, CSV, plots")
    paper = sub.add_parser("paper", help="reproduce the paper's figures and claims")
    paper.add_argument("--out", type=Path, required=True, help="output folder")
    analyze = sub.add_parser("analyze", help="PD design, zero dynamics, adaptive design, "
                                             "failure map")
    analyze.add_argument("--out", type=Path, required=True, help="output folder")
    analyze.add_argument("--grid", type=int, default=41,
                         help="failure-map points per axis (default 41)")
    export = sub.add_parser("export", help="write a controller as a C99 module for a flight "
                                           "controller (README: On a flight controller)")
    export.add_argument("--controller", required=True,
                        help="pd, fl, adaptive (any name of quadcog.controllers.BY_NAME)")
    export.add_argument("--precision", default="float32", choices=("float32", "double"))
    export.add_argument("--out", type=Path, required=True, help="folder for the .h and .c")
    sweep = sub.add_parser("sweep", help="fly a sweep file (TOML) locally or on Dask")
    sweep.add_argument("sweep", help="sweep file, or the name of a shipped one (failure-map)")
    sweep.add_argument("--out", type=Path, required=True,
                       help="results folder; run again with the same folder to resume")
    where = sweep.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, help="start a Dask LocalCluster of N processes")
    where.add_argument("--scheduler", help="address of a running Dask scheduler")
    args = ap.parse_args(argv)
    try:
        if getattr(args, "out", None) is not None:
            try:
                args.out.mkdir(parents=True, exist_ok=True)
            except OSError as e:
                raise QuadcogError(f"--out {args.out}: cannot create the folder "
                                   f"({e.strerror})") from None
        if args.command == "tour":
            from .tour import tour
            tour()
        elif args.command == "scenarios":
            from .catalog import shipped_scenarios
            scenarios = shipped_scenarios()
            width = max(map(len, scenarios), default=0)
            for name, description in scenarios.items():
                print(f"{name:<{width}}  {description}")
        elif args.command == "run":
            from .scenario import run_file
            run_file(args.scenario, args.out)
        elif args.command == "paper":
            from .paper import run_paper
            run_paper(args.out)
        elif args.command == "export":
            from .embedded import export_controller
            for path in export_controller(args.controller, args.precision, args.out):
                print(f"wrote {path}")
        elif args.command == "sweep":
            from .sweeps.runner import run_cli
            run_cli(args.sweep, args.out, workers=args.workers, scheduler=args.scheduler)
        elif args.command == "analyze":
            from .analysis import analyze
            analyze(args.out, grid=args.grid)
    except QuadcogError as e:
        print(f"quadcog: error: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"quadcog: error: {e.filename or ''}: {e.strerror or e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
