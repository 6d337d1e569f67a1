"""A minimum-snap trajectory through waypoints, with exact derivatives.

Each axis is a piecewise polynomial of degree 7, one piece per segment between waypoints. With
the segment times fixed, the curve that passes through the waypoints, starts and ends at rest
(velocity, acceleration and jerk zero) and minimizes the integral of the squared snap is the
septic spline whose pieces join with continuous derivatives up to the 6th (the Euler-Lagrange
equation of the snap integral is p^(8) = 0 on each piece, and the free interior derivatives
make the jumps of the 4th..6th derivatives vanish). That is a square linear system of 8 rows per
segment, solved once; position, velocity, acceleration and jerk are the polynomial and its
exact derivatives.

Time allocation (when ``times`` is not given): each segment gets the time a rest-to-rest
trapezoidal speed profile along its straight line needs with speed at most ``max_speed`` and
acceleration at most ``max_acceleration``: ``T = d / v + v / a`` when the segment is long
enough to reach the speed (``d >= v^2 / a``), else ``T = 2 sqrt(d / a)``; at least
``min_segment_time``. The smooth curve then stays near those limits (not exactly within them:
``quadcog.trajectories.feasibility.check_reference`` checks a reference against what the
vehicle can follow).
"""
import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.errors import InputError
from quadcog.kinds import Number, Points, Vector
from quadcog.model.parameters import LARGEST
from quadcog.trajectories.analytic import Trajectory, sample_times

__all__ = ["MinimumSnap", "allocate_times", "DEGREE"]

DEGREE = 7                   # minimum snap: 2 r - 1 with r = 4
N_COEF = DEGREE + 1
# Segment durations (s) the degree-7 system can be solved for in floating point: T^7 must
# neither underflow (1e-300 s gives a singular matrix) nor make the flight absurdly long.
MIN_SEGMENT_TIME = 1e-3
MAX_SEGMENT_TIME = 1e6


def _derivative_row(tau, order):
    """Row of d^order/dtau^order [1, tau, ..., tau^7] at tau (one row, written out: the
    tests' dense system is built from it)."""
    row = np.zeros(N_COEF)
    for k in range(order, N_COEF):
        row[k] = np.prod(np.arange(k - order + 1, k + 1)) * tau ** (k - order)
    return row


def _derivative_rows(tau, order):
    """Rows (m, 8) of d^order/dtau^order [1, tau, ..., tau^7] at each tau (m,)."""
    tau = np.asarray(tau, dtype=float)
    powers = np.ones((tau.size, N_COEF))          # 1, tau, ..., tau^7 by products
    powers[:, 1:] = tau[:, None]
    np.cumprod(powers, axis=1, out=powers)
    rows = np.zeros((tau.size, N_COEF))
    for k in range(order, N_COEF):
        rows[:, k] = np.prod(np.arange(k - order + 1, k + 1)) * powers[:, k - order]
    return rows


def allocate_times(points: npt.ArrayLike, max_speed: float = 1.0,
                   max_acceleration: float = 1.0,
                   min_segment_time: float = 0.5) -> npt.NDArray[np.float64]:
    """Segment durations by the rest-to-rest trapezoidal rule of the module docstring.

    Parameters
    ----------
    points : (n+1, 3) array_like
        Waypoints (m).
    max_speed : float
        Largest speed along a segment (m/s), > 0.
    max_acceleration : float
        Largest acceleration along a segment (m/s^2), > 0.
    min_segment_time : float
        Shortest segment duration (s).

    Returns
    -------
    (n,) numpy.ndarray
        Duration of each segment (s).

    Raises
    ------
    InputError
        ``points`` not at least 2 rows of 3 finite numbers, a limit not a positive number, or
        a segment whose time overflows (a speed of 1e-320 m/s).
    """
    what = "at least 2 rows of 3 finite numbers (m)"
    pts = validate.array(points, "points", (None, 3), what=what)
    if pts.shape[0] < 2:
        validate.fail("points", what, points)
    v = validate.positive(max_speed, "max_speed", unit="m/s")
    a = validate.positive(max_acceleration, "max_acceleration", unit="m/s^2")
    min_segment_time = validate.nonnegative(min_segment_time, "min_segment_time", unit="s")
    with np.errstate(over="ignore", invalid="ignore"):     # refused below, by name
        d = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        full = d >= v * v / a
        T = np.maximum(np.where(full, d / v + v / a, 2 * np.sqrt(d / a)), min_segment_time)
    if not np.isfinite(T).all():
        k = int(np.argmax(~np.isfinite(T)))
        raise InputError(f"max_speed = {validate.plain(v)} m/s, max_acceleration = "
                         f"{validate.plain(a)} m/s^2: segment {k} ({validate.plain(float(d[k]))} "
                         "m) would take longer than a float can hold; expected a speed and an "
                         "acceleration that cross it in finite time")
    return T


