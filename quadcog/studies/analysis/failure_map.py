"""Where each controller fails: tail RMS position error after a CoG step at hover, over a grid
of CoG offsets (x_G, y_G) in the rotor plane: the shipped sweep file ``failure-map``."""
from collections.abc import Callable, Sequence
import os
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from quadcog import config, validate
from quadcog.controllers import AdaptiveFeedbackLinearization, CascadePD, FeedbackLinearization, make_controller
from quadcog.controllers.adaptive import admissible_estimate_radius
from quadcog.controllers.base import Controller
from quadcog.errors import ParameterError, SizeError
from quadcog.files import atomic_write, replacing, save_figure
from quadcog.model.conventions import N_PARAM, N_STATE, R_G
from quadcog.model.parameters import check_parameters, inertia_about_cog, with_cog
from quadcog.sim.flight import RK4_LIMIT
from quadcog.sweeps.spec import MAX_FLIGHTS, MAX_THRESHOLD
from quadcog.trajectories.analytic import Hover
from quadcog.vehicles.vehicle import HUMMINGBIRD, default_parameters

__all__ = ["THRESHOLD", "LABELS", "default_controllers", "admissibility", "rk4_stiffness",
           "failure_map", "adaptive_failures_vs_projection", "save_failure_map",
           "plot_failure_map"]

THRESHOLD = 0.5          # m: tail RMS above this (or a diverged run) counts as a failure
LABELS = {"pd": "cascade PD", "fl": "feedback linearization", "adaptive": "adaptive FL"}


def default_controllers() -> dict[str, Controller]:
    """The three controllers of the paper at their default settings.

    Returns
    -------
    dict of str to quadcog.Controller
        {short name: controller}.
    """
    return {"pd": CascadePD(), "fl": FeedbackLinearization(),
            "adaptive": AdaptiveFeedbackLinearization()}


def admissibility(x_G: Sequence[float] | NDArray[np.float64],
                  y_G: Sequence[float] | NDArray[np.float64], z_G: float = 0.0,
                  base: NDArray[np.float64] | None = None
                  ) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """Where on a grid of CoG offsets the vehicle is admissible.

    Parameters
    ----------
    x_G : (nx,) array_like
        Offsets along body x [m].
    y_G : (ny,) array_like
        Offsets along body y [m].
    z_G : float
        The offset along body z [m].
    base : (14,) numpy.ndarray, optional
        The parameters (default: the default vehicle's).

    Returns
    -------
    tuple of (numpy.ndarray, numpy.ndarray)
        admissible (ny, nx) bool: whether quadcog.check_parameters accepts the base vehicle
        with r_G = (x_G, y_G, z_G); lambda_min (ny, nx) [kg m^2], the smallest eigenvalue of
        the inertia about the CoG (<= 0 where it is not admissible).

    Raises
    ------
    quadcog.errors.InputError
        For offsets that are not 1-D arrays of finite numbers, a z_G that is not a finite
        number, a ``base`` that is not 14 finite numbers (an offset beyond the model's scale
        is a quadcog.errors.ParameterError).
    quadcog.errors.SizeError
        For more than ``MAX_FLIGHTS`` grid points.
    """
    x_G = validate.array(x_G, "admissibility: x_G", (None,), what="a 1-D array of offsets (m)")
    y_G = validate.array(y_G, "admissibility: y_G", (None,), what="a 1-D array of offsets (m)")
    z_G = validate.real(z_G, "admissibility: z_G", unit="m")
    base = default_parameters() if base is None else validate.vector(
        base, "admissibility: base", N_PARAM)
    if x_G.size * y_G.size > MAX_FLIGHTS:
        raise SizeError(f"admissibility: {y_G.size} x {x_G.size} grid points; expected at most "
                        f"{MAX_FLIGHTS} (the points of one failure map)")
    adm = np.zeros((len(y_G), len(x_G)), dtype=bool)
    lam = np.zeros_like(adm, dtype=float)
    for i, yg in enumerate(y_G):
        for j, xg in enumerate(x_G):
            p = with_cog(base, (xg, yg, z_G))
            lam[i, j] = np.linalg.eigvalsh(inertia_about_cog(p))[0]
            try:
                check_parameters(p)
                adm[i, j] = True
            except ParameterError:
                pass
    return adm, lam


