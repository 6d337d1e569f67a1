"""AdaptiveQuadBench's payload experiment for its peers and quadcog's laws (docs/aqb.md).

For each controller, in a process of its own (AdaptiveQuadBench's vehicles keep payload state
between controllers of one process, vendor README): the payload experiment (``--trials``
trials, seed 42), ``--when2fail`` to intensity 2 (payload of 0, 1 and 2 vehicle masses) and
``--delay_margin`` (5 motion primitives, delay up in steps of 10 ms until the position error
passes 1 m), all through AdaptiveQuadBench's own ExperimentRunner; the numbers are read from
what it computes (its summary file, its when2fail arrays, its delay margins). Writes one JSON
per controller and ``out/aqb/aqb.json`` with the table; ``python bench/publish.py aqb`` puts
it into docs/aqb.md.

    python bench/aqb_suite.py [--trials 100] [--controllers geo geo-a ...] [--out out/aqb]

Peers: geo, geo-a, l1geo, indi-a. quadcog's laws: ``qc-<name>`` for each name of its registry
(``qc-geometric`` is flown where the registry has it).
"""
import argparse
import json
import os
from pathlib import Path
import platform
import subprocess
import sys
import time

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from quadcog.files import atomic_write, cpu_model

PEERS = ("geo", "geo-a", "l1geo", "indi-a")
OURS = ("geometric", "composite", "payload_adaptive")
SEED = 42
MAX_INTENSITY = 2.0


def default_controllers():
    """The peers, then quadcog's laws that its registry has."""
    from quadcog.controllers.registry import controller_names
    return list(PEERS) + ["qc-" + n for n in OURS if n in controller_names()]


def run_one(controller, trials, out):
    """One controller's three experiments in this process; writes ``out`` (JSON)."""
    os.environ.setdefault("MPLBACKEND", "Agg")
    import numpy as np
    import pandas as pd

    from quadcog.aqb.adapter import aqb_controller_factory, register_template
    from quadcog.aqb.install import require_aqb
    tree = require_aqb()
    register_template()
    sys.path.insert(0, str(tree.aqb))
    from aqb.experiments.config_manager import ExperimentConfig
    from aqb.experiments.experiment_runner import ExperimentRunner
    import run_eval  # AdaptiveQuadBench's own controller switch (patched imports)
    factory = aqb_controller_factory(run_eval.switch_controller, on_nonfinite="cut")

    def config(**kw):
        base = dict(controller_types=[controller], experiment_type="payload",
                    num_trials=trials, seed=SEED, save_trials=False, use_serial=True,
                    visualize=False, when2fail=False, max_intensity=MAX_INTENSITY,
                    intensity_step=1.0, trajectory_type="random", delay_margin=False)
        base.update(kw)
        return ExperimentConfig(**base)

    record = {"controller": controller, "trials": trials, "seed": SEED,
              "aqb": tree.stamp().get("commits", {})}
    t0 = time.time()
    runner = ExperimentRunner(config(), factory)
    runner.run()
    df = pd.read_csv(runner.results_manager.data_dir / f"summary_{controller}_payload.csv")
    ok = df["pos_tracking_error"] < 5          # AdaptiveQuadBench's success: RMSE < 5 m
    record["payload"] = {"success": float(ok.mean() * 100),
                         "rmse_mean": float(df["pos_tracking_error"][ok].mean()),
                         "rmse_std": float(df["pos_tracking_error"][ok].std()),
                         "rmse": df.sort_values("traj_number")["pos_tracking_error"].tolist(),
                         "seconds": time.time() - t0}

    t0 = time.time()
    runner = ExperimentRunner(config(when2fail=True), factory)
    caught = {}
    runner.visualizer.plot_when2fail_results = lambda **kw: caught.update(kw)
    runner.run()
    record["when2fail"] = {"intensity": [float(v) for v in caught["intensities"][controller]],
                           "success": [float(v) for v in caught["success_rates"][controller]],
                           "rmse_mean": [float(v) for v in caught["pos_errors"][controller]],
                           "seconds": time.time() - t0}

    t0 = time.time()
    np.random.seed(SEED)     # its delay test draws its 5 trajectories unseeded: the same for all
    runner = ExperimentRunner(config(delay_margin=True), factory)
    margins = runner.run()[controller]["delay_margins"]
    record["delay_margin"] = {"margins": [float(m) for m in margins],
                              "mean": float(np.mean(margins)), "seconds": time.time() - t0}
    atomic_write(out, json.dumps(record, indent=1), "the controller's results")


