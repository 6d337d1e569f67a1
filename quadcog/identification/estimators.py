"""The two estimators of the CoG offset r_G and the mass m from one flight log.

Static balance at hover (``static_balance``). Level and at rest, the rotor thrusts f_i at
(x_i, y_i) hold the weight: the thrust balance ``sum f_i cos(phi) cos(theta) = m (g + a_z)``
(a_z the measured vertical acceleration) gives m, and the moment balance about O,
``[sum y_i f_i, -sum x_i f_i] = m g [y_G, -x_G]`` (docs/model.md sec. 3.3), gives x_G, y_G.
z_G does not enter a level hover. Needs only the rotor outputs, the height (for the hover
window) and, when logged, the vertical acceleration and the tilt.

Whole flight by least squares (``regression``). The equations of motion are affine in r_G:
``B_u U - n(nu, eta, 0) - M(0) nu_dot = Phi(nu, eta, nu_dot) r_G`` (docs/model.md sec. 3.1,
``regressor`` of ``quadcog.load()``). Both sides pass through the filter F(s) = lam / (s + lam)
of the composite adaptive law (quadcog/controllers/composite.py, its default ``filter_rate``),
so that no acceleration is needed: ``F[M nu_dot] = lam (M nu - F[M nu])``, and

    z = F[B_u U - n_0] - lam (M_0 nu - F[M_0 nu]),    Y = F[Phi_0] + lam (W - F[W]),

with n_0, Phi_0, M_0 at r_G = 0 and W = Phi(nu, eta, nu) - Phi_0. Rows are scaled to metres
of CoG as in the composite law (moments by 1 / (m g), forces by l / (m g)); the mass comes
from the thrust balance. z = Y r_G is solved by least squares; the covariance is the
cluster-robust (sandwich) one over 1 s blocks, because neighbouring samples share their noise.
Needs the velocity, the three Euler angles, the body rates and the rotor outputs.
"""
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from quadcog.controllers.design import REFERENCE
from quadcog.errors import IdentificationError
from quadcog.identification import _checks
from quadcog.identification.segments import (
    BLOCK_SECONDS,
    MIN_BLOCKS,
    SPEED_SPREAD,
    HoverWindow,
    _block_mean_ci95,
    _block_means,
    _speed_corrected,
    body_velocity,
    check_arguments,
    hover_window,
    rotor_thrusts,
    t_quantile,
    vertical_acceleration,
)
from quadcog.logs.flightlog import FlightLog
from quadcog.logs.signals import SIGNALS
from quadcog.model.conventions import B_U, rotation_matrix
from quadcog.model.functions import load
from quadcog.model.parameters import LARGEST, with_cog
from quadcog.validate import array, fail, integer, nonnegative, positive, real
from quadcog.vehicles.rotor_model import RotorModel
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["FILTER_RATE", "WARM_UP", "STATIC_SIGNALS", "REGRESSION_SIGNALS", "Z_G_MIN_TILT",
           "MAX_CONDITION", "R_G_NAMES",
           "STATIC_MAX_TILT", "FlightEstimate", "static_balance", "regression", "missing_for"]

# the composite law's filter rate lam (1/s) of its reference design (the Hummingbird's): one
# definition, quadcog.controllers.design
FILTER_RATE = REFERENCE.filter_rate
WARM_UP = 5.0 / FILTER_RATE            # s: the filter's start-up term has decayed by e^-5
R_G_NAMES = ("x_G", "y_G", "z_G")      # the entries of r_G, in messages and results
STATIC_SIGNALS = ("position",)         # + the rotor model's signals
REGRESSION_SIGNALS = ("position", "velocity", "roll", "pitch", "yaw", "body_rates")
# z_G enters the moments through m g z_G sin(tilt) and the linear accelerations: below this
# RMS tilt about the mean the logged attitude noise dominates that column, and least squares
# biases z_G toward 0 (errors in variables) with an interval that looks tight; z_G is then
# not estimated
Z_G_MIN_TILT = np.radians(2.0)
# the static balance assumes a level hover; beyond this RMS tilt it says it is biased
STATIC_MAX_TILT = np.radians(3.0)
# the scaled regressor's condition number beyond which least squares determines nothing (its
# columns are dependent to the float64's precision: A^T A cannot be inverted)
MAX_CONDITION = 1e12