def rk4_stiffness(controller: Controller, params: NDArray[np.float64],
                  dt: float | None = None) -> NDArray[np.float64]:
    """|lambda|_max dt of the closed-loop Jacobian at level hover (1 m, r_hat = 0).

    Above quadcog.simulate's RK4_LIMIT (2.5) a fixed RK4 step of dt is itself unstable, so a
    'diverged' result there says more about the integrator than about the controller.

    Parameters
    ----------
    controller : quadcog.Controller
        The controller.
    params : (B, 14) numpy.ndarray
        Truth parameter rows, the CoG already moved.
    dt : float, optional
        Step [s] (default ``config.defaults["simulate.dt"]``).

    Returns
    -------
    (B,) numpy.ndarray
        |lambda|_max dt of each row (dimensionless).
    """
    dt = config.get("simulate.dt", dt)
    ref = Hover()(0.0)
    x0 = np.zeros(N_STATE)
    x0[2] = ref[2]
    J = controller.closed_loop_jacobian()
    Js = np.array(J.map(params.shape[0])(x0, ref, params.T)).reshape(12, params.shape[0], 12)
    return np.array([np.max(np.abs(np.linalg.eigvals(Js[:, b, :]))) for b in
                     range(params.shape[0])]) * dt


def _flight_dt():
    """The step of the failure map's flights: the shipped sweep's, else its base scenario's,
    else the configured default (s)."""
    from quadcog.scenarios.lookup import read_toml, scenario_path
    from quadcog.sweeps.spec import read_sweep_file
    data, _ = read_sweep_file("failure-map")
    fixed = data.get("set", {})
    if "dt" in fixed:
        return fixed["dt"]
    return read_toml(scenario_path(data["scenario"])).get("dt", config.get("simulate.dt"))


def check_arguments(grid, half_width, duration, t_step, threshold, controllers, progress):
    """failure_map's arguments checked (InputError naming the argument), as plain values:
    the duration at least one step and at most ``simulate.max_steps`` of them, the step time
    within the run."""
    grid = validate.integer(grid, "failure_map: grid (points per axis)", lo=1)
    half_width = validate.positive(half_width, "failure_map: half_width", unit="m")
    duration = validate.positive(duration, "failure_map: duration", unit="s")
    dt = validate.positive(_flight_dt(), "failure_map: dt of the sweep failure-map", unit="s")
    if duration < dt:
        validate.fail("failure_map: duration", f"at least one step of the flights, dt = "
                      f"{dt:g} s", duration)
    validate.step_count(duration, dt, int(config.get("simulate.max_steps")),
                        "failure_map: duration", SizeError)
    # a step at or after the end never happens: every flight would hover with r_G = 0
    t_step = validate.real(t_step, "failure_map: t_step", lo=0.0, hi=duration, hi_open=True,
                           unit="s, a time within the run: 0 <= t_step < duration")
    threshold = validate.real(threshold, "failure_map: threshold", lo=0.0, lo_open=True,
                              hi=MAX_THRESHOLD, unit="m")
    if isinstance(controllers, (str, bytes)) or not isinstance(controllers, Sequence):
        validate.fail("failure_map: controllers", "a sequence of controller names such as "
                      "('pd', 'fl')", controllers)
    controllers = tuple(controllers)
    if len(set(map(repr, controllers))) != len(controllers):
        validate.fail("failure_map: controllers", "distinct controller names", controllers)
    if progress is not None and not callable(progress):
        validate.fail("failure_map: progress", "a callable(fraction) or None", progress)
    if grid * grid * max(len(controllers), 1) > MAX_FLIGHTS:
        raise SizeError(f"failure_map: grid = {grid}: {grid}^2 offsets x {len(controllers)} "
                        f"controllers is more than the {MAX_FLIGHTS} flights of one sweep")
    return grid, half_width, duration, t_step, threshold, controllers


