"""`quadcog animate RUN_DIR`: the flight of a run folder as a 3D GIF (matplotlib + Pillow).

Each frame shows the body axes (x red, y green, z blue), the arms and rotor discs, the CoG
(filled dot) and its estimate (open dot) at their offsets from O, the trail flown so far, the
reference (dashed) with its current point, and the time. The vehicle is magnified by one
factor, stated in the title, so that it is visible on the scale of the path; the CoG offset is
drawn with the same factor, so it is to scale with the body.
"""
import dataclasses
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.errors import InputError
from quadcog.files import one_line, path_kind, read_json
from quadcog.model import columns as col
from quadcog.model.conventions import rotation_matrix

if TYPE_CHECKING:
    pass

__all__ = ["ROTOR_RADIUS", "read_run", "frame_times", "animate_run"]

ROTOR_RADIUS = 0.3         # rotor disc radius as a fraction of the arm length (drawing only)


def _older_column_sets(names):
    """The column sets of older run folders: before the rotor columns, before the mass."""
    return (names[:col.ROTOR_COMMAND.start], names[:col.MASS.start])


def _text(path):
    """The UTF-8 text of a run file, or an InputError naming it."""
    try:
        return path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as e:
        raise InputError(f"{path}: not UTF-8 text (byte {e.start}): a damaged run file; "
                         f"write the folder again with `quadcog run`") from None


def _json_table(path):
    """The JSON object (dict) of a run file, or an InputError naming it."""
    value = read_json(path, "run file")
    if not isinstance(value, dict):
        raise InputError(f"{path}: expected a JSON object, got {type(value).__name__}")
    return value


MAX_TABLE_VALUE = 1e9     # beyond any run's values; matplotlib cannot draw near 1e300


def read_table(path: Path) -> np.ndarray:
    """The (N, 37) trajectory table of ``trajectory.csv`` or ``trajectory.parquet``.

    Parameters
    ----------
    path : pathlib.Path
        The file; its suffix says the format.

    Returns
    -------
    numpy.ndarray, shape (N, len(trajectory_columns())), N >= 1
        Finite values, time (column 0) non-decreasing.

    Raises
    ------
    InputError
        A damaged, truncated, foreign or non-numeric table, naming the file.
    """
    names = col.trajectory_columns()
    if path.suffix == ".parquet":
        try:
            import pyarrow.parquet as pq
            t = pq.read_table(path)
        except ImportError:
            raise InputError(f"{path}: reading Parquet needs pyarrow: pip install pyarrow") \
                from None
        except Exception as e:      # noqa: BLE001 - pyarrow raises many kinds on damage
            raise InputError(f"{path}: not a readable Parquet file ({type(e).__name__})") \
                from None
        if tuple(t.column_names) in _older_column_sets(names):  # a folder from before the later columns
            names = tuple(t.column_names)
        missing = [n for n in names if n not in t.column_names]
        if missing:
            raise InputError(f"{path}: lacks the columns {missing[:3]}... of "
                             f"quadcog.model.columns.trajectory_columns()")
        try:
            table = np.column_stack([np.asarray(t.column(n).to_numpy(), dtype=float)
                                     for n in names])
        except (TypeError, ValueError):
            raise InputError(f"{path}: a column is not numeric") from None
    else:
        lines = _text(path).splitlines()
        header = lines[0].strip().split(",") if lines else []
        if tuple(header) in _older_column_sets(names):    # a folder from before the later columns
            names = tuple(header)
        if tuple(header) != names:
            raise InputError(f"{path}: unexpected columns (expected those of "
                             f"quadcog.model.columns.trajectory_columns(), starting {names[:3]})")
        rows = []
        for k, line in enumerate(lines[1:], start=2):
            cells = line.split(",")
            if len(cells) != len(names):
                raise InputError(f"{path}: line {k} has {len(cells)} values, expected "
                                 f"{len(names)} (a truncated or damaged file)")
            try:
                rows.append([float(c) for c in cells])
            except ValueError:
                bad = next(c for c in cells if not _is_float(c))
                raise InputError(f"{path}: line {k}: {bad!r} is not a number") from None
        if not rows:
            raise InputError(f"{path}: no samples (header only)")
        table = np.array(rows, dtype=float)
    if table.shape[0] == 0:
        raise InputError(f"{path}: no samples")
    if not np.isfinite(table).all():
        r, c = np.argwhere(~np.isfinite(table))[0]
        raise InputError(f"{path}: sample {r}, column {names[c]!r} is {table[r, c]} (expected "
                         f"a finite number)")
    if np.any(np.diff(table[:, 0]) < 0):
        raise InputError(f"{path}: the time column {names[0]!r} decreases")
    big = np.abs(table) > MAX_TABLE_VALUE
    if big.any():        # no run writes such a value (it stops at divergence); none can be drawn
        r, c = np.argwhere(big)[0]
        raise InputError(f"{path}: sample {r}, column {names[c]!r} is {table[r, c]:.6g}; a run "
                         f"writes values within +-{MAX_TABLE_VALUE:g} (a damaged file?)")
    return table