class MinimumSnap(Trajectory):
    """Minimum-snap trajectory through ``waypoints`` (n+1, 3) m.

    Parameters
    ----------
    waypoints : (n+1, 3) array_like
        Positions in m, n >= 1 segments.
    times : (n+1,) array_like, optional
        Arrival times in s, increasing, starting at 0 (or any start). Default: allocated by
        ``allocate_times`` from ``max_speed`` and ``max_acceleration``, starting at 0.
    max_speed : float
        m/s, for the time allocation.
    max_acceleration : float
        m/s^2, for the time allocation.
    yaw : float
        Heading held along the path (rad).

    Raises
    ------
    InputError
        When the waypoints, times or limits are not what is expected.

    Notes
    -----
    Before the first time the reference rests at the first waypoint; after the last, at the
    last one.
    """

    def __init__(self, waypoints: Points,
                 times: Vector | npt.NDArray[np.float64] | None = None,
                 max_speed: Number = 1.0, max_acceleration: Number = 1.0,
                 yaw: Number = 0.0) -> None:
        what = "at least 2 rows of 3 finite numbers (m)"
        pts = validate.array(waypoints, "waypoints", (None, 3), what=what)
        if pts.shape[0] < 2:
            validate.fail("waypoints", what, waypoints)
        if not np.abs(pts).max() <= LARGEST:
            validate.fail("waypoints", f"coordinates within +-{LARGEST:g} m", waypoints)
        if not np.any(np.diff(pts, axis=0)):
            validate.fail("waypoints", "at least two different points (m)", waypoints)
        max_speed = validate.positive(max_speed, "max_speed", unit="m/s")
        max_acceleration = validate.positive(max_acceleration, "max_acceleration", unit="m/s^2")
        yaw = validate.real(yaw, "yaw", unit="rad")
        if times is None:
            T = allocate_times(pts, max_speed, max_acceleration)
            if not T.max() <= MAX_SEGMENT_TIME:
                raise InputError(f"max_speed = {max_speed!r} m/s, max_acceleration = "
                                 f"{max_acceleration!r} m/s^2: a segment would take "
                                 f"{float(T.max()):.3g} s; expected speeds and accelerations "
                                 f"that give segments of at most {MAX_SEGMENT_TIME:g} s")
            times = np.r_[0.0, np.cumsum(T)]
        times = validate.array(times, "times", what=f"{len(pts)} increasing finite numbers (s)")
        if times.shape != (len(pts),) or not np.isfinite(times).all() or np.any(
                np.diff(times) <= 0):
            # plain: a list of 10,000 times is named by its shape, not printed
            raise InputError(f"times: expected {len(pts)} increasing finite numbers (s), one "
                             f"per waypoint, got {validate.plain(times)}")
        T = np.diff(times)
        if T.min() < MIN_SEGMENT_TIME or T.max() > MAX_SEGMENT_TIME:
            k = int(np.argmin(T)) if T.min() < MIN_SEGMENT_TIME else int(np.argmax(T))
            raise InputError(f"times: segment {k} lasts {T[k]:.3g} s (from {float(times[k])!r} to "
                             f"{float(times[k + 1])!r}); expected every segment between "
                             f"{MIN_SEGMENT_TIME:g} s and {MAX_SEGMENT_TIME:g} s")
        self.waypoints, self.times, self.yaw = pts, times, float(yaw)
        self.coefficients = self._solve()          # (n, 8, 3), in tau = t - t_i

    @property
    def duration(self) -> float:
        """float: Time of the last waypoint minus the first (s)."""
        return float(self.times[-1] - self.times[0])

    def _solve(self):
        # The system is banded: with the rows in segment order (the start's rest, then each
        # segment's two passes and the six joins to the next, the end's rest last), row
        # 3 + 8 i + k touches only the 16 coefficients of segments i and i + 1. LAPACK's
        # banded LU (partial pivoting, as a dense solve) then costs time and memory linear in
        # the waypoints: a dense solve of the 8n x 8n matrix grows as n^3 (1 GB at 1,600
        # waypoints), SuperLU's sparse one as n^1.4, and a Python call per row took 13 s for
        # 10,000 waypoints.
        from scipy.linalg import LinAlgError, solve_banded  # here: slow to import
        n = len(self.waypoints) - 1
        T = np.diff(self.times)
        seg = np.arange(n)
        base = 3 + N_COEF * seg                  # the first row of segment i's block
        rows, cols, vals, rhs = [], [], [], np.zeros((N_COEF * n, 3))

        def put(row, segs, tau, order, sign=1.0):
            """Rows ``row`` (m,) hold d^order/dtau^order of segment ``segs`` (m,) at ``tau``."""
            rows.append(np.repeat(row, N_COEF))
            cols.append((N_COEF * segs[:, None] + np.arange(N_COEF)).ravel())
            vals.append((sign * _derivative_rows(tau, order)).ravel())

        for order in (1, 2, 3):                  # at rest at both ends
            put(np.array([order - 1]), seg[:1], np.zeros(1), order)
            put(base[-1:] + 1 + order, seg[-1:], T[-1:], order)
        put(base, seg, np.zeros(n), 0)           # each piece passes through both its ends
        put(base + 1, seg, T, 0)
        rhs[base], rhs[base + 1] = self.waypoints[:-1], self.waypoints[1:]
        for order in range(1, 7):                # interior joins: derivatives 1..6 continuous
            put(base[:-1] + 1 + order, seg[:-1], T[:-1], order)
            put(base[:-1] + 1 + order, seg[1:], np.zeros(n - 1), order, sign=-1.0)
        r, c, v = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
        lower, upper = int((r - c).max()), int((c - r).max())
        band = np.zeros((lower + upper + 1, N_COEF * n))
        band[upper + r - c, c] = v
        try:
            coef = solve_banded((lower, upper), band, rhs, check_finite=False)
        except LinAlgError:                      # an exactly singular system
            coef = np.full((N_COEF * n, 3), np.nan)
        if not np.isfinite(coef).all():
            raise InputError(f"waypoints: the minimum-snap system of {len(self.waypoints)} "
                             "waypoints and their times is singular (no finite polynomial "
                             "passes them); expected distinct times and finite points")
        return coef.reshape(n, N_COEF, 3)

    def _pvaj(self, t):
        t = np.clip(t, self.times[0], self.times[-1])
        seg = np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 2)
        tau = t - self.times[seg]
        c = self.coefficients[seg]                    # (N, 8, 3)
        out = []
        for order in range(4):
            k = np.arange(order, N_COEF)
            factor = np.array([np.prod(np.arange(j - order + 1, j + 1)) for j in k])
            powers = tau[:, None] ** (k - order)[None, :]           # (N, len(k))
            out.append(np.einsum("nk,nkd->nd", powers * factor, c[:, order:, :]))
        return out[0], out[1], out[2], out[3]

    def sample(self, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Reference rows; at rest before the first and after the last waypoint.

        Parameters
        ----------
        t : float or (N,) array_like
            Times (s).

        Returns
        -------
        (N, 14) numpy.ndarray
            One row ``[p (m), v (m/s), a (m/s^2), j (m/s^3), yaw (rad), yaw_rate (rad/s)]``
            per time.

        Raises
        ------
        InputError
            When a row is not finite or beyond ``REFERENCE_LIMIT``.
        """
        t = sample_times(t)
        ref = super().sample(t)
        resting = (t < self.times[0]) | (t > self.times[-1])
        ref[resting, 3:12] = 0.0
        return ref
