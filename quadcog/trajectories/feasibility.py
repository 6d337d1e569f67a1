"""Can the vehicle follow a reference? Acceleration and jerk against what its rotors allow.

A reference asks for the thrust vector ``f = m (a + g e_z)`` (ground axes): its size must stay
within the rotors' total thrust, it must point up (rotors only push; unless the divergence
limit ``limits.max_tilt_deg`` is 90 deg or more, when the vehicle may fly upside down) and tilt
no further than that limit. The jerk turns that vector: its direction rotates
at ``|j_perp| / |a + g e_z|`` (rad/s, ``j_perp`` the part of the jerk across the thrust), a body
rate the vehicle must reach. The largest rate allowed is the one its rotors build up at full
differential thrust within 45 deg of rotation, ``omega_max = sqrt(2 alpha_max pi / 4)`` with
``alpha_max`` the smaller of the roll and pitch angular accelerations the mixer can give
(moment / inertia about O). These are necessary conditions, not sufficient ones: a reference
within them may still be hard to track, but one outside them cannot be followed exactly.
"""
from dataclasses import asdict, dataclass
import itertools
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from quadcog import config, validate
from quadcog.errors import InputError
from quadcog.numerics import row_norms
from quadcog.trajectories.analytic import ACC, JERK, REF_SIZE
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["ReferenceLimits", "ReferenceCheck", "reference_limits", "check_reference"]


@dataclass
class ReferenceLimits:
    """What a vehicle can follow (see the module docstring).

    Parameters
    ----------
    max_specific_thrust : float
        The rotors' largest total thrust per mass (m/s^2).
    max_tilt : float
        The largest tilt of the thrust vector (rad).
    max_rate : float
        The largest rate of the thrust direction (rad/s).
    """
    max_specific_thrust: float
    max_tilt: float
    max_rate: float


@dataclass
class ReferenceCheck:
    """The worst demands of a reference against a vehicle's ReferenceLimits.

    Parameters
    ----------
    feasible : bool
        True when no sample exceeds a limit.
    max_acceleration : float
        Largest |a| of the reference (m/s^2).
    max_jerk : float
        Largest |j| (m/s^3).
    max_specific_thrust : float
        Largest |a + g e_z| asked for (m/s^2).
    min_vertical_thrust : float
        Smallest (a + g e_z)_z (m/s^2); must be > 0 (rotors only push).
    max_tilt_deg : float
        Largest tilt of the thrust vector asked for (deg).
    max_rate : float
        Largest thrust-direction rate asked for (rad/s).
    limits : ReferenceLimits
        The vehicle's limits the reference was checked against.
    first_violation_t : float or None
        Time of the first sample beyond a limit (s), None when feasible.
    reason : str or None
        Which limits are exceeded and by how much, None when feasible.
    """
    feasible: bool
    max_acceleration: float          # m/s^2, largest |a| of the reference
    max_jerk: float                  # m/s^3, largest |j|
    max_specific_thrust: float       # m/s^2, largest |a + g e_z| asked for
    min_vertical_thrust: float       # m/s^2, smallest (a + g e_z)_z (must be > 0: push only)
    max_tilt_deg: float              # largest tilt of the thrust vector asked for
    max_rate: float                  # rad/s, largest thrust-direction rate asked for
    limits: ReferenceLimits
    first_violation_t: float | None  # s
    reason: str | None

    def as_dict(self) -> dict[str, Any]:
        """Plain values, for metrics.json.

        Returns
        -------
        dict of str to Any
            {field: value}, ``limits`` as a dict of its own.
        """
        return asdict(self)


def reference_limits(vehicle: Vehicle, max_tilt: float | None = None) -> ReferenceLimits:
    """What a vehicle can follow.

    Parameters
    ----------
    vehicle : quadcog.Vehicle
        The vehicle (its mass, inertia, mixer and rotor thrust limits).
    max_tilt : float, optional
        Largest tilt of the thrust (rad); default the divergence limit
        ``config.defaults["limits.max_tilt_deg"]``.

    Returns
    -------
    ReferenceLimits
        Thrust per mass (m/s^2), tilt (rad) and thrust-direction rate (rad/s).

    Raises
    ------
    InputError
        ``vehicle`` not a Vehicle, or ``max_tilt`` not a number in (0, pi] rad.
    """
    if not isinstance(vehicle, Vehicle):
        validate.fail("vehicle", "a quadcog Vehicle", vehicle)
    if max_tilt is None:
        max_tilt = math.radians(config.get("limits.max_tilt_deg"))
    # the divergence limit's range (quadcog.config: max_tilt_deg in (0, 180])
    max_tilt = validate.real(max_tilt, "max_tilt", lo=0.0, hi=math.pi, lo_open=True, unit="rad")
    mixer = vehicle.mixer()                     # U = mixer @ f
    lo, hi = vehicle.min_rotor_thrust, vehicle.max_rotor_thrust
    corners = np.array(list(itertools.product((lo, hi), repeat=mixer.shape[1])))
    U = corners @ mixer.T                       # every corner of the rotor-thrust box
    alpha = min(U[:, 1].max() / vehicle.Ixx, U[:, 2].max() / vehicle.Iyy)
    return ReferenceLimits(max_specific_thrust=float(U[:, 0].max() / vehicle.m),
                           max_tilt=float(max_tilt),
                           max_rate=float(math.sqrt(2 * alpha * math.pi / 4)))


