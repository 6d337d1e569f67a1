"""Layer 2, what derive/ wrote: the contract and conventions (``conventions``), the files of
generated/ (``generated_files``), the compiled generated functions (``functions``: ``load``,
``Model``), parameter vectors and their admissibility (``parameters``, ``admissibility``),
seeded admissible samples (``sampling``) and the run table's columns (``columns``).
"""
from quadcog.model.functions import Linearization, Model, load

__all__ = ["Linearization", "Model", "load"]
