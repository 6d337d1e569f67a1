"""`quadcog animate RUN_DIR`: the flight of a run folder as a 3D GIF (matplotlib + Pillow).

Each frame shows the body axes (x red, y green, z blue), the arms and rotor discs, the CoG
(filled dot) and its estimate (open dot) at their offsets from O, the trail flown so far, the
reference (dashed) with its current point, and the time. The vehicle is magnified by one
factor, stated in the title, so that it is visible on the scale of the path; the CoG offset is
drawn with the same factor, so it is to scale with the body.
"""
import json
from pathlib import Path

import numpy as np

from quadcog.errors import InputError
from quadcog.model import columns as col
from quadcog.model.conventions import rotation_matrix

ROTOR_RADIUS = 0.3         # rotor disc radius as a fraction of the arm length (drawing only)


def read_run(run_dir):
    """(table (N, 37), metrics dict, Vehicle) of a folder written by `quadcog run`."""
    from quadcog.vehicles.vehicle import HUMMINGBIRD, Vehicle
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise InputError(f"run folder {run_dir}: no such folder (write one with "
                         f"`quadcog run SCENARIO --out {run_dir}`)")
    csv_path, pq_path = run_dir / "trajectory.csv", run_dir / "trajectory.parquet"
    names = col.trajectory_columns()
    if csv_path.is_file():
        header = csv_path.open().readline().strip().split(",")
        if tuple(header) == names[:col.ROTOR_COMMAND.start]:     # a folder of before rotor columns
            names = tuple(header)
        if tuple(header) != names:
            raise InputError(f"{csv_path}: unexpected columns (expected those of "
                             f"quadcog.model.columns.trajectory_columns(), starting {names[:3]})")
        table = np.loadtxt(csv_path, delimiter=",", skiprows=1, ndmin=2)
    elif pq_path.is_file():
        import pyarrow.parquet as pq
        t = pq.read_table(pq_path)
        table = np.column_stack([t.column(n).to_numpy() for n in names])
    else:
        raise InputError(f"run folder {run_dir}: no trajectory.csv or trajectory.parquet")
    metrics_path = run_dir / "metrics.json"
    metrics = json.loads(metrics_path.read_text()) if metrics_path.is_file() else {}
    vehicle_path = run_dir / "vehicle.json"
    vehicle = (Vehicle(**{k: (tuple(map(tuple, v)) if k == "rotor_positions" else
                              tuple(v) if isinstance(v, list) else v)
                          for k, v in json.loads(vehicle_path.read_text()).items()})
               if vehicle_path.is_file() else HUMMINGBIRD)
    return table, metrics, vehicle


def frame_times(t, fps, speed, max_frames):
    """Sample times of the frames: ``speed`` simulated seconds per second at ``fps``, raised so
    that there are at most ``max_frames``; always includes the last sample."""
    step = speed / fps
    span = t[-1] - t[0]
    if span / step + 1 > max_frames:
        step = span / max(max_frames - 1, 1)
    times = np.arange(t[0], t[-1], step) if span > 0 else np.array([t[0]])
    return np.append(times, t[-1]) if times[-1] < t[-1] else times


