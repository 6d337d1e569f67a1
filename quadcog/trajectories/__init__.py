"""Layer 4, references: analytic trajectories (``analytic``), minimum-snap waypoints
(``waypoints``) and what a vehicle can follow (``feasibility``)."""
