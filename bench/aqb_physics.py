"""The same AdaptiveQuadBench payload trials in both simulators, and its payload model's flaws
measured (docs/aqb.md).

The trials are ``quadcog.aqb.protocol.payload_trials`` (seed 42: trial i is AdaptiveQuadBench's
trial i). Each controller flies them in RotorPy with the payload model as shipped and with a
rigid body's (``quadcog.aqb.physics.corrected_multirotor``), everything else the same (100 Hz,
RotorPy's aerodynamics and motor noise); quadcog's laws also fly them in quadcog's simulator,
whose truth carries the payload as a rigid body, at 1 kHz with the true state and with the
real-sensing options (noise, one-period delay; rotor saturation and motor lag on in both).
Writes ``out/aqb/physics.json`` and ``out/aqb/flaws.json``; ``python bench/publish.py
aqb-physics`` and ``aqb-flaws`` put their tables into docs/aqb.md.

    python bench/aqb_physics.py [--trials 100] [--intensity K] [--controllers ...]
"""
import argparse
import json
import os
from pathlib import Path
import sys
import time

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from aqb_suite import PEERS, default_controllers, machine_line
import numpy as np

from quadcog.aqb.protocol import SUCCESS_RMSE, fly, payload_trials
from quadcog.sim.sensing import Sensing

COLUMNS = ("RotorPy, payload as shipped", "RotorPy, rigid-body payload",
           "quadcog 1 kHz, true state", "quadcog 1 kHz, real sensing")


def summary(costs):
    """(success %, mean RMSE of the successes) in AdaptiveQuadBench's way."""
    c = np.asarray(costs, float)
    ok = c < SUCCESS_RMSE
    return 100.0 * ok.mean(), (float(c[ok].mean()) if ok.any() else float("nan"))


def cell(costs):
    if costs is None:
        return "—"
    s, e = summary(costs)
    return f"{s:.0f} % / {e:.3f} m" if e == e else f"{s:.0f} % / —"


def main():
    os.environ.setdefault("MPLBACKEND", "Agg")
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=100)
    ap.add_argument("--intensity", type=float, default=None,
                    help="a when2fail step (payload of K vehicle masses); default the payload "
                         "experiment's U(0, 0.5)")
    ap.add_argument("--controllers", nargs="+")
    ap.add_argument("--out", default=str(ROOT / "out" / "aqb"))
    ap.add_argument("--flaws-only", action="store_true", help="only measure the flaws")
    ap.add_argument("--merge", nargs="+", metavar="FOLDER",
                    help="only write one table of the physics.json files of these folders")
    a = ap.parse_args()
    if a.merge:
        merge(a.merge, a.out)
        return
    from quadcog.aqb.physics import flaw_measures, fly_rotorpy
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    trials = payload_trials(a.trials, intensity=a.intensity)
    what = ("payload experiment, mass U(0, 0.5) x 0.826 kg" if a.intensity is None
            else f"when2fail intensity {a.intensity:g}: payload {a.intensity:g} x 0.826 kg")

    flaws = flaw_measures(trials)
    flaw_rows = [
        "| flaw of the shipped payload model | measured over the trials' toggles |", "|---|---|",
        f"| inertia about the CoM after attach (parallel-axis term subtracted), largest relative "
        f"error | {100 * flaws['inertia_error_attach']:.1f} % |",
        f"| extra payload torque (body offset x world gravity, fixed at attach), largest | "
        f"{flaws['extra_torque_max']:.3f} N m |",
        f"| extra torque / the CoG offset's own moment through the rotor arms, largest | "
        f"{flaws['extra_torque_ratio']:.2f} |",
        f"| CoM after detach, largest distance from the bare vehicle's | "
        f"{1000 * flaws['com_error_detach']:.1f} mm |",
        f"| inertia after detach, largest relative error from the bare vehicle's | "
        f"{100 * flaws['inertia_error_detach']:.1f} % |"]
    (out / "flaws.json").write_text(json.dumps(
        {"table": "\n".join(flaw_rows),
         "machine": machine_line([]) + f" {len(trials)} trials ({what}), seed 42.",
         "measures": flaws}, indent=1))
    print("\n".join(flaw_rows), flush=True)
    if a.flaws_only:
        return

    records = []
    for c in a.controllers or default_controllers():
        t0 = time.time()
        r = {"controller": c, "trials": len(trials),
             "condition": None if a.intensity is None else f"{a.intensity:g}x mass"}
        r["shipped"] = [fly_rotorpy(t, c, corrected=False) for t in trials]
        r["rigid"] = [fly_rotorpy(t, c, corrected=True) for t in trials]
        if c not in PEERS:
            law = c.removeprefix("qc-")
            r["quadcog"] = [fly(t, law, dt=1e-3)[0] for t in trials]
            r["quadcog_sensing"] = [fly(t, law, dt=1e-3, sensing=Sensing(seed=t.index + 1))[0]
                                    for t in trials]
        r["seconds"] = time.time() - t0
        records.append(r)
        print(c, {k: cell(v) for k, v in r.items() if isinstance(v, list)}, flush=True)

    write_table(records, out, machine_line(records) + f" {what}; cells: success / mean "
                "RMSE of the successes.")


def write_table(records, out, machine):
    """The same-trials table of the records into ``out / "physics.json"``."""
    rows = ["| controller | trials | " + " | ".join(COLUMNS) + " | mean abs. change of RMSE, "
            "shipped -> rigid (m) |", "|---|---|" + "---|" * (len(COLUMNS) + 1)]
    for r in records:
        d = np.abs(np.asarray(r["shipped"]) - np.asarray(r["rigid"]))
        label = r["controller"] + (f" ({r['condition']})" if r.get("condition") else "")
        rows.append(f"| {label} | {r['trials']} | {cell(r['shipped'])} | "
                    f"{cell(r['rigid'])} | {cell(r.get('quadcog'))} | "
                    f"{cell(r.get('quadcog_sensing'))} | {float(np.mean(d)):.4f} |")
    table = "\n".join(rows)
    (Path(out) / "physics.json").write_text(json.dumps(
        {"table": table, "machine": machine, "records": records}, indent=1))
    print(table)


def merge(folders, out):
    """One table of the records of several runs (runs split over processes); the flaws of
    the first run (the same trials measure the same flaws)."""
    runs = [json.loads((Path(f) / "physics.json").read_text()) for f in folders]
    Path(out).mkdir(parents=True, exist_ok=True)
    write_table([r for run in runs for r in run["records"]], out, runs[0]["machine"])
    flaws = Path(folders[0]) / "flaws.json"
    if not (Path(out) / "flaws.json").is_file() or Path(out).resolve() != Path(folders[0]).resolve():
        (Path(out) / "flaws.json").write_text(flaws.read_text())

if __name__ == "__main__":
    main()
