"""When a run counts as diverged: one rule for every path (single flight compiled or Python
loop, batches), written once as a CasADi expression, and the cause as an enum."""
from dataclasses import dataclass, field
import enum
import math

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog import config, validate
from quadcog.codegen.fastcall import evaluate
from quadcog.errors import EulerSingularityError
from quadcog.model.conventions import N_STATE

__all__ = ["Limits", "DivergenceCause", "divergence_code", "divergence_rule", "magnitude",
           "first_divergence", "check_euler_singularity"]


@dataclass(frozen=True)
class Limits:
    """When a run counts as diverged.

    A run diverges when its position error exceeds ``max_position_error`` or |phi| or |theta|
    exceeds ``max_tilt``. Defaults: ``quadcog.config.defaults``.

    Parameters
    ----------
    max_position_error : float
        Largest position error |p - p_ref| (m), > 0; default
        ``config.defaults["limits.max_position_error"]``.
    max_tilt : float
        Largest roll or pitch angle (rad), in (0, pi]; default
        ``config.defaults["limits.max_tilt_deg"]`` in radians.

    Raises
    ------
    quadcog.InputError
        A limit that is not a number in its range, or a default in ``quadcog.config.defaults``
        that is not one (named by its key).
    """
    max_position_error: float = field(
        default_factory=lambda: config.get("limits.max_position_error"))
    max_tilt: float = field(
        default_factory=lambda: math.radians(config.get("limits.max_tilt_deg")))

    def __post_init__(self) -> None:
        # frozen: set the checked floats through object.__setattr__
        object.__setattr__(self, "max_position_error", validate.positive(
            self.max_position_error, "Limits.max_position_error", "m"))
        object.__setattr__(self, "max_tilt", validate.real(
            self.max_tilt, "Limits.max_tilt", lo=0.0, hi=math.pi, lo_open=True, unit="rad"))


class DivergenceCause(enum.IntEnum):
    """Why a run stopped; ``describe(limits)`` says it in words.

    The values are the codes of ``divergence_rule`` (0: running): ``NON_FINITE`` (1), a
    non-finite state, controller state or input; ``POSITION_ERROR`` (2); ``TILT`` (3).
    """
    NON_FINITE = 1
    POSITION_ERROR = 2
    TILT = 3

    def describe(self, limits: Limits) -> str:
        """A readable sentence naming the limit, e.g. 'position error over 10 m'.

        Parameters
        ----------
        limits : Limits
            The limits the run was held to (their values are named).

        Returns
        -------
        str
            The cause in words.
        """
        if self is DivergenceCause.NON_FINITE:
            return "non-finite state, controller state or input"
        if self is DivergenceCause.POSITION_ERROR:
            return f"position error over {limits.max_position_error:g} m"
        return f"|phi| or |theta| over {math.degrees(limits.max_tilt):.0f} deg"


def divergence_code(x: ca.SX, position_error: ca.SX | float, limits: Limits,
                    rest: ca.SX | float = 0.0) -> ca.SX:
    """The divergence code of a sample, as a CasADi expression.

    Non-finite is checked first, then the position error, then the tilt.

    Parameters
    ----------
    x : (12,) casadi.SX
        The state [m, rad, m/s, rad/s].
    position_error : casadi.SX or float
        Its position error |p - p_ref| (m).
    limits : Limits
        When the sample counts as diverged.
    rest : casadi.SX or float
        The sum of |.| of everything else the sample carries (rotor thrusts, controller
        state, input), which must be finite too.

    Returns
    -------
    casadi.SX
        0 while running, else the ``DivergenceCause`` value.
    """
    # a sum propagates NaN (fmax would drop it) and overflows to inf
    finite = (ca.sum1(ca.fabs(x)) + position_error + rest) < np.inf
    tilt = ca.fmax(ca.fabs(x[3]), ca.fabs(x[4]))
    return ca.if_else(ca.logic_not(finite), int(DivergenceCause.NON_FINITE),
                      ca.if_else(position_error > limits.max_position_error,
                                 int(DivergenceCause.POSITION_ERROR),
                                 ca.if_else(tilt > limits.max_tilt, int(DivergenceCause.TILT), 0)))


