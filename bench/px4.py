"""PX4 in the loop, measured (`make px4`): the simulator link's MAVLink codec (struct against
pymavlink's generated codec) and, where PX4 is built in the cache, the lockstep flights of the
shipped PX4 scenarios with their speed (simulated seconds per wall second) and the CPU each
side used, `quadcog identify` on the ULogs PX4 wrote, and PX4's controllers side by side with
quadcog's laws.

    .venv/bin/python bench/px4.py [--codec-only] [--out out/px4]

Prints markdown tables (no assertions): the machine and its load first, since the lockstep
speed depends on both (PX4 and quadcog take turns, so the idle-machine speed is about
simulated time / (PX4's CPU + quadcog's CPU)).
"""
import argparse
from pathlib import Path
import sys
import time

sys.path.insert(0, str(Path(__file__).resolve().parent))

from machine import loadavg  # noqa: E402

from quadcog.files import cpu_model  # noqa: E402
from quadcog.px4.mavlink import MESSAGES, FrameReader, frame, pack_hil_sensor, unpack_hil_actuator_controls  # noqa: E402

__all__ = ["SIDE_CASES", "codec_rows", "flights", "flight_rows", "identification_rows",
           "side_by_side_rows", "main"]

_SENSOR = (123456789, (0.25, -0.5, -9.75), (0.01, -0.02, 0.03), (0.21, 0.013, 0.43), 955.98,
           0.0, 488.0, 11.8)


def _per_call(fn, n=20000):
    fn()
    t0 = time.perf_counter()
    for _ in range(n):
        fn()
    return (time.perf_counter() - t0) / n * 1e6


def codec_rows():
    """Microseconds per message: packing a HIL_SENSOR frame and reading a
    HIL_ACTUATOR_CONTROLS frame, with quadcog's struct codec and with pymavlink's.

    Returns
    -------
    list of tuple
        (operation, quadcog us, pymavlink us or None).
    """
    seq = [0]

    def ours_pack():
        seq[0] += 1
        return frame(MESSAGES["HIL_SENSOR"], pack_hil_sensor(*_SENSOR), seq[0])

    import struct
    controls = frame(MESSAGES["HIL_ACTUATOR_CONTROLS"],
                     struct.pack("<2Q16fB", 4000, 1, *([0.7] * 4 + [0.0] * 12), 129), 1)
    reader = FrameReader({93})

    def ours_read():
        for _, _, _, p, _ in reader.feed(controls):
            unpack_hil_actuator_controls(p)

    rows = [["HIL_SENSOR: pack and frame", _per_call(ours_pack), None],
            ["HIL_ACTUATOR_CONTROLS: split, check and read", _per_call(ours_read), None]]
    try:
        from pymavlink.dialects.v20 import common as c
    except ImportError:
        return rows
    mav = c.MAVLink(None, srcSystem=1, srcComponent=200)
    t, acc, gyro, mag, p, dp, alt, temp = _SENSOR
    rows[0][2] = _per_call(lambda: c.MAVLink_hil_sensor_message(
        t, *acc, *gyro, *mag, p, dp, alt, temp, 0x1FFF, 0).pack(mav))
    parser = c.MAVLink(None)
    rows[1][2] = _per_call(lambda: parser.parse_buffer(controls))
    return [tuple(r) for r in rows]


def _fly(name, out, overrides=(), seed=1):
    from quadcog.px4 import fly, scenario_path
    return fly(scenario_path(name), out=out, overrides=overrides + (f"sensing.seed={seed}",))


def flights(out: Path):
    """Fly the PX4 flights of the tables (when PX4 is built in the cache).

    Parameters
    ----------
    out : pathlib.Path
        Where each flight's folder goes.

    Returns
    -------
    dict or None
        name -> Px4Flight: the hover and mission flights with the parcel, their baselines
        without it, a second baseline (another noise seed) where nothing changed, and the
        hover with a CoG step; None without a build.
    """
    from quadcog.px4.tree import cached_build
    if cached_build() is None:
        print("PX4 is not built in the cache: `make px4-build` first (flights skipped)")
        return None
    none = ('payload=[]',)
    plan = {"px4-payload": ("px4-payload", (), 1),
            "px4-payload, no parcel": ("px4-payload", none, 2),
            "px4-payload, no parcel, again": ("px4-payload", none, 3),
            "px4-mission": ("px4-mission", (), 1),
            "px4-mission, no parcel": ("px4-mission", none, 2),
            "px4-cog-step": ("px4-cog-step", (), 1)}
    return {key: _fly(name, out / key.replace(", ", "-").replace(" ", "-"), over, seed)
            for key, (name, over, seed) in plan.items()}


