"""The figures of docs/logs.md: every Crazyflie uSD log under a folder read with quadcog.logs
and measured (time base, flights, heights, battery, motors, derivatives, signs).

    .venv/bin/python docs/logs_survey.py tests/data/crazypad      # or the whole CrazyPAD set
"""
from pathlib import Path
import sys

import numpy as np
from scipy.integrate import cumulative_trapezoid

from quadcog.logs import read_log
from quadcog.logs.checks import airborne_segments, bandpass, fit_gain, lowpass

G = 9.81
flights, fit = airborne_segments, fit_gain


def span(values, fmt="{:.3g}"):
    values = np.asarray(values, dtype=float)
    return f"{fmt.format(values.min())}..{fmt.format(values.max())}"


def main(folder):
    files = sorted(p for p in Path(folder).rglob("E*_log*") if p.is_file())
    rows, pooled = [], {"ay": [], "rhs": [], "rhs_flip_yaw": []}
    summary = {k: [] for k in ("records", "duration", "rate_E8", "rate_E9", "lost", "lost_until",
                               "hover_z", "ground_z", "x_max", "y_abs", "takeoff", "landing",
                               "retakeoff", "end_z", "vbat", "sat", "vx_gain", "vz_gain",
                               "vz_corr", "ax_gain", "az_gain", "pwm_err", "yaw_range",
                               "q_corr", "p_corr", "zero_run", "m13", "m24", "vx_corr",
                               "late_step", "sat_t")}
    for path in files:
        log = read_log(path)
        name = path.relative_to(folder).as_posix()
        t, steps = log.t, np.diff(log.t)
        med = np.median(steps)
        gaps = steps > 1.5 * med
        z = log.signal("position")[:, 2]
        segs = flights(log)
        up = np.flatnonzero(z > 0.3)
        down = np.flatnonzero((z < 0.3) & (t > t[up[0]] + 1))
        summary["records"].append(log.n_samples)
        summary["duration"].append(t[-1])
        summary["rate_" + path.name[:2]].append(1 / med)
        summary["lost"].append(np.sum(steps[gaps] / med - 1))
        summary["lost_until"].append(t[1:][gaps].max() if gaps.any() else 0.0)
        late = steps[t[1:] > 1.0] / med
        summary["late_step"] += [late.min(), late.max()]
        summary["hover_z"] += [np.median(z[s]) for s in segs]
        summary["takeoff"].append(t[up[0]])
        summary["landing"].append(t[down[0]])
        again = np.flatnonzero((z > 0.3) & (t > t[down[0]]))
        summary["retakeoff"].append(t[again[0]])
        summary["end_z"].append(z[-1])
        ground = (t > t[down[0]] + 1.5) & (t < t[again[0]] - 1.0)
        summary["ground_z"].append(np.median(z[ground]))
        p = log.signal("position")
        summary["x_max"].append(p[:, 0].max())
        airborne = np.concatenate([np.flatnonzero(s) for s in segs])
        summary["y_abs"].append(np.abs(p[airborne, 1]).max())
        row = f"| {name} | {log.n_samples} | {1 / med:.2f} | {int(round(summary['lost'][-1]))} |"
        row += " ".join(f" {np.median(z[s]):.3f}" for s in segs) + " |"
        if log.has("motor_command"):
            v, a = lowpass(log.signal("velocity")), lowpass(log.signal("acceleration"))
            dp = np.gradient(lowpass(p), t, axis=0)
            dv = np.gradient(v, t, axis=0)
            for s in segs:
                g, c = fit(dp[s, 0], v[s, 0])
                summary["vx_gain"].append(g)
                summary["vx_corr"].append(c)
                g, c = fit(dp[s, 2], v[s, 2])
                summary["vz_gain"].append(g)
                summary["vz_corr"].append(c)
                summary["ax_gain"].append(fit(dv[s, 0], a[s, 0])[0])
                summary["az_gain"].append(fit(dv[s, 2], a[s, 2])[0])
            vb = log.signal("battery_voltage")
            summary["vbat"] += [vb.min(), vb.max()]
            m = log.signal("motor_command")
            summary["sat"].append(np.mean(m.max(axis=1) >= 0.999))
            summary["sat_t"] += t[m.max(axis=1) >= 0.999].tolist()
            for k in range(4):
                thrust = m[:, k] * 65535 / 65536 * 60
                pwm = np.minimum((-0.0006239 * thrust ** 2 + 0.088 * thrust) / vb, 1) * 65535
                on = m[:, k] * 65535 > 1000
                summary["pwm_err"].append(np.abs(pwm[on] - log.signal("motor_pwm")[on, k]
                                                 * 65535).max())
            hover = np.median(np.concatenate([m[s] for s in segs]), axis=0)
            summary["m13"] += [hover[0], hover[2]]
            summary["m24"] += [hover[1], hover[3]]
            yaw = np.degrees(np.unwrap(log.signal("yaw")))
            summary["yaw_range"] += [yaw[np.concatenate([np.flatnonzero(s) for s in segs])].min(),
                                     yaw[np.concatenate([np.flatnonzero(s) for s in segs])].max()]
            phi, psi = lowpass(log.signal("roll")), lowpass(np.unwrap(log.signal("yaw")))
            for s in segs:
                pooled["ay"].append(-np.sin(psi[s]) * a[s, 0] + np.cos(psi[s]) * a[s, 1])
                pooled["rhs"].append(-G * np.sin(phi[s]))
                pooled["rhs_flip_yaw"].append((np.sin(psi[s]) * a[s, 0] + np.cos(psi[s])
                                               * a[s, 1], -G * np.sin(phi[s])))
            split = [(-hover[0] - hover[1] + hover[2] + hover[3]) / 4,
                     (-hover[0] + hover[1] + hover[2] - hover[3]) / 4,
                     -(hover[0] - hover[1] + hover[2] - hover[3]) / 4]
            row += (f" {np.round(hover, 3).tolist()}, splits {np.round(split, 4).tolist()} | "
                    f"{vb.min():.2f}..{vb.max():.2f} |")
        else:
            zero = log.raw["controller.cmd_thrust"] == 0
            airborne_zero = zero & (t > t[up[0]]) & (t < t[again[0]])
            summary["zero_run"].append(airborne_zero.sum() * med)
            angle = bandpass(cumulative_trapezoid(log.signal("body_rates"), t, axis=0, initial=0))
            acc = np.gradient(np.gradient(bandpass(p), t, axis=0), t, axis=0)
            for s in segs:
                summary["q_corr"].append(np.corrcoef(angle[s, 1], acc[s, 0] / G)[0, 1])
                summary["p_corr"].append(np.corrcoef(angle[s, 0], -acc[s, 1] / G)[0, 1])
            mc = np.median(np.concatenate([log.signal("moment_command")[s] for s in segs]),
                           axis=0)
            tc = np.median(np.concatenate([log.signal("thrust_command")[s] for s in segs]))
            row += f" thrust {tc:.3f}, moments {np.round(mc, 4).tolist()} | |"
        rows.append(row)
    print("| file | records | rate (Hz) | lost records | hover z (m) per flight | hover motor "
          "commands M1..M4 and splits [m_x, m_y, m_z], or controller commands | battery (V) |")
    print("|---|---|---|---|---|---|---|")
    print("\n".join(rows))
    print()
    s = summary
    print(f"files: {len(files)}; records {span(s['records'], '{:.0f}')}; duration "
          f"{span(s['duration'], '{:.2f}')} s")
    for drone in ("E8", "E9"):
        if s["rate_" + drone]:
            print(f"rate of {drone}: {span(s['rate_' + drone], '{:.3f}')} Hz")
    print(f"records lost (steps > 1.5 x median): {span(s['lost'], '{:.0f}')} per file, all "
          f"before t = {max(s['lost_until']):.2f} s; after 1 s the steps are "
          f"{span(s['late_step'], '{:.3f}')} x the median")
    print(f"take-off (z > 0.3 m) at {span(s['takeoff'], '{:.2f}')} s, landing at "
          f"{span(s['landing'], '{:.2f}')} s, second take-off at {span(s['retakeoff'], '{:.2f}')} "
          f"s, z at the end of the log {span(s['end_z'], '{:.3f}')} m")
    print(f"hover z (median per flight): {span(s['hover_z'], '{:.3f}')} m; z on the ground "
          f"between the flights: {span(s['ground_z'], '{:.3f}')} m")
    print(f"x reaches {span(s['x_max'], '{:.2f}')} m; |y| in flight at most "
          f"{max(s['y_abs']):.3f} m")
    if s["vbat"]:
        print(f"battery {span(s['vbat'], '{:.2f}')} V; samples with a motor command >= 0.999: "
              f"{span(np.array(s['sat']) * 100, '{:.1f}')} %, at t = "
              f"{span(s['sat_t'], '{:.2f}')} s")
        print(f"hover motor commands: M1, M3 {span(s['m13'], '{:.3f}')}; M2, M4 "
              f"{span(s['m24'], '{:.3f}')}")
        print(f"vx vs dx/dt gain {span(s['vx_gain'], '{:.2f}')} (correlation "
              f"{span(s['vx_corr'], '{:.3f}')}); vz vs dz/dt gain "
              f"{span(s['vz_gain'], '{:.2f}')} (correlation {span(s['vz_corr'], '{:.2f}')})")
        print(f"ax vs dvx/dt gain {span(s['ax_gain'], '{:.2f}')}; az vs dvz/dt gain "
              f"{span(s['az_gain'], '{:.2f}')}")
        print(f"pwm vs the firmware's battery compensation of motor: at most "
              f"{max(s['pwm_err']):.0f} counts of 65535")
        print(f"yaw in flight: {span(s['yaw_range'], '{:.1f}')} deg")
        gain, corr = fit(np.concatenate(pooled["rhs"]), np.concatenate(pooled["ay"]))
        flip = [fit(r, a) for a, r in pooled["rhs_flip_yaw"]]
        gf, cf = fit(np.concatenate([r for _, r in pooled["rhs_flip_yaw"]]),
                     np.concatenate([a for a, _ in pooled["rhs_flip_yaw"]]))
        print(f"lateral acceleration vs -g sin(roll), pooled: gain {gain:.2f}, correlation "
              f"{corr:.2f}; with the yaw sign flipped: gain {gf:.2f}, correlation {cf:.2f}"
              f" ({len(flip)} flights)")
    if s["zero_run"]:
        print(f"controller commands exactly 0 between the flights for "
              f"{span(s['zero_run'], '{:.2f}')} s")
        print(f"integrated q vs x''/g correlation {span(s['q_corr'], '{:.2f}')}; integrated p vs "
              f"-y''/g {span(s['p_corr'], '{:.2f}')}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "tests/data/crazypad"))
