"""What the Euler laws cannot fly: the flip and the 60-degree banked circle (the shipped
scenarios ``flip`` and ``banked-circle``, each with a CoG step), flown by every law of the
registry on the truth integrated on SE(3); each Euler law at its defaults and with its tilt
clip opened to 90 degrees (the widest its Euler-angle chart allows); the geometric law also on
the Euler-angle truth, whose kinematics are singular at 90 degrees of pitch. Writes geometric.json,
the table and the figures that docs/tour/geometric.md publishes (bench/publish.py geometric):

    python -m quadcog.studies.geometric [--out out/geometric]
"""
import argparse
import dataclasses
from pathlib import Path
import platform
import re
import sys
import time
from typing import Any
import warnings

import numpy as np

from quadcog.controllers.registry import CONTROLLERS, controller_names, controller_settings
from quadcog.errors import EulerSingularityError, ReferenceWarning
from quadcog.files import atomic_write, run_stamp, strict_json
from quadcog.model.functions import load
from quadcog.model.parameters import with_cog
from quadcog.scenarios.scenario import Scenario, load_scenario

__all__ = ["FLIGHTS", "FOLLOWS", "fly", "rows", "table", "main"]

FLIGHTS = ("flip", "banked-circle")
FOLLOWS = 0.25        # m: a flight whose largest position error stays below this follows
_WIDE = float(np.pi / 2)


def _tilt_deg(x: np.ndarray) -> np.ndarray:
    """Angle between the body z axis and the vertical (deg): arccos(cos phi cos theta)."""
    return np.degrees(np.arccos(np.clip(np.cos(x[:, 3]) * np.cos(x[:, 4]), -1.0, 1.0)))


def _worst_conditioning(sc: Scenario, x: np.ndarray) -> float:
    """The largest condition number of feedback linearization's decoupling matrix alpha along
    the flown states (the nominal model: alpha carries Q(eta), singular at 90 deg of pitch)."""
    model, p = load(), with_cog(sc.vehicle.parameters(), np.zeros(3))
    return max(float(np.linalg.cond(model.decoupling(xk, p))) for xk in x[::10])


def fly(sc: Scenario, law: str, settings: dict[str, Any], quaternion: bool) -> dict[str, Any]:
    """One flight of scenario ``sc`` by ``law`` and what it shows.

    Parameters
    ----------
    sc : Scenario
        The shipped scenario.
    law : str
        A controller's short name.
    settings : dict
        Controller settings over the law's defaults.
    quaternion : bool
        The truth integrates the attitude on SE(3) (else Euler angles).

    Returns
    -------
    dict
        outcome (words), max_error (m), tilt flown and asked (deg), |theta| max (deg),
        cond (of alpha, Euler laws), r_hat error at the end (m, estimating laws).
    """
    truth = dataclasses.replace(sc.truth, quaternion=quaternion)
    run = dataclasses.replace(sc, controller=law, controller_params=settings, truth=truth)
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ReferenceWarning)   # the reference is aerobatic
            res = run.run()
    except EulerSingularityError as e:
        # its message: "|theta| = ... rad reached pi/2 at t = ... s: the Euler-angle ..."
        at = re.search(r"at t = ([-\d.e+]+) s", str(e))
        return dict(outcome=f"the truth stops at t = {float(at.group(1)) if at else np.nan:.3f} "
                            f"s: pitch reached 90 deg (EulerSingularityError)",
                    max_error=None, tilt=None,
                    asked=None, pitch=None, cond=None, r_hat_error=None,
                    seconds=time.perf_counter() - t0)
    m = res.metrics
    x = res.x
    asked = float((m.reference or {}).get("max_tilt_deg", np.nan))
    if m.diverged:
        outcome = f"diverges at {m.diverged_at:.2f} s: {m.diverged_reason}"
    elif m.max_position_error <= FOLLOWS:
        outcome = "follows"
    else:
        outcome = "does not follow"
    estimating = CONTROLLERS[law].estimates_cog
    return dict(
        outcome=outcome, max_error=float(m.max_position_error),
        tilt=float(_tilt_deg(x).max()), asked=asked,
        pitch=float(np.degrees(np.abs(x[:, 4]).max())),
        cond=None if law in ("geometric", "pd") else _worst_conditioning(sc, x),
        r_hat_error=(float(np.linalg.norm(res.r_hat[-1] - res.r_G[-1]))
                     if estimating and not m.diverged else None),
        seconds=time.perf_counter() - t0)