def failure_map(grid: int = 41, half_width: float = HUMMINGBIRD.arm_length,
                duration: float = 20.0, t_step: float = 1.0,
                controllers: Sequence[str] = ("pd", "fl", "adaptive"),
                threshold: float = THRESHOLD,
                progress: Callable[[float], object] | None = None) -> dict[str, Any]:
    """Tail RMS position error after a CoG step at hover, over a grid of CoG offsets.

    The tail is the last ``config.defaults["metrics.tail_fraction"]`` of each run. This is
    the shipped sweep ``failure-map`` (``quadcog/sweeps/failure-map.toml``, also ``quadcog
    sweep failure-map --out DIR``) with its grid, duration, step time, controllers and
    threshold set from the arguments. Inadmissible offsets (quadcog.check_parameters raises
    ParameterError) are not simulated.

    Parameters
    ----------
    grid : int
        Points per axis; the offsets are x_G, y_G = linspace(-half_width, half_width, grid),
        z_G = 0.
    half_width : float
        The grid's half width [m].
    duration : float
        Seconds per flight [s] (fixed RK4, dt = 1 ms).
    t_step : float
        When the CoG steps from 0 to (x_G, y_G, 0) [s].
    controllers : sequence of str
        Short names ("pd", "fl", "adaptive").
    threshold : float
        Tail RMS [m] above which a run counts as failed (diverged runs always do).
    progress : callable, optional
        Called with the fraction done of the whole map.

    Returns
    -------
    dict
        x_G (grid,), y_G (grid,) [m]; admissible (grid, grid) bool and lambda_min
        (grid, grid) [kg m^2], indexed [i_y, i_x]; per controller name a dict with tail_rms
        (grid, grid) [m; NaN where inadmissible, inf where diverged], diverged, failed
        (bool), diverged_at [s, NaN if not], survive_fraction (of the admissible offsets),
        rk4_stiff (number of admissible points with |lambda|_max dt > RK4_LIMIT), seconds;
        and the totals.
    """
    from quadcog.sweeps.runner import sweep
    from quadcog.sweeps.spec import from_dict, read_sweep_file
    t0 = time.perf_counter()
    grid, half_width, duration, t_step, threshold, controllers = check_arguments(
        grid, half_width, duration, t_step, threshold, controllers, progress)
    data, path = read_sweep_file("failure-map")
    data["set"].update({"duration": float(duration), "cog[0].t": float(t_step)})
    data["threshold"] = float(threshold)
    dims = {d["key"]: d for d in data["dimension"]}
    dims["controller"]["values"] = list(controllers)
    for key in ("cog[0].r[0]", "cog[0].r[1]"):
        dims[key]["range"] = {"start": -float(half_width), "stop": float(half_width),
                              "num": int(grid)}
    spec = from_dict(data, str(path), path.parent)
    total = len(spec.flights)
    done = [0]

    def report(n_new):
        done[0] += n_new
        progress(done[0] / total)
    result = sweep(spec, None, progress=report if progress else False)
    cols = result.columns
    xs = np.linspace(-half_width, half_width, grid)
    ys = xs.copy()
    _, lam = admissibility(xs, ys)
    shape = (len(controllers), grid, grid)           # rows: controller, y_G, x_G
    adm = cols["admissible"].reshape(shape)[0]
    params = np.array([HUMMINGBIRD.with_cog((x, y, 0.0)).parameters()
                       for x, y in zip(cols["cog[0].r[0]"].reshape(shape)[0][adm],
                                       cols["cog[0].r[1]"].reshape(shape)[0][adm])])
    out = {"x_G": xs, "y_G": ys, "admissible": adm, "lambda_min": lam,
           "n_points": int(adm.size), "n_admissible": int(adm.sum()), "duration": duration,
           "t_step": t_step, "threshold": threshold,
           "tail_fraction": config.get("metrics.tail_fraction"), "controllers": {}}
    for k, name in enumerate(controllers):
        tail = cols["rms_position_error_tail"].reshape(shape)[k]
        div = cols["diverged"].reshape(shape)[k]
        failed = cols["failed"].reshape(shape)[k]
        stiff = int(np.sum(rk4_stiffness(make_controller(name), params) > RK4_LIMIT)) \
            if len(params) else 0
        out["controllers"][name] = {
            "label": LABELS.get(name, name), "tail_rms": tail, "diverged": div,
            "diverged_at": cols["diverged_at"].reshape(shape)[k], "failed": failed,
            "survive_fraction": float(np.sum(adm & ~failed) / max(adm.sum(), 1)),
            "n_diverged": int(div.sum()), "n_failed": int(failed.sum()),
            "rk4_stiff": stiff, "seconds": result.seconds / len(controllers)}
    out["seconds"] = time.perf_counter() - t0
    return out


