"""Layer 4, references: analytic trajectories (``analytic``), minimum-snap waypoints
(``waypoints``), what a vehicle can follow (``feasibility``) and the one table of trajectory
kinds (``registry``); ``template`` states the trajectory interface as a Protocol."""

__all__: list[str] = []
