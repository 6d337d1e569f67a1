"""The exported C on the host: strict compile checks, a ctypes handle on a step, and a
closed-loop flight of an exported step against the double truth plant (the same plant, held
input and Euler update of c as ``quadcog.simulate``)."""
from collections.abc import Sequence
import ctypes
import os
from pathlib import Path
import subprocess
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from quadcog.codegen.compiled import compile_function
from quadcog.codegen.compiler import find_compiler
from quadcog.codegen.fastcall import FastCall
from quadcog.errors import CompileError
from quadcog.model.conventions import N_STATE, R_G
from quadcog.model.functions import load
from quadcog.scenarios.scenario import Scenario
from quadcog.sim.plant import Actuation, initial_rotor_thrusts, plant_step_function
from quadcog.sim.result import SimulationResult, position_metrics
from quadcog.sim.timeline import wrench_table
from quadcog.trajectories.analytic import REF_SIZE

__all__ = ["STRICT_FLAGS", "NP_TYPE", "C_TYPE", "compile_checked", "build_host_library",
           "HostStep", "fly"]

# What the issue promises the code compiles with, on the host and on the target.
STRICT_FLAGS = ("-std=c99", "-pedantic", "-Wall", "-Wextra", "-Wdouble-promotion",
                "-Wfloat-conversion", "-Werror")
NP_TYPE = {"double": np.float64, "float32": np.float32}
C_TYPE = {"double": ctypes.c_double, "float32": ctypes.c_float}


def compile_checked(cmd: Sequence[str | os.PathLike[str]]) -> subprocess.CompletedProcess[str]:
    """Run a compiler command.

    Parameters
    ----------
    cmd : sequence of str or os.PathLike
        The command and its arguments.

    Returns
    -------
    subprocess.CompletedProcess
        The finished command (exit code 0).

    Raises
    ------
    quadcog.errors.CompileError
        When it fails, with the end of its output.
    """
    res = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    if res.returncode != 0:
        raise CompileError(f"`{' '.join(map(str, cmd))}` failed with exit code "
                           f"{res.returncode}:\n{res.stderr[-4000:]}")
    return res


def build_host_library(folder: str | os.PathLike[str], names: Sequence[str],
                       out: str | os.PathLike[str]) -> Path:
    """Compile exported modules into one shared library with the strict flags.

    Parameters
    ----------
    folder : str or os.PathLike
        The folder of the ``quadcog_<name>.c`` files.
    names : sequence of str
        The controllers' short names.
    out : str or os.PathLike
        The shared library to write.

    Returns
    -------
    pathlib.Path
        ``out``.

    Raises
    ------
    quadcog.errors.CompileError
        Without a C compiler, or when a module does not compile with ``STRICT_FLAGS``.
    """
    cc = find_compiler()
    if cc is None:
        raise CompileError("no C compiler found (looked for $CC or `cc` on PATH)")
    folder = Path(folder)
    sources = [folder / f"quadcog_{n}.c" for n in names]
    compile_checked([cc, *STRICT_FLAGS, "-O2", "-shared", "-fPIC", "-I", folder, *sources,
                     "-o", out, "-lm"])
    return Path(out)


