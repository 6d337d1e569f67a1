"""A griffe extension for the API pages: the shared argument descriptions filled into the
docstrings as the package's import does (``quadcog.model.shared_docs``), since mkdocstrings
reads docstrings from the source text, where a ``%(x)s`` line stands."""
from typing import Any

import griffe

__all__ = ["SharedDocs"]


class SharedDocs(griffe.Extension):
    """Fill ``%(name)s`` lines of a function's docstring from ``quadcog.model.shared_docs``."""

    def on_function_instance(self, *, node: Any, func: griffe.Function, agent: Any,
                             **kwargs: Any) -> None:
        """Interpolate the docstring of ``func`` (griffe's hook).

        Parameters
        ----------
        node : ast.AST or griffe.ObjectNode
            The function's node.
        func : griffe.Function
            The function griffe built.
        agent : griffe.Visitor or griffe.Inspector
            The agent that built it.
        **kwargs
            Griffe's other arguments.
        """
        if func.docstring is not None and "%(" in func.docstring.value:
            from quadcog.model.shared_docs import interpolate
            func.docstring.value = interpolate(func.docstring.value)
