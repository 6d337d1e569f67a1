"""Vehicles: rotor models (``quadcog.vehicles.rotor_model``)."""
