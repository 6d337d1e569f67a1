"""Allocation-free calls of a CasADi function through preallocated numpy buffers."""
from collections import OrderedDict
import threading
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog.errors import InputError

__all__ = ["FastCall", "evaluate"]


def _bound_buffers(function: ca.Function) -> tuple[list[npt.NDArray[np.float64]],
                                                  list[npt.NDArray[np.float64]], Any, Any]:
    """Zeroed flat arrays, one per input and per output (their nonzeros), bound to the
    Function's call buffer: (inputs, outputs, buffer, its evaluator)."""
    ins = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
    outs = [np.zeros(function.nnz_out(j)) for j in range(function.n_out())]
    buffer, evaluator = function.buffer()
    # casadi's signatures list a size that its SWIG typemap takes from the buffer itself,
    # and numpy's stubs do not declare ndarray a Buffer: both are false alarms
    for i, a in enumerate(ins):
        buffer.set_arg(i, memoryview(a))  # type: ignore[call-arg, arg-type]
    for j, a in enumerate(outs):
        buffer.set_res(j, memoryview(a))  # type: ignore[call-arg, arg-type]
    return ins, outs, buffer, evaluator


class FastCall:
    """Preallocated single-call wrapper around a CasADi Function.

    Write inputs into ``inputs[i]`` (1-D float arrays, column-major for matrices), call the
    object (or, without the Python method call, ``eval()``), read ``outputs[j]`` (views
    shaped like the outputs). Nothing is allocated or checked per call: about 0.2 us through
    ``eval`` for the compiled functions. Not thread-safe: use one FastCall per thread.

    Parameters
    ----------
    function : casadi.Function
        The Function to call (compiled or VM). Its outputs must be dense (a sparse one has
        no view of its shape, and a sparse column's nonzeros are not the column:
        ``evaluate`` densifies them, or ``ca.densify`` the Function's outputs).

    Raises
    ------
    InputError
        An output of ``function`` is sparse.
    """

    def __init__(self, function: ca.Function) -> None:
        for j in range(function.n_out()):
            sp = function.sparsity_out(j)
            if not sp.is_dense():
                raise InputError(
                    f"FastCall: function {function.name()!r} output {j} "
                    f"({function.name_out(j)}) is a sparse {sp.size1()}x{sp.size2()} matrix "
                    f"with {sp.nnz()} nonzeros; expected dense outputs (use "
                    f"quadcog.codegen.fastcall.evaluate, or ca.densify the outputs)")
        self.function = function
        self.inputs, self._flat_out, self._buffer, self._eval = _bound_buffers(function)
        self.outputs: list[npt.NDArray[np.float64]] = []
        for j, flat in enumerate(self._flat_out):
            shape = function.size_out(j)
            self.outputs.append(flat if shape[1] == 1 else flat.reshape(shape, order="F"))
        self.eval = self._eval          # the raw evaluator, for the tightest loops

    def __call__(self) -> list[npt.NDArray[Any]]:
        self._eval()
        return self.outputs


class _Evaluator:
    """A Function's buffers for ``evaluate``: dense inputs and outputs, sparse ones mapped
    through their patterns."""

    def __init__(self, function: ca.Function) -> None:
        self.function = function           # kept: the cache is keyed by its id
        self._in, self._out, self._buffer, self._eval = _bound_buffers(function)
        # (shape, rows, cols) of each entry of a sparse argument; None for a dense one
        self._in_pattern = [self._pattern(function.sparsity_in(i)) for i in range(len(self._in))]
        self._out_pattern = [self._pattern(function.sparsity_out(j))
                             for j in range(len(self._out))]

    @staticmethod
    def _pattern(sp: ca.Sparsity) -> tuple[tuple[int, int], Any, Any] | None:
        if sp.is_dense():
            return None
        rows, cols = sp.get_triplet()
        return (sp.size1(), sp.size2()), np.array(rows, dtype=int), np.array(cols, dtype=int)

    def __call__(self, args: tuple[npt.ArrayLike, ...]) -> list[npt.NDArray[np.float64]]:
        for buffer, a, pattern in zip(self._in, args, self._in_pattern):
            if pattern is None:
                buffer[:] = np.ravel(a, order="F")
            else:
                buffer[:] = np.asarray(a, dtype=float).reshape(pattern[0])[pattern[1], pattern[2]]
        self._eval()
        out = []
        for flat, pattern, j in zip(self._out, self._out_pattern, range(len(self._out))):
            shape = self.function.size_out(j)
            if pattern is None:
                out.append(flat.copy() if shape[1] == 1 else flat.reshape(shape, order="F").copy())
            else:
                dense = np.zeros(shape)
                dense[pattern[1], pattern[2]] = flat
                out.append(dense[:, 0] if shape[1] == 1 else dense)
        return out


# evaluators kept for ``evaluate``, by the Function's id (each holds its Function, so the id
# stays its own), the most recent last
_kept: "OrderedDict[int, _Evaluator]" = OrderedDict()
_KEEP = 32
_kept_lock = threading.Lock()


def evaluate(function: ca.Function, *args: npt.ArrayLike) -> list[npt.NDArray[np.float64]]:
    """One call of a CasADi Function with numpy inputs, through buffers kept for it.

    A plain call from Python converts every argument and result to a DM (about 0.1 ms); this
    writes into preallocated buffers. For the calls made once per flight on small inputs.

    Parameters
    ----------
    function : casadi.Function
        The Function (the last 32 used keep their buffers).
    *args : array_like
        Its inputs, each of the input's shape (or its entries in column-major order).

    Returns
    -------
    list of numpy.ndarray
        Its outputs, dense: (rows,) for a column, (rows, cols) otherwise.
    """
    with _kept_lock:
        kept = _kept.get(id(function))
        if kept is None:
            kept = _kept[id(function)] = _Evaluator(function)
            if len(_kept) > _KEEP:
                _kept.popitem(last=False)
        else:
            _kept.move_to_end(id(function))
        return kept(args)
