"""The standard signals of a flight log (``SIGNALS``), the log formats (``LOG_FORMATS``) and
the column names of a log table (CSV, Parquet), each defined once.

Every reader (quadcog.logs) converts its source into these signals: float64, SI units,
quadcog's frames, one row per sample of the log's time base ``t``:

- ground frame: z up. PX4's NED ground frame becomes x north, y west, z up (``[x, -y, -z]``);
  the Crazyflie's ground frame is already z up.
- body frame: x forward, y left, z up. PX4's FRD body becomes ``[x, -y, -z]``.
- attitude: quadcog's ZYX Euler angles ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (body to ground,
  ``quadcog.model.conventions.rotation_matrix``). ``roll``, ``pitch`` and ``yaw`` are separate
  signals because a log may carry only some of them.
- rotors: quadcog's order (``quadcog.vehicles.vehicle.x_layout``): 1 front-right, 2 back-right,
  3 back-left, 4 front-left.

Column names follow ``quadcog.model.columns``: ``<signal>_<component>_<unit>``, the unit written
with ``_`` for ``/`` and without ``^`` (``acceleration_x_m_s2``); a scalar signal has no
component (``roll_rad``, ``battery_voltage_V``), a dimensionless one no unit
(``motor_command_m1``). Time is ``t_s``.
"""
from collections.abc import Iterable
from dataclasses import dataclass

from quadcog.validate import fail

__all__ = ["LOG_FORMATS", "SIGNALS", "SignalSpec", "TIME_COLUMN", "signal_columns",
           "table_columns", "unit_token"]

# The formats read_log reads and write_log writes.
LOG_FORMATS = ("crazyflie-usd", "ulog", "csv", "parquet")

TIME_COLUMN = "t_s"


@dataclass(frozen=True)
class SignalSpec:
    """One standard signal: the shape of one sample, its unit, what it means, its components.

    Parameters
    ----------
    shape : tuple
        Shape of one sample: ``()`` for a scalar signal (the array is (N,)), ``(k,)`` for a
        vector (the array is (N, k)).
    unit : str
        SI unit (``"m/s^2"``); ``"1"`` for a dimensionless signal.
    meaning : str
        What the signal is, its frame and sign convention.
    components : tuple of str
        Names of the vector's entries, used in column names (empty for a scalar).

    Returns
    -------
    SignalSpec
    """
    shape: tuple
    unit: str
    meaning: str
    components: tuple = ()


SIGNALS = {
    "position": SignalSpec(
        (3,), "m", "position of O in the ground frame (z up)", ("x", "y", "z")),
    "velocity": SignalSpec(
        (3,), "m/s", "velocity of O in the ground frame (z up)", ("x", "y", "z")),
    "acceleration": SignalSpec(
        (3,), "m/s^2", "kinematic acceleration of O in the ground frame (z up), the second "
        "derivative of position: gravity is not included (hover: 0)", ("x", "y", "z")),
    "roll": SignalSpec((), "rad", "ZYX Euler angle phi (about body x)"),
    "pitch": SignalSpec((), "rad", "ZYX Euler angle theta (about body y, y left: positive "
                        "pitch lowers the nose)"),
    "yaw": SignalSpec((), "rad", "ZYX Euler angle psi (about ground z, z up), in (-pi, pi]"),
    "body_rates": SignalSpec(
        (3,), "rad/s", "angular velocity [p, q, r] in the body frame (x forward, y left, "
        "z up)", ("p", "q", "r")),
    "motor_command": SignalSpec(
        (4,), "1", "commanded motor power 0..1 of full scale, rotors in quadcog's order "
        "(1 front-right, 2 back-right, 3 back-left, 4 front-left); the Crazyflie's before its "
        "battery compensation, PX4's normalized motor output", ("m1", "m2", "m3", "m4")),
    "motor_pwm": SignalSpec(
        (4,), "1", "motor output 0..1 as applied: the Crazyflie's PWM duty cycle (after its "
        "battery compensation), PX4's actuator_outputs scaled by its PWM range; rotors in "
        "quadcog's order", ("m1", "m2", "m3", "m4")),
    "battery_voltage": SignalSpec((), "V", "battery voltage"),
    "thrust_command": SignalSpec(
        (), "1", "collective thrust command in motor-command units (0..1 of full scale per "
        "motor): the Crazyflie's controller.cmd_thrust / 65535, PX4's normalized thrust set-point "
        "along -z of FRD"),
    "moment_command": SignalSpec(
        (3,), "1", "the attitude-rate controller's moment commands about body x, y, z (quadcog "
        "signs) in motor-command units: the Crazyflie's mixer gives rotor i the command "
        "thrust_command + sgn(y_i) m_x - sgn(x_i) m_y + d_i m_z (rotor position (x_i, y_i), "
        "spin sign d_i of quadcog.vehicles.vehicle.CRAZYFLIE)", ("x", "y", "z")),
}


def unit_token(unit: str) -> str:
    """The unit as written in a column name: ``"m/s^2"`` -> ``"m_s2"``, ``"1"`` -> ``""``.

    Parameters
    ----------
    unit : str
        A unit of ``SIGNALS``.

    Returns
    -------
    str
        The unit with ``_`` for ``/`` and no ``^``; empty for the dimensionless ``"1"``.

    Raises
    ------
    InputError
        ``unit`` not a str.
    """
    if not isinstance(unit, str):
        fail("unit_token: unit", "a unit (a str such as 'm/s^2')", unit)
    return "" if unit == "1" else unit.replace("/", "_").replace("^", "")


def _signal_name(name: object, where: str) -> str:
    """``name`` if it is the name of a standard signal (a str key of ``SIGNALS``)."""
    if not isinstance(name, str) or name not in SIGNALS:
        fail(where, f"a name of quadcog.logs.SIGNALS ({', '.join(SIGNALS)})", name)
    return str(name)


def signal_columns(name: str) -> tuple:
    """The column names of one signal, in component order.

    Parameters
    ----------
    name : str
        A key of ``SIGNALS``.

    Returns
    -------
    tuple of str
        One name for a scalar signal (``"roll_rad"``), one per component for a vector
        (``"position_x_m", "position_y_m", "position_z_m"``).

    Raises
    ------
    InputError
        ``name`` not a name of ``SIGNALS``.
    """
    name = _signal_name(name, "signal_columns: name")
    spec = SIGNALS[name]
    unit = unit_token(spec.unit)
    parts = [(name, c) for c in spec.components] if spec.components else [(name,)]
    return tuple("_".join(p + ((unit,) if unit else ())) for p in parts)


def table_columns(names: Iterable[str] | None = None) -> tuple:
    """The column names of a log table: ``t_s``, then the columns of each signal.

    Parameters
    ----------
    names : iterable of str, optional
        Signals to include, in ``SIGNALS`` order; default all.

    Returns
    -------
    tuple of str
        ``t_s`` and each signal's ``<name>_<unit>`` columns.

    Raises
    ------
    InputError
        ``names`` a str (one name is not a sequence of its letters) or not iterable, or one
        that is not a name of ``SIGNALS`` (it was left out silently).
    """
    if names is not None and (isinstance(names, (str, bytes)) or not isinstance(names, Iterable)):
        fail("table_columns: names", "None or an iterable of names of quadcog.logs.SIGNALS",
             names)
    chosen = set(SIGNALS) if names is None else {
        _signal_name(n, f"table_columns: names[{i}]") for i, n in enumerate(names)}
    return (TIME_COLUMN,) + tuple(c for n in SIGNALS if n in chosen for c in signal_columns(n))