def missing_for(log: FlightLog, names: Sequence[str]) -> list[str]:
    """The signals of ``names`` that ``log`` lacks.

    Parameters
    ----------
    log : quadcog.logs.FlightLog
        The flight.
    names : sequence of str
        Standard signal names (``quadcog.logs.SIGNALS``).

    Returns
    -------
    list of str
        Those of ``names`` the log does not have, in their order.

    Raises
    ------
    IdentificationError
        ``log`` not a FlightLog; ``names`` not a list or tuple of names of ``SIGNALS`` (a
        str is one name, not a sequence of its letters).
    """
    check_arguments("missing_for", log)
    names = _checks.sequence(names, "missing_for: names", str, "signal name (str)")
    for i, n in enumerate(names):
        if n not in SIGNALS:
            fail(f"missing_for: names[{i}]", "a name of quadcog.logs.SIGNALS", n,
                 IdentificationError)
    return [n for n in names if not log.has(n)]


def _check_window(where: str, log: FlightLog, window: object) -> None:
    """Refuse a ``window`` that is neither None nor a HoverWindow of ``log``'s samples."""
    if window is None:
        return
    if not isinstance(window, HoverWindow):
        fail(f"{where}: window", "a HoverWindow (segments.hover_window) or None", window,
             IdentificationError)
    _checks.mask(window.mask, f"{where}: window.mask", log.n_samples)


@dataclass(frozen=True, eq=False)
class FlightEstimate:
    """What one estimator found in one log.

    Parameters
    ----------
    source : str
        The log.
    method : str
        ``"static"`` or ``"regression"``.
    blocks_r : numpy.ndarray, shape (B, 3)
        Per-block estimates of r_G (m) (static: z entry 0); the regression's are per-block
        least-squares solutions, for the figure only.
    blocks_m : numpy.ndarray, shape (B,)
        Per-block masses (kg).
    blocks_v : numpy.ndarray, shape (B, 2)
        Per-block mean speeds forward and left (m/s), for ``speed_corrected``.
    r_G : numpy.ndarray, shape (3,)
        Estimate and 95 % half-widths (m); NaN half-width where the method does not estimate.
    r_G_ci95 : numpy.ndarray, shape (3,)
        Estimate and 95 % half-widths (m); NaN half-width where the method does not estimate.
    mass : float
        kg.
    mass_ci95 : float
        kg.
    samples : int
        Samples used.
    t : numpy.ndarray
        For the figure: sample times (s), the rotor moments [sum y_i f_i, -sum x_i f_i] (N m)
        and m g (N) over the window.
    moment : numpy.ndarray
        For the figure: sample times (s), the rotor moments [sum y_i f_i, -sum x_i f_i] (N m)
        and m g (N) over the window.
    weight : numpy.ndarray
        For the figure: sample times (s), the rotor moments [sum y_i f_i, -sum x_i f_i] (N m)
        and m g (N) over the window.
    condition : float or None
        Condition number of the scaled regressor (regression only).
    rotor : str
        How the thrusts were obtained.
    notes : tuple of str
        What the estimator assumed.

    Returns
    -------
    FlightEstimate

    Raises
    ------
    IdentificationError
        A field of another type, shape or range, named ``FlightEstimate.<field>``: arrays
        not finite (a half-width may be NaN where not estimated, never negative or infinite),
        blocks_m and blocks_v or t, moment and weight of different lengths, a mass not > 0,
        samples not a whole number >= 0, a method not ``"static"`` or ``"regression"``.
    """
    source: str
    method: str
    blocks_r: np.ndarray
    blocks_m: np.ndarray
    blocks_v: np.ndarray
    r_G: np.ndarray
    r_G_ci95: np.ndarray
    mass: float
    mass_ci95: float
    samples: int
    t: np.ndarray
    moment: np.ndarray
    weight: np.ndarray
    condition: float | None
    rotor: str
    notes: tuple

    def __post_init__(self) -> None:
        def put(name, value):
            object.__setattr__(self, name, value)
        at = "FlightEstimate."
        put("source", _checks.text(self.source, at + "source"))
        if not (isinstance(self.method, str) and self.method in ("static", "regression")):
            fail(at + "method", "'static' or 'regression'", self.method, IdentificationError)
        put("method", str(self.method))
        put("blocks_r", _checks.rows(self.blocks_r, at + "blocks_r", columns=3, min_rows=1))
        put("blocks_m", _checks.rows(self.blocks_m, at + "blocks_m", ndim=1, min_rows=1))
        put("blocks_v", _checks.rows(self.blocks_v, at + "blocks_v", columns=2,
                                     n_rows=len(self.blocks_m)))
        put("r_G", array(self.r_G, at + "r_G", shape=(3,), error=IdentificationError))
        half = array(self.r_G_ci95, at + "r_G_ci95", shape=(3,), finite=False,
                     error=IdentificationError)
        if not ((half >= 0) | np.isnan(half)).all() or np.isinf(half).any():
            fail(at + "r_G_ci95", "3 half-widths (m), each a finite number >= 0 or NaN (not "
                 "estimated)", self.r_G_ci95, IdentificationError)
        put("r_G_ci95", half)
        put("mass", positive(self.mass, at + "mass", "kg", IdentificationError))
        put("mass_ci95", nonnegative(self.mass_ci95, at + "mass_ci95", "kg",
                                     IdentificationError))
        put("samples", integer(self.samples, at + "samples", lo=0, error=IdentificationError))
        put("t", _checks.rows(self.t, at + "t", ndim=1))
        put("moment", _checks.rows(self.moment, at + "moment", columns=2, n_rows=len(self.t)))
        put("weight", _checks.rows(self.weight, at + "weight", ndim=1, n_rows=len(self.t)))
        if self.condition is not None:
            put("condition", positive(self.condition, at + "condition",
                                      error=IdentificationError))
        put("rotor", _checks.text(self.rotor, at + "rotor"))
        notes = _checks.sequence(self.notes, at + "notes", str, "str")
        put("notes", tuple(str(n) for n in notes))


