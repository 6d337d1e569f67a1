"""The round trip of docs/identify.md: a simulated Crazyflie hover with a known CoG, logged in
each format, read back and identified by both estimators; z_G forced at hover; a circle.

    .venv/bin/python docs/identify_roundtrip.py
"""
from pathlib import Path
import tempfile

import numpy as np

from quadcog import CRAZYFLIE, Circle, Sensed, Sensing, make_controller, simulate
from quadcog.identification import identify
from quadcog.identification.estimators import regression
from quadcog.identification.simulated import simulated_log
from quadcog.logs import LOG_FORMATS, read_log, write_log
from quadcog.vehicles.rotor_model import px4_thrust_curve

R_TRUE = np.array([0.004, -0.003, 0.002])
EXTENSIONS = {"crazyflie-usd": "", "ulog": ".ulg", "csv": ".csv", "parquet": ".parquet"}


def main():
    vehicle = CRAZYFLIE.with_cog(R_TRUE)
    sensing = Sensing(seed=1)
    ctl = Sensed(make_controller("fl_integral", vehicle=CRAZYFLIE), sensing, 0.001)
    result = simulate(ctl, "hover", duration=20.0, dt=0.001, vehicle=vehicle)
    print(f"true r_G = {1e3 * R_TRUE} mm")
    with tempfile.TemporaryDirectory() as tmp:
        for fmt in LOG_FORMATS:
            v = vehicle if fmt != "ulog" else vehicle.replace(
                rotor_model=px4_thrust_curve(2 * vehicle.max_rotor_thrust, 0.5))
            log = simulated_log(result, v, sensing=sensing)
            back = read_log(write_log(log, Path(tmp) / f"flight{EXTENSIONS[fmt]}", fmt))
            for method in ("static", "regression"):
                res = identify(back, v.with_cog(np.zeros(3)), method=method)
                err = 1e3 * (np.array(res.r_G[:2]) - R_TRUE[:2])
                half = 1e3 * np.array(res.r_G_ci95[:2])
                print(f"{fmt:13s} {method:10s} error x, y = {err[0]:+.4f}, {err[1]:+.4f} mm, "
                      f"95 % half-widths {half[0]:.4f}, {half[1]:.4f} mm, "
                      f"mass {1e3 * res.mass:.3f} g")
    forced = regression(simulated_log(result, vehicle, sensing=sensing), CRAZYFLIE, min_tilt=0.0)
    print(f"z_G forced at hover: {1e3 * forced.r_G[2]:+.2f} +- {1e3 * forced.r_G_ci95[2]:.2f} mm "
          f"(true {1e3 * R_TRUE[2]:.1f} mm)")
    # a 0.6 m circle in 2.5 s: 23 deg of tilt
    r = np.array([0.004, -0.003, 0.003])
    vehicle = CRAZYFLIE.with_cog(r)
    for label, s in (("no noise", Sensing(noise=False, delay=False)), ("*-real noise", sensing)):
        ctl = Sensed(make_controller("fl_integral", vehicle=CRAZYFLIE), s, 0.001)
        result = simulate(ctl, Circle(radius=0.6, period=2.5), duration=20.0, dt=0.001,
                          vehicle=vehicle)
        tilt = np.degrees(np.abs(result.x[:, 3:5]).max())
        for method in ("static", "regression"):
            res = identify(simulated_log(result, vehicle, sensing=s), CRAZYFLIE, method=method)
            err = 1e3 * (np.array(res.r_G) - r)
            half = [None if h is None else round(1e3 * h, 4) for h in res.r_G_ci95]
            print(f"circle ({tilt:.0f} deg), {label:12s} {method:10s} error "
                  f"{err[0]:+.4f}, {err[1]:+.4f}, {err[2]:+.3f} mm, half-widths {half} mm")


if __name__ == "__main__":
    main()
