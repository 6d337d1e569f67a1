"""The generated functions as fast numpy callables: ``quadcog.load()``."""
from collections import namedtuple
import os
from pathlib import Path
import threading
from typing import Any
import warnings

import numpy as np
from numpy.typing import ArrayLike

from quadcog.codegen.compiled import external
from quadcog.codegen.compiler import compile_library, find_compiler
from quadcog.codegen.fastcall import FastCall
from quadcog.errors import GeneratedFilesError, InputError, ParameterError, QuadcogWarning
from quadcog.model.attitude import QUATERNION, check_rotation, check_unit_quaternion
from quadcog.model.generated_files import C_SOURCE, load_casadi_function, read_contract, verify
from quadcog.model.inertial_parameters import check_physically_consistent
from quadcog.model.parameters import check_parameters
from quadcog.model.shared_docs import shared_parameters
from quadcog.paths import generated_dir
from quadcog.validate import array, nonnegative, plain, positive, vector

__all__ = ["Linearization", "Model", "load"]

Linearization = namedtuple("Linearization", "A B")
Linearization.__doc__ = """The dynamics linearized about a point: x_dot ~ A dx + B dU.

Parameters
----------
A : (12, 12) numpy.ndarray
    d x_dot / d x (1/s and the units of the state entries).
B : (12, 4) numpy.ndarray
    d x_dot / d U.
"""
_warned_no_compiler = False
_cache: dict[Path, "_Library"] = {}
_cache_lock = threading.Lock()


def _as_vector(name: str, value: ArrayLike, n: int) -> np.ndarray:
    return vector(value, name, n)


def _as_vector_or_matrix(value: ArrayLike) -> np.ndarray:
    """``value`` as a float array of real numbers for reshaping, or InputError naming R
    (``validate.array``: bools, complex numbers, strings and ragged lists refused, not cast)."""
    return array(value, "R", finite=False, what="a finite (3, 3) rotation matrix")


def _checked_out(out: Any, spec_out: Any) -> tuple[np.ndarray, ...]:
    """``out`` as a tuple of writeable float64 arrays of the output shapes, or InputError (a
    list, an int or a read-only array would raise raw or truncate the results silently)."""
    if len(spec_out) > 1:
        if not isinstance(out, (tuple, list)) or len(out) != len(spec_out):
            raise InputError(f"out: expected a tuple of {len(spec_out)} arrays (one per output: "
                             f"{', '.join(n for n, _ in spec_out)}), got {plain(out)}")
        outs = tuple(out)
    else:
        outs = (out,)
    for dst, (oname, shape) in zip(outs, spec_out):
        if not (isinstance(dst, np.ndarray) and dst.shape == shape and dst.dtype == np.float64
                and dst.flags.writeable):
            kind = ("a read-only array" if isinstance(dst, np.ndarray) and dst.shape == shape
                    and dst.dtype == np.float64 else
                    f"an array of shape {dst.shape} and dtype {dst.dtype}"
                    if isinstance(dst, np.ndarray) else plain(dst))
            raise InputError(f"out for {oname} must have shape {shape} (expected a writeable "
                             f"float64 numpy array), got {kind}")
    return outs


def _key(value: object) -> bytes | None:
    """The bytes of ``value`` as floats, or None when it is not numbers (a string, a ragged
    list): the check that follows then says what is wrong, as a typed error."""
    try:
        return np.asarray(value, dtype=float).tobytes()
    except (TypeError, ValueError):
        return None