_rules: dict[Limits, ca.Function] = {}


def divergence_rule(limits: Limits) -> ca.Function:
    """The divergence rule as a CasADi Function, one per Limits (cached).

    ``first_divergence`` maps it over samples.

    Parameters
    ----------
    limits : Limits
        When a sample counts as diverged.

    Returns
    -------
    casadi.Function
        ``divergence(x (12), position_error, rest) -> code`` (see ``divergence_code``).
    """
    if limits not in _rules:
        x, e, rest = ca.SX.sym("x", N_STATE), ca.SX.sym("position_error"), ca.SX.sym("rest")
        _rules[limits] = ca.Function("divergence", [x, e, rest],
                                     [divergence_code(x, e, limits, rest)],
                                     ["x", "position_error", "rest"], ["code"])
    return _rules[limits]


def magnitude(a: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Sum of |a| over the last axis: the ``rest`` of ``divergence_rule``, quietly.

    Parameters
    ----------
    a : (..., k) array_like
        What a sample carries besides its state (rotor thrusts, controller state, input).

    Returns
    -------
    (...) numpy.ndarray
        The sums (inf or NaN when an entry is; no warning).
    """
    with np.errstate(over="ignore", invalid="ignore"):
        return np.abs(np.asarray(a, dtype=float)).sum(axis=-1)


def first_divergence(x: npt.NDArray[np.float64], position_error: npt.ArrayLike, limits: Limits,
                     rest: npt.ArrayLike | None = None
                     ) -> tuple[int, DivergenceCause] | tuple[None, None]:
    """The first diverged sample: ``divergence_rule`` over every sample.

    Parameters
    ----------
    x : (N, 12) numpy.ndarray
        States [m, rad, m/s, rad/s].
    position_error : (N,) array_like
        Their position errors (m).
    limits : Limits
        When a sample counts as diverged.
    rest : (N,) array_like, optional
        The ``rest`` of each sample (see ``divergence_code``); default 0.

    Returns
    -------
    tuple of (int, DivergenceCause) or (None, None)
        The index of the first diverged sample and why, or (None, None) when none is.
    """
    n = x.shape[0]
    if n == 0:
        return None, None
    rest = np.zeros(n) if rest is None else np.asarray(rest, dtype=float).reshape(n)
    e = np.asarray(position_error, dtype=float).reshape(n)
    if n == 1:          # one sample (a run's start and end) without DM conversions
        codes = evaluate(divergence_rule(limits), x[0], e, rest)[0]
    else:
        codes = np.array(divergence_rule(limits).map(n)(x.T, e[None, :], rest[None, :])).ravel()
    hit = np.flatnonzero(codes)
    if not hit.size:
        return None, None
    return int(hit[0]), DivergenceCause(int(codes[hit[0]]))


def check_euler_singularity(t: npt.NDArray[np.float64], x: npt.NDArray[np.float64],
                            limits: Limits) -> None:
    """Raise EulerSingularityError when |theta| reaches pi/2.

    Only possible when the tilt limit is at or above 90 deg.

    Parameters
    ----------
    t : (N,) numpy.ndarray
        Sample times (s).
    x : (N, 12) numpy.ndarray
        States [m, rad, m/s, rad/s].
    limits : Limits
        The run's limits (``max_tilt``).

    Raises
    ------
    quadcog.EulerSingularityError
        |theta| reached pi/2: the Euler-angle kinematics are singular there.
    """
    if limits.max_tilt < np.pi / 2 - 1e-6:
        return
    th = np.abs(x[:, 4])
    hit = np.flatnonzero(np.isfinite(th) & (th >= np.pi / 2 - 1e-6))
    if hit.size:
        k = hit[0]
        raise EulerSingularityError(
            f"|theta| = {th[k]:.6f} rad reached pi/2 at t = {t[k]:.4f} s: the Euler-angle "
            f"kinematics (Q(eta2)) are singular there; lower Limits.max_tilt below 90 deg")
