"""Layer 3, vehicles: the ``Vehicle`` (mass, inertia, drag, CoG, rotors) and its presets."""
from quadcog.vehicles.vehicle import CRAZYFLIE, HUMMINGBIRD, PRESETS, Vehicle

__all__ = ["CRAZYFLIE", "HUMMINGBIRD", "PRESETS", "Vehicle"]
