"""When a run counts as diverged: one rule for every path (single flight compiled or Python
loop, batches), written once as a CasADi expression, and the cause as an enum."""
from dataclasses import dataclass, field
import enum
import math

import casadi as ca
import numpy as np

from quadcog import config, validate
from quadcog.errors import EulerSingularityError


@dataclass(frozen=True)
class Limits:
    """When a run counts as diverged: position error over ``max_position_error`` (m) or
    |phi| or |theta| over ``max_tilt`` (rad). Defaults: ``quadcog.config.defaults``."""
    max_position_error: float = field(
        default_factory=lambda: config.defaults["limits.max_position_error"])
    max_tilt: float = field(
        default_factory=lambda: math.radians(config.defaults["limits.max_tilt_deg"]))

    def __post_init__(self):
        # frozen: set the checked floats through object.__setattr__
        object.__setattr__(self, "max_position_error", validate.positive(
            self.max_position_error, "Limits.max_position_error", "m"))
        object.__setattr__(self, "max_tilt", validate.real(
            self.max_tilt, "Limits.max_tilt", lo=0.0, hi=math.pi, lo_open=True, unit="rad"))


class DivergenceCause(enum.IntEnum):
    """Why a run stopped; ``describe(limits)`` says it in words. The values are the codes of
    ``divergence_rule`` (0: running)."""
    NON_FINITE = 1
    POSITION_ERROR = 2
    TILT = 3

    def describe(self, limits):
        """A readable sentence naming the limit, e.g. 'position error over 10 m'."""
        if self is DivergenceCause.NON_FINITE:
            return "non-finite state, controller state or input"
        if self is DivergenceCause.POSITION_ERROR:
            return f"position error over {limits.max_position_error:g} m"
        return f"|phi| or |theta| over {math.degrees(limits.max_tilt):.0f} deg"


def divergence_code(x, position_error, limits, rest=0.0):
    """SX: 0 while running, else the DivergenceCause value of a sample: the state x (12) with
    its position error (m); ``rest`` is the sum of |.| of everything else the sample carries
    (rotor thrusts, controller state, input), which must be finite too. Non-finite first, then
    the position error, then the tilt."""
    # a sum propagates NaN (fmax would drop it) and overflows to inf
    finite = (ca.sum1(ca.fabs(x)) + position_error + rest) < np.inf
    tilt = ca.fmax(ca.fabs(x[3]), ca.fabs(x[4]))
    return ca.if_else(ca.logic_not(finite), int(DivergenceCause.NON_FINITE),
                      ca.if_else(position_error > limits.max_position_error,
                                 int(DivergenceCause.POSITION_ERROR),
                                 ca.if_else(tilt > limits.max_tilt, int(DivergenceCause.TILT), 0)))


_rules = {}


def divergence_rule(limits):
    """CasADi Function (x (12), position_error, rest) -> code (see ``divergence_code``), one
    per Limits (cached). ``first_divergence`` maps it over samples."""
    if limits not in _rules:
        x, e, rest = ca.SX.sym("x", 12), ca.SX.sym("position_error"), ca.SX.sym("rest")
        _rules[limits] = ca.Function("divergence", [x, e, rest],
                                     [divergence_code(x, e, limits, rest)],
                                     ["x", "position_error", "rest"], ["code"])
    return _rules[limits]


def magnitude(a):
    """Sum of |a| over the last axis (inf or NaN when an entry is): the ``rest`` of
    ``divergence_rule``, quietly."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.abs(np.asarray(a, dtype=float)).sum(axis=-1)


def first_divergence(x, position_error, limits, rest=None):
    """(index, DivergenceCause) of the first diverged sample of x (N, 12) with errors (N,) and
    ``rest`` (N,) (see ``divergence_code``; default 0), or (None, None): ``divergence_rule``
    over every sample."""
    n = x.shape[0]
    if n == 0:
        return None, None
    rest = np.zeros(n) if rest is None else np.asarray(rest, dtype=float).reshape(n)
    rule = divergence_rule(limits)
    codes = np.array((rule if n == 1 else rule.map(n))(
        x.T, np.asarray(position_error, dtype=float)[None, :], rest[None, :])).ravel()
    hit = np.flatnonzero(codes)
    if not hit.size:
        return None, None
    return int(hit[0]), DivergenceCause(int(codes[hit[0]]))


def check_euler_singularity(t, x, limits):
    """Raise EulerSingularityError when |theta| reaches pi/2 in x (N, 12) at times t (N,)
    (only possible when the tilt limit is at or above 90 deg)."""
    if limits.max_tilt < np.pi / 2 - 1e-6:
        return
    th = np.abs(x[:, 4])
    hit = np.flatnonzero(np.isfinite(th) & (th >= np.pi / 2 - 1e-6))
    if hit.size:
        k = hit[0]
        raise EulerSingularityError(
            f"|theta| = {th[k]:.6f} rad reached pi/2 at t = {t[k]:.4f} s: the Euler-angle "
            f"kinematics (Q(eta2)) are singular there; lower Limits.max_tilt below 90 deg")
