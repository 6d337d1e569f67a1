"""The CrazyPAD survey: every flight's CoG shift against the same drone's normal flights.

    python -m quadcog.identification.survey CRAZYPAD_FOLDER [--out FILE] [--update MD]

The folder holds ``<kind>/<folder>/<drone>_logNN`` files (kind ``motor_data`` or
``controller_data``, folder ``normal_flight`` or ``add_weight_*``). For each flight the static
balance is run against a baseline of the same drone and kind: all its normal flights for a
weighted flight, the other normal flights for a normal one (their scatter is what the method
cannot resolve between sessions). The tables are markdown: one row per flight, one pooled row
per weighted folder, and the pooled shifts with each Crazyflie rotor model. ``--update``
replaces the text between ``<!-- survey:begin -->`` and ``<!-- survey:end -->`` of a markdown
file with them.
"""
import argparse
import math
from pathlib import Path
import sys
from typing import Any

from quadcog.errors import IdentificationError, QuadcogError
from quadcog.files import atomic_write
from quadcog.identification import _checks
from quadcog.identification.core import identify
from quadcog.logs import read_log
from quadcog.validate import choice
from quadcog.vehicles.rotor_model import ROTOR_MODELS

__all__ = ["EXPECTED_DIRECTION", "flights", "survey_rows", "rotor_model_rows", "tables", "main"]

# where the weight was taped, as a direction in the body frame (deg from x forward toward y
# left): M3 back-left, M4 front-left (motor positions of quadcog.vehicles.vehicle.x_layout)
EXPECTED_DIRECTION = {"add_weight_W1_near_M3": 135.0, "add_weight_W1_near_M4": 45.0}
NORMAL = "normal_flight"
BEGIN, END = "<!-- survey:begin -->", "<!-- survey:end -->"


def flights(root: str | Path) -> list[tuple[str, str, str, Path]]:
    """The flights under ``root``: (kind, folder, drone, path), sorted.

    Parameters
    ----------
    root : str or Path
        The CrazyPAD folder.

    Returns
    -------
    list of (str, str, str, Path)
        Kind, folder, drone and file of each flight.

    Raises
    ------
    quadcog.QuadcogError
        No flight files under ``root``.
    quadcog.IdentificationError
        ``root`` not a path (a non-empty str or Path).
    """
    root = _checks.path(root, "flights: root")
    out = []
    for path in sorted(root.glob("*/*/*_log*")):
        kind, folder = path.parent.parent.name, path.parent.name
        out.append((kind, folder, path.name.split("_")[0], path))
    if not out:
        raise QuadcogError(f"{root}: no <kind>/<folder>/<drone>_logNN flight files")
    return out


def _direction(dx: float, dy: float) -> float:
    return math.degrees(math.atan2(dy, dx))


def _row(result: Any) -> dict[str, Any]:
    dx, dy = result.r_G[0], result.r_G[1]
    hx, hy = result.r_G_ci95[0], result.r_G_ci95[1]
    return dict(dx=1e3 * dx, dy=1e3 * dy, size=1e3 * math.hypot(dx, dy),
                direction=_direction(dx, dy), hx=1e3 * hx, hy=1e3 * hy,
                dm=1e3 * result.mass_change, mass=1e3 * result.mass)


def survey_rows(root: str | Path, rotor_model: str | None = None) -> list[dict[str, Any]]:
    """One row per flight (and a pooled row per weighted folder), each a dict.

    Parameters
    ----------
    root : str or Path
        The CrazyPAD folder.
    rotor_model : str, optional
        A name of ``ROTOR_MODELS`` instead of the Crazyflie's.

    Returns
    -------
    list of dict
        Keys kind, folder, drone, log, dx, dy (mm), size (mm), direction (deg), hx, hy
        (95 % half-widths, mm), dm (mass change, g), mass (g).

    Raises
    ------
    quadcog.IdentificationError
        ``root`` not a path, ``rotor_model`` not None or a name of ``ROTOR_MODELS`` (before
        any log is read).
    """
    root = _checks.path(root, "survey_rows: root")
    if rotor_model is not None:
        choice(rotor_model, "survey_rows: rotor_model", ROTOR_MODELS, IdentificationError)
    items = flights(root)
    logs = {path: read_log(path) for *_, path in items}
    rows = []
    groups = sorted({(k, d) for k, _, d, _ in items})
    for kind, drone in groups:
        normal = [p for k, f, d, p in items if (k, f, d) == (kind, NORMAL, drone)]
        for k, folder, d, path in items:
            if (k, d) != (kind, drone):
                continue
            base = [logs[p] for p in normal if p != path]
            if not base:
                continue
            res = identify(logs[path], "crazyflie", baseline=base, rotor_model=rotor_model)
            rows.append(dict(kind=kind, folder=folder, drone=drone, log=path.name,
                             **_row(res)))
        for folder in sorted({f for k, f, d, _ in items if (k, d) == (kind, drone)} - {NORMAL}):
            weighted = [logs[p] for k, f, d, p in items if (k, f, d) == (kind, folder, drone)]
            res = identify(weighted, "crazyflie", baseline=[logs[p] for p in normal],
                           rotor_model=rotor_model)
            rows.append(dict(kind=kind, folder=folder, drone=drone,
                             log=f"pooled ({len(weighted)})", **_row(res)))
    return rows