def _tilt_cosine(log: FlightLog, notes: list[str]) -> npt.NDArray[np.float64]:
    if log.has("roll") and log.has("pitch"):
        return np.cos(log.signal("roll")) * np.cos(log.signal("pitch"))
    notes.append("no roll and pitch together in the log: the thrust taken as vertical")
    return np.ones(log.n_samples)


def _rms_tilt(log: FlightLog, sel: npt.NDArray[np.bool_]) -> float | None:
    """RMS of the logged roll and pitch (those present) over the window (rad), or None."""
    have = [log.signal(n)[sel] for n in ("roll", "pitch") if log.has(n)]
    return float(np.sqrt(sum((a ** 2).mean() for a in have))) if have else None


def static_balance(log: FlightLog, vehicle: Vehicle, rotor_model: RotorModel | str | None = None,
                   window: HoverWindow | None = None) -> FlightEstimate:
    """x_G, y_G and m from the thrust and moment balance of the hover (module docstring).

    Parameters
    ----------
    log : quadcog.logs.FlightLog
        With "position" and the rotor model's signals.
    vehicle : quadcog.Vehicle
        Rotor positions, g and the rotor model.
    rotor_model : RotorModel or str, optional
        Instead of the vehicle's.
    window : HoverWindow, optional
        Default: ``hover_window(log)``.

    Returns
    -------
    FlightEstimate
        ``method = "static"``; r_G[2] = 0 with a NaN half-width (not estimated).

    Raises
    ------
    IdentificationError
        Missing signals or too few hover samples; ``log``, ``vehicle``, ``rotor_model`` or
        ``window`` of another type (a window of another log's samples).
    """
    check_arguments("static_balance", log, vehicle)
    _checks.vehicle(vehicle, "static_balance: vehicle")
    _checks.rotor_model(rotor_model, "static_balance: rotor_model")
    _check_window("static_balance", log, window)
    window = hover_window(log) if window is None else window
    f_all, rotor, _ = rotor_thrusts(log, vehicle, rotor_model)
    notes: list[str] = []
    a_z, a_from = vertical_acceleration(log)
    cos_tilt = _tilt_cosine(log, notes)
    sel = window.mask
    t, f = log.t[sel], f_all[sel]
    g = vehicle.g
    pos = np.asarray(vehicle.rotor_positions)
    thrust_up = f.sum(axis=1) * cos_tilt[sel]
    moment = np.column_stack([f @ pos[:, 1], -(f @ pos[:, 0])])      # [U2, U3] (N m)
    lift = g + a_z[sel]
    blocks = _block_means(window.blocks(t), np.column_stack([thrust_up, lift, moment,
                                                            body_velocity(log)[sel]]))
    if len(blocks) < MIN_BLOCKS:
        raise IdentificationError(f"{log.source}: too few hover samples ({sel.sum()} in "
                                  f"{len(blocks)} blocks of {BLOCK_SECONDS:g} s)")
    m_b = blocks[:, 0] / blocks[:, 1]
    # U2 = m g y_G, U3 = -m g x_G
    r_b = np.column_stack([-blocks[:, 3] / (m_b * g), blocks[:, 2] / (m_b * g),
                           np.zeros(len(m_b))])
    v_b = blocks[:, 4:6]
    r, half, slopes = _speed_corrected(r_b, v_b)
    half[2] = np.nan
    m, m_half = _block_mean_ci95(m_b)
    notes.append(f"vertical acceleration: {a_from}")
    tilt = _rms_tilt(log, sel)
    if tilt is not None and tilt > STATIC_MAX_TILT:
        notes.append(f"not a hover: RMS tilt {np.degrees(tilt):.1f} deg (above "
                     f"{np.degrees(STATIC_MAX_TILT):g} deg); the level balance is biased here, "
                     "use method 'regression'")
    if slopes.any():
        notes.append("moving at constant height (block speeds spread by more than "
                     f"{SPEED_SPREAD:g} m/s): r_G is the zero-speed intercept of the blocks")
    notes.append("z_G not estimated: it does not enter the moment balance of a level hover")
    return FlightEstimate(log.source, "static", r_b, m_b, v_b, r, half, float(m), float(m_half),
                          int(sel.sum()), t, moment, m * g * np.ones(len(t)), None, rotor,
                          tuple(notes))


