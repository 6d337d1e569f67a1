"""What every controller is: a CasADi control law, compiled on demand, callable from Python.

A controller maps (t, x, ref, c) to (U, c_dot): time (s), state x (12,), reference ref (14,)
(see ``quadcog.trajectories.analytic``), its own state c (``n_state``,; the adaptive controller's r_hat)
to the input U (4,) and the rate of its state. ``function()`` is that law as a CasADi Function
(SX, to compose into bigger expressions), ``compiled()`` an allocation-free compiled call.

A controller is designed for a model of the vehicle, ``controller.vehicle`` (a Vehicle: what
the controller believes; by default the Hummingbird with r_G = 0). ``for_vehicle(v)`` gives the
same controller (same settings) designed for another model; ``quadcog.simulate`` uses it for
its ``controller_model`` argument. Subclasses take ``vehicle`` and ``model`` as their first two
parameters and their settings as keywords.
"""

import casadi as ca
import numpy as np

from quadcog.codegen.compiled import compile_function
from quadcog.codegen.fastcall import FastCall
from quadcog.errors import InputError
from quadcog.model.functions import load
from quadcog.model.parameters import with_cog
from quadcog.trajectories.analytic import REF_SIZE
from quadcog.validate import array, plain, real, vector
from quadcog.vehicles.vehicle import HUMMINGBIRD, Vehicle


class Controller:
    """Base class; subclasses set ``name``, ``n_state`` and implement ``expression``."""

    name = "controller"
    n_state = 0
    estimates_cog = False        # True when the first 3 states are an estimate of r_G

    def __new__(cls, *args, **kwargs):
        self = super().__new__(cls)
        self._init_args = (args, kwargs)        # to redesign the same controller: for_vehicle
        return self

    def __init__(self, vehicle=None, model=None):
        """vehicle: the controller's model of the vehicle, a Vehicle (default: the Hummingbird
        with r_G = 0: the controller does not know the CoG). model: a quadcog Model (the
        generated functions; default ``quadcog.load()``)."""
        self.model = model or load()
        vehicle = HUMMINGBIRD if vehicle is None else vehicle
        if not isinstance(vehicle, Vehicle):
            raise InputError(f"vehicle must be a quadcog Vehicle (the controller's model), got "
                             f"{vehicle!r}")
        self.vehicle = vehicle
        self.nominal = vehicle.parameters()       # the model's parameter vector p (14,)
        self._function = None
        self._compiled = None
        self._cache_key = None
        self._jacobian = None
        self._designs = {}

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
        """The control law at one instant, arguments checked.

        Parameters
        ----------
        t : float
            Time (s), finite.
        x : array_like, shape (12,)
            State (quadcog.model.conventions.STATE_NAMES), finite real numbers.
        ref : array_like, shape (14,)
            Reference (position, velocity, acceleration, jerk, yaw, yaw rate).
        c : array_like, shape (n_state,), optional
            Controller state (default ``initial_state()``).

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            U (4,) = [U1 (N), U2, U3, U4 (N m)] and c_dot (n_state,).

        Raises
        ------
        InputError
            A wrong type, shape or non-finite entry (strings, complex numbers, sets and
            ragged lists included), or a state at which the law is not finite (such as a
            1e200 m/s velocity: U would be NaN).
        """
        t = real(t, "t", unit="s")
        x = vector(x, "x", 12)
        ref = vector(ref, "ref", REF_SIZE)
        c = self.initial_state() if c is None else (
            vector(c, "c", self.n_state) if self.n_state else array(c, "c", (0,)))
        U, c_dot = self.function()(t, x, ref, c)
        U, c_dot = np.array(U).ravel(), np.array(c_dot).ravel()
        if not (np.isfinite(U).all() and np.isfinite(c_dot).all()):
            k = int(np.argmax(np.abs(x)))
            raise InputError(f"controller {self.name!r}: the law is not finite at t = {t} "
                             f"(U = {plain(U.tolist())}); the largest state entry is "
                             f"x[{k}] = {plain(float(x[k]))}: expected a state within the "
                             f"range in which the law can be evaluated in floating point")
        return U, c_dot

    def for_vehicle(self, vehicle):
        """This controller, with the same settings, designed for the model ``vehicle`` (a
        Vehicle); ``self`` when that is already its model. Designs are kept per vehicle."""
        if vehicle == self.vehicle:
            return self
        if vehicle not in self._designs:
            args, kwargs = self._init_args
            kwargs = dict(kwargs, **dict(zip(("vehicle", "model"), args)))
            if len(args) > 2:
                raise InputError(f"{type(self).__name__} was built with positional settings; "
                                 "pass them as keywords so that it can be redesigned")
            kwargs.update(vehicle=vehicle, model=self.model)
            self._designs[vehicle] = type(self)(**kwargs)
        return self._designs[vehicle]

    def cache_key(self):
        """What identifies this controller's compiled code: its class and its law, serialized
        (computed once)."""
        if self._cache_key is None:
            self._cache_key = (type(self).__name__, self.function().serialize())
        return self._cache_key

    def closed_loop_jacobian(self):
        """CasADi Function (x (12), ref (14), p (14)) -> d/dx f(x, U(0, x, ref, c0), p): the
        Jacobian of the closed loop at the controller's initial state ``c0``, f the truth
        dynamics without extra effects (built once)."""
        if self._jacobian is None:
            x, ref, p = ca.SX.sym("x", 12), ca.SX.sym("ref", REF_SIZE), ca.SX.sym("p", 14)
            U, _ = self.function()(0.0, x, ref, self.initial_state())
            f = self.model.casadi_function("truth_dynamics")
            self._jacobian = ca.Function(
                "closed_loop_jacobian", [x, ref, p],
                [ca.jacobian(f(x, U, p, ca.DM.zeros(3), ca.DM.zeros(6)), x)],
                ["x", "ref", "p"], ["A"])
        return self._jacobian

    def nominal_with_cog(self, r):
        """The nominal parameters with r_G = r (SX or numbers)."""
        if isinstance(r, (ca.SX, ca.MX)):
            p = ca.SX(ca.DM(self.nominal))
            return ca.vertcat(p[:11], r)
        return with_cog(self.nominal, r)