def adaptive_failures_vs_projection(fm: dict[str, Any],
                                    name: str = "adaptive") -> dict[str, Any] | None:
    """Where a controller failed, against the default projection radius of the adaptive
    controller (the estimate cannot leave that ball).

    Parameters
    ----------
    fm : dict
        The result of ``failure_map``.
    name : str
        The controller's short name.

    Returns
    -------
    dict or None
        radius [m], n_failed, n_beyond (failed offsets with |r_G| > radius), the largest
        and smallest failed |r_G| [m]; None when nothing failed.
    """
    c = fm["controllers"].get(name)
    if c is None or not np.any(c["failed"]):
        return None
    radius = admissible_estimate_radius(HUMMINGBIRD)
    X, Y = np.meshgrid(fm["x_G"], fm["y_G"])
    r = np.hypot(X, Y)[c["failed"]]
    return {"radius": radius, "n_failed": int(r.size), "n_beyond": int(np.sum(r > radius)),
            "min_failed_radius": float(r.min()), "max_failed_radius": float(r.max())}


def save_failure_map(fm: dict[str, Any], npz_path: str | os.PathLike[str],
                     json_path: str | os.PathLike[str]) -> None:
    """Write the raw grid of ``failure_map`` to an .npz and a .json.

    Parameters
    ----------
    fm : dict
        The result of ``failure_map``.
    npz_path : str or os.PathLike
        The .npz (arrays).
    json_path : str or os.PathLike
        The .json (lists; inf/NaN as the strings "inf"/"nan").
    """
    import json
    arrays = {"x_G": fm["x_G"], "y_G": fm["y_G"], "admissible": fm["admissible"],
              "lambda_min": fm["lambda_min"]}
    for name, c in fm["controllers"].items():
        for key in ("tail_rms", "diverged", "diverged_at", "failed"):
            arrays[f"{name}_{key}"] = c[key]
    # each all or nothing, never through a link, FIFO or device (quadcog.files.replacing)
    with replacing(npz_path, "failure map .npz") as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    from quadcog.studies.analysis.analysis_files import jsonable
    atomic_write(json_path, json.dumps(jsonable({k: v for k, v in fm.items()})) + "\n",
                 "failure map .json")


