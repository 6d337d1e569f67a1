"""Aerobatic references that leave the Euler-angle chart or its small-angle laws: a flip (a
vertical loop flown upside down over its top) and a circle banked far beyond the tilt limits of
the Euler laws (docs/tour/geometric.md).

Both are a point moving on a circle, ``p = center + radius (e_a cos th + e_b sin th)``, with the
angle th(t) a smooth function of time, so position, velocity, acceleration and jerk are exact:
with ``u = e_a cos th + e_b sin th`` and ``u' = -e_a sin th + e_b cos th``,

    v = r th' u',   a = r (th'' u' - th'^2 u),
    j = r ((th''' - th'^3) u' - 3 th' th'' u).

th(t) starts and ends at rest through the septic step ``s(tau) = 35 tau^4 - 84 tau^5 + 70 tau^6
- 20 tau^7`` (zero velocity, acceleration and jerk at both ends), so a flight starts in hover.
"""
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.errors import InputError
from quadcog.kinds import Number, Vec3
from quadcog.trajectories.analytic import REFERENCE_LIMIT, Trajectory

__all__ = ["Flip", "BankedCircle", "septic_step"]

_Array = npt.NDArray[np.float64]


def septic_step(tau: npt.ArrayLike) -> tuple[_Array, _Array, _Array, _Array]:
    """The septic step from 0 to 1 on [0, 1] and its first three derivatives in tau.

    Parameters
    ----------
    tau : array_like
        Normalized time; clipped to [0, 1] (0 before, 1 after).

    Returns
    -------
    s, s1, s2, s3 : numpy.ndarray
        s(tau) and its derivatives (zero outside [0, 1]).

    Raises
    ------
    InputError
        ``tau`` not finite real numbers (NaN gave a NaN step).
    """
    t = validate.array(tau, "septic_step: tau", what="normalized times: finite real numbers")
    inside = (t > 0) & (t < 1)
    t = np.clip(t, 0.0, 1.0)
    s = 35 * t**4 - 84 * t**5 + 70 * t**6 - 20 * t**7
    s1 = np.where(inside, 140 * t**3 - 420 * t**4 + 420 * t**5 - 140 * t**6, 0.0)
    s2 = np.where(inside, 420 * t**2 - 1680 * t**3 + 2100 * t**4 - 840 * t**5, 0.0)
    s3 = np.where(inside, 840 * t - 5040 * t**2 + 8400 * t**3 - 4200 * t**4, 0.0)
    return s, s1, s2, s3


# The largest |s1|, |s2|, |s3| of the septic step's derivatives on [0, 1] (35/16, about 7.51
# and 52.5)
_PEAKS = tuple(float(np.abs(d).max()) for d in septic_step(np.linspace(0.0, 1.0, 10001))[1:])


def _check_peaks(where, radius, rates, settings):
    """Refuse a motion on a circle whose velocity, acceleration or jerk can exceed
    ``REFERENCE_LIMIT`` somewhere: ``rates`` bound the angle's first three derivatives
    (w1, w2, w3) over the motion, and ``|v| = r w1``, ``|a| <= r (w2 + w1^2)``,
    ``|j| <= r (w3 + w1^3 + 3 w1 w2)``. Checked when the trajectory is made: sampled at a
    flight's steps only, a loop flown in a nanosecond fell between two samples and the
    reference stayed a hover."""
    with np.errstate(over="ignore", invalid="ignore"):
        w1, w2, w3 = (np.float64(x) for x in rates)
        peaks = {"velocity": radius * w1, "acceleration": radius * (w2 + w1 * w1),
                 "jerk": radius * (w3 + w1 * w1 * w1 + 3 * w1 * w2)}
    worst = next((k for k, v in peaks.items() if not v <= REFERENCE_LIMIT), None)
    if worst is not None:
        unit = {"velocity": "m/s", "acceleration": "m/s^2", "jerk": "m/s^3"}[worst]
        raise InputError(f"{where}: expected settings whose reference stays within "
                         f"+-{REFERENCE_LIMIT:g} (SI units), got {settings}, which ask for "
                         + (f"up to {float(peaks[worst]):.3g} {unit}" if np.isfinite(peaks[worst])
                            else "more than a float holds")
                         + f" of {worst}")


def _point(where, value):
    """A point (m) as a float array (untyped, as the dataclass field holds a Vec3)."""
    return validate.array(value, where, (3,), what="3 finite numbers (m)")


def _on_circle(center, radius, e_a, e_b, th, th1, th2, th3):
    """p, v, a, j (N, 3) of the point at angle th (with its time derivatives) on the circle."""
    c, s = np.cos(th)[:, None], np.sin(th)[:, None]
    u, du = c * e_a + s * e_b, -s * e_a + c * e_b
    th1, th2, th3 = th1[:, None], th2[:, None], th3[:, None]
    p = center + radius * u
    v = radius * th1 * du
    a = radius * (th2 * du - th1**2 * u)
    j = radius * ((th3 - th1**3) * du - 3 * th1 * th2 * u)
    return p, v, a, j


_E1, _E2, _E3 = np.eye(3)