def flight_rows(done):
    """Rows of the speed table.

    Parameters
    ----------
    done : dict
        ``flights``'s.

    Returns
    -------
    list of tuple
        (flight, simulated s in lockstep, wall s, speed x, PX4 CPU s, quadcog CPU s,
        idle-machine speed x, what flew).
    """
    rows = []
    for name, f in done.items():
        r = f.recording
        what = ("partial: " + r.reason) if f.partial else (
            f"armed {r.armed_at:.1f} s, disarmed {r.disarmed_at:.1f} s")
        rows.append((name, r.lockstep_seconds, r.wall_seconds, f.speed, r.cpu_px4,
                     r.cpu_quadcog, r.lockstep_seconds / max(r.cpu_px4 + r.cpu_quadcog, 1e-9),
                     what))
    return rows


def identification_rows(done):
    """`quadcog identify` on PX4's ULogs against a baseline flight without the parcel.

    Parameters
    ----------
    done : dict
        ``flights``'s.

    Returns
    -------
    list of tuple
        (flight, baseline, true shift x, y (mm), found x, y (mm) with 95 % half-widths,
        true mass (kg), found mass (kg), mass error (%)).
    """
    from quadcog.px4.identify import identify_flight
    cases = (("px4-payload", "px4-payload, no parcel"),
             ("px4-mission", "px4-mission, no parcel"),
             ("px4-payload, no parcel, again", "px4-payload, no parcel"),
             ("px4-cog-step", "px4-payload, no parcel"))
    rows = []
    for flight, base in cases:
        r = identify_flight(done[flight], done[base])
        i = r.identification
        half = [h if h is not None else float("nan") for h in i.r_G_ci95]
        rows.append((flight, base, 1e3 * r.true_shift[0], 1e3 * r.true_shift[1],
                     1e3 * i.r_G[0], 1e3 * half[0], 1e3 * i.r_G[1], 1e3 * half[1],
                     r.true_mass, i.mass, 100 * (i.mass - r.true_mass) / r.true_mass))
    return rows


# (case, flight, span start, span end (s of scenario time))
SIDE_CASES = (("hover, parcel picked up", "px4-payload", 25.0, 50.0),
              ("waypoint mission, parcel picked up", "px4-mission", 25.0, 60.0),
              ("hover, CoG step", "px4-cog-step", 25.0, 50.0))
PX4_SEES = "EKF2 of the IMU (Sensing()), GPS, baro, mag"
TRUE_STATE = "true state"
SENSED = "Sensing(): noise, gyro bias, 1-period delay"


def side_by_side_rows(done):
    """PX4's controllers (default parameters) against quadcog's laws on each case's vehicle,
    events and trajectory (``SIDE_CASES``), over the same span of scenario time (from the
    event to the end of the trajectory).

    PX4's error is against the position setpoint its position controller tracked (the ULog's
    ``vehicle_local_position_setpoint``: the hold point, or the path between waypoints), the
    laws' against the scenario's trajectory; PX4 sees its EKF2's estimate of the sensors made
    from quadcog's Sensing model, each law flies twice: on the true state and with the same
    Sensing model (``quadcog.Sensed``) at its 1 kHz.

    Parameters
    ----------
    done : dict
        ``flights``'s.

    Returns
    -------
    list of tuple
        (case, span, state seen, Comparison), PX4 first in each case.
    """
    from quadcog.px4 import scenario_path
    from quadcog.px4.compare import compare, setpoint_reference
    from quadcog.scenarios.scenario import load_scenario
    rows = []
    for case, name, t0, t1 in SIDE_CASES:
        f = done[name]
        vehicle = f.scenario.vehicle
        ref = setpoint_reference(f.ulog, f.result.t)
        rows.append((case, (t0, t1), PX4_SEES,
                     compare("PX4 (EKF2, mc_pos/att/rate_control)", f.result, vehicle, t0, t1,
                             offset=f.recording.armed_at or 0.0, diverged=f.partial,
                             reference=ref)))
        for law in ("pd", "payload_adaptive"):
            for seen, extra in ((TRUE_STATE, ()), (SENSED, ("sensing.seed=1",))):
                sc = load_scenario(scenario_path(name), (f"controller={law!r}",) + extra)
                rows.append((case, (t0, t1), seen,
                             compare(f"quadcog {law}", sc.run(), vehicle, t0, t1)))
    return rows