def plot_failure_map(fm: dict[str, Any], path: str | os.PathLike[str]) -> None:
    """Heat maps side by side, one per controller.

    Log colour scale of the tail RMS [m], inadmissible offsets grey, diverged runs red,
    failure boundary (tail RMS = threshold or diverged) and admissible boundary as contours.

    Parameters
    ----------
    fm : dict
        The result of ``failure_map``.
    path : str or os.PathLike
        The PNG to write.
    """
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.colors import ListedColormap, LogNorm
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    import matplotlib.pyplot as plt
    xs, ys, adm = fm["x_G"] * 100, fm["y_G"] * 100, fm["admissible"]
    ctls = fm["controllers"]
    finite = np.concatenate([c["tail_rms"][np.isfinite(c["tail_rms"])] for c in ctls.values()])
    finite = finite[finite > 0]          # r_G = 0 gives exactly 0: drawn in the lowest colour
    vmin = max(float(finite.min()), 1e-4) if finite.size else 1e-3
    vmax = max(float(finite.max()), vmin * 10) if finite.size else 10.0
    norm = LogNorm(vmin=vmin, vmax=vmax)
    n = len(ctls)
    fig = plt.figure(figsize=(5.0 * n + 1.4, 5.6))
    gs = fig.add_gridspec(1, n + 1, width_ratios=[1] * n + [0.05], left=0.05, right=0.93,
                          bottom=0.2, top=0.84, wspace=0.28)
    axes = np.array([[fig.add_subplot(gs[0, k]) for k in range(n)]])
    cax = fig.add_subplot(gs[0, n])
    # fine grid for the admissible boundary (min eigenvalue of I_G = 0)
    fx = np.linspace(xs[0], xs[-1], 301) / 100
    base = default_parameters()
    grid = np.broadcast_to(np.asarray(base, dtype=float), (fx.size, fx.size, base.size)).copy()
    grid[..., R_G.start], grid[..., R_G.start + 1], grid[..., R_G.start + 2] = fx[None, :], \
        fx[:, None], 0.0                  # row b, column a: r_G = (a, b, 0)
    lam = np.linalg.eigvalsh(inertia_about_cog(grid))[..., 0]
    mesh = None
    for ax, (name, c) in zip(axes[0], ctls.items()):
        tail = c["tail_rms"]
        ax.set_facecolor("0.8")
        grey = np.ma.masked_where(adm, np.ones_like(tail))
        ax.pcolormesh(xs, ys, grey, cmap=ListedColormap(["0.8"]), shading="nearest")
        ok = np.ma.masked_where(~adm | c["diverged"], np.maximum(tail, vmin))
        mesh = ax.pcolormesh(xs, ys, ok, cmap="viridis", norm=norm, shading="nearest")
        red = np.ma.masked_where(~c["diverged"], np.ones_like(tail))
        ax.pcolormesh(xs, ys, red, cmap=ListedColormap(["red"]), shading="nearest")
        fail_field = np.where(c["diverged"], 1e6, np.where(adm, tail, 1.0))
        fail_field = np.ma.masked_where(~adm, np.log10(np.maximum(fail_field, 1e-12)))
        if np.any(c["failed"]) and np.any(adm & ~c["failed"]):
            ax.contour(xs, ys, fail_field, levels=[np.log10(fm["threshold"])], colors="white",
                       linestyles="solid",
                       linewidths=2.2)
        ax.contour(fx * 100, fx * 100, lam, levels=[0.0], colors="black", linestyles="--",
                   linewidths=1.5)
        ax.plot(0, 0, "w+", ms=10)
        ax.set_aspect("equal")
        ax.set_xlabel(r"$x_G$ (cm)")
        ax.set_ylabel(r"$y_G$ (cm)")
        ax.set_title(f"{c['label']}\nsurvives {100 * c['survive_fraction']:.0f} % of the "
                     f"admissible offsets")
    handles = [Patch(color="0.8", label="inadmissible ($I_G$ not positive definite)"),
               Patch(color="red", label="diverged"),
               Line2D([], [], color="white", lw=2.2,
                      label=f"failure boundary (tail RMS = {fm['threshold']:g} m)"),
               Line2D([], [], color="black", ls="--", lw=1.5, label="admissible boundary")]
    leg = fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=9, frameon=True)
    leg.get_frame().set_facecolor("0.6")
    # mesh is set: the loop above runs once per controller, and there is at least one
    cb = fig.colorbar(mesh, cax=cax)  # type: ignore[arg-type]
    cb.set_label(f"tail RMS position error, last "
                 f"{100 * config.get('metrics.tail_fraction'):g} % of "
                 f"{fm['duration']:g} s (m)")
    fig.suptitle(f"CoG step at hover at t = {fm['t_step']:g} s to ($x_G$, $y_G$, 0): "
                 f"{len(xs)} x {len(ys)} grid, arm = {xs[-1]:.0f} cm", y=0.99)
    save_figure(fig, path, "failure map figure", dpi=120)
    plt.close(fig)