def rows(progress: Any = None) -> list[dict[str, Any]]:
    """Every flight of the study (module docstring), in table order.

    Parameters
    ----------
    progress : callable, optional
        Called with a line of text after each flight.

    Returns
    -------
    list of dict
        flight, law, settings (words), truth (words) and ``fly``'s entries.
    """
    out = []
    for name in FLIGHTS:
        sc = load_scenario(name)
        runs: list[tuple[str, dict[str, Any], str, bool]] = [
            ("geometric", {}, "defaults", True), ("geometric", {}, "defaults", False)]
        for law in controller_names():
            if law == "geometric":
                continue
            runs.append((law, {}, "defaults", True))
            if "max_tilt" in controller_settings(law):
                runs.append((law, {"max_tilt": _WIDE}, "max_tilt = 90 deg", True))
        for law, settings, words, quaternion in runs:
            row = dict(flight=name, law=law, settings=words,
                       truth="SE(3)" if quaternion else "Euler angles",
                       **fly(sc, law, settings, quaternion))
            out.append(row)
            if progress:
                progress(f"{name:14s} {law:17s} {words:18s} {row['truth']:12s} {row['outcome']}")
    return out


def _num(v: float | None, fmt: str) -> str:
    return "-" if v is None else format(v, fmt)


def table(data: list[dict[str, Any]]) -> str:
    """The Markdown table of ``rows``.

    Parameters
    ----------
    data : list of dict
        ``rows()``.

    Returns
    -------
    str
        One row per flight.
    """
    head = ("| flight | law | settings | truth | outcome | max error (m) | tilt flown / asked "
            "(deg) | max pitch (deg) | cond(alpha) | CoG estimate error (mm) |\n"
            "|---|---|---|---|---|---|---|---|---|---|")
    lines = [head]
    for r in data:
        tilt = "-" if r["tilt"] is None else f"{r['tilt']:.0f} / {r['asked']:.0f}"
        r_hat = None if r["r_hat_error"] is None else 1000 * r["r_hat_error"]
        lines.append(f"| {r['flight']} | {r['law']} | {r['settings']} | {r['truth']} | "
                     f"{r['outcome']} | {_num(r['max_error'], '.3f')} | {tilt} | "
                     f"{_num(r['pitch'], '.1f')} | {_num(r['cond'], '.3g')} | "
                     f"{_num(r_hat, '.2f')} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """``python -m quadcog.studies.geometric``: fly the study, print and write the table.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        0.
    """
    ap = argparse.ArgumentParser(prog="python -m quadcog.studies.geometric",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("out") / "geometric",
                    help="folder of geometric.json (default out/geometric)")
    args = ap.parse_args(argv)
    data = rows(progress=lambda s: print(s, flush=True))
    machine = (f"Measured by `python -m quadcog.studies.geometric` {run_stamp()}, Python "
               f"{platform.python_version()}.")
    results: dict[str, dict[str, Any]] = {}
    for r in data:
        key = r["law"] + ("-wide" if r["settings"] != "defaults" else "") \
            + ("-euler-truth" if r["truth"] != "SE(3)" else "")
        results.setdefault(r["flight"], {})[key] = {k: v for k, v in r.items()
                                                     if k not in ("flight", "law")}
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out / "geometric.json", strict_json(
        {"machine": machine, "table": table(data), "results": results}))
    print(table(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
