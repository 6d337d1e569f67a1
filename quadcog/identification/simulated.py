"""A simulated flight as a flight log: what a real vehicle's logger would have recorded.

``simulated_log`` samples a ``quadcog.simulate`` result at a logger's rate and turns it into a
``quadcog.logs.FlightLog``: the state estimate with the measurement noise of a
``quadcog.Sensing`` (its standard deviations, its gyroscope bias), the kinematic acceleration,
and the motor outputs that the vehicle's rotor model needs for the applied rotor thrusts
(``RotorModel.command``, the inverse of the map ``quadcog identify`` reads them with), at a
battery voltage that falls linearly over the flight. It is the other end of the round trip
simulate -> log -> ``identify``.
"""
from typing import TYPE_CHECKING

import numpy as np

from quadcog.errors import IdentificationError
from quadcog.identification import _checks
from quadcog.model.conventions import rotation_matrix
from quadcog.sim.sensing import Sensing
from quadcog.validate import fail, integer, positive, vector

if TYPE_CHECKING:
    from quadcog.logs.flightlog import FlightLog
    from quadcog.sim.result import SimulationResult
    from quadcog.vehicles.rotor_model import RotorModel
    from quadcog.vehicles.vehicle import Vehicle

__all__ = ["LOG_RATE", "simulated_log"]

LOG_RATE = 100.0           # Hz: the Crazyflie uSD deck's rate in the CrazyPAD flights
PWM_STEP = 1.0 / 65535     # the 16-bit resolution of a logged motor output


def simulated_log(result: "SimulationResult", vehicle: "Vehicle", sensing: Sensing | None = None,
                  rate: float = LOG_RATE, voltage: tuple[float, float] = (4.1, 3.7),
                  rotor_model: "RotorModel | None" = None, seed: int | None = None,
                  source: str = "simulated") -> "FlightLog":
    """The FlightLog a logger on ``vehicle`` would have written during ``result``.

    Parameters
    ----------
    result : quadcog.SimulationResult
        The flight (state x, applied input U on t).
    vehicle : quadcog.Vehicle
        The vehicle that flew: its mixer gives the rotor thrusts from U, its rotor model the
        motor outputs.
    sensing : quadcog.Sensing, optional
        Noise of the logged state (default ``Sensing()``: the *-real scenarios'); ``noise``
        False logs the true state.
    rate : float
        Logging rate (Hz).
    voltage : (float, float)
        Battery voltage (V) at the start and at the end, linear in between.
    rotor_model : RotorModel, optional
        Instead of the vehicle's.
    seed : int, optional
        Seed of the logged noise (default: the sensing's seed).
    source : str
        The log's name.

    Returns
    -------
    quadcog.logs.FlightLog
        Signals position, velocity, acceleration, roll, pitch, yaw, body_rates,
        battery_voltage and the rotor model's motor output (motor_pwm or motor_command),
        quantized to 16 bits.

    Raises
    ------
    IdentificationError
        No rotor model, or a log rate faster than the simulation's; an argument of another
        type (``result`` not a SimulationResult of two samples at least, ``rate`` not a
        finite number > 0, ``voltage`` not two finite numbers > 0, ``seed`` not an integer
        >= 0, ``source`` not a str).
    """
    from quadcog.logs import FlightLog
    from quadcog.sim.result import SimulationResult
    from quadcog.vehicles.rotor_model import RotorModel
    if not isinstance(result, SimulationResult) or len(result.t) < 2:
        fail("simulated_log: result", "a quadcog SimulationResult of 2 samples at least",
             result, IdentificationError)
    _checks.vehicle(vehicle, "simulated_log: vehicle")
    if sensing is not None and not isinstance(sensing, Sensing):
        fail("simulated_log: sensing", "a quadcog Sensing or None", sensing,
             IdentificationError)
    rate = positive(rate, "simulated_log: rate", "Hz", IdentificationError)
    v = vector(voltage, "simulated_log: voltage", 2, error=IdentificationError)
    if not (v > 0).all():
        fail("simulated_log: voltage", "two battery voltages > 0 (V)", voltage,
             IdentificationError)
    voltage = (float(v[0]), float(v[1]))
    if rotor_model is not None and not isinstance(rotor_model, RotorModel):
        fail("simulated_log: rotor_model", "a RotorModel or None", rotor_model,
             IdentificationError)
    if seed is not None:
        seed = integer(seed, "simulated_log: seed", lo=0, error=IdentificationError)
    source = _checks.text(source, "simulated_log: source")
    model = vehicle.rotor_model if rotor_model is None else rotor_model
    if model is None:
        raise IdentificationError(f"vehicle {vehicle.name!r} has no rotor_model: the motor "
                                  "outputs of a simulated log cannot be written")
    sensing = Sensing() if sensing is None else sensing
    dt_sim = float(np.median(np.diff(result.t)))
    every = int(round(1.0 / (rate * dt_sim)))
    if every < 1:
        raise IdentificationError(f"log rate {rate} Hz is faster than the simulation's "
                                  f"{1 / dt_sim:g} Hz")
    k = np.arange(0, len(result.t), every)
    t = result.t[k] - result.t[0]
    x = result.x[k].copy()
    U = result.U[k]
    R = np.array([rotation_matrix(*e) for e in x[:, 3:6]])
    v_ground = np.einsum("kij,kj->ki", R, x[:, 6:9])
    accel = np.gradient(v_ground, t, axis=0)
    rng = np.random.default_rng(sensing.seed if seed is None else seed)
    if sensing.noise:
        sig = sensing.sigmas(1.0 / rate)
        x[:, :6] += rng.normal(size=(len(t), 6)) * sig[:6]
        v_ground = v_ground + rng.normal(size=v_ground.shape) * sig[6]
        x[:, 9:12] += rng.normal(size=(len(t), 3)) * sig[9:12] + sensing.bias()
    f = np.maximum(np.array([vehicle.rotor_thrusts(u) for u in U]), 0.0)
    volts = np.linspace(voltage[0], voltage[1], len(t))
    u = model.command(f, volts)
    u = np.round(u / PWM_STEP) * PWM_STEP
    signals = {"position": x[:, :3], "velocity": v_ground, "acceleration": accel,
               "roll": x[:, 3], "pitch": x[:, 4], "yaw": x[:, 5], "body_rates": x[:, 9:12],
               "battery_voltage": volts, model.signal: u}
    return FlightLog(source, "csv", t, signals, {}, {"vehicle": vehicle.name,
                                                      "rotor_model": model.name})
