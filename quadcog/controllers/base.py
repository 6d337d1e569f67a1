"""What every controller is: a CasADi control law, compiled on demand, callable from Python.

A controller maps (t, x, ref, c) to (U, c_dot): time (s), state x (12,), reference ref (14,)
(see ``quadcog.trajectories.analytic``), its own state c (``n_state``,; the adaptive
controller's r_hat) to the input U (4,) and the rate of its state. ``function()`` is that law
as a CasADi Function (SX, to compose into bigger expressions), ``compiled()`` an
allocation-free compiled call.

A controller is designed for a model of the vehicle, ``controller.vehicle`` (a Vehicle: what
the controller believes; by default the Hummingbird with r_G = 0). ``for_vehicle(v)`` gives the
same controller (same settings) designed for another model; ``quadcog.simulate`` uses it for
its ``controller_model`` argument. Subclasses take ``vehicle`` and ``model`` as their first two
parameters and their settings as keywords. ``quadcog.controllers.template`` states the
interface a Python controller of your own implements; every Controller satisfies it.
"""
from collections import OrderedDict
from collections.abc import Hashable, Sequence
import inspect
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.codegen.compiled import compile_function
from quadcog.codegen.fastcall import FastCall
from quadcog.errors import InputError
from quadcog.model.conventions import N_PARAM, N_STATE
from quadcog.model.functions import Model, load
from quadcog.model.parameters import check_parameters, with_cog
from quadcog.trajectories.analytic import REF_SIZE
from quadcog.validate import array, plain, real, vector
from quadcog.vehicles.vehicle import HUMMINGBIRD, Vehicle

__all__ = ["Controller", "DESIGNS_KEPT"]

# how many designs' law, Jacobian and cache key the process keeps (newest first out last): a
# second Controller of the same class, settings and model then skips its symbolic build
DESIGNS_KEPT = 16
_designs_built: "OrderedDict[Hashable, dict[str, Any]]" = OrderedDict()


def _frozen(value: Any) -> Hashable:
    """A hashable stand-in of a constructor argument that is equal only for equal values;
    TypeError for a kind it does not know (that design is then not kept)."""
    if value is None or isinstance(value, (bool, int, str)):
        return (type(value).__name__, value)
    if isinstance(value, float):            # repr: -0.0 and 0.0 differ
        return ("float", repr(float(value)))
    if isinstance(value, np.ndarray):
        return ("ndarray", value.dtype.str, value.shape, value.tobytes())
    if isinstance(value, (list, tuple)):
        return (type(value).__name__, tuple(_frozen(v) for v in value))
    if isinstance(value, dict):
        return ("dict", tuple(sorted((str(k), _frozen(v)) for k, v in value.items())))
    if isinstance(value, Model):
        return ("model", str(value.folder))
    if isinstance(value, Vehicle):
        return ("vehicle", value)
    raise TypeError(type(value).__name__)


