"""Translate SymPy expressions into CasADi SX, sharing identical subtrees.

Only the atoms this model needs are supported; anything else (Piecewise, sign, Abs,
...) raises ``UnsupportedAtomError`` naming the object being exported and the atom, so
that ``make derive`` stops before it writes anything.
"""
import casadi as ca
import sympy as sp

_FUNCTIONS = {sp.sin: ca.sin, sp.cos: ca.cos, sp.tan: ca.tan, sp.exp: ca.exp, sp.log: ca.log}


class UnsupportedAtomError(ValueError):
    """An expression contains a SymPy atom with no CasADi counterpart here."""

    def __init__(self, obj_name, atom):
        self.obj_name, self.atom = obj_name, atom
        if atom.is_Symbol:
            what = "is not an argument of the function"
        else:
            what = ("has no CasADi translation here (supported: +, *, integer and half powers, "
                    f"{', '.join(f.__name__ for f in _FUNCTIONS)})")
        super().__init__(f"cannot export {obj_name!r}: it contains {type(atom).__name__} "
                         f"{atom}, which {what}")


class Translator:
    """Maps SymPy symbols to SX and translates expressions with a shared memo."""

    def __init__(self, bindings):
        self._memo = dict(bindings)

    def bind(self, symbol, sx):
        self._memo[symbol] = sx

    def matrix(self, mat, obj_name):
        """Translate a SymPy Matrix into an SX matrix of the same shape."""
        out = ca.SX.zeros(mat.rows, mat.cols)
        for i in range(mat.rows):
            for j in range(mat.cols):
                out[i, j] = self.expr(mat[i, j], obj_name)
        return out

    def expr(self, e, obj_name):
        memo = self._memo
        if e in memo:
            return memo[e]
        # Iterative post-order walk: these trees are deep enough to hit recursion limits.
        stack = [(e, False)]
        while stack:
            node, ready = stack.pop()
            if node in memo:
                continue
            if node.is_Number:
                memo[node] = ca.SX(float(node))
                continue
            if not ready:
                self._check_supported(node, obj_name)
                stack.append((node, True))
                stack.extend((a, False) for a in node.args if a not in memo)
                continue
            memo[node] = self._combine(node, [memo[a] for a in node.args], obj_name)
        return memo[e]

    @staticmethod
    def _check_supported(node, obj_name):
        """Fail on the outermost unsupported node, before descending into its arguments."""
        if not (node.is_Add or node.is_Mul or node.is_Pow or node.func in _FUNCTIONS):
            raise UnsupportedAtomError(obj_name, node)

    @staticmethod
    def _combine(node, args, obj_name):
        if node.is_Add:
            out = args[0]
            for a in args[1:]:
                out = out + a
            return out
        if node.is_Mul:
            out = args[0]
            for a in args[1:]:
                out = out * a
            return out
        if node.is_Pow:
            base, ex = node.args
            if ex.is_Integer:
                n = int(ex)
                if n == 2:
                    return args[0] * args[0]
                if n == -1:
                    return 1 / args[0]
                if n == -2:
                    return 1 / (args[0] * args[0])
                return ca.constpow(args[0], n)
            if ex == sp.Rational(1, 2):
                return ca.sqrt(args[0])
            if ex == sp.Rational(-1, 2):
                return 1 / ca.sqrt(args[0])
            raise UnsupportedAtomError(obj_name, node)
        fn = _FUNCTIONS.get(node.func)
        if fn is not None:
            return fn(args[0])
        raise UnsupportedAtomError(obj_name, node)