def _lowpass(u, t, lam, restart, held=False):
    """F(s) = lam / (s + lam) on samples u (N, ...) at times t (N,), exactly: for a command
    ``held`` from its sample to the next (what a logged motor command does), else for a
    signal linear between samples (a sampled state). Starts in steady state (F[u] = u) at
    every sample where ``restart`` (N,) is True (the first one of each segment)."""
    h = np.diff(t)
    a = np.exp(-lam * h)
    ramp = 0.0 * h if held else 1.0 - (1.0 - a) / (lam * h)
    y = np.empty_like(u)
    y[0] = u[0]
    for k in range(1, len(t)):
        if restart[k]:
            y[k] = u[k]
        else:
            y[k] = a[k - 1] * y[k - 1] + (1.0 - a[k - 1]) * u[k - 1] \
                + ramp[k - 1] * (u[k] - u[k - 1])
    return y


def _states(log, sel):
    """States x (N, 12) on the window: ground position, ZYX angles, body velocities, rates."""
    p, v = log.signal("position")[sel], log.signal("velocity")[sel]
    eta = np.column_stack([log.signal(n)[sel] for n in ("roll", "pitch", "yaw")])
    nu1 = np.array([rotation_matrix(*e).T @ vk for e, vk in zip(eta, v)])
    return np.column_stack([p, eta, nu1, log.signal("body_rates")[sel]])


