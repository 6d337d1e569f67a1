"""Allocation-free calls of a CasADi function through preallocated numpy buffers."""
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

__all__ = ["FastCall"]


class FastCall:
    """Preallocated single-call wrapper around a CasADi Function.

    Write inputs into ``inputs[i]`` (1-D float arrays, column-major for matrices), call the
    object (or, without the Python method call, ``eval()``), read ``outputs[j]`` (views
    shaped like the outputs). Nothing is allocated or checked per call: about 0.2 us through
    ``eval`` for the compiled functions. Not thread-safe: use one FastCall per thread.

    Parameters
    ----------
    function : casadi.Function
        The Function to call (compiled or VM).
    """

    def __init__(self, function: ca.Function) -> None:
        self.function = function
        self.inputs = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
        self._flat_out = [np.zeros(function.nnz_out(j)) for j in range(function.n_out())]
        self.outputs: list[npt.NDArray[np.float64]] = []
        for j, flat in enumerate(self._flat_out):
            shape = function.size_out(j)
            self.outputs.append(flat if shape[1] == 1 else flat.reshape(shape, order="F"))
        self._buffer, self._eval = function.buffer()
        # casadi's signatures list a size that its SWIG typemap takes from the buffer itself,
        # and numpy's stubs do not declare ndarray a Buffer: both are false alarms
        for i, a in enumerate(self.inputs):
            self._buffer.set_arg(i, memoryview(a))  # type: ignore[call-arg, arg-type]
        for j, a in enumerate(self._flat_out):
            self._buffer.set_res(j, memoryview(a))  # type: ignore[call-arg, arg-type]
        self.eval = self._eval          # the raw evaluator, for the tightest loops

    def __call__(self) -> list[npt.NDArray[Any]]:
        self._eval()
        return self.outputs