def _is_float(text):
    try:
        float(text)
    except ValueError:
        return False
    return True


def _run_folder_path(run_dir: object) -> Path:
    """``run_dir`` as a Path; InputError for what is no path or is empty (Path("") is the
    current folder, which would be named '.')."""
    if isinstance(run_dir, bytes) or not isinstance(run_dir, (str, os.PathLike)) \
            or not str(run_dir):
        validate.fail("run folder", "the path of a folder written by `quadcog run`", run_dir)
    return Path(run_dir)


def read_run(run_dir: "str | Path") -> tuple:
    """(table (N, 37), metrics dict, Vehicle) of a folder written by `quadcog run`.

    Parameters
    ----------
    run_dir : str or pathlib.Path
        The folder.

    Returns
    -------
    (numpy.ndarray, dict, Vehicle)
        The trajectory table (``read_table``), metrics.json (``{}`` when absent) and the
        vehicle of vehicle.json (``HUMMINGBIRD`` when absent).

    Raises
    ------
    InputError
        A missing folder or a damaged file, naming it.
    """
    from quadcog.vehicles.vehicle import FIELD_NAMES, HUMMINGBIRD, Vehicle
    run_dir = _run_folder_path(run_dir)
    if not run_dir.is_dir():
        kind = path_kind(run_dir)
        found = "no such folder" if kind is None and not run_dir.exists() else \
            f"is {kind or 'a file'}, not a folder"
        raise InputError(f"run folder {run_dir}: {found} (write one with "
                         f"`quadcog run SCENARIO --out DIR`)")
    csv_path, pq_path = run_dir / "trajectory.csv", run_dir / "trajectory.parquet"
    if csv_path.is_file():
        table = read_table(csv_path)
    elif pq_path.is_file():
        table = read_table(pq_path)
    else:
        raise InputError(f"run folder {run_dir}: no trajectory.csv or trajectory.parquet")
    metrics_path = run_dir / "metrics.json"
    metrics = _json_table(metrics_path) if metrics_path.is_file() else {}
    for key in ("name", "controller"):
        if key in metrics and not isinstance(metrics[key], str):
            raise InputError(f"{metrics_path}: {key!r}: expected a string, got "
                             f"{metrics[key]!r}")
    vehicle_path = run_dir / "vehicle.json"
    if vehicle_path.is_file():
        data = _json_table(vehicle_path)
        unknown = sorted(set(data) - set(FIELD_NAMES))
        if unknown:
            raise InputError(f"{vehicle_path}: unknown vehicle field(s) {unknown} (expected "
                             f"some of {FIELD_NAMES})")
        required = [f.name for f in dataclasses.fields(Vehicle)
                    if f.default is dataclasses.MISSING
                    and f.default_factory is dataclasses.MISSING]
        missing = [k for k in required if k not in data]
        if missing:
            raise InputError(f"{vehicle_path}: missing vehicle field(s) {missing}; a run's "
                             "vehicle.json has every field of quadcog.Vehicle")
        fields: dict[str, Any] = {}
        for k, v in data.items():
            try:
                fields[k] = (tuple(map(tuple, v)) if k == "rotor_positions" else
                             tuple(v) if isinstance(v, list) else v)
            except TypeError:
                raise InputError(f"{vehicle_path}: key {k!r}: expected a list of [x, y] "
                                 f"rotor positions (m), got {v!r:.80}") from None
        try:
            vehicle = Vehicle(**fields)
        except (TypeError, ValueError) as e:
            raise InputError(f"{vehicle_path}: not a valid vehicle: {e}") from None
    else:
        vehicle = HUMMINGBIRD
    return table, metrics, vehicle


def check_output(output: "str | Path") -> Path:
    """The GIF path ``output`` when it can be written, else an InputError naming it.

    Parameters
    ----------
    output : str or pathlib.Path
        Must end in ``.gif`` and not be a folder.

    Returns
    -------
    pathlib.Path
    """
    if isinstance(output, bytes) or not isinstance(output, (str, os.PathLike)) \
            or not str(output):
        validate.fail("output", "the path of a file ending in .gif", output)
    text = os.fspath(output)
    shown = one_line(repr(text))
    # Path() drops a trailing "/": "x.gif/" names a folder, never the file x.gif
    if text.endswith(("/", os.sep)) or Path(text).name in ("", ".", ".."):
        raise InputError(f"output {shown}: expected a file name ending in .gif, not a folder "
                         "path")
    output = Path(text)
    if output.suffix.lower() != ".gif":
        raise InputError(f"output {shown}: expected a file name ending in .gif (the "
                         f"animation is written as a GIF), got "
                         + (f"suffix {output.suffix!r}" if output.suffix else
                            "a name without a stem (.gif alone)" if output.name.lower() == ".gif"
                            else "no suffix"))
    kind = path_kind(output) if os.path.lexists(output) else None
    if kind == "a folder":
        raise InputError(f"output {shown}: is a folder; give a file name ending in .gif")
    if os.path.islink(output) or kind is not None:  # only a regular file is ever replaced
        raise InputError(f"output {shown}: is {'a symbolic link' if os.path.islink(output) else kind}"
                         "; quadcog replaces only regular files (give the name of a new or "
                         "regular file)")
    return output