def fmt(v, spec):
    return "—" if v is None or v != v else format(v, spec)


def table(records, trials):
    """The Markdown table of the records (one row per controller)."""
    rows = ["| controller | trials | success (%) | mean RMSE (m) | success at 2x mass (%) "
            "| mean RMSE at 2x mass (m) | delay margin (s) | wall time (s) |",
            "|---|---|---|---|---|---|---|---|"]
    for r in records:
        name = r["controller"]
        if "error" in r:
            rows.append(f"| {name} | {trials} | failed to run: {r['error']} | | | | | |")
            continue
        w = r["when2fail"]
        at2 = w["intensity"].index(2.0) if 2.0 in w["intensity"] else None
        s2 = w["success"][at2] if at2 is not None else 0.0
        e2 = w["rmse_mean"][at2] if at2 is not None else None
        secs = r["payload"]["seconds"] + w["seconds"] + r["delay_margin"]["seconds"]
        rows.append(f"| {name} | {r['trials']} | {fmt(r['payload']['success'], '.0f')} | "
                    f"{fmt(r['payload']['rmse_mean'], '.3f')} | {fmt(s2, '.0f')} | "
                    f"{fmt(e2, '.3f')} | {fmt(r['delay_margin']['mean'], '.2f')} | {secs:.0f} |")
    return "\n".join(rows)


def machine_line(records):
    commits = next((r["aqb"] for r in records if "aqb" in r), None)
    if commits is None:
        from quadcog.aqb.install import installed_tree
        tree = installed_tree()
        commits = tree.stamp().get("commits", {}) if tree else {}
    return (f"Measured on {cpu_model() or platform.processor() or 'unknown CPU'} "
            f"({platform.machine()}, {os.cpu_count()} cores, shared), Python "
            f"{platform.python_version()}, AdaptiveQuadBench {commits.get('aqb', '?')} with "
            f"RotorPy fork {commits.get('rotorpy', '?')}, {time.strftime('%Y-%m-%d')}.")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=100)
    ap.add_argument("--controllers", nargs="+")
    ap.add_argument("--out", default=str(ROOT / "out" / "aqb"))
    ap.add_argument("--table", action="store_true",
                    help="only rebuild the table from the controllers' files in --out")
    ap.add_argument("--one", help=argparse.SUPPRESS)        # the child process
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if a.one:       # into a file of its own: the parent keeps the last result until it is done
        run_one(a.one, a.trials, out / f"{a.one}.json.part")
        return
    records = []
    for c in [] if a.table else a.controllers or default_controllers():
        f, part = out / f"{c}.json", out / f"{c}.json.part"
        part.unlink(missing_ok=True)
        print(f"== {c}: {a.trials} trials", flush=True)
        done = subprocess.run([sys.executable, __file__, "--one", c, "--trials", str(a.trials),
                               "--out", str(out)], cwd=ROOT)
        if done.returncode == 0 and part.is_file():
            os.replace(part, f)
            records.append(json.loads(f.read_text()))
        else:       # a failed or interrupted run replaces no earlier result
            part.unlink(missing_ok=True)
            records.append({"controller": c, "error": f"exit status {done.returncode}"})
            if f.is_file():
                print(f"   {c} failed; its earlier result is kept in {f} (--table rebuilds "
                      "the table from the kept results)", flush=True)
    # the table holds every controller measured into this folder (a rerun of one keeps the rest)
    known = default_controllers() + sorted(p.stem for p in out.glob("*.json")
                                           if p.stem not in default_controllers() + ["aqb"])
    ran = {r["controller"]: r for r in records}
    records = [ran.get(c) or json.loads((out / f"{c}.json").read_text()) for c in known
               if c in ran or (out / f"{c}.json").is_file()]
    text = table(records, a.trials)
    result = {"table": text, "machine": machine_line(records), "records": records}
    atomic_write(out / "aqb.json", json.dumps(result, indent=1), "the table's results")
    print(result["machine"])
    print(text)


if __name__ == "__main__":
    main()
