"""Layer 12, studies built on everything below: the paper's figures and claims (``paper``),
beyond the paper (``beyond``), the analysis (``analysis``) and the tour (``tour``)."""

__all__: list[str] = []            # the subpackages are imported by their own names