def frame_times(t: npt.NDArray[np.float64], fps: float, speed: float, max_frames: int
                ) -> npt.NDArray[np.float64]:
    """Sample times of the frames.

    ``speed`` simulated seconds per second at ``fps``, raised so that there are at most
    ``max_frames``; always includes the last sample.

    Parameters
    ----------
    t : (N,) numpy.ndarray
        The run's sample times (s), increasing.
    fps : float
        Frames per second of the GIF.
    speed : float
        Simulated seconds per second of GIF.
    max_frames : int
        At most this many frames.

    Returns
    -------
    (F,) numpy.ndarray
        The frames' times (s).
    """
    if max_frames <= 1:                     # one frame: the end of the run
        return np.array([t[-1]])
    step = speed / fps
    span = t[-1] - t[0]
    if span > step * (max_frames - 1):      # (not span / step: 1e-308 s per s overflows it)
        step = span / max(max_frames - 1, 1)
    times = np.arange(t[0], t[-1], step) if span > 0 else np.array([t[0]])
    return np.append(times, t[-1]) if times[-1] < t[-1] else times


def animate_run(run_dir: str | Path, output: str | Path | None = None, fps: int = 15,
                speed: float = 1.0, max_frames: int = 120, progress: bool = False) -> Path:
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

    Returns
    -------
    pathlib.Path
        The GIF written (renamed into place only once complete).
    """
    output = check_output(output if output is not None else _run_folder_path(run_dir)
                          / "flight.gif")
    _check_settings(fps, speed, max_frames)
    table, metrics, vehicle = read_run(run_dir)
    from quadcog.files import RunFiles
    with RunFiles(output.parent, owned=()) as files:      # a GIF whole or not at all
        animate_table(table, metrics, vehicle, files.path(output.name), fps=fps, speed=speed,
                      max_frames=max_frames, progress=progress)
    return output


def _check_settings(fps, speed, max_frames):
    import numbers
    for name, v in (("fps", fps), ("max_frames", max_frames)):
        if isinstance(v, bool) or not isinstance(v, numbers.Integral) or not 1 <= v <= 10_000:
            raise InputError(f"{name}: expected a whole number 1..10000, got {v!r}")
    if isinstance(speed, bool) or not isinstance(speed, numbers.Real) or \
            not (np.isfinite(speed) and speed > 0):
        raise InputError(f"speed: expected a positive number of simulated seconds per second, "
                         f"got {speed!r}")


def animate_table(table: np.ndarray, metrics: dict, vehicle: Any, output: Path,
                  fps: int = 15, speed: float = 1.0, max_frames: int = 120,
                  progress: bool = False) -> Path:
    """Draw the GIF of a trajectory table (as ``read_run`` returns it) into ``output``.

    Parameters
    ----------
    table : numpy.ndarray, shape (N, 37)
        The trajectory (``quadcog.model.columns.trajectory_columns()``).
    metrics : dict
        metrics.json of the run (``name`` and ``controller`` for the title; may be empty).
    vehicle : Vehicle
        The vehicle drawn.
    output : pathlib.Path
        The GIF to write (written directly: callers make it atomic).
    fps, speed, max_frames, progress
        As for ``animate_run``.

    Returns
    -------
    pathlib.Path
        ``output``.
    """
    import matplotlib
    matplotlib.use("Agg", force=False)
    from matplotlib.animation import FuncAnimation, PillowWriter
    import matplotlib.pyplot as plt

    from quadcog.viz.plots import flight_title

    _check_settings(fps, speed, max_frames)
    output = Path(output)
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
    # metrics.get("controller") may be None, which mypy refuses as a key (the lookup then gives
    # the default) and then takes ctl for str | None; it is a str of metrics.json
    ctl = {"pd": "cascade_pd", "fl": "feedback_linearization",
           "adaptive": "adaptive_feedback_linearization"}.get(metrics.get("controller"),  # type: ignore[arg-type]
                                                               metrics.get("controller", ""))
    ax.set_title(f"{flight_title(ctl, name)}\nvehicle and CoG offset drawn {scale:.1f}x",  # type: ignore[arg-type]
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
    except Exception as e:
        # matplotlib finishes the file in a `finally`; after Ctrl-C with no frame yet that
        # fails (IndexError) and hides the interrupt: report the interrupt
        if isinstance(e.__context__, KeyboardInterrupt):
            raise e.__context__ from None
        raise
    finally:
        if bar:
            bar.close()
        plt.close(fig)
    return output
