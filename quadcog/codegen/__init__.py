"""Layer 1, the C back-ends of the runtime: the compile cache (``compiler``), compiled CasADi
functions (``compiled``), allocation-free calls (``fastcall``), the table of CasADi operations
to C (``sx_to_c``) and the vectorized batch kernel (``vector_kernel``).

Imports only the floor (``quadcog.errors``, ``quadcog.config``, ``quadcog.paths``).
"""

__all__: list[str] = []         # the modules are imported by name: quadcog.codegen.compiler, ...
