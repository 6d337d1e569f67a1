"""PX4 in the loop, measured: the simulator link's MAVLink codec (struct against pymavlink's
generated codec) and, where PX4 is built in the cache, the lockstep flights of the shipped PX4
scenarios with their speed (simulated seconds per wall second) and the CPU each side used.

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

__all__ = ["codec_rows", "flight_rows", "main"]

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


def flight_rows(out: Path):
    """Fly the shipped PX4 scenarios (when PX4 is built in the cache).

    Parameters
    ----------
    out : pathlib.Path
        Where each flight's folder goes.

    Returns
    -------
    list of tuple
        (scenario, simulated s in lockstep, wall s, speed x, PX4 CPU s, quadcog CPU s,
        idle-machine speed x, what flew), or [] without a build.
    """
    from quadcog.px4 import fly, scenario_path
    from quadcog.px4.tree import cached_build
    if cached_build() is None:
        print("PX4 is not built in the cache: `make px4-build` first (flights skipped)")
        return []
    rows = []
    for name in ("px4-hover", "px4-payload"):
        f = fly(scenario_path(name), out=out / name)
        r = f.recording
        what = ("partial: " + r.reason) if f.partial else (
            f"armed {r.armed_at:.1f} s, disarmed {r.disarmed_at:.1f} s")
        rows.append((name, r.lockstep_seconds, r.wall_seconds, f.speed, r.cpu_px4,
                     r.cpu_quadcog, r.lockstep_seconds / max(r.cpu_px4 + r.cpu_quadcog, 1e-9),
                     what))
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
    print(f"CPU: {cpu_model()}; load average before: {loadavg()}\n")
    print("| simulator-link message | quadcog (struct) us | pymavlink us |")
    print("|---|---:|---:|")
    for op, ours, theirs in codec_rows():
        print(f"| {op} | {ours:.1f} | {'' if theirs is None else f'{theirs:.1f}'} |")
    if args.codec_only:
        return 0
    rows = flight_rows(args.out)
    if rows:
        print("\n| scenario | lockstep s | wall s | speed x | PX4 CPU s | quadcog CPU s | "
              "idle-machine speed x | flight |")
        print("|---|---:|---:|---:|---:|---:|---:|---|")
        for name, sim, wall, speed, cpx, cq, idle, what in rows:
            print(f"| {name} | {sim:.1f} | {wall:.1f} | {speed:.1f} | {cpx:.2f} | {cq:.2f} | "
                  f"{idle:.1f} | {what} |")
        print(f"\nload average after: {loadavg()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
