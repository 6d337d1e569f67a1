"""Layer 3, vehicles: the ``Vehicle`` (mass, inertia, drag, CoG, rotors), its presets and the
rotor models that turn a logged motor command into thrust (``rotor_model``)."""
from quadcog.vehicles.rotor_model import ROTOR_MODELS, RotorModel
from quadcog.vehicles.vehicle import CRAZYFLIE, CRAZYFLIE_21, HUMMINGBIRD, PRESETS, X500, Vehicle

__all__ = ["CRAZYFLIE", "CRAZYFLIE_21", "HUMMINGBIRD", "PRESETS", "ROTOR_MODELS", "RotorModel", "Vehicle", "X500"]