def regression(log: FlightLog, vehicle: Vehicle, rotor_model: RotorModel | str | None = None,
               window: HoverWindow | None = None, filter_rate: float = FILTER_RATE,
               mass: float | None = None, min_tilt: float = Z_G_MIN_TILT) -> FlightEstimate:
    """r_G by filtered least squares with the generated regressor (module docstring).

    Parameters
    ----------
    log : quadcog.logs.FlightLog
        With ``REGRESSION_SIGNALS`` and the rotor model's signals.
    vehicle : quadcog.Vehicle
        Inertia, drag, rotor geometry, rotor model (its r_G is not used).
    rotor_model : RotorModel or str, optional
        Instead of the vehicle's.
    window : HoverWindow, optional
        Default: ``hover_window(log)``; the first ``5 / filter_rate`` s are the filter's
        warm-up and not used.
    filter_rate : float
        lam (1/s) of F(s).
    mass : float, optional
        The mass (kg); default: the thrust balance of ``static_balance`` on the same window.
    min_tilt : float
        RMS tilt (rad) below which z_G is not estimated (``Z_G_MIN_TILT``; 0 forces it).

    Returns
    -------
    FlightEstimate
        ``method = "regression"``, with the condition number of the scaled regressor.

    Raises
    ------
    IdentificationError
        Missing signals or too few samples; ``log``, ``vehicle``, ``rotor_model``, ``window``
        of another type (a window of another log's samples), ``filter_rate``, ``mass`` or
        ``min_tilt`` not a finite number in range.
    """
    check_arguments("regression", log, vehicle)
    _checks.vehicle(vehicle, "regression: vehicle")
    _checks.rotor_model(rotor_model, "regression: rotor_model")
    _check_window("regression", log, window)
    # within the model's scale: lam (M nu - F[M nu]) of a rate of 1e300 overflowed to inf
    filter_rate = real(filter_rate, "regression: filter_rate", lo=0.0, lo_open=True,
                       hi=LARGEST, unit="1/s", error=IdentificationError)
    min_tilt = nonnegative(min_tilt, "regression: min_tilt", "rad", IdentificationError)
    if mass is not None:
        mass = positive(mass, "regression: mass", "kg", IdentificationError)
    missing = missing_for(log, REGRESSION_SIGNALS)
    if missing:
        raise IdentificationError(f"{log.source}: the whole-flight least squares needs "
                                  f"{', '.join(missing)}, which the log lacks")
    window = hover_window(log) if window is None else window
    static = static_balance(log, vehicle, rotor_model, window)
    m = static.mass if mass is None else float(mass)
    f_all, rotor, _ = rotor_thrusts(log, vehicle, rotor_model)
    sel = window.mask
    t = log.t[sel]
    x = _states(log, sel)
    U = f_all[sel] @ vehicle.mixer().T
    p0 = with_cog(vehicle.replace(m=m).parameters(), np.zeros(3))
    model = load()
    M0 = model.mass_matrix(p0)
    D = model.damping(p0)
    N = len(t)
    n0 = np.empty((N, 6))
    Phi0 = np.empty((N, 6, 3))
    W = np.empty((N, 6, 3))
    # the arguments were checked above (the log's finite signals, p0 admissible): the
    # unchecked calls of the generated functions, about 1 us each, in one pass over the log
    cor, grav, reg = (model.fast(name) for name in ("coriolis", "gravity", "regressor"))
    for call in (cor, grav, reg):
        call.inputs[-1][:] = p0
    for k in range(N):
        nu = x[k, 6:]
        cor.inputs[0][:] = x[k]
        grav.inputs[0][:] = x[k]
        reg.inputs[0][:] = x[k]
        C, = cor()
        G_k, = grav()
        n0[k] = C @ nu + D @ nu + G_k
        reg.inputs[1][:] = 0.0
        Phi0[k] = reg()[0]
        reg.inputs[1][:] = nu
        W[k] = reg()[0] - Phi0[k]
    if not (np.isfinite(n0).all() and np.isfinite(Phi0).all() and np.isfinite(W).all()):
        raise IdentificationError(f"{log.source}: the model is not finite along the logged "
                                  "states (rates or velocities beyond the model's range)")
    lam = float(filter_rate)
    seg = np.searchsorted(np.array([a for a, _ in window.segments]), t, side="right") - 1
    restart = np.r_[True, np.diff(seg) != 0]
    seg_start = np.array([a for a, _ in window.segments])[seg]
    Mnu = x[:, 6:] @ M0.T
    z = (_lowpass(U @ B_U.T, t, lam, restart, held=True) - _lowpass(n0, t, lam, restart)
         - lam * (Mnu - _lowpass(Mnu, t, lam, restart)))
    Y = _lowpass(Phi0, t, lam, restart) + lam * (W - _lowpass(W, t, lam, restart))
    index_all = window.blocks(t)
    warm_up = 5.0 / lam           # WARM_UP at the default rate: the start-up term is e^-5
    keep = (t >= seg_start + warm_up) & (index_all >= 0)
    t, z, Y, index = t[keep], z[keep], Y[keep], index_all[keep]
    n_blocks = int(index.max(initial=-1)) + 1
    if n_blocks < MIN_BLOCKS:
        raise IdentificationError(f"{log.source}: too few samples for the least squares "
                                  f"({len(t)} in {n_blocks} blocks of {BLOCK_SECONDS:g} s "
                                  f"after the filter's warm-up of {warm_up:.3g} s)")
    scale = np.r_[[vehicle.arm_length / (m * vehicle.g)] * 3, [1.0 / (m * vehicle.g)] * 3]
    zn, Yn = z * scale, Y * scale[None, :, None]
    eta = x[keep, 3:5]
    tilt = float(np.sqrt(((eta - eta.mean(axis=0)) ** 2).sum(axis=1).mean()))
    cols = [0, 1, 2] if tilt >= min_tilt else [0, 1]
    Yn = Yn[:, :, cols]
    A, b = Yn.reshape(-1, len(cols)), zn.reshape(-1)
    condition = float(np.linalg.cond(A))
    if not condition <= MAX_CONDITION:
        names = ", ".join(R_G_NAMES[c] for c in cols)
        why = (f"; the RMS tilt of {np.degrees(tilt):.3g} deg does not excite z_G (min_tilt "
               f"{np.degrees(min_tilt):g} deg let it in)" if len(cols) == 3 else "")
        raise IdentificationError(
            f"{log.source}: the flight does not determine {names} by least squares: the "
            f"scaled regressor's condition number is {condition:.3g}, expected at most "
            f"{MAX_CONDITION:.3g} (its columns are dependent){why}")
    r = np.zeros(3)
    r[cols], *_ = np.linalg.lstsq(A, b, rcond=None)
    e = (b - A @ r[cols]).reshape(-1, 6)
    AtA_inv = np.linalg.inv(A.T @ A)
    meat = np.zeros((len(cols), len(cols)))
    blocks_r = np.zeros((n_blocks, 3))
    order = np.argsort(index, kind="stable")          # the samples of each block, in one pass
    bounds = np.searchsorted(index[order], np.arange(n_blocks + 1))
    for bl in range(n_blocks):
        s = order[bounds[bl]:bounds[bl + 1]]
        gb = np.einsum("kij,ki->j", Yn[s], e[s])
        meat += np.outer(gb, gb)
        Ab, bb = Yn[s].reshape(-1, len(cols)), zn[s].reshape(-1)
        blocks_r[bl, cols] = np.linalg.lstsq(Ab, bb, rcond=None)[0]
    cov = AtA_inv @ meat @ AtA_inv * n_blocks / (n_blocks - 1)
    half = np.full(3, np.nan)
    half[cols] = t_quantile(n_blocks - 1) * np.sqrt(np.diag(cov))
    notes = list(static.notes[:-1]) + [
        f"filter F(s) = {lam:g} / (s + {lam:g}) as the composite law's; first {warm_up:g} s "
        "of the window are its warm-up",
        "the mass from the thrust balance of the same window"]
    if len(cols) == 2:
        notes.append(f"z_G not estimated: RMS tilt {np.degrees(tilt):.2f} deg is below "
                     f"{np.degrees(min_tilt):g} deg, too little for the attitude noise")
    return FlightEstimate(log.source, "regression", blocks_r, static.blocks_m, static.blocks_v, r,
                          half, m if mass is not None else static.mass,
                          0.0 if mass is not None else static.mass_ci95, int(keep.sum()),
                          static.t, static.moment, static.weight, condition, rotor,
                          tuple(notes))
