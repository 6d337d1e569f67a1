"""The whole chain against real flights: CrazyPAD motor logs -> `quadcog identify` (mass, CoG)
-> the Crazyflie 2.1 with that mass and CoG -> the firmware PID in quadcog's loop -> its hover
commands, beside the commands the firmware PID logged in the CrazyPAD controller flights of the
same drone and folder. A script that prints a table and writes it (no assertions):

    python bench/crazyflie_real.py [OUT]   # default out/crazyflie/real-flights.md (make crazyflie)

Units. The CrazyPAD flights (2024) ran a firmware whose thrust command meant 65536 <=> 60 g
of total thrust (``quadcog.vehicles.rotor_model.CRAZYFLIE_FIRMWARE_COMMAND``); the firmware in
the loop means 65535 <=> 4 THRUST_MAX. In a steady hover the PID's commands hold the weight and
the moment m g r_G, so they scale with the unit: the simulated commands are shown in the loop's
unit and in the logged firmware's (times k_loop / k_logged). The logged hover values are the
means over each flight's hover (the samples above 90 % of the median height, without the first
3 s and the last 1 s), then the mean and the spread (max - min) over the folder's flights.
"""
from pathlib import Path
import sys
import time

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.machine import machine  # noqa: E402
from quadcog.crazyflie import constants, simulate  # noqa: E402
from quadcog.identification.core import identify  # noqa: E402
from quadcog.logs.crazyflie import parse_usd  # noqa: E402
from quadcog.sim.plant import TruthOptions  # noqa: E402
from quadcog.trajectories.analytic import Hover  # noqa: E402
from quadcog.vehicles.rotor_model import CRAZYFLIE_FIRMWARE_COMMAND  # noqa: E402
from quadcog.vehicles.vehicle import CRAZYFLIE_21  # noqa: E402

DATA = ROOT.parent / "shared" / "data" / "crazypad"
FOLDERS = (("normal_flight", "E8"), ("normal_flight", "E9"), ("add_weight_W1_near_M3", "E9"),
           ("add_weight_W1_near_M4", "E8"))
COMMANDS = ("cmd_thrust", "cmd_roll", "cmd_pitch", "cmd_yaw")


def logged(folder, drone):
    """Mean and spread over the flights of each logged command's hover mean."""
    means = []
    for path in sorted((DATA / "controller_data" / folder).glob(f"{drone}_*")):
        _, events = parse_usd(path)
        t, v = events["fixedFrequency"]
        z = v["stateEstimate.z"]
        up = np.nonzero(z > 0.9 * np.median(z[z > 0.2]))[0]
        keep = (t >= t[up[0]] + 3.0) & (t <= t[up[-1]] - 1.0) & (z > 0.9 * np.median(z[z > 0.2]))
        means.append([np.mean(v[f"controller.{c}"][keep]) for c in COMMANDS])
    means = np.array(means)
    return means.mean(axis=0), means.max(axis=0) - means.min(axis=0), len(means)


def main(out):
    t0 = time.perf_counter()
    k_loop = constants()["THRUST_MAX"] / 65535          # N per unit, per rotor
    k_logged = CRAZYFLIE_FIRMWARE_COMMAND.coefficients[1]
    scale = k_loop / k_logged
    lines = ["| folder | drone | identified mass (g) | identified x_G, y_G (mm) | command | "
             "simulated (loop's unit) | simulated (logged unit) | logged: mean over flights | "
             "spread | flights |", "|---|---|---|---|---|---|---|---|---|---|"]
    for folder, drone in FOLDERS:
        motor_logs = sorted((DATA / "motor_data" / folder).glob(f"{drone}_*"))
        ident = identify(motor_logs, "crazyflie")
        x_G, y_G, _ = ident.r_G
        vehicle = CRAZYFLIE_21.replace(m=ident.mass).with_cog([x_G, y_G, 0.0])
        res = simulate("pid", Hover(position=(0.0, 0.0, 0.5)), 15.0, vehicle=vehicle,
                       truth=TruthOptions(motor_lag=True))
        sim = [res.info["log"][f"controller.{c}"][-3000:].mean() for c in COMMANDS]
        mean, spread, n = logged(folder, drone)
        for c, s, m, d in zip(COMMANDS, sim, mean, spread):
            lines.append(f"| {folder} | {drone} | {1000 * ident.mass:.2f} | "
                         f"{1000 * x_G:+.2f}, {1000 * y_G:+.2f} | {c} | {s:.0f} | "
                         f"{s * scale:.0f} | {m:.0f} | {d:.0f} | {n} |")
            print(lines[-1], flush=True)
    m = machine()
    text = (f"# The firmware PID in the loop against the CrazyPAD flights\n\nRan on {m['cpu']} "
            f"({m['machine']}), {m['cores']} cores, {time.strftime('%Y-%m-%d')}; "
            f"{time.perf_counter() - t0:.0f} s (`make crazyflie`); k_loop / k_logged = "
            f"{scale:.4f}\n\n" + "\n".join(lines) + "\n")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "out" / "crazyflie" / "real-flights.md")