@dataclass
class Flip(Trajectory):
    """One vertical loop in the x-z plane: from hover at its bottom, forward and up, over the
    top upside down, and back to hover, in ``duration`` seconds from ``start``.

    The angle around the loop is ``2 pi s((t - start) / duration)`` (septic step), fastest
    at the top, where the centripetal acceleration ``radius (2 pi 35/16 / duration)^2`` points
    down: above g the thrust points down too and the vehicle is inverted.

    Parameters
    ----------
    bottom : (3,) array_like
        The loop's lowest point, where it starts and ends (m); default [0, 0, 1].
    radius : float
        Radius (m), > 0; default 1.
    start : float
        Time the loop starts (s), >= 0; default 1.
    duration : float
        Time of the loop (s), > 0; default 3 (2.1 g down at the top with radius 1).
    yaw : float
        Heading held (rad), default 0: the loop is flown about the body y axis.

    Raises
    ------
    InputError
        When a setting is not finite, out of range or of the wrong shape.
    """
    bottom: Vec3 = (0.0, 0.0, 1.0)
    radius: Number = 1.0
    start: Number = 1.0
    duration: Number = 3.0
    yaw: Number = 0.0

    def __post_init__(self) -> None:
        self.bottom = _point("flip bottom", self.bottom)
        self.radius = validate.positive(self.radius, "flip radius", "m")
        self.start = validate.nonnegative(self.start, "flip start", "s")
        self.duration = validate.positive(self.duration, "flip duration", "s")
        self.yaw = validate.real(self.yaw, "flip yaw", unit="rad")
        k, T = 2 * np.pi, np.float64(self.duration)
        with np.errstate(over="ignore", divide="ignore"):
            rates = (k * _PEAKS[0] / T, k * _PEAKS[1] / T**2, k * _PEAKS[2] / T**3)
        _check_peaks("flip", self.radius, rates, f"radius {validate.plain(self.radius)} m "
                     f"and duration {validate.plain(self.duration)} s")

    def _pvaj(self, t):
        T = np.float64(self.duration)   # numpy's powers: T**3 of 1e308 s is inf, not OverflowError
        s, s1, s2, s3 = septic_step((t - self.start) / T)
        k = 2 * np.pi
        heading = np.cos(self.yaw) * _E1 + np.sin(self.yaw) * _E2
        center = np.asarray(self.bottom, float) + self.radius * _E3
        # th = 0 at the bottom: u = -e3 cos th + heading sin th
        return _on_circle(center, self.radius, -_E3, heading, k * s, k * s1 / T,
                          k * s2 / T**2, k * s3 / T**3)


@dataclass
class BankedCircle(Trajectory):
    """A horizontal circle flown at the speed that banks the thrust by ``bank_deg``: from hover
    at center + [radius, 0, 0] the angular rate ramps up in ``ramp`` seconds (septic step) to
    ``w = sqrt(g tan(bank) / radius)`` and stays there, counter-clockwise.

    Parameters
    ----------
    center : (3,) array_like
        Centre (m); default [0, 0, 1].
    radius : float
        Radius (m), > 0; default 2.
    bank_deg : float
        The tilt of the thrust on the circle (deg), in (0, 85]; default 60 (2 g of thrust).
    ramp : float
        Time to reach the circle's speed (s), > 0; default 2.
    g : float
        The gravity the bank is measured against (m/s^2), > 0; default 9.81.
    yaw : float
        Heading held (rad), default 0.

    Raises
    ------
    InputError
        When a setting is not finite, out of range or of the wrong shape.
    """
    center: Vec3 = (0.0, 0.0, 1.0)
    radius: Number = 2.0
    bank_deg: Number = 60.0
    ramp: Number = 2.0
    g: Number = 9.81
    yaw: Number = 0.0

    def __post_init__(self) -> None:
        self.center = _point("banked_circle center", self.center)
        self.radius = validate.positive(self.radius, "banked_circle radius", "m")
        self.bank_deg = validate.real(self.bank_deg, "banked_circle bank_deg", lo=0.0, hi=85.0,
                                      lo_open=True, unit="deg")
        self.ramp = validate.positive(self.ramp, "banked_circle ramp", "s")
        self.g = validate.positive(self.g, "banked_circle g", "m/s^2")
        self.yaw = validate.real(self.yaw, "banked_circle yaw", unit="rad")
        with np.errstate(over="ignore", divide="ignore"):
            w, T = np.sqrt(self.g * np.tan(np.radians(self.bank_deg)) / self.radius), \
                np.float64(self.ramp)
            rates = (w, w * _PEAKS[0] / T, w * _PEAKS[1] / T**2)
        _check_peaks("banked_circle", self.radius, rates, f"radius {validate.plain(self.radius)} "
                     f"m, bank_deg {validate.plain(self.bank_deg)}, ramp "
                     f"{validate.plain(self.ramp)} s and g {validate.plain(self.g)} m/s^2")

    @property
    def rate(self) -> float:
        """The angular rate on the circle, sqrt(g tan(bank) / radius) (rad/s)."""
        return float(np.sqrt(self.g * np.tan(np.radians(self.bank_deg)) / self.radius))

    def _pvaj(self, t):
        w, T = self.rate, np.float64(self.ramp)     # numpy's powers (inf, not OverflowError)
        tau = t / T
        sigma, sigma1, sigma2, _ = septic_step(tau)
        c = np.clip(tau, 0.0, 1.0)
        # th = w T S(tau) on the ramp, S the integral of the septic step (S(1) = 1/2)
        ramp_angle = w * T * (7 * c**5 - 14 * c**6 + 10 * c**7 - 2.5 * c**8)
        th = ramp_angle + w * np.maximum(t - T, 0.0)
        return _on_circle(np.asarray(self.center, float), self.radius, _E1, _E2, th,
                          w * sigma, w * sigma1 / T, w * sigma2 / T**2)
