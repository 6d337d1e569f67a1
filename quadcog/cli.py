"""The `quadcog` command.

One pair of functions per subcommand: ``add_<name>(sub)`` declares it (a one-line ``help``
for the list, a ``description`` for its own --help, its arguments) and sets ``func`` to
``cmd_<name>(args)``, which runs it. To add a subcommand, write the pair and append
``add_<name>`` to SUBCOMMANDS; errors (QuadcogError, OSError) are turned into one line and
exit status 2 by ``main``.
"""
# annotations as text: argparse's subparsers type is generic only to a type checker
from __future__ import annotations

import argparse
from collections.abc import Callable, Iterator, Sequence
import contextlib
import os
from pathlib import Path
import sys
from typing import NoReturn
import warnings

from quadcog.errors import QuadcogError

__all__ = ["SUBCOMMANDS", "parser", "main",
           "add_tour", "cmd_tour", "add_scenarios", "cmd_scenarios", "add_run", "cmd_run",
           "add_animate", "cmd_animate", "add_paper", "cmd_paper", "add_analyze", "cmd_analyze",
           "add_export", "cmd_export", "add_sweep", "cmd_sweep", "add_identify", "cmd_identify",
           "add_targets", "cmd_targets", "export_names"]
__all__ += ["add_px4", "cmd_px4"]

_Subparsers = argparse._SubParsersAction  # the type of ``add_subparsers()``: for the hints


def _check_out_dir(path: str | Path) -> Path:
    """Refuse, before any work, an --out that exists and is not a folder (a file, a FIFO, a
    device), or that cannot be made (``quadcog.files.creatable_folder``): QuadcogError naming
    --out."""
    from quadcog.files import creatable_folder
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise QuadcogError(f"--out {path}: is a file (or a FIFO or device), not a folder; "
                           "expected a folder for the results (a new or existing folder)")
    return creatable_folder(p, "--out", QuadcogError)


@contextlib.contextmanager
def _out_dir(path: str | Path) -> Iterator[Path]:
    """The output folder ``path``, created for the block (QuadcogError naming --out if it
    cannot be made); the folders it created are removed again when the block fails and
    leaves them empty, so a refused command leaves nothing behind."""
    from quadcog.files import make_folder, remove_made
    _check_out_dir(path)
    made = make_folder(path, "--out", QuadcogError)
    try:
        yield Path(path)
    except BaseException:
        remove_made(made)
        raise


def _path(text: str) -> Path:
    """An option's path; an empty one is refused, since Path("") is the current folder (an
    --out "" wrote the results into it, an animate "" read it as the run folder)."""
    if not text:
        raise argparse.ArgumentTypeError("expected a path, got an empty string")
    return Path(text)


_SET_PATHS = ("A file path (vehicle.file, vehicle.identified and the same keys of "
              "controller_model) given with --set is relative to the current folder; in the "
              "scenario file it is relative to that file's folder; a file that does not "
              "exist is refused.")


def _file_path(text: str) -> Path:
    """An output file's path: an empty one is refused, and so is one that ends in "/" (Path()
    drops it, but "x.gif/" names a folder, never the file x.gif), as --json refuses it."""
    if text.endswith(("/", os.sep)):
        raise argparse.ArgumentTypeError(f"expected a file name, not a folder path, got "
                                         f"{text!r}")
    return _path(text)


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return value