def check_reference(t: npt.NDArray[np.float64], ref: npt.NDArray[np.float64], vehicle: Vehicle,
                    max_tilt: float | None = None, constant: bool = False) -> ReferenceCheck:
    """Check reference rows against what a vehicle can follow.

    Parameters
    ----------
    t : (N,) numpy.ndarray
        Times of the rows (s).
    ref : (N, 14) numpy.ndarray
        Reference rows (``quadcog.trajectories.analytic``: p, v, a (m/s^2), j (m/s^3), yaw,
        yaw rate).
    vehicle : quadcog.Vehicle
        The vehicle that is to follow them.
    max_tilt : float, optional
        Largest tilt of the thrust (rad); default as ``reference_limits``.
    constant : bool
        The rows are all the same (``Trajectory.constant``): only the first is read and
        checked.

    Returns
    -------
    ReferenceCheck
        The worst demands, whether they are feasible, and the first time they are not.

    Raises
    ------
    InputError
        ``t`` not (N,) finite times, ``ref`` not (N, 14) finite rows (N >= 1), ``constant`` not
        a bool, or what ``reference_limits`` raises.
    """
    constant = validate.flag(constant, "constant")
    if constant and isinstance(t, np.ndarray) and isinstance(ref, np.ndarray) and \
            t.ndim == 1 and ref.ndim == 2 and t.size == ref.shape[0]:
        # every row the same (a hover): the first says it all, and only it is read (the
        # check of a long run's rows reads them all twice)
        t, ref = t[:1], ref[:1]
    t, ref = _rows(t, ref)
    limits = reference_limits(vehicle, max_tilt)
    a, j = ref[:, ACC], ref[:, JERK]
    if constant:
        a, j, t = a[:1], j[:1], t[:1]
    f = a + np.array([0.0, 0.0, vehicle.g])                     # specific thrust vector
    # row_norms and the sums written out: the bits of np.linalg.norm(., axis=1) and
    # np.sum(., axis=1), in a fraction of their time (they loop per row of 3)
    size = row_norms(f)
    safe = np.maximum(size, 1e-12)
    tilt = np.arccos(np.clip(f[:, 2] / safe, -1.0, 1.0))
    along = (j[:, 0] * f[:, 0] + j[:, 1] * f[:, 1] + j[:, 2] * f[:, 2]) / safe
    j_perp = row_norms(j - along[:, None] * f / safe[:, None])
    rate = j_perp / safe
    a_size, j_size = row_norms(a).max(), row_norms(j).max()
    bad = {"thrust": size > limits.max_specific_thrust,
           # upside down (a flip) the rotors push along a body z that points down: a thrust
           # vector below the horizon is a fault only where the tilt limit keeps it upright
           "push": (f[:, 2] <= 0) & (limits.max_tilt < math.pi / 2),
           "tilt": tilt > limits.max_tilt,
           "jerk": rate > limits.max_rate}
    words = {"thrust": f"|a + g e_z| up to {size.max():.3g} m/s^2 > "
                       f"{limits.max_specific_thrust:.3g} (rotors' total thrust / m)",
             "push": f"the thrust would have to pull down ((a + g e_z)_z = {f[:, 2].min():.3g} "
                     f"m/s^2)",
             "tilt": f"tilt of the thrust up to {math.degrees(tilt.max()):.3g} deg > "
                     f"{math.degrees(limits.max_tilt):.3g} deg",
             "jerk": f"jerk {j_size:.3g} m/s^3 turns the thrust at "
                     f"up to {rate.max():.3g} rad/s > {limits.max_rate:.3g} rad/s"}
    any_bad = np.zeros(len(t), bool)
    for b in bad.values():
        any_bad |= b
    first = float(t[np.argmax(any_bad)]) if any_bad.any() else None
    reason = "; ".join(words[k] for k, b in bad.items() if b.any()) or None
    return ReferenceCheck(
        feasible=not any_bad.any(),
        max_acceleration=float(a_size), max_jerk=float(j_size),
        max_specific_thrust=float(size.max()), min_vertical_thrust=float(f[:, 2].min()),
        max_tilt_deg=float(np.degrees(tilt.max())), max_rate=float(rate.max()),
        limits=limits, first_violation_t=first, reason=reason)


def _rows(t, ref):
    """``t`` (N,) and ``ref`` (N, 14) as float arrays of finite numbers, N >= 1. A run's own
    float64 arrays are taken as they are (no copy of a long run's rows); their finiteness is
    read from their extremes (NaN and inf carry through min and max), the rest converted and
    checked by ``quadcog.validate.array``."""
    def checked(value, where, shape, what):
        if isinstance(value, np.ndarray) and value.dtype == np.float64 and \
                value.ndim == len(shape) and value.size and \
                all(d is None or d == n for d, n in zip(shape, value.shape)) and \
                np.isfinite(value.min()) and np.isfinite(value.max()):
            return value
        return validate.array(value, where, shape, what=what)
    t = checked(t, "t", (None,), "(N,) finite times (s)")
    ref = checked(ref, "ref", (None, REF_SIZE), f"(N, {REF_SIZE}) finite reference rows")
    if not (t.size and ref.shape[0] == t.size):
        raise InputError(f"t, ref: expected one time per reference row and at least one row, "
                         f"got {t.size} times and {ref.shape[0]} rows")
    return t, ref