class Controller:
    """Base class; subclasses set ``name``, ``n_state`` and implement ``expression``.

    Parameters
    ----------
    vehicle : Vehicle, optional
        The controller's model of the vehicle (default: the Hummingbird with r_G = 0).
    model : quadcog.model.functions.Model, optional
        The generated functions (default ``quadcog.load()``). These and a subclass's settings
        are kept to redesign the same controller for another model (``for_vehicle``).

    Attributes
    ----------
    name : str
        Short name of the law (results and files name the controller by it).
    n_state : int
        Length of the controller's own state c (0: none).
    estimates_cog : bool
        True when the first 3 states are an estimate r_hat of r_G (m).
    vehicle : Vehicle
        The controller's model of the vehicle (what it believes).
    model : quadcog.model.functions.Model
        The generated functions it is built from.
    nominal : (14,) numpy.ndarray
        ``vehicle.parameters()``.
    """

    name: str = "controller"
    n_state: int = 0
    estimates_cog: bool = False        # True when the first 3 states are an estimate of r_G
    # set by __new__ and __init__ (annotations only, for the type checker)
    _init_args: tuple[tuple[Any, ...], dict[str, Any]]
    _function: ca.Function | None
    _compiled: Any
    _cache_key: tuple[str, str] | None
    _jacobian: ca.Function | None
    _designs: dict[Vehicle, "Controller"]

    def __new__(cls, *args: Any, **kwargs: Any) -> "Controller":
        self = super().__new__(cls)
        self._init_args = (args, kwargs)        # to redesign the same controller: for_vehicle
        return self

    def __init__(self, vehicle: Vehicle | None = None, model: Model | None = None) -> None:
        """Design the controller for a model of the vehicle.

        Parameters
        ----------
        vehicle : Vehicle, optional
            The controller's model of the vehicle (default: the Hummingbird with r_G = 0: the
            controller does not know the CoG).
        model : quadcog.model.functions.Model, optional
            The generated functions (default ``quadcog.load()``).

        Raises
        ------
        InputError
            When ``vehicle`` is not a quadcog Vehicle.
        """
        if model is not None and not isinstance(model, Model):
            # was taken as is (a falsy one replaced by load() in silence), failing at first use
            raise InputError(f"model: expected a quadcog Model (quadcog.load()) or None, got "
                             f"{validate.plain(model)}")
        self.model = load() if model is None else model
        vehicle = HUMMINGBIRD if vehicle is None else vehicle
        if not isinstance(vehicle, Vehicle):
            raise InputError(f"vehicle: expected a quadcog Vehicle (the controller's model of "
                             f"the vehicle) or None, got {validate.plain(vehicle)}")
        self.vehicle = vehicle
        # the model's parameter vector p (14,); a loaded vehicle's p is the paper's model of
        # the whole body (diagonal I_O), which must itself be admissible to design with
        self.nominal = (check_parameters(vehicle.parameters(), f"controller model {vehicle.name!r}")
                        if vehicle.payloads else vehicle.parameters())
        self._function = None
        self._compiled = None
        self._cache_key = None
        self._jacobian = None
        self._designs = {}

    # -- to implement -------------------------------------------------------------------
    def expression(self, t: ca.SX, x: ca.SX, ref: ca.SX, c: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The control law as CasADi expressions: what a subclass implements.

        Parameters
        ----------
        t : casadi.SX
            Time (s), a scalar symbol.
        x : casadi.SX
            State (12,) [x, y, z (m), phi, theta, psi (rad), u, v, w (m/s), p, q, r (rad/s)].
        ref : casadi.SX
            Reference row (14,) (``quadcog.trajectories.analytic``).
        c : casadi.SX
            The controller's own state (``n_state``,).

        Returns
        -------
        U : casadi.SX
            Input (4x1) [U1 (N), U2, U3, U4 (N m, about O)].
        c_dot : casadi.SX
            Rate of the controller's state (``n_state`` x 1).
        """
        raise NotImplementedError

    def project(self, c: ca.SX) -> ca.SX:
        """The controller state after an update step is mapped through this; identity.

        Parameters
        ----------
        c : casadi.SX
            The controller state (``n_state``,) after an update step.

        Returns
        -------
        casadi.SX
            The projected state.
        """
        return c

    def project_numpy(self, c: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """``project`` for numpy arrays, in place where possible.

        Parameters
        ----------
        c : (n_state,) numpy.ndarray
            The controller state after an update step.

        Returns
        -------
        (n_state,) numpy.ndarray
            The projected state (``c`` itself when changed in place).
        """
        return c

    # -- provided ---------------------------------------------------------------------
    def initial_state(self) -> npt.NDArray[np.float64]:
        """The controller state at t = 0.

        Returns
        -------
        (n_state,) numpy.ndarray
            Zeros here (e.g. r_hat = 0 m); a subclass may start elsewhere.
        """
        return np.zeros(self.n_state)

    def function(self) -> ca.Function:
        """The control law as a CasADi Function (built once).

        Returns
        -------
        casadi.Function
            ``(t, x (12), ref (14), c (n_state)) -> (U (4), c_dot (n_state))``, SX, to
            compose into bigger expressions.
        """
        if self._function is None:
            self._function = self._built("function", self._build_function)
        return self._function

    def _build_function(self) -> ca.Function:
        t, x = ca.SX.sym("t"), ca.SX.sym("x", N_STATE)
        ref, c = ca.SX.sym("ref", REF_SIZE), ca.SX.sym("c", self.n_state)
        U, c_dot = self.expression(t, x, ref, c)
        # the generated functions share trigonometry and I_G^{-1}: merge it once here
        U, c_dot = ca.cse([ca.SX(U), ca.SX(c_dot) if self.n_state else ca.SX(0, 1)])
        return ca.Function(f"{self.name}_law", [t, x, ref, c], [U, c_dot],
                           ["t", "x", "ref", "c"], ["U", "c_dot"])

    def _design_key(self) -> Hashable | None:
        """What determines this design: class, constructor arguments, model and folder; None
        where that is not known (a class outside quadcog.controllers, whose expression may
        read attributes set after construction, or an argument ``_frozen`` does not know)."""
        if not type(self).__module__.startswith("quadcog.controllers."):
            return None
        args, kwargs = self._init_args
        try:
            return (type(self).__qualname__, type(self).__module__, _frozen(args),
                    _frozen(kwargs), _frozen(self.vehicle), str(self.model.folder))
        except TypeError:
            return None

    def _built(self, what: str, build: Any) -> Any:
        """``build()``, kept for the designs of the same key (``DESIGNS_KEPT`` of them)."""
        key = self._design_key()
        if key is None:
            return build()
        kept = _designs_built.get(key)
        if kept is None:
            kept = _designs_built[key] = {}
            while len(_designs_built) > DESIGNS_KEPT:
                _designs_built.popitem(last=False)
        else:
            _designs_built.move_to_end(key)
        if what not in kept:
            kept[what] = build()
        return kept[what]

    def compiled(self) -> FastCall:
        """The compiled law, allocation-free.

        Returns
        -------
        FastCall
            Write ``.inputs`` [t, x, ref, c], call, read ``.outputs`` [U, c_dot]. About a
            microsecond per call; one per thread.
        """
        if self._compiled is None:
            self._compiled = compile_function(self.function())
        return FastCall(self._compiled)

    def __call__(self, t: float, x: npt.ArrayLike, ref: npt.ArrayLike,
                 c: npt.ArrayLike | None = None
                 ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """The law at one instant, in numpy; arguments are checked.

        Parameters
        ----------
        t : float
            Time (s).
        x : (12,) array_like
            State [x, y, z (m), phi, theta, psi (rad), u, v, w (m/s), p, q, r (rad/s)].
        ref : (14,) array_like
            Reference row (``quadcog.trajectories.analytic``).
        c : (n_state,) array_like, optional
            The controller's own state (default ``initial_state()``).

        Returns
        -------
        U : (4,) numpy.ndarray
            Input [U1 (N), U2, U3, U4 (N m, about O)].
        c_dot : (n_state,) numpy.ndarray
            Rate of the controller's state.

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
        U_dm, c_dot_dm = self.function()(t, x, ref, c)
        U, c_dot = np.array(U_dm).ravel(), np.array(c_dot_dm).ravel()
        if not (np.isfinite(U).all() and np.isfinite(c_dot).all()):
            k = int(np.argmax(np.abs(x)))
            raise InputError(f"controller {self.name!r}: the law is not finite at t = {t} "
                             f"(U = {plain(U.tolist())}); the largest state entry is "
                             f"x[{k}] = {plain(float(x[k]))}: expected a state within the "
                             f"range in which the law can be evaluated in floating point")
        return U, c_dot

    def for_vehicle(self, vehicle: Vehicle) -> "Controller":
        """This controller, with the same settings, designed for another model.

        Parameters
        ----------
        vehicle : Vehicle
            The model to design for.

        Returns
        -------
        Controller
            ``self`` when ``vehicle`` is already its model, else a new design (kept per
            vehicle).

        Raises
        ------
        InputError
            When the controller was built with positional settings.
        """
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

    def cache_key(self) -> tuple[str, str]:
        """What identifies this controller's compiled code (computed once).

        Returns
        -------
        tuple of (str, str)
            Its class name and its law, serialized.
        """
        if self._cache_key is None:
            self._cache_key = self._built(
                "cache_key", lambda: (type(self).__name__, self.function().serialize()))
        return self._cache_key

    def closed_loop_jacobian(self) -> ca.Function:
        """The Jacobian of the closed loop at the controller's initial state (built once).

        Returns
        -------
        casadi.Function
            ``(x (12), ref (14), p (14)) -> A = d/dx f(x, U(0, x, ref, c0), p)`` (12x12), f the
            truth dynamics without extra effects, c0 = ``initial_state()``.
        """
        if self._jacobian is None:
            self._jacobian = self._built("jacobian", self._build_jacobian)
        return self._jacobian

    def _build_jacobian(self) -> ca.Function:
        x, ref, p = ca.SX.sym("x", N_STATE), ca.SX.sym("ref", REF_SIZE), ca.SX.sym("p", N_PARAM)
        U, _ = self.function()(0.0, x, ref, self.initial_state())
        f = self.model.casadi_function("truth_dynamics")
        return ca.Function("closed_loop_jacobian", [x, ref, p],
                           [ca.jacobian(f(x, U, p, ca.DM.zeros(3), ca.DM.zeros(6)), x)],
                           ["x", "ref", "p"], ["A"])

    def nominal_with_cog(self, r: ca.SX | npt.NDArray[np.float64] | Sequence[float]
                         ) -> ca.SX | npt.NDArray[np.float64]:
        """The nominal parameters with another CoG.

        Parameters
        ----------
        r : casadi.SX or (3,) numpy.ndarray or sequence of float
            The CoG offset r_G (m).

        Returns
        -------
        casadi.SX or (14,) numpy.ndarray
            The parameter vector p with r_G = r (SX when ``r`` is symbolic).
        """
        if isinstance(r, (ca.SX, ca.MX)):
            p = ca.SX(ca.DM(self.nominal))
            return ca.vertcat(p[:11], r)
        return with_cog(self.nominal, r)


# inspect.signature (numpydoc) reads __new__ before __init__ when a class defines both: show
# what a caller passes, __init__'s parameters, as griffe (the API pages) does
Controller.__new__.__signature__ = inspect.signature(Controller.__init__)  # type: ignore[attr-defined]