def add_tour(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog tour`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    p = sub.add_parser("tour", help="evaluate the generated functions at hover and print them",
                       description="Load the generated model and print every generated "
                                   "function evaluated at hover.")
    p.set_defaults(func=cmd_tour)


def cmd_tour(args: argparse.Namespace) -> None:
    """Run `quadcog tour`: print the generated functions evaluated at hover
    (``quadcog.studies.tour``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from quadcog.studies.tour import tour
    tour()


def add_scenarios(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog scenarios`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    p = sub.add_parser("scenarios", help="list the shipped scenarios with their descriptions",
                       description="List the scenarios that ship with quadcog; `quadcog run "
                                   "NAME` runs one, `--show NAME` prints one to copy and edit.")
    p.add_argument("--show", metavar="NAME", default=None,
                   help="print the TOML of the shipped scenario NAME")
    p.set_defaults(func=cmd_scenarios)


def _list_or_show(kind: str, listing: dict[str, str], show: str | None) -> None:
    from quadcog.sweeps.listing import shipped_text
    if show is not None:
        print(shipped_text(show, kind), end="")
        return
    width = max(map(len, listing), default=0)
    for name, description in listing.items():
        print(f"{name:<{width}}  {description}")


def cmd_scenarios(args: argparse.Namespace) -> None:
    """Run `quadcog scenarios`: list the shipped scenarios with their descriptions, or print one
    (``--show NAME``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from quadcog.scenarios.lookup import shipped_scenarios
    _list_or_show("scenario", shipped_scenarios(), args.show)


def add_sweeps(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog sweeps`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    p = sub.add_parser("sweeps", help="list the shipped sweep files with their descriptions",
                       description="List the sweep files that ship with quadcog; `quadcog sweep "
                                   "NAME --out DIR` flies one, `--show NAME` prints one.")
    p.add_argument("--show", metavar="NAME", default=None,
                   help="print the TOML of the shipped sweep file NAME")
    p.set_defaults(func=cmd_sweeps)


def cmd_sweeps(args: argparse.Namespace) -> None:
    """Run `quadcog sweeps`: list the shipped sweep files, or print one (``--show NAME``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from quadcog.sweeps.listing import shipped_sweeps
    _list_or_show("sweep", shipped_sweeps(), args.show)


def add_run(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog run`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    p = sub.add_parser(
        "run", help="fly one scenario (a shipped name or a TOML file) and write its results",
        description="Fly one scenario and write metrics.json, vehicle.json, the sampled\n"
                    "trajectory (trajectory.csv; column names carry units) and flight.png.",
        epilog="examples:\n  quadcog run fig7\n  quadcog run fig6 --set controller=fl\n"
               "  quadcog run my.toml --set vehicle.m=0.8 --set 'cog=[{t=1, r=[0.03, 0, 0]}]'",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenario", help="scenario file (docs: Reference, Scenario keys) or the name "
                                    "of a shipped one (`quadcog scenarios` lists them)")
    p.add_argument("--out", type=_path, default=None,
                   help="folder for the results (default: out/<scenario> in this folder)")
    p.add_argument("--set", dest="overrides", action="append", default=[],
                   metavar="KEY=VALUE",
                   help="override a scenario key (dotted: vehicle.m=0.8, controller=adaptive, "
                        "controller_params.gamma=0.02; VALUE in TOML syntax); repeatable; "
                        "validated like the file. " + _SET_PATHS)
    p.add_argument("--plot", action=argparse.BooleanOptionalAction, default=True,
                   help="draw flight.png (default: yes)")
    p.add_argument("--animate", action="store_true",
                   help="also write flight.gif, a 3D animation (as `quadcog animate`)")
    rate = p.add_mutually_exclusive_group()
    rate.add_argument("--every", type=_positive_int, default=None, metavar="N",
                      help="write every N-th sample (and the last) to the table (default: "
                           "every 10 ms, quadcog.config.defaults['run.sample_period'])")
    rate.add_argument("--full-rate", dest="every", action="store_const", const=1,
                      help="write every sample (as --every 1)")
    p.add_argument("--format", dest="fmt", choices=("csv", "parquet"), default="csv",
                   help="table format (parquet needs pyarrow; default: csv)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--identified", type=_path, default=None, metavar="FILE",
                   help="JSON of `quadcog identify --json`: its r_G becomes the vehicle's CoG "
                        "and the controller's starting estimate")
    p.add_argument("--stack", choices=("crazyflie",), default=None,
                   help="fly a flight stack's own controller instead (as --set stack.name=...; "
                        "docs: The Crazyflie firmware in the loop)")
    p.add_argument("--controller", dest="stack_controller", default=None, metavar="NAME",
                   help="with --stack: the stack's controller (crazyflie: pid, mellinger, indi, "
                        "brescianini, lee, an out-of-tree controller's folder or a quadcog "
                        "law such as composite, flown as its app; default pid)")
    p.add_argument("--vehicle", type=_path, default=None, metavar="FILE",
                   help="fly the vehicle of a URDF or SDF file (Vehicle.from_urdf, "
                        "Vehicle.from_sdf) as the truth; the controller's model starts from it")
    p.set_defaults(func=cmd_run)


def cmd_run(args: argparse.Namespace) -> None:
    """Run `quadcog run`: fly one scenario and write its results
    (``quadcog.scenarios.scenario.run_file``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    import json

    from quadcog.scenarios.lookup import scenario_path
    from quadcog.scenarios.scenario import default_out, run_file
    scenario_path(args.scenario)    # a name that is no scenario, before the --out it implies
    # made only when the results are written (quadcog.files.RunFiles): a refused scenario
    # leaves no folder
    out = _check_out_dir(args.out if args.out is not None else default_out(args.scenario))
    inputs = [(f"--{name}", getattr(args, name)) for name in ("identified", "vehicle")
              if getattr(args, name) is not None]
    if args.identified is not None:     # as --set vehicle.identified=... (and the model's)
        path = json.dumps(str(args.identified.resolve()))
        args.overrides = list(args.overrides) + [f"vehicle.identified={path}",
                                                 f"controller_model.identified={path}"]
    if args.vehicle is not None:        # as --set vehicle.file=...
        args.overrides = list(args.overrides) + [
            f"vehicle.file={json.dumps(str(args.vehicle.resolve()))}"]
    if args.stack is not None:
        args.overrides = list(args.overrides) + [f"stack.name={json.dumps(args.stack)}"]
    if args.stack_controller is not None:
        if args.stack is None:
            raise QuadcogError(f"--controller {args.stack_controller}: names a flight stack's "
                               "controller; give --stack too (a quadcog law is --set "
                               "controller=NAME)")
        args.overrides = list(args.overrides) + [
            f"stack.controller={json.dumps(args.stack_controller)}"]
    from quadcog.crazyflie.scenario import run_scenario
    run_file(args.scenario, out, progress=not args.quiet, overrides=args.overrides,
             plot=args.plot, every=args.every, fmt=args.fmt, animate=args.animate,
             stack_runner=run_scenario, inputs=inputs)


def add_animate(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog animate`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    p = sub.add_parser("animate", help="animate a run folder as a 3D GIF",
                       description="Read RUN_DIR (written by `quadcog run`) and write a GIF of "
                                   "the flight in 3D: body axes, rotors, the CoG offset to scale, "
                                   "the trail and the reference, with the time.")
    p.add_argument("run_dir", type=_path, help="folder written by `quadcog run`")
    p.add_argument("--out", "--output", dest="out", type=_file_path, default=None,
                   help="GIF to write (default: RUN_DIR/flight.gif; --output is the old name)")
    p.add_argument("--fps", type=_positive_int, default=15, help="frames per second (default 15)")
    p.add_argument("--speed", type=float, default=1.0,
                   help="simulated seconds per wall-clock second (default 1)")
    p.add_argument("--max-frames", type=_positive_int, default=120,
                   help="at most this many frames; the speed goes up to fit (default 120)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_animate)


def cmd_animate(args: argparse.Namespace) -> None:
    """Run `quadcog animate`: write the GIF of a run folder
    (``quadcog.viz.animation.animate_run``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from quadcog.viz.animation import animate_run
    path = animate_run(args.run_dir, args.out, fps=args.fps, speed=args.speed,
                       max_frames=args.max_frames, progress=not args.quiet)
    print(f"wrote {path}")


def add_paper(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog paper`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    p = sub.add_parser("paper", help="reproduce the paper's figures and claims",
                       description="Run the paper's Figs. 3-8 as scenarios, draw each figure "
                                   "and write summary.md / summary.json with a verdict per "
                                   "claim.")
    p.add_argument("--out", type=_path, default=Path("out/paper"),
                   help="output folder (default: out/paper)")
    p.set_defaults(func=cmd_paper)


def cmd_paper(args: argparse.Namespace) -> None:
    """Run `quadcog paper`: reproduce the paper's figures and claims
    (``quadcog.studies.paper.run_paper``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from quadcog.studies.paper import run_paper
    with _out_dir(args.out) as out:
        run_paper(out)


def add_analyze(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog analyze`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    p = sub.add_parser("analyze", help="PD margins, zero dynamics, adaptive design, failure map",
                       description="Cascade PD margins and singular values (python-control), "
                                   "zero dynamics for moving CoG, the adaptive law's Lyapunov "
                                   "function along Fig. 6, and the failure map over CoG "
                                   "offsets.")
    p.add_argument("--out", type=_path, default=Path("out/analysis"),
                   help="output folder (default: out/analysis)")
    p.add_argument("--grid", type=_positive_int, default=41,
                   help="failure-map points per axis (default 41)")
    p.add_argument("--duration", type=float, default=20.0,
                   help="seconds per failure-map flight (default 20)")
    p.set_defaults(func=cmd_analyze)


def cmd_analyze(args: argparse.Namespace) -> None:
    """Run `quadcog analyze`: run the analysis (``quadcog.studies.analysis.analyze``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from quadcog.studies.analysis import analyze
    with _out_dir(args.out) as out:
        analyze(out, grid=args.grid, duration=args.duration)


def add_export(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog export`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    from quadcog.controllers.registry import controller_names
    p = sub.add_parser("export", help="write a controller as a C99 module for a flight "
                                      "controller (docs: On a flight controller)",
                       description="Write one controller's law as a self-contained C99 module "
                                   "(.h and .c) in float32 or double.")
    which = p.add_mutually_exclusive_group(required=True)
    which.add_argument("--controller",
                       help="the controller's short name, with its default settings: "
                            + ", ".join(controller_names()))
    which.add_argument("--scenario", metavar="SCENARIO",
                       help="a scenario file or shipped name: its controller, with its "
                            "controller_params, designed for its controller model (your own "
                            "vehicle or gains; --set changes keys as for `quadcog run`)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="with --scenario: override a scenario key (repeatable). " + _SET_PATHS)
    p.add_argument("--precision", default="float32", choices=("float32", "double"),
                   help="float32 (default) or double")
    p.add_argument("--out", type=_path, required=True, help="folder for the .h and .c")
    p.add_argument("--target", default="c", choices=("c", "crazyflie"),
                   help="c (default: the C99 module) or crazyflie (an out-of-tree controller "
                        "app of the Crazyflie firmware, float32; docs: On a Crazyflie)")
    p.add_argument("--vehicle", help="with --target crazyflie: the vehicle preset the law is "
                                     "designed for (default crazyflie21, the Crazyflie 2.1)")
    p.add_argument("--build", action="store_true",
                   help="with --target crazyflie: also build cf2.elf with the app in quadcog's "
                        "cache and print its size (needs gcc-arm-none-eabi)")
    p.add_argument("--firmware", type=_path,
                   help="with --build: the firmware tree (default $QUADCOG_CRAZYFLIE_FIRMWARE, "
                        "else the vendored tarball); never written")
    p.set_defaults(func=cmd_export)


def cmd_export(args: argparse.Namespace) -> None:
    """Run `quadcog export`: write a controller as a C99 module
    (``quadcog.embedded.export_controller``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from quadcog.embedded import export_controller
    if args.target == "crazyflie":
        _export_crazyflie(args)
        return
    for flag in ("vehicle", "firmware"):
        if getattr(args, flag) is not None:
            raise QuadcogError(f"--{flag} needs --target crazyflie")
    if args.build:
        raise QuadcogError("--build needs --target crazyflie")
    if args.scenario is None:
        if args.overrides:
            raise QuadcogError("--set needs --scenario (the keys of a scenario file)")
        with _out_dir(args.out) as out:
            paths = export_controller(args.controller, args.precision, out,
                                      command=f"quadcog export --controller {args.controller} "
                                              f"--precision {args.precision} --out DIR")
    else:
        from quadcog.scenarios.scenario import load_scenario
        _check_out_dir(args.out)
        scenario = load_scenario(args.scenario, args.overrides)
        law = scenario.make_controller()
        law = getattr(law, "inner", law)        # without Sensed: on a vehicle the sensors are real
        command = " ".join(["quadcog export --scenario", str(args.scenario)]
                           + [f"--set {o}" for o in args.overrides]
                           + [f"--precision {args.precision} --out DIR"])
        _check_export_outputs("c", Path(args.out), scenario)
        with _out_dir(args.out) as out:
            paths = export_controller(law, args.precision, out, name=scenario.controller,
                                      command=command)
    for path in paths:
        print(f"wrote {path}")


def export_names(target: str, name: str) -> list[str]:
    """The files `quadcog export` writes for a law named ``name``, relative to --out
    (``quadcog.embedded.controller_export.file_names``, ``crazyflie_app.app_file_names``).

    Parameters
    ----------
    target : str
        "c" or "crazyflie".
    name : str
        The law's C name part (the controller's short name).

    Returns
    -------
    list of str
        Paths relative to the output folder.
    """
    from quadcog.embedded.controller_export import file_names
    from quadcog.embedded.crazyflie_app import app_file_names
    return list(file_names(name)) if target == "c" else app_file_names(name)


def _check_export_outputs(target: str, out: Path, scenario: object) -> None:
    """Refuse, before anything is written, an export whose files would replace one that the
    scenario reads (``--scenario DIR/quadcog_fl.c --out DIR`` overwrote the scenario)."""
    from quadcog.files import check_outputs
    inputs = list(getattr(scenario, "inputs", ()))
    name = str(getattr(scenario, "controller", ""))
    check_outputs([(f"--out (its {rel})", out / rel) for rel in export_names(target, name)],
                  inputs, QuadcogError)


def _export_crazyflie(args: argparse.Namespace) -> None:
    """`quadcog export --target crazyflie`: write (and with --build, build) the firmware app
    (``quadcog.embedded.crazyflie_app.write_crazyflie_app``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from quadcog.embedded.crazyflie_app import write_crazyflie_app
    if args.firmware is not None and not args.build:
        raise QuadcogError("--firmware needs --build")
    vehicle = [f"--vehicle {args.vehicle}"] if args.vehicle else []
    if args.scenario is None:
        if args.overrides:
            raise QuadcogError("--set needs --scenario (the keys of a scenario file)")
        law, name = args.controller, None
        which = [f"--controller {args.controller}"]
    else:
        from quadcog.scenarios.scenario import load_scenario
        scenario = load_scenario(args.scenario, args.overrides)
        _check_export_outputs("crazyflie", Path(args.out), scenario)
        law = scenario.make_controller()
        law, name = getattr(law, "inner", law), scenario.controller
        which = [f"--scenario {args.scenario}"] + [f"--set {o}" for o in args.overrides]
    command = " ".join(["quadcog export --target crazyflie", *which, *vehicle, "--out DIR"])
    if args.build:
        # what the build needs, before the app is written: a refused build left a written app
        from quadcog.embedded.crazyflie_firmware import check_build_inputs
        check_build_inputs(args.firmware)
    with _out_dir(args.out) as out:
        paths = write_crazyflie_app(law, out, vehicle=args.vehicle, name=name, command=command)
    for path in paths:
        print(f"wrote {path}")
    if args.build:
        from quadcog.embedded.crazyflie_firmware import build_app
        built = build_app(out, args.firmware)
        print(f"{'found' if built.cached else 'built'} {built.elf}: flash {built.flash} B, "
              f"RAM {built.ram} B (text {built.text}, data {built.data}, bss {built.bss})")


def add_sweep(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog sweep`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    p = sub.add_parser("sweep", help="fly a sweep file (TOML) locally or on Dask",
                       description="Fly every flight of a sweep file (scenario keys as lists, "
                                   "ranges or samples) and write one table, a summary and "
                                   "plots; resumable. Needs the sweep extra (pyarrow, dask, "
                                   "distributed): pip install 'quadcog[sweep]'.")
    p.add_argument("sweep", help="sweep file, or the name of a shipped one (`quadcog sweeps` "
                                 "lists them)")
    p.add_argument("--out", type=_path, required=True,
                   help="results folder; run again with the same folder to resume")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, help="start a Dask LocalCluster of N processes")
    where.add_argument("--scheduler", help="address of a running Dask scheduler")
    p.set_defaults(func=cmd_sweep)


def cmd_sweep(args: argparse.Namespace) -> None:
    """Run `quadcog sweep`: fly a sweep file (``quadcog.sweeps.runner.run_cli``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from quadcog.validate import require_extra
    require_extra("sweep", "pyarrow", "dask", "distributed")   # before any flight
    import quadcog.crazyflie  # noqa: F401  (registers the flight stack for [stack] flights)
    from quadcog.sweeps.runner import run_cli
    # the folder is made by the sweep once the file validates: a rejected file leaves none
    run_cli(args.sweep, _check_out_dir(args.out), workers=args.workers,
            scheduler=args.scheduler)


def add_identify(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog identify`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    p = sub.add_parser("identify", help="identify a real vehicle's CoG offset and mass from "
                                        "flight logs",
                       description="Estimate the CoG offset r_G and the mass from flight logs "
                                   "(Crazyflie uSD, PX4 ULog, CSV, Parquet; several are "
                                   "pooled) and print them with 95 % intervals (docs/"
                                   "identify.md). Try it on the flights shipped with quadcog: "
                                   "quadcog identify sample:crazypad/motor_data/"
                                   "add_weight_W1_near_M4 --baseline sample:crazypad/"
                                   "motor_data/normal_flight")
    p.add_argument("logs", nargs="+", metavar="LOG",
                   help="flight log file(s); sample:NAME for a log shipped with quadcog, or "
                        "a folder of them (python -m quadcog.logs.samples lists the names; "
                        "e.g. sample:crazypad/motor_data/normal_flight)")
    p.add_argument("--vehicle", default="crazyflie", help="vehicle preset (default crazyflie)")
    p.add_argument("--baseline", nargs="+", default=None, metavar="LOG",
                   help="flights of the same vehicle without the payload (files or "
                        "sample:NAME): report the shift relative to them")
    p.add_argument("--method", default="auto", help="auto (default), static or regression")
    p.add_argument("--rotor-model", default=None,
                   help="rotor model name instead of the vehicle's (bitcraze-voltage, "
                        "foerster, firmware-command)")
    p.add_argument("--json", default=None, metavar="FILE",
                   help="write r_G, r_G_ci95, mass, mass_ci95, mass_change, samples, "
                        "identifiable as JSON")
    p.add_argument("--out", type=_path, default=None, metavar="DIR",
                   help="folder for the figure identify.png")
    p.set_defaults(func=cmd_identify)


def cmd_identify(args: argparse.Namespace) -> None:
    """Run `quadcog identify`: identify the CoG offset and mass from flight logs
    (``quadcog.identification.identify``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from quadcog.errors import LogError
    from quadcog.files import RunFiles, atomic_write, check_outputs, input_file, one_line, output_path, strict_json
    from quadcog.identification import identify
    from quadcog.identification.figure import plot_identification
    from quadcog.logs.samples import resolve_log_argument
    args.logs = [p for arg in args.logs for p in resolve_log_argument(arg)]
    if args.baseline is not None:
        args.baseline = [p for arg in args.baseline for p in resolve_log_argument(arg)]
    inputs = list(args.logs) + list(args.baseline or [])
    for path in inputs:             # what the path is, before the readers' work
        input_file(path, "a flight log file (Crazyflie uSD .bin, ULog .ulg, .csv or "
                   ".parquet)", LogError, hint="; a folder of shipped logs is given as "
                   "sample:NAME")
        if not path.exists():
            raise LogError(f"{one_line(path)}: no such log file")
    # every output refused before the work: a link, a FIFO, a device, a log, each other
    outputs = []
    if args.json is not None:
        outputs.append(("--json", output_path(args.json, "--json", protect=inputs)))
    if args.out is not None:
        outputs.append(("--out (its identify.png)",
                        _check_out_dir(args.out) / "identify.png"))
    check_outputs(outputs, [("the log", p) for p in inputs], QuadcogError)
    result = identify(args.logs, vehicle=args.vehicle, baseline=args.baseline,
                      method=args.method, rotor_model=args.rotor_model)
    print(result.summary())
    if args.out is not None:
        path = Path(args.out) / "identify.png"
        title = f"quadcog identify: {len(args.logs)} log(s) of {args.vehicle}" + (
            f" against {len(args.baseline)} baseline log(s)" if args.baseline else "")
        # whole or absent, even on Ctrl-C; the folder is made here, after the work
        with RunFiles(path.parent, owned=(), protect=inputs) as files:
            plot_identification(result, files.path(path.name), title=title)
        print(f"wrote {one_line(path)}")
    if args.json is not None:
        atomic_write(args.json, strict_json(result.as_json()), "--json", protect=inputs)
        print(f"wrote {one_line(args.json)}")


def add_targets(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog targets`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    from quadcog.studies.targets import CASES, LAWS
    from quadcog.vehicles.vehicle import PRESETS
    p = sub.add_parser("targets", help="measure the controllers' default settings on every "
                                       "preset vehicle against the targets (docs: Targets)",
                       description="Fly every preset x law x case with the realistic truth and "
                                   "sensing of the *-real scenarios and the defaults derived "
                                   "for the vehicle; print the table and write targets.csv, "
                                   "targets.json and targets.md.")
    p.add_argument("--out", type=_path, default=Path("out/targets"),
                   help="output folder (default: out/targets)")
    # a metavar, the choices in the help: the usage line stays within the docs' column
    p.add_argument("--vehicles", nargs="+", choices=tuple(PRESETS), default=tuple(PRESETS),
                   metavar="VEHICLE",
                   help=f"preset names: {', '.join(PRESETS)} (default: all)")
    p.add_argument("--laws", nargs="+", choices=LAWS, default=LAWS, metavar="LAW",
                   help=f"controller short names: {', '.join(LAWS)} (default: all)")
    cases = tuple(c.name for c in CASES)
    p.add_argument("--cases", nargs="+", choices=cases, default=None, metavar="CASE",
                   help=f"case names: {', '.join(cases)} (default: all)")
    p.set_defaults(func=cmd_targets)


def cmd_targets(args: argparse.Namespace) -> None:
    """Run `quadcog targets` (``quadcog.studies.targets``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from quadcog.files import check_outputs
    from quadcog.studies.targets import CASES, TARGET_FILES, markdown_table, run_targets, write_targets
    cases = None if args.cases is None else [c for c in CASES if c.name in args.cases]
    # before the minutes of flights: a folder that can be made, files that can be replaced
    out = _check_out_dir(args.out)
    check_outputs([(f"--out (its {name})", out / name) for name in TARGET_FILES],
                  error=QuadcogError)
    rows = run_targets(args.vehicles, args.laws, cases, progress=print)
    print()
    print(markdown_table(rows), end="")
    with _out_dir(args.out) as out:
        print(f"written: {write_targets(rows, out)}")


def add_px4(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog px4`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    p = sub.add_parser("px4", help="fly a scenario with PX4's estimator and controllers on "
                                   "quadcog's plant, in lockstep (docs/px4.md)",
                       description="PX4 (SITL, built into quadcog's cache) flies the "
                                   "scenario's vehicle, CoG changes and payload events on "
                                   "quadcog's truth plant; writes the run files, px4.ulg (PX4's "
                                   "own log) and px4.log.")
    p.add_argument("scenario", help="px4-hover, px4-payload, or any scenario name or file")
    p.add_argument("--px4", type=_path, default=None, metavar="PATH",
                   help="PX4-Autopilot tree or tarball (default: $QUADCOG_PX4, else "
                        "shared/vendor/px4-autopilot.tar.xz next to the checkout)")
    p.add_argument("--out", type=_path, default=None,
                   help="folder for the results (default: out/<scenario>-px4)")
    p.add_argument("--set", dest="overrides", action="append", default=[],
                   metavar="KEY=VALUE", help="override a scenario key (as for `quadcog run`). "
                                             + _SET_PATHS)
    p.add_argument("--no-build", action="store_true",
                   help="fail instead of building PX4 when the cache has no build")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=cmd_px4)


def cmd_px4(args: argparse.Namespace) -> None:
    """Run `quadcog px4` (``quadcog.px4.fly``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from quadcog.px4 import fly, scenario_path
    name = scenario_path(args.scenario)
    with _out_dir(args.out if args.out is not None
                  else Path("out") / f"{Path(args.scenario).stem}-px4") as out:
        flight = fly(name, px4=args.px4, out=out, allow_build=not args.no_build,
                     progress=not args.quiet, overrides=tuple(args.overrides))
    r = flight.recording
    line = (f"{flight.scenario.name}: PX4 armed at {r.armed_at:.1f} s, disarmed at "
            f"{r.disarmed_at:.1f} s; " if r.armed_at is not None and r.disarmed_at is not None
            else f"{flight.scenario.name}: ")
    print(f"{line}{r.lockstep_seconds:.1f} s in lockstep in {r.wall_seconds:.1f} s of wall "
          f"time ({flight.speed:.1f}x real time); wrote {out}/metrics.json, trajectory.csv, "
          f"px4.ulg, px4.log")
    if flight.partial:
        raise QuadcogError(f"the PX4 flight is partial: {r.reason}; kept what was flown, "
                           f"marked partial, in {out}")


SUBCOMMANDS: list[Callable[[_Subparsers[argparse.ArgumentParser]], None]] = [
    add_tour, add_scenarios, add_run, add_animate, add_paper, add_analyze,
    add_export, add_sweep, add_sweeps, add_identify, add_targets]
SUBCOMMANDS.append(add_px4)


def add_cache(sub: _Subparsers[argparse.ArgumentParser]) -> None:
    """Declare `quadcog cache`.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of ``parser()``.
    """
    p = sub.add_parser("cache", help="list quadcog's cache (compiled code, PX4's build, ...) "
                                     "and clear it",
                       description="List the entries of quadcog's cache ($QUADCOG_CACHE_DIR, "
                                   "else ~/.cache/quadcog) by kind with their sizes; --clear "
                                   "removes them (all, or the kinds named). Each entry is "
                                   "rebuilt when it is next needed; one being built is left.")
    p.add_argument("--clear", nargs="*", metavar="KIND", default=None,
                   help="remove every entry, or those of the kinds named (libraries, px4, "
                        "aqb, crazyflie, stacks, vendor)")
    p.add_argument("--all", action="store_true", help="list every entry, not only the kinds")
    p.set_defaults(func=cmd_cache)


def cmd_cache(args: argparse.Namespace) -> None:
    """Run `quadcog cache` (``quadcog.codegen.cache``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    import time

    from quadcog.codegen.cache import clear, entries, human_size
    from quadcog.paths import cache_dir
    if args.clear is not None:
        removed, busy = clear(args.clear)
        print(f"removed {len(removed)} entries ({human_size(sum(e.size for e in removed))}) "
              f"from {cache_dir()}")
        for e in busy:
            print(f"left {e.name}: a build holds its lock")
        return
    found = entries()
    print(f"{cache_dir()}: {len(found)} entries, {human_size(sum(e.size for e in found))}")
    kinds: dict[str, list] = {}
    for e in found:
        kinds.setdefault(e.kind, []).append(e)
    for kind, group in kinds.items():
        newest = time.strftime("%Y-%m-%d", time.localtime(max(e.modified for e in group)))
        print(f"  {kind:<10} {len(group):>5} entries {human_size(sum(e.size for e in group)):>9}"
              f"  newest {newest}")
        if args.all:
            for e in group:
                print(f"    {e.name}  {human_size(e.size)}")


SUBCOMMANDS.append(add_cache)


def _version() -> str:
    from quadcog import __version__
    return f"quadcog {__version__}"


class _Parser(argparse.ArgumentParser):
    """argparse's parser, whose usage errors are one line like every other error (argparse
    repeats the value given: a name of thousands of characters, a newline)."""

    def error(self, message: str) -> NoReturn:
        self.print_usage(sys.stderr)
        self.exit(2, f"{self.prog}: error: {_line(message)}\n")


def parser() -> argparse.ArgumentParser:
    """The argument parser of the `quadcog` command.

    Returns
    -------
    argparse.ArgumentParser
        With every subcommand of ``SUBCOMMANDS``.
    """
    ap: argparse.ArgumentParser = _Parser(
        prog="quadcog", description="Quadrotor with a moving centre of gravity: simulate, "
                                    "reproduce the paper, analyse.")
    ap.add_argument("--version", action="version", version=_version())
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in SUBCOMMANDS:
        add(sub)
    return ap


MAX_WARNINGS = 20
"""Warnings a command prints; the rest are counted in one last line (a scenario of 20000 CoG
changes after its end gave 20000 lines)."""
_warned = [0]


def _show_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                  file: object = None, line: str | None = None) -> None:
    _warned[0] += 1
    if _warned[0] <= MAX_WARNINGS:
        print(f"quadcog: warning: {_line(message)}", file=sys.stderr)


def _more_warnings() -> None:
    """The line that counts the warnings beyond MAX_WARNINGS, if any."""
    if _warned[0] > MAX_WARNINGS:
        print(f"quadcog: warning: {_warned[0] - MAX_WARNINGS} more warnings not shown",
              file=sys.stderr)
    _warned[0] = 0


def _line(message: object) -> str:
    """A message as one line: the one place where values from the command line or a file
    (a name with a newline, a 300-digit number) are escaped or shortened for printing."""
    from quadcog.files import one_line
    return one_line(message)


def main(argv: Sequence[str] | None = None) -> int:
    """The `quadcog` command.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments (default: the command line's).

    Returns
    -------
    int
        The exit status: 0; 2 for an error (QuadcogError, OSError: one line on stderr); 3
        for an unexpected one (one line; QUADCOG_TRACEBACK=1 shows it); 130 when interrupted
        (Ctrl-C), 143 when terminated (SIGTERM).
    """
    from quadcog.errors import Interrupted
    from quadcog.interrupts import install_handlers, restore_handlers
    previous = install_handlers()   # first: SIGINT/SIGTERM -> Interrupted, cleaned up on the way
    try:
        return _main(argv)
    except Interrupted as e:        # during parsing, or after a command's own handling
        print("quadcog: interrupted", file=sys.stderr)
        return e.status
    finally:
        restore_handlers(previous)


def _silence_stdout() -> None:
    """Point stdout at /dev/null: Python's flush at exit would raise the broken pipe again."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):   # stdout without a descriptor (captured in a test)
        pass
    finally:
        os.close(devnull)


def _main(argv):
    from quadcog.errors import Interrupted
    try:
        args = parser().parse_args(argv)
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning      # one line, no source location
            _warned[0] = 0
            try:
                args.func(args)
            finally:
                _more_warnings()
    except Interrupted as e:        # files being written were not committed
        print("quadcog: interrupted", file=sys.stderr)
        return e.status             # 128 + the signal, as shells report it: 130, 143
    except QuadcogError as e:
        from quadcog.interrupts import received
        if received() is not None:  # a signal inside compiled code, reported as a wrong input
            print("quadcog: interrupted", file=sys.stderr)
            return received().status
        print(f"quadcog: error: {_line(e)}", file=sys.stderr)
        return 2
    except BrokenPipeError:         # `quadcog ... | head`: the reader left, as for any tool
        _silence_stdout()
        return 141                  # 128 + SIGPIPE, as shells report it
    except OSError as e:
        print(f"quadcog: error: {_line(e.filename or '')}: {_line(e.strerror or e)}",
              file=sys.stderr)
        return 2
    except KeyboardInterrupt:       # Ctrl-C: files being written were not committed
        print("quadcog: interrupted", file=sys.stderr)
        return 130                  # 128 + SIGINT, as shells report it
    except (MemoryError, RecursionError) as e:
        print(f"quadcog: error: out of resources ({type(e).__name__}); the input is too large "
              f"for this machine", file=sys.stderr)
        return 2
    except Exception as e:          # a bug: one line for users, the traceback on request
        from quadcog.interrupts import received
        interrupt = received()
        if interrupt is not None:   # the signal came out of compiled code as another error
            print("quadcog: interrupted", file=sys.stderr)
            return interrupt.status
        if os.environ.get("QUADCOG_TRACEBACK"):
            raise
        print(f"quadcog: internal error: {type(e).__name__}: {_line(e)} (a bug in quadcog; "
              f"QUADCOG_TRACEBACK=1 shows where)", file=sys.stderr)
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
