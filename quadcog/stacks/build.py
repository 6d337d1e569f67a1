"""Cache-keyed builds of third-party C with quadcog's own C, and the compiler's first error line.

The names of ``quadcog.codegen.third_party`` (shared with the embedded firmware builds), under
the names the stacks have used.
"""
from quadcog.codegen.third_party import Source, build_library, c_function, first_error_line

__all__ = ["Source", "first_error_line", "build_library", "c_function"]
