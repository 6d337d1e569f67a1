"""Side by side on the Crazyflie 2.1: the firmware's five controllers (default gains, in the
loop of quadcog.crazyflie) against quadcog's laws (quadcog.simulate), over the cases of issue 30.
A script that prints a table and writes it (no assertions):

    python bench/crazyflie.py [OUT]      # default out/crazyflie/side-by-side.md (make crazyflie)

Every flight has the same truth (parallel-axis inertia, rotor saturation at the firmware's
THRUST_MAX of 0.12 N, 12.5 ms motor lag) and starts at the reference. quadcog's laws are
designed for the firmware's CF_MASS vehicle (29 g) with the CoG at O, as the firmware's
controllers are; the sensing case adds quadcog's realistic noise and gyroscope bias
(``Sensing(delay=False)``) to what both are told.

The firmware's controllers start from their zero state at t = 0 (as after arming: its first
tick sends no thrust, INDI's filters start at 0), quadcog's at their hover state; the columns
after the event leave that start-up out except where the event is the start (the 37 g case).

Columns: diverged (when), tail RMS position error (last quarter, cm), largest excursion (the
largest position error from the event on, cm), settling time (s from the case's event until the error stays
below 2 cm; "never" when it does not within the flight), time at a motor limit (share of the
samples at which a rotor is at 0 N or at THRUST_MAX).
"""
from pathlib import Path
import sys
import time

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.machine import loadavg, machine  # noqa: E402
from quadcog import simulate as quadcog_simulate  # noqa: E402
from quadcog.controllers.registry import make_controller  # noqa: E402
from quadcog.crazyflie import simulate as firmware_simulate  # noqa: E402
from quadcog.sim.plant import TruthOptions  # noqa: E402
from quadcog.sim.sensing import Sensing  # noqa: E402
from quadcog.trajectories.analytic import Circle, Hover  # noqa: E402
from quadcog.vehicles.vehicle import CRAZYFLIE_21  # noqa: E402

FIRMWARE = ("pid", "mellinger", "indi", "brescianini", "lee")
LAWS = ("composite", "payload_adaptive")
TRUTH = TruthOptions(parallel_axis=True, rotor_saturation=True, motor_lag=True)
DURATION = 10.0
SETTLED = 0.02        # m
HOVER = Hover(position=(0.0, 0.0, 1.0))
# (name, event time (s), flight settings)
CASES = (
    ("taped weight: 2 g at M1, 42 mm out", 1.0,
     dict(payloads=[dict(t=1.0, action="attach", name="tape", mass=0.002,
                         position=(0.03, -0.03, 0.0))])),
    ("payload +20 %: picked up at 1 s, dropped at 6 s", 1.0,
     dict(payloads=[dict(t=1.0, action="attach", name="parcel", mass=0.0058,
                         position=(0.0, 0.0, -0.01)),
                    dict(t=6.0, action="drop", name="parcel")])),
    ("CF_MASS 29 g, vehicle 37 g", 0.0, dict(vehicle=CRAZYFLIE_21.replace(m=0.037))),
    ("CoG step (5, 5, 0) mm at 2 s on a circle", 2.0,
     dict(trajectory=Circle(center=(0.0, 0.0, 1.0), radius=0.5, period=8.0),
          cog=[(2.0, (0.005, 0.005, 0.0), 0.0)])),
    ("hover with sensing noise (from 1 s)", 1.0, dict(sensing=Sensing(delay=False, seed=1))),
)


def _row(res, event):
    m = res.metrics
    e = np.linalg.norm(res.x[:, :3] - res.ref[:, :3], axis=1)
    after = res.t >= event
    over = np.nonzero(after & (e > SETTLED))[0]
    if m.diverged:
        settle = "-"
    elif over.size == 0:
        settle = "0.00"
    elif over[-1] == len(e) - 1:
        settle = "never"
    else:
        settle = f"{res.t[over[-1] + 1] - event:.2f}"
    f = res.rotor_thrust
    at_limit = np.mean((f <= 1e-9).any(axis=1) | (f >= CRAZYFLIE_21.max_rotor_thrust - 1e-9)
                       .any(axis=1))
    return ("at %.2f s" % m.diverged_at if m.diverged else "no",
            f"{100 * m.rms_position_error_tail:.2f}" if not m.diverged else "-",
            f"{100 * e[after].max():.2f}", settle, f"{100 * at_limit:.1f} %")


def _fly(controller, settings):
    s = dict(settings)
    trajectory = s.pop("trajectory", HOVER)
    vehicle = s.pop("vehicle", CRAZYFLIE_21)
    if controller in FIRMWARE:
        return firmware_simulate(controller, trajectory, DURATION, vehicle=vehicle, truth=TRUTH,
                                 log=(), **s)
    law = make_controller(controller, vehicle=CRAZYFLIE_21)
    return quadcog_simulate(law, trajectory, DURATION, vehicle=vehicle,
                            controller_model=CRAZYFLIE_21, truth=TRUTH, **s)


def main(out):
    t0 = time.perf_counter()
    lines = ["| case | controller | diverged | tail RMS (cm) | largest excursion (cm) | "
             "settling (s) | time at a motor limit |", "|---|---|---|---|---|---|---|"]
    for case, event, settings in CASES:
        for controller in FIRMWARE + LAWS:
            res = _fly(controller, settings)
            who = f"firmware {controller}" if controller in FIRMWARE else f"quadcog {controller}"
            lines.append(f"| {case} | {who} | " + " | ".join(_row(res, event)) + " |")
            print(lines[-1], flush=True)
    m = machine()
    text = (f"# Side by side on the Crazyflie 2.1\n\nRan on {m['cpu']} ({m['machine']}), "
            f"{m['cores']} cores, {m['compiler']}, {time.strftime('%Y-%m-%d')}; load {loadavg()}; "
            f"{time.perf_counter() - t0:.0f} s for {len(CASES) * (len(FIRMWARE) + len(LAWS))} "
            f"flights of {DURATION:g} s (`make crazyflie`)\n\n" + "\n".join(lines) + "\n")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "out" / "crazyflie" / "side-by-side.md")