def animate_run(run_dir, output=None, fps=15, speed=1.0, max_frames=120, progress=False):
    """Write the GIF of a run folder; returns its path.

    Parameters
    ----------
    run_dir : str or Path
        A folder written by `quadcog run` (trajectory.csv or .parquet; metrics.json and
        vehicle.json when present).
    output : str or Path, optional
        The GIF to write; default ``run_dir/flight.gif``.
    fps : int
        Frames per second of the GIF.
    speed : float
        Simulated seconds per second of GIF (1 = real time).
    max_frames : int
        At most this many frames (the speed is raised to fit).
    progress : bool
        Show a progress bar of the frames drawn on stderr (`quadcog animate`).
    """
    import matplotlib
    matplotlib.use("Agg", force=False)
    from matplotlib.animation import FuncAnimation, PillowWriter
    import matplotlib.pyplot as plt

    from quadcog.viz.plots import flight_title

    if not (np.isfinite(speed) and speed > 0):
        raise InputError(f"speed: expected a positive number of simulated seconds per second, "
                         f"got {speed!r}")
    table, metrics, vehicle = read_run(run_dir)
    output = Path(output) if output is not None else Path(run_dir) / "flight.gif"
    t, x, ref = table[:, 0], table[:, col.X], table[:, col.REF]
    r_hat, r_G = table[:, col.R_HAT], table[:, col.R_G]
    times = frame_times(t, fps, speed, max_frames)
    idx = np.minimum(np.searchsorted(t, times - 1e-9), len(t) - 1)

    pts = np.vstack([x[:, :3], ref[:, :3]])
    lo, hi = pts.min(0), pts.max(0)
    span = float(max((hi - lo).max(), 0.5))
    arm = vehicle.arm_length
    scale = max(1.0, 0.12 * span / arm)          # the vehicle about a quarter of the view
    centre, half = (lo + hi) / 2, (hi - lo) / 2 + 2 * arm * scale
    rotors = np.array([[px, py, 0.0] for px, py in vehicle.rotor_positions]) * scale
    ring = np.linspace(0, 2 * np.pi, 25)
    disc = ROTOR_RADIUS * arm * scale * np.stack([np.cos(ring), np.sin(ring), 0 * ring], 1)
    estimating = bool(np.any(r_hat))
    thin = max(1, len(t) // 2000)                # the trail needs no more than ~2000 points

    fig = plt.figure(figsize=(6.4, 5.6))
    ax = fig.add_subplot(projection="3d")
    ax.set(xlim=(centre[0] - half[0], centre[0] + half[0]),
           ylim=(centre[1] - half[1], centre[1] + half[1]),
           zlim=(centre[2] - half[2], centre[2] + half[2]),
           xlabel="x (m)", ylabel="y (m)", zlabel="z (m)")
    ax.set_box_aspect(2 * half)
    ax.plot(*ref[::thin, :3].T, color="0.4", ls="--", lw=1, label="reference")
    trail, = ax.plot([], [], [], color="C0", lw=1.2, label="trail")
    ref_dot, = ax.plot([], [], [], "o", color="0.4", ms=4)
    axes_lines = [ax.plot([], [], [], color=c, lw=2)[0] for c in ("r", "g", "b")]
    arm_lines = [ax.plot([], [], [], color="k", lw=1.5)[0] for _ in rotors]
    discs = [ax.plot([], [], [], color="C1", lw=1)[0] for _ in rotors]
    cog_line, = ax.plot([], [], [], color="m", lw=1)
    origin, = ax.plot([], [], [], "o", color="k", ms=3)
    cog_dot, = ax.plot([], [], [], "o", color="m", ms=4, label="CoG")
    est_dot, = ax.plot([], [], [], "o", mfc="none", mec="m", ms=7,
                       label="CoG estimate" if estimating else None)
    clock = ax.text2D(0.02, 0.95, "", transform=ax.transAxes, fontsize=11)
    name = metrics.get("name")
    ctl = {"pd": "cascade_pd", "fl": "feedback_linearization",
           "adaptive": "adaptive_feedback_linearization"}.get(metrics.get("controller"),
                                                               metrics.get("controller", ""))
    ax.set_title(f"{flight_title(ctl, name)}\nvehicle and CoG offset drawn {scale:.1f}x",
                 fontsize=10)
    fig.legend(loc="lower center", ncol=4, fontsize=8, frameon=False)

    def put(line, p):
        p = np.atleast_2d(p)
        line.set_data_3d(p[:, 0], p[:, 1], p[:, 2])

    def draw(k):
        i = idx[k]
        o = x[i, :3]
        R = rotation_matrix(*x[i, 3:6])
        for j, line in enumerate(axes_lines):
            put(line, [o, o + R[:, j] * 1.6 * arm * scale])   # beyond the rotors
        for r, a_line, d_line in zip(rotors, arm_lines, discs):
            put(a_line, [o, o + R @ r])
            put(d_line, o + (R @ (r + disc).T).T)
        g = o + R @ (r_G[i] * scale)
        put(origin, o)
        put(cog_line, [o, g])
        put(cog_dot, g)
        if estimating:
            put(est_dot, o + R @ (r_hat[i] * scale))
        put(trail, x[:i + 1:thin, :3])
        put(ref_dot, ref[i, :3])
        clock.set_text(f"t = {t[i]:.2f} s")
        return []

    anim = FuncAnimation(fig, draw, frames=len(idx), blit=False)
    output.parent.mkdir(parents=True, exist_ok=True)
    bar = None
    if progress:                    # drawing the frames takes tens of seconds
        from quadcog.viz.progress import ProgressBar
        bar = ProgressBar(f"animate {output.name}")
    try:
        anim.save(output, writer=PillowWriter(fps=fps),
                  progress_callback=(lambda i, n: bar((i + 1) / n)) if bar else None)
    finally:
        if bar:
            bar.close()
    plt.close(fig)
    return output