class Model:
    """The derived model: one method per generated function.

    Methods take numpy arrays (vectors of shape (n,)) and return new arrays, matrices as
    2-D arrays; every argument is checked (shape, finiteness, admissible ``p``). Pass
    ``out=`` (arrays of the output shapes) to reuse memory, or use ``fast(name)`` for the
    unchecked allocation-free path. ``backend`` is "c" (the generated C, compiled on the first
    call of a method or of ``fast``) or "casadi-vm" (CasADi's virtual machine, when there is
    no C compiler). ``casadi_function`` never compiles: simulations build their own code.

    Use ``quadcog.load()`` rather than the constructor.

    Parameters
    ----------
    library : _Library
        The shared, lazily compiled functions of ``folder`` (``load`` keeps one per folder).
    folder : pathlib.Path
        The generated/ folder this model was loaded from.
    """

    def __init__(self, library: "_Library", folder: Path) -> None:
        self.folder = folder                # the generated/ folder this model was loaded from
        self._library = library             # the shared, lazily compiled functions
        # name -> casadi.Function (SX), for expressions: shared by the Models of one folder
        # (every controller design loads one; verified and loaded once per process)
        self._symbolic: dict[str, Any] = library.symbolic
        self.backend = library.backend
        self._calls: dict[str, FastCall] = {}
        self._last_p: bytes | None = None
        self._last_pi: bytes | None = None

    @property
    def functions(self) -> dict[str, Any]:
        """{name: (inputs ((argument, length), ...), outputs ((name, shape), ...))}: the
        generated functions of this folder, as its manifest declares them."""
        return self._library.contract

    def _known(self, name: str) -> None:
        if not isinstance(name, str) or name not in self._library.contract:
            raise InputError(f"name: expected one of {tuple(self._library.contract)} (a "
                             f"generated function), got {plain(name)}")

    def call(self, name: str, *args: ArrayLike, out: Any = None) -> Any:
        """Evaluate the generated function ``name`` on numpy arguments.

        Parameters
        ----------
        name : str
            A generated function (a key of ``functions``).
        *args : array_like
            Its arguments, in the order and with the lengths of ``functions[name]``.
        out : numpy.ndarray or tuple of numpy.ndarray, optional
            Arrays of the output shapes to write into.

        Returns
        -------
        numpy.ndarray or tuple of numpy.ndarray
            One array per output (a tuple when several; a Linearization for
            ``"linearization"``).

        Raises
        ------
        InputError
            An unknown name, a wrong number of arguments, a bad argument or ``out``.
        ParameterError
            ``p`` is not admissible (or ``pi`` not physically consistent).
        """
        self._known(name)
        if len(args) != len(self._library.contract[name][0]):
            raise InputError(f"{name} takes {len(self._library.contract[name][0])} arguments "
                             f"{tuple(a for a, _ in self._library.contract[name][0])}, got "
                             f"{len(args)}")
        return self._call(name, args, out)

    def casadi_function(self, name: str) -> Any:
        """The generated CasADi Function ``name`` (SX), callable on SX/MX symbols.

        Parameters
        ----------
        name : str
            A generated function (a key of ``functions``).

        Returns
        -------
        casadi.Function
            The SX Function, loaded once per generated folder and process.

        Raises
        ------
        InputError
            An unknown name.
        """
        self._known(name)
        if name not in self._symbolic:
            function = load_casadi_function(name, self.folder)
            self._symbolic.setdefault(name, function)     # the first one, if two threads race
        return self._symbolic[name]

    def fast(self, name: str) -> FastCall:
        """A new FastCall (preallocated buffers) of the compiled function ``name``.

        Parameters
        ----------
        name : str
            A generated function (a key of ``functions``).

        Returns
        -------
        quadcog.codegen.fastcall.FastCall
            Unchecked, allocation-free calls (the C is compiled on the first use).

        Raises
        ------
        InputError
            An unknown name.
        """
        self._known(name)
        return FastCall(self._library.functions()[name])

    def _call(self, name: str, args: tuple[Any, ...], out: Any) -> Any:
        spec = self._library.contract.get(name)
        if spec is None:        # a method of Model whose function the manifest does not list
            raise GeneratedFilesError(
                f"{self.folder / 'manifest.json'}: lists no function {name!r} (it lists "
                f"{', '.join(self._library.contract) or 'none'}): the manifest is damaged or "
                f"from another version; run `make derive` in a checkout, or reinstall quadcog")
        spec_in, spec_out = spec
        outs = None if out is None else _checked_out(out, spec_out)
        call = self._calls.get(name)
        if call is None:
            call = self._calls[name] = self.fast(name)
        for buf, (arg_name, n), value in zip(call.inputs, spec_in, args):
            if arg_name == "p":
                self._check_p(value)
            elif arg_name == "pi":
                self._check_pi(value)
            if arg_name == "R":          # a (3, 3) rotation, or its 9 entries row by row
                R = _as_vector_or_matrix(value)
                value = check_rotation(R.reshape(3, 3) if R.size == 9 else R, "R").ravel()
            buf[:] = _as_vector(arg_name, value, n)
            if arg_name == "xq":         # the state on SE(3): its attitude a unit quaternion
                check_unit_quaternion(buf[QUATERNION], "xq[3:7] (the quaternion)")
            elif arg_name == "quaternion":
                check_unit_quaternion(buf, "quaternion")
            if arg_name == "g":          # the model in pi: g > 0, drag >= 0 (as in p)
                positive(buf[0], "g", unit="m/s^2", error=ParameterError)
            elif arg_name == "c":
                for k, v in enumerate(buf):
                    nonnegative(v, f"c[{k}]", error=ParameterError)
        call()
        for (oname, _), o in zip(spec_out, call.outputs):
            if not np.isfinite(o).all():    # never a silent NaN: overflow at extreme inputs
                given = ", ".join(f"max |{a}| = {float(np.abs(b).max()):.3g}"
                                  for (a, _), b in zip(spec_in, call.inputs))
                raise InputError(
                    f"{name}: {oname} is not finite (it overflows) at {given}; expected "
                    "inputs within the model's range (states, inputs and parameters of a "
                    "vehicle that flies)")
        if outs is None:
            results = [o.copy() for o in call.outputs]
        else:
            for dst, src in zip(outs, call.outputs):
                dst[...] = src
            results = list(outs)
        if len(results) == 1:
            return results[0]
        return Linearization(*results) if name == "linearization" else tuple(results)

    def _check_p(self, p: ArrayLike) -> None:
        key = _key(p)
        if key is None or key != self._last_p:   # admissibility once per distinct p
            check_parameters(p)
            self._last_p = key

    def _check_pi(self, pi: ArrayLike) -> None:
        key = _key(pi)
        if key is None or key != self._last_pi:    # consistency once per distinct pi
            check_physically_consistent(pi, "pi")
            self._last_pi = key

    @shared_parameters
    def dynamics(self, x: ArrayLike, U: ArrayLike, p: ArrayLike,
                 out: np.ndarray | None = None) -> np.ndarray:
        """The state derivative of the model.

        Parameters
        ----------
        %(x)s
        %(U)s
        %(p)s
        out : (12,) numpy.ndarray, optional
            Where to write the result (returned).

        Returns
        -------
        (12,) numpy.ndarray
            x_dot.

        Raises
        ------
        InputError
            An argument of the wrong shape or not finite.
        ParameterError
            ``p`` is not admissible (docs/model.md sec. 1.4).
        """
        return self._call("dynamics", (x, U, p), out)

    @shared_parameters
    def mass_matrix(self, p: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
        """M, the mass and inertia matrix about O.

        Parameters
        ----------
        %(p)s
        out : (6, 6) numpy.ndarray, optional
            Where to write the result (returned).

        Returns
        -------
        (6, 6) numpy.ndarray
            M (kg, kg m, kg m^2).

        Raises
        ------
        InputError
            An argument of the wrong shape or not finite.
        ParameterError
            ``p`` is not admissible (docs/model.md sec. 1.4).
        """
        return self._call("mass_matrix", (p,), out)

    @shared_parameters
    def inverse_mass_matrix(self, p: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
        """M^{-1}, by block elimination (no 6x6 solve).

        Parameters
        ----------
        %(p)s
        out : (6, 6) numpy.ndarray, optional
            Where to write the result (returned).

        Returns
        -------
        (6, 6) numpy.ndarray
            M^{-1}.

        Raises
        ------
        InputError
            An argument of the wrong shape or not finite.
        ParameterError
            ``p`` is not admissible (docs/model.md sec. 1.4).
        """
        return self._call("inverse_mass_matrix", (p,), out)

    @shared_parameters
    def coriolis(self, x: ArrayLike, p: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
        """The Coriolis and centripetal matrix C(nu).

        Parameters
        ----------
        %(x)s
        %(p)s
        out : (6, 6) numpy.ndarray, optional
            Where to write the result (returned).

        Returns
        -------
        (6, 6) numpy.ndarray
            C(nu), skew-symmetric.

        Raises
        ------
        InputError
            An argument of the wrong shape or not finite.
        ParameterError
            ``p`` is not admissible (docs/model.md sec. 1.4).
        """
        return self._call("coriolis", (x, p), out)

    @shared_parameters
    def damping(self, p: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
        """The damping matrix D.

        Parameters
        ----------
        %(p)s
        out : (6, 6) numpy.ndarray, optional
            Where to write the result (returned).

        Returns
        -------
        (6, 6) numpy.ndarray
            D = diag(c_x, c_y, c_z, c_phi, c_theta, c_psi).

        Raises
        ------
        InputError
            An argument of the wrong shape or not finite.
        ParameterError
            ``p`` is not admissible (docs/model.md sec. 1.4).
        """
        return self._call("damping", (p,), out)

    @shared_parameters
    def gravity(self, x: ArrayLike, p: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
        """The gravity wrench g_G = -[f_G; r_G x f_G].

        Parameters
        ----------
        %(x)s
        %(p)s
        out : (6,) numpy.ndarray, optional
            Where to write the result (returned).

        Returns
        -------
        (6,) numpy.ndarray
            g_G in N and N m.

        Raises
        ------
        InputError
            An argument of the wrong shape or not finite.
        ParameterError
            ``p`` is not admissible (docs/model.md sec. 1.4).
        """
        return self._call("gravity", (x, p), out)

    @shared_parameters
    def regressor(self, x: ArrayLike, vartheta: ArrayLike, p: ArrayLike,
                  out: np.ndarray | None = None) -> np.ndarray:
        """The CoG regressor Phi = d/dr_G [M vartheta + C nu + g_G].

        Parameters
        ----------
        %(x)s
        vartheta : (6,) array_like
            A generalized acceleration (m/s^2, rad/s^2).
        %(p)s
        out : (6, 3) numpy.ndarray, optional
            Where to write the result (returned).

        Returns
        -------
        (6, 3) numpy.ndarray
            Phi; it does not depend on r_G.

        Raises
        ------
        InputError
            An argument of the wrong shape or not finite.
        ParameterError
            ``p`` is not admissible (docs/model.md sec. 1.4).
        """
        return self._call("regressor", (x, vartheta, p), out)

    @shared_parameters
    def decoupling(self, x: ArrayLike, p: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
        """The decoupling matrix alpha = L_g L_f h for y = [z, phi, theta, psi].

        Parameters
        ----------
        %(x)s
        %(p)s
        out : (4, 4) numpy.ndarray, optional
            Where to write the result (returned).

        Returns
        -------
        (4, 4) numpy.ndarray
            alpha, so that y_ddot = alpha U + b.

        Raises
        ------
        InputError
            An argument of the wrong shape or not finite.
        ParameterError
            ``p`` is not admissible (docs/model.md sec. 1.4).
        """
        return self._call("decoupling", (x, p), out)

    @shared_parameters
    def drift(self, x: ArrayLike, p: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
        """The drift b = L_f^2 h of y = [z, phi, theta, psi].

        Parameters
        ----------
        %(x)s
        %(p)s
        out : (4,) numpy.ndarray, optional
            Where to write the result (returned).

        Returns
        -------
        (4,) numpy.ndarray
            b, so that y_ddot = alpha U + b.

        Raises
        ------
        InputError
            An argument of the wrong shape or not finite.
        ParameterError
            ``p`` is not admissible (docs/model.md sec. 1.4).
        """
        return self._call("drift", (x, p), out)


    @shared_parameters
    def truth_dynamics(self, x: ArrayLike, U: ArrayLike, p: ArrayLike, I_products: ArrayLike,
                       wrench: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
        """The state derivative of the truth model: full inertia about O and an external wrench.

        Parameters
        ----------
        %(x)s
        %(U)s
        %(p)s
        I_products : (3,) array_like
            Off-diagonal entries [Ixy, Ixz, Iyz] of the inertia about O (kg m^2); the
            diagonal is p's.
        wrench : (6,) array_like
            [force at O in ground axes (N), moment in body axes (N m)].
        out : (12,) numpy.ndarray, optional
            Where to write the result (returned).

        Returns
        -------
        (12,) numpy.ndarray
            x_dot.

        Raises
        ------
        InputError
            An argument of the wrong shape or not finite.
        ParameterError
            ``p`` is not admissible (docs/model.md sec. 1.4).
        """
        return self._call("truth_dynamics", (x, U, p, I_products, wrench), out)

    def inertial_regressor(self, x: ArrayLike, nu_dot: ArrayLike, g: float | ArrayLike,
                           out: np.ndarray | None = None) -> np.ndarray:
        """The regressor of the model in the ten inertial parameters (docs/model.md sec. 7.1).

        Parameters
        ----------
        x : array_like, shape (12,)
            State.
        nu_dot : array_like, shape (6,)
            A generalized acceleration [u_dot, v_dot, w_dot] (m/s^2), [p_dot, q_dot, r_dot]
            (rad/s^2).
        g : float or array_like, shape (1,)
            Gravitational acceleration (m/s^2), > 0.
        out : numpy.ndarray, shape (6, 10), optional
            Where to write the result.

        Returns
        -------
        numpy.ndarray, shape (6, 10)
            Y with ``Y pi = M nu_dot + C(nu) nu + g_G`` (N, N m) for any inertial parameters
            pi (``quadcog.model.inertial_parameters``); drag is not in Y.
        """
        # a scalar g as the (1,) argument (numpy's ArrayLike does not see the list as one)
        g = [g] if np.ndim(g) == 0 and not isinstance(g, (str, bytes)) else g  # type: ignore[assignment]
        return self._call("inertial_regressor", (x, nu_dot, g), out)

    def inertial_mass_matrix(self, pi: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
        """M about O of the rigid body with inertial parameters ``pi``.

        Parameters
        ----------
        pi : array_like, shape (10,)
            ``[m, m r_G, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`` (kg, kg m, kg m^2), physically
            consistent (else PhysicalConsistencyError).
        out : numpy.ndarray, shape (6, 6), optional
            Where to write the result.

        Returns
        -------
        numpy.ndarray, shape (6, 6)
            M (kg, kg m, kg m^2).
        """
        return self._call("inertial_mass_matrix", (pi,), out)

    def inertial_dynamics(self, x: ArrayLike, U: ArrayLike, pi: ArrayLike, g: float | ArrayLike,
                          c: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
        """The state derivative of the rigid body with inertial parameters ``pi``.

        Parameters
        ----------
        x : array_like, shape (12,)
            State.
        U : array_like, shape (4,)
            Thrust (N) and body moments about O (N m).
        pi : array_like, shape (10,)
            Inertial parameters about O (kg, kg m, kg m^2), physically consistent (else
            PhysicalConsistencyError).
        g : float or array_like, shape (1,)
            Gravitational acceleration (m/s^2), > 0.
        c : array_like, shape (6,)
            Drag coefficients [c_x, c_y, c_z] (N s/m), [c_phi, c_theta, c_psi] (N m s/rad),
            >= 0.
        out : numpy.ndarray, shape (12,), optional
            Where to write the result.

        Returns
        -------
        numpy.ndarray, shape (12,)
            x_dot; equals ``dynamics(x, U, p)`` for ``(pi, g, c) =
            quadcog.model.inertial_parameters.inertial_arguments(p)``.
        """
        # a scalar g as the (1,) argument (numpy's ArrayLike does not see the list as one)
        g = [g] if np.ndim(g) == 0 and not isinstance(g, (str, bytes)) else g  # type: ignore[assignment]
        return self._call("inertial_dynamics", (x, U, pi, g, c), out)

    def se3_dynamics(self, xq: ArrayLike, U: ArrayLike, pi: ArrayLike, g: float | ArrayLike,
                     c: ArrayLike, wrench: ArrayLike | None = None,
                     out: np.ndarray | None = None) -> np.ndarray:
        """The state derivative on SE(3) of the rigid body with inertial parameters ``pi``
        (docs/model.md sec. 8).

        Parameters
        ----------
        xq : array_like, shape (13,)
            SE(3) state [x, y, z, q_w, q_x, q_y, q_z, u, v, w, p, q, r]: position of O in
            ground axes (m), the attitude as a unit quaternion (Hamilton, scalar first, body
            to ground; else AttitudeError), body-axis velocities (m/s) and rates (rad/s).
        U : array_like, shape (4,)
            Thrust (N) and body moments about O (N m).
        pi : array_like, shape (10,)
            Inertial parameters about O (kg, kg m, kg m^2), physically consistent (else
            PhysicalConsistencyError).
        g : float or array_like, shape (1,)
            Gravitational acceleration (m/s^2), > 0.
        c : array_like, shape (6,)
            Drag coefficients (N s/m, N m s/rad), >= 0.
        wrench : array_like, shape (6,), optional
            External force at O in ground axes (N) and moment in body axes (N m); default 0.
        out : numpy.ndarray, shape (13,), optional
            Where to write the result.

        Returns
        -------
        numpy.ndarray, shape (13,)
            [R(q) nu1; q (0, nu2) / 2; nu_dot].
        """
        g = [g] if np.ndim(g) == 0 and not isinstance(g, (str, bytes)) else g  # type: ignore[assignment]
        wrench = np.zeros(6) if wrench is None else wrench
        return self._call("se3_dynamics", (xq, U, pi, g, c, wrench), out)

    def se3_regressor(self, R: ArrayLike, nu: ArrayLike, nu_dot: ArrayLike,
                      g: float | ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
        """The inertial regressor with the attitude as a rotation matrix (docs/model.md sec. 8).

        Parameters
        ----------
        R : array_like, shape (3, 3) or (9,)
            Rotation matrix, body to ground (or its entries row by row); else AttitudeError.
        nu : array_like, shape (6,)
            Body velocities [u, v, w] (m/s), [p, q, r] (rad/s).
        nu_dot : array_like, shape (6,)
            Their derivatives (m/s^2, rad/s^2).
        g : float or array_like, shape (1,)
            Gravitational acceleration (m/s^2), > 0.
        out : numpy.ndarray, shape (6, 10), optional
            Where to write the result.

        Returns
        -------
        numpy.ndarray, shape (6, 10)
            Y with ``Y pi = M nu_dot + C(nu) nu + g_G(R)`` (N, N m); at R = R(eta) it is
            ``inertial_regressor``.
        """
        g = [g] if np.ndim(g) == 0 and not isinstance(g, (str, bytes)) else g  # type: ignore[assignment]
        return self._call("se3_regressor", (R, nu, nu_dot, g), out)

    def quaternion_rotation(self, quaternion: ArrayLike,
                            out: np.ndarray | None = None) -> np.ndarray:
        """R(q), body to ground, of a unit quaternion.

        Parameters
        ----------
        quaternion : array_like, shape (4,)
            [q_w, q_x, q_y, q_z] (Hamilton, scalar first), of norm 1 (else AttitudeError).
        out : numpy.ndarray, shape (3, 3), optional
            Where to write the result.

        Returns
        -------
        numpy.ndarray, shape (3, 3)
            R with ``R v = q (0, v) q^*``.
        """
        return self._call("quaternion_rotation", (quaternion,), out)

    @shared_parameters
    def linearization(self, x: ArrayLike, U: ArrayLike, p: ArrayLike,
                      out: tuple[np.ndarray, np.ndarray] | None = None) -> Linearization:
        """The dynamics linearized about (x, U).

        Parameters
        ----------
        %(x)s
        %(U)s
        %(p)s
        out : tuple of numpy.ndarray, optional
            Arrays of shapes (12, 12) and (12, 4) to write A and B into.

        Returns
        -------
        Linearization
            Linearization(A (12, 12), B (12, 4)) with x_dot ~ A dx + B dU.

        Raises
        ------
        InputError
            An argument of the wrong shape or not finite.
        ParameterError
            ``p`` is not admissible (docs/model.md sec. 1.4).
        """
        return self._call("linearization", (x, U, p), out)


class _Library:
    """The numeric functions of one generated folder, made on first use: the generated C
    compiled into the cache, or CasADi's virtual machine without a compiler."""

    def __init__(self, folder: Path) -> None:
        global _warned_no_compiler
        self.folder = folder
        self.contract = read_contract(folder).functions
        self.cc = find_compiler()
        self.backend = "c" if self.cc else "casadi-vm"
        if self.cc is None and not _warned_no_compiler:
            warnings.warn("no C compiler found ($CC or `cc`): quadcog falls back to CasADi's "
                          "virtual machine, which is about 100x slower per call",
                          QuadcogWarning, stacklevel=4)
            _warned_no_compiler = True
        self._functions: dict[str, Any] | None = None
        self.symbolic: dict[str, Any] = {}     # Model.casadi_function's, shared
        self._lock = threading.Lock()

    def functions(self) -> dict[str, Any]:
        """name -> casadi.Function (external C or VM), built once."""
        with self._lock:
            if self._functions is None:
                if self.cc is None:
                    self._functions = {n: load_casadi_function(n, self.folder)
                                       for n in self.contract}
                else:
                    verify(self.folder, only={C_SOURCE})
                    lib = compile_library((self.folder / C_SOURCE).read_bytes(), "quadcog_gen",
                                          self.cc)
                    self._functions = {n: external(n, lib) for n in self.contract}
        return self._functions


def load(folder: str | os.PathLike[str] | None = None) -> Model:
    """The Model of generated/ (or ``folder``).

    Every file is checked against the manifest now; the generated C is compiled (once, into
    the cache) when a method first needs it.

    Parameters
    ----------
    folder : str or os.PathLike, optional
        A generated folder (default ``quadcog.paths.generated_dir()``).

    Returns
    -------
    Model
        The generated functions of that folder.

    Raises
    ------
    InputError
        ``folder`` is not a path (or an empty one).
    GeneratedFilesError
        Naming the file when generated/ is missing, corrupted or incomplete, and what to do
        about it.
    """
    if folder is not None and (not isinstance(folder, (str, os.PathLike))
                               or not os.fspath(folder)):
        raise InputError(f"folder: expected the path of a generated folder (a non-empty str "
                         f"or os.PathLike), got {plain(folder)}")
    folder = generated_dir() if folder is None else folder
    folder = Path(folder).resolve()
    with _cache_lock:
        if folder not in _cache:
            verify(folder)
            _cache[folder] = _Library(folder)
    return Model(_cache[folder], folder)