def main(argv=None):
    """Print the tables.

    Parameters
    ----------
    argv : list of str, optional
        ``[--codec-only] [--out DIR]``.

    Returns
    -------
    int
        0.
    """
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--codec-only", action="store_true")
    ap.add_argument("--out", type=Path, default=Path("out/px4"))
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    load_before = loadavg()
    print(f"CPU: {cpu_model()}; load average before: {load_before}\n")
    print("| simulator-link message | quadcog (struct) us | pymavlink us |")
    print("|---|---:|---:|")
    for op, ours, theirs in codec_rows():
        print(f"| {op} | {ours:.1f} | {'' if theirs is None else f'{theirs:.1f}'} |")
    if args.codec_only:
        return 0
    done = flights(args.out)
    if done is None:
        return 0
    from quadcog.px4.tree import cached_build
    built = cached_build()
    machine = (f"{time.strftime('%Y-%m-%d')}, CPU: {cpu_model()}, 2 cores shared with other "
               f"work (load average {load_before} before the flights, {loadavg()} after); "
               f"PX4 {built.commit()} "
               f"(PX4-Autopilot main 02e73e3b6f, tree {built.key}), airframe 10016 with the "
               f"x500's parameters, lockstep period 4 ms, plant dt 1 ms.")
    speed = ["| flight | lockstep s | wall s | speed x | PX4 CPU s | quadcog CPU s | "
             "idle-machine speed x | flight |", "|---|---:|---:|---:|---:|---:|---:|---|"]
    for name, sim, wall, sp, cpx, cq, idle, what in flight_rows(done):
        speed.append(f"| {name} | {sim:.1f} | {wall:.1f} | {sp:.1f} | {cpx:.2f} | {cq:.2f} | "
                     f"{idle:.1f} | {what} |")
    ident = ["| ULog | baseline | true x_G mm | true y_G mm | found x_G mm (95 %) | "
             "found y_G mm (95 %) | truth within the interval x, y | true mass kg | "
             "found mass kg | mass error % |",
             "|---|---|---:|---:|---:|---:|---|---:|---:|---:|"]
    for fl, base, tx, ty, x, hx, y, hy, tm, m, err in identification_rows(done):
        inside = ", ".join("yes" if abs(f - t) <= h else f"no ({abs(f - t):.3f} mm off)"
                           for f, t, h in ((x, tx, hx), (y, ty, hy)))
        ident.append(f"| {fl} | {base} | {tx:+.3f} | {ty:+.3f} | {x:+.3f} +- {hx:.3f} | "
                     f"{y:+.3f} +- {hy:.3f} | {inside} | {tm:.3f} | {m:.4f} | {err:+.2f} |")
    from quadcog.px4.compare import settling_text
    side = ["| case (span, s from arming / start) | who flies | state it sees | diverged | "
            "tail RMS m | largest m | settling s (5 cm) | at a rotor limit s |",
            "|---|---|---|---|---:|---:|---:|---:|"]
    for case, (t0, t1), seen, c in side_by_side_rows(done):
        side.append(f"| {case} ({t0:g}..{t1:g}) | {c.name} | {seen} | "
                    f"{'yes' if c.diverged else 'no'} | {c.tail_rms:.4f} | {c.largest:.4f} | "
                    f"{settling_text(c.settling)} | {c.at_limit:.2f} |")
    for name, table in (("speed", speed), ("identify", ident), ("side", side)):
        text = f"# PX4 in the loop: {name}\n\n{machine}\n\n" + "\n".join(table) + "\n"
        (args.out / f"{name}.md").write_text(text)
        print("\n" + "\n".join(table))
    print(f"\n{machine}\nwritten: {', '.join(str(args.out / f'{n}.md') for n in ('speed', 'identify', 'side'))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
