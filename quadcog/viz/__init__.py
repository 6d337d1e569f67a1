"""Layer 6, what people look at: flight figures (``plots``), the animation (``animation``) and
progress bars (``progress``). Draws arrays and Vehicles; knows nothing of the simulation."""

__all__: list[str] = []      # the names live in the modules
