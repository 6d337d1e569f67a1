"""The exported C on the host: strict compile checks, a ctypes handle on a step, and a
closed-loop flight of an exported step against the double truth plant (the same plant, held
input and Euler update of c as ``quadcog.simulate``)."""
import ctypes
from pathlib import Path
import subprocess

import numpy as np

from quadcog.codegen.compiled import compile_function
from quadcog.codegen.compiler import find_compiler
from quadcog.codegen.fastcall import FastCall
from quadcog.errors import CompileError
from quadcog.model.conventions import R_G
from quadcog.model.functions import load
from quadcog.sim.plant import Actuation, initial_rotor_thrusts, plant_step_function
from quadcog.sim.result import position_metrics
from quadcog.sim.timeline import wrench_table
from quadcog.trajectories.analytic import REF_SIZE

# What the issue promises the code compiles with, on the host and on the target.
STRICT_FLAGS = ("-std=c99", "-pedantic", "-Wall", "-Wextra", "-Wdouble-promotion",
                "-Wfloat-conversion", "-Werror")
NP_TYPE = {"double": np.float64, "float32": np.float32}
C_TYPE = {"double": ctypes.c_double, "float32": ctypes.c_float}


def compile_checked(cmd):
    """Run a compiler command; CompileError with its output when it fails."""
    res = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    if res.returncode != 0:
        raise CompileError(f"`{' '.join(map(str, cmd))}` failed with exit code "
                           f"{res.returncode}:\n{res.stderr[-4000:]}")
    return res


def build_host_library(folder, names, out):
    """Compile ``quadcog_<name>.c`` of ``folder`` for every name into one shared library
    ``out`` with the strict flags; returns its path."""
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
    (numpy float64 in; U (4,) float64 out). The controller state is ``self.c``."""

    def __init__(self, library, name, precision, nc):
        self.lib = ctypes.CDLL(str(library))
        self.dtype = NP_TYPE[precision]
        self.nc = nc
        self.x, self.ref = np.zeros(12, self.dtype), np.zeros(REF_SIZE, self.dtype)
        self.c, self.U = np.zeros(max(nc, 1), self.dtype), np.zeros(4, self.dtype)
        self.dt_type = C_TYPE[precision]
        self._step = getattr(self.lib, f"quadcog_{name}_step")
        self._init = getattr(self.lib, f"quadcog_{name}_init")
        self._step.restype = self._init.restype = None
        ptr = lambda a: a.ctypes.data_as(ctypes.c_void_p)
        self._args = (ptr(self.x), ptr(self.ref), ptr(self.c))
        self._U = ptr(self.U)
        self._c = ptr(self.c)

    def init(self):
        self._init(self._c)
        return self.c

    def call(self, dt):
        """The step on what is in ``self.x`` and ``self.ref``: the fast path for loops."""
        self._step(*self._args, dt, self._U)

    def step(self, x, ref, dt):
        self.x[:] = x
        self.ref[:] = ref
        self.call(self.dt_type(dt))
        return self.U.astype(np.float64)


def fly(step, reference_result, scenario):
    """Fly ``step`` (a HostStep) in closed loop over the steps of ``reference_result`` (the
    Python run of ``scenario``): same start, references, CoG and disturbances at each step,
    the scenario's truth plant in double. Returns (x (N, 12), c (N, nc), metrics dict)."""
    vehicle = scenario.vehicle
    actuation = Actuation.of(vehicle, scenario.truth)
    plant = FastCall(compile_function(plant_step_function(load(), actuation)))
    px, pf, pU, pP, pw, pdt = plant.inputs
    x_next, f_next, _ = plant.outputs
    evaluate = plant.eval
    t, refs = reference_result.t, reference_result.ref
    n = len(t)
    P = np.repeat(vehicle.parameters()[None, :], n, axis=0)
    P[:, R_G] = reference_result.r_G
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
        pw[:] = wrenches[k]
        evaluate()
        X[k + 1] = x_next
        pf[:] = f_next
        C[k + 1] = sc[:nc]
    bad = np.flatnonzero(~np.isfinite(X).all(axis=1))
    if bad.size:
        raise CompileError(f"exported step diverged (non-finite state) at t = {t[bad[0]]} s")
    return X, C, position_metrics(t, X, refs, scenario.duration)
