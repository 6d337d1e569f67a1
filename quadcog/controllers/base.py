"""What every controller is: a CasADi control law, compiled on demand, callable from Python.

A controller maps (t, x, ref, c) to (U, c_dot): time (s), state x (12,), reference ref (11,)
(see ``quadcog.trajectory``), its own state c (``n_state``,; the adaptive controller's r_hat)
to the input U (4,) and the rate of its state. ``function()`` is that law as a CasADi Function
(SX, to compose into bigger expressions), ``compiled()`` an allocation-free compiled call.
"""
import casadi as ca
import numpy as np

from ..compiled import compile_function
from ..errors import InputError
from ..fastcall import FastCall
from ..model import load
from ..params import check_parameters, default_parameters, with_cog
from ..trajectory import REF_SIZE


class Controller:
    """Base class; subclasses set ``name``, ``n_state`` and implement ``expression``."""

    name = "controller"
    n_state = 0

    def __init__(self, nominal=None, model=None):
        """nominal: the controller's model parameters p (14,); default: the default vehicle
        with r_G = 0 (the controller does not know the CoG). model: a quadcog Model."""
        self.model = model or load()
        nominal = default_parameters() if nominal is None else np.asarray(nominal, float)
        self.nominal = check_parameters(nominal, "nominal")
        self._function = None
        self._compiled = None

    # -- to implement -------------------------------------------------------------------
    def expression(self, t, x, ref, c):
        """(U (4x1 SX), c_dot (n_state x 1 SX)) for SX symbols t, x, ref, c."""
        raise NotImplementedError

    def project(self, c):
        """The controller state after an update step is mapped through this (SX); identity."""
        return c

    def project_numpy(self, c):
        """``project`` for numpy arrays, in place where possible."""
        return c

    # -- provided ---------------------------------------------------------------------
    def initial_state(self):
        """The controller state at t = 0 (zeros: e.g. r_hat = 0)."""
        return np.zeros(self.n_state)

    def function(self):
        """The control law as a CasADi Function (t, x, ref, c) -> (U, c_dot)."""
        if self._function is None:
            t, x = ca.SX.sym("t"), ca.SX.sym("x", 12)
            ref, c = ca.SX.sym("ref", REF_SIZE), ca.SX.sym("c", self.n_state)
            U, c_dot = self.expression(t, x, ref, c)
            # the generated functions share trigonometry and I_G^{-1}: merge it once here
            U, c_dot = ca.cse([ca.SX(U), ca.SX(c_dot) if self.n_state else ca.SX(0, 1)])
            self._function = ca.Function(f"{self.name}_law", [t, x, ref, c], [U, c_dot],
                                         ["t", "x", "ref", "c"], ["U", "c_dot"])
        return self._function

    def compiled(self):
        """A FastCall of the compiled law: write .inputs [t, x, ref, c], call, read .outputs
        [U, c_dot]. About a microsecond per call; one per thread."""
        if self._compiled is None:
            self._compiled = compile_function(self.function())
        return FastCall(self._compiled)

    def __call__(self, t, x, ref, c=None):
        """(U (4,), c_dot (n_state,)) as numpy arrays; arguments are checked."""
        x = np.asarray(x, dtype=float)
        ref = np.asarray(ref, dtype=float)
        c = self.initial_state() if c is None else np.asarray(c, dtype=float)
        for name, a, n in (("x", x, 12), ("ref", ref, REF_SIZE), ("c", c, self.n_state)):
            if a.shape != (n,):
                raise InputError(f"{name} must have shape ({n},), got shape {a.shape}")
            if not np.isfinite(a).all():
                raise InputError(f"{name} has non-finite entries: {a}")
        U, c_dot = self.function()(float(t), x, ref, c)
        return np.array(U).ravel(), np.array(c_dot).ravel()

    def nominal_with_cog(self, r):
        """The nominal parameters with r_G = r (SX or numbers)."""
        if isinstance(r, (ca.SX, ca.MX)):
            p = ca.SX(ca.DM(self.nominal))
            return ca.vertcat(p[:11], r)
        return with_cog(self.nominal, r)