def rotor_model_rows(root: str | Path) -> list[dict[str, Any]]:
    """The pooled shift of each weighted folder with each Crazyflie rotor model.

    Parameters
    ----------
    root : str or Path
        The CrazyPAD folder.

    Returns
    -------
    list of dict
        As ``survey_rows`` plus key ``model``; only the pooled rows.

    Raises
    ------
    quadcog.IdentificationError
        ``root`` not a path.
    """
    root = _checks.path(root, "rotor_model_rows: root")
    out = []
    for name in ROTOR_MODELS:
        for row in survey_rows(root, rotor_model=name):
            if row["log"].startswith("pooled"):
                out.append(dict(row, model=name))
    return out


def _fmt(v: float, spec: str = "+.2f") -> str:
    return format(v, spec)


def tables(root: str | Path) -> str:
    """The survey as markdown (both tables, with the command that made them).

    Parameters
    ----------
    root : str or Path
        The CrazyPAD folder.

    Returns
    -------
    str
        The markdown, ending in a newline.

    Raises
    ------
    quadcog.IdentificationError
        ``root`` not a path.
    """
    root = _checks.path(root, "tables: root")
    lines = ["Shift of the CoG against the same drone's normal flights (static hover balance, "
             "rotor model bitcraze-voltage where the log has PWM and battery voltage, else "
             "firmware-command; direction in degrees from body x forward toward y left: "
             "M4 front-left 45, M3 back-left 135; half-widths of the 95 % intervals):", "",
             "| drone | data | folder | log | dx_G (mm) | dy_G (mm) | shift (mm) | direction "
             "(deg) | 95 % half-width x, y (mm) | mass change (g) | mass (g) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in survey_rows(root):
        lines.append(f"| {r['drone']} | {r['kind']} | {r['folder']} | {r['log']} | "
                     f"{_fmt(r['dx'])} | {_fmt(r['dy'])} | {r['size']:.2f} | "
                     f"{r['direction']:.0f} | {r['hx']:.2f}, {r['hy']:.2f} | "
                     f"{_fmt(r['dm'])} | {r['mass']:.2f} |")
    lines += ["", "Pooled shift of each weighted folder with each rotor model (motor_data: the "
              "logs with PWM and battery voltage; controller_data logs carry only the commands, "
              "so every model falls back to firmware-command there):", "",
              "| rotor model | drone | data | folder | dx_G (mm) | dy_G (mm) | shift (mm) | "
              "direction (deg) | mass change (g) | mass (g) |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rotor_model_rows(root):
        if r["kind"] != "motor_data":
            continue
        lines.append(f"| {r['model']} | {r['drone']} | {r['kind']} | {r['folder']} | "
                     f"{_fmt(r['dx'])} | {_fmt(r['dy'])} | {r['size']:.2f} | "
                     f"{r['direction']:.0f} | {_fmt(r['dm'])} | {r['mass']:.2f} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    """The command line (module docstring).

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0, or 2 after a one-line error.

    Raises
    ------
    quadcog.IdentificationError
        ``argv`` neither None nor a list or tuple of str.
    """
    if argv is not None:
        argv = _checks.sequence(argv, "main: argv", str, "str")
    ap = argparse.ArgumentParser(prog="python -m quadcog.identification.survey",
                                 description="CoG shift of every CrazyPAD flight")
    ap.add_argument("root", type=Path, help="the CrazyPAD folder")
    ap.add_argument("--out", type=Path, default=None, help="write the tables to this file")
    ap.add_argument("--update", type=Path, default=None,
                    help=f"replace the text between {BEGIN} and {END} of this markdown file")
    args = ap.parse_args(argv)
    try:
        text = tables(args.root)
        if args.out is not None:
            atomic_write(args.out, text, "--out")
        if args.update is not None:
            doc = args.update.read_text()
            if BEGIN not in doc or END not in doc:
                raise QuadcogError(f"{args.update}: no {BEGIN} ... {END} markers")
            head, rest = doc.split(BEGIN, 1)
            _, tail = rest.split(END, 1)
            atomic_write(args.update, f"{head}{BEGIN}\n{text}{END}{tail}", "--update")
    except (QuadcogError, OSError) as e:
        print(f"survey: error: {e}", file=sys.stderr)
        return 2
    print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