class HostStep:
    """One exported controller in a host library: ``init()``, then ``step(x, ref, dt)``
    (numpy float64 in; U (4,) float64 out). The controller state is ``self.c``.

    Parameters
    ----------
    library : str or os.PathLike
        The shared library (``build_host_library``).
    name : str
        The controller's short name (``quadcog_<name>_step``).
    precision : str
        'float32' or 'double': the module's C type.
    nc : int
        Size of the controller state c.
    """

    def __init__(self, library: str | os.PathLike[str], name: str, precision: str,
                 nc: int) -> None:
        self.lib = ctypes.CDLL(str(library))
        self.dtype = NP_TYPE[precision]
        self.nc = nc
        self.x, self.ref = np.zeros(N_STATE, self.dtype), np.zeros(REF_SIZE, self.dtype)
        self.c, self.U = np.zeros(max(nc, 1), self.dtype), np.zeros(4, self.dtype)
        self.dt_type = C_TYPE[precision]
        self._step = getattr(self.lib, f"quadcog_{name}_step")
        self._init = getattr(self.lib, f"quadcog_{name}_init")
        self._step.restype = self._init.restype = None
        ptr = lambda a: a.ctypes.data_as(ctypes.c_void_p)
        self._args = (ptr(self.x), ptr(self.ref), ptr(self.c))
        self._U = ptr(self.U)
        self._c = ptr(self.c)

    def init(self) -> NDArray[Any]:
        """Set the controller state to its initial value (``quadcog_<name>_init``).

        Returns
        -------
        (max(nc, 1),) numpy.ndarray
            ``self.c``, in the module's precision.
        """
        self._init(self._c)
        return self.c

    def call(self, dt: Any) -> None:
        """The step on what is in ``self.x`` and ``self.ref``: the fast path for loops.

        Parameters
        ----------
        dt : ctypes.c_float or ctypes.c_double
            The control period [s] as the module's C type (``self.dt_type``).
        """
        self._step(*self._args, dt, self._U)

    def step(self, x: ArrayLike, ref: ArrayLike, dt: float) -> NDArray[np.float64]:
        """One control period: U from (x, ref, c), c updated in place.

        Parameters
        ----------
        x : (12,) array_like
            State [m, rad, m/s, rad/s].
        ref : (14,) array_like
            Reference: position, velocity, acceleration, jerk (m, m/s, m/s^2, m/s^3), yaw
            [rad], yaw rate [rad/s].
        dt : float
            Control period [s].

        Returns
        -------
        (4,) numpy.ndarray
            U = [U1 (N), U2, U3, U4 (N m)] as float64.
        """
        self.x[:] = x
        self.ref[:] = ref
        self.call(self.dt_type(dt))
        return self.U.astype(np.float64)


def fly(step: HostStep, reference_result: SimulationResult,
        scenario: Scenario) -> tuple[NDArray[np.float64], NDArray[np.float64], dict[str, Any]]:
    """Fly an exported step in closed loop over the steps of a Python run.

    Same start, references, CoG and disturbances at each step as ``reference_result``, the
    scenario's truth plant in double.

    Parameters
    ----------
    step : HostStep
        The exported controller.
    reference_result : quadcog.sim.result.SimulationResult
        The Python run of ``scenario``.
    scenario : quadcog.scenarios.scenario.Scenario
        Its scenario (vehicle, truth options, disturbances, dt).

    Returns
    -------
    tuple of (numpy.ndarray, numpy.ndarray, dict)
        x (N, 12) [m, rad, m/s, rad/s], c (N, nc), and the position metrics (m).

    Raises
    ------
    quadcog.errors.CompileError
        When the exported step diverges (a non-finite state).
    """
    vehicle = scenario.vehicle
    actuation = Actuation.of(vehicle, scenario.truth)
    plant = FastCall(compile_function(plant_step_function(load(), actuation)))
    px, pf, pU, pP, pload, pr, pw, pdt = plant.inputs
    x_next, f_next, _ = plant.outputs
    evaluate = plant.eval
    t, refs = reference_result.t, reference_result.ref
    n = len(t)
    # the plant as simulate has it: the airframe at its CoG profile, plus the payloads
    airframe = vehicle.airframe
    pr[:] = airframe.r_G                   # where the vehicle states its inertia
    P = np.repeat(airframe.parameters()[None, :], n, axis=0)
    P[:, R_G] = airframe.r_G + scenario.cog.sample(t)
    loads = scenario.payload_profile().sample(t)
    wrenches = wrench_table(scenario.disturbances, t)
    X = np.empty((n, 12))
    C = np.empty((n, step.nc))
    X[0] = reference_result.x[0]
    C[0] = step.init()[:step.nc]
    pf[:] = initial_rotor_thrusts(P[0], actuation)
    dt = step.dt_type(scenario.dt)
    pdt[0] = scenario.dt
    sx, sref, sU, sc, call, nc = step.x, step.ref, step.U, step.c, step.call, step.nc
    for k in range(n - 1):
        sx[:] = px[:] = X[k]
        sref[:] = refs[k]
        call(dt)
        pU[:] = sU
        pP[:] = P[k]
        pload[:] = loads[k]
        pw[:] = wrenches[k]
        evaluate()
        X[k + 1] = x_next
        pf[:] = f_next
        C[k + 1] = sc[:nc]
    bad = np.flatnonzero(~np.isfinite(X).all(axis=1))
    if bad.size:
        raise CompileError(f"exported step diverged (non-finite state) at t = {t[bad[0]]} s")
    return X, C, position_metrics(t, X, refs, scenario.duration)
