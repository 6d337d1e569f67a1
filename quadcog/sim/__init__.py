"""Layer 7, the simulation: prepare -> step loop -> result. The per-step inputs
(``schedule``), the truth plant (``plant``), the closed-loop step (``closed_loop``), the
divergence rule (``divergence``), one flight (``flight``), many flights (``batch``,
``vector_batch``), sensing (``sensing``), CoG changes and disturbances (``timeline``) and the
results (``result``)."""

__all__: list[str] = []      # the names live in the modules (and in ``quadcog``)
