"""Rotor models: what turns a logged motor command (and the battery voltage) into rotor thrust.

A ``RotorModel`` is data with its source: a frozen, validated record of one published map from
the motor output a flight log records to the thrust of one rotor (N). Four forms:

- ``"polynomial"``: ``f = c0 + c1 (s u) + c2 (s u)^2`` for the logged output u in 0..1 and
  the scale s of the source's command (65535 for the Crazyflie's 16-bit PWM);
- ``"voltage"``: the voltage across the motor, ``u V_bat``, is a quadratic of the thrust,
  ``u V_bat = c0 + c1 F + c2 F^2`` with F in the source's unit (``thrust_unit`` N per unit per
  rotor); the model solves it for F (0 below ``c0``: the motor does not turn);
- ``"voltage_cubic"``: the thrust of one rotor is a cubic of the voltage across the motor,
  ``f = c0 + c1 v + c2 v^2 + c3 v^3`` (N) with ``v = u V_bat`` (the Crazyflie firmware's
  ``VMOTOR2THRUST0..3`` since 2025); 0 where the cubic is below 0 (the motor does not turn);
- ``"thr_mdl_fac"``: PX4's thrust curve, ``f = T_max ((1 - k) u + k u^2)`` for the normalized
  motor output u in 0..1, k the vehicle's ``THR_MDL_FAC``.

``thrust(u, voltage)`` maps (N, 4) outputs to (N, 4) thrusts; ``command(f, voltage)`` is its
inverse (for writing simulated flights as logs). ``signal`` names the log signal the model
reads (``quadcog.logs`` standard names: ``"motor_pwm"`` or ``"motor_command"``) and
``uses_voltage`` whether it needs ``"battery_voltage"``.
"""
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.errors import InputError

__all__ = ["RotorModel", "ROTOR_MODELS", "STANDARD_GRAVITY", "MAX_BATTERY_VOLTAGE", "CRAZYFLIE_BITCRAZE_VOLTAGE",
           "CRAZYFLIE_FOERSTER", "CRAZYFLIE_FIRMWARE_COMMAND", "CRAZYFLIE_21_PLUS_CUBIC",
           "cubic_voltage", "px4_thrust_curve",
           "px4_thrust_curve_from_log"]

KINDS = ("polynomial", "voltage", "thr_mdl_fac", "voltage_cubic")
SIGNALS_READ = ("motor_pwm", "motor_command")
STANDARD_GRAVITY = 9.80665          # m/s^2: grams-force to newtons (CGPM 1901)
# The largest battery voltage taken (V): multirotor packs reach 14 cells (about 60 V); far
# beyond, a voltage is a unit or data error, and the maps' powers of it overflow.
MAX_BATTERY_VOLTAGE = 1000.0


@dataclass(frozen=True)
class RotorModel:
    """One map from logged motor output to the thrust of one rotor (see the module docstring).

    Parameters
    ----------
    name : str
        Short identifier (``ROTOR_MODELS`` key), e.g. ``"bitcraze-voltage"``.
    kind : str
        ``"polynomial"``, ``"voltage"`` or ``"thr_mdl_fac"``.
    signal : str
        The log signal read: ``"motor_pwm"`` (the duty the motor sees) or ``"motor_command"``.
    coefficients : tuple of float
        ``"polynomial"``: (c0, c1, c2) in N; ``"voltage"``: (c0, c1, c2) in V, V per unit and
        V per unit^2 of the source's thrust; ``"thr_mdl_fac"``: (k,), dimensionless in [0, 1];
        ``"voltage_cubic"``: (c0, c1, c2, c3) in N, N/V, N/V^2, N/V^3 (a thrust rising with v).
    scale : float
        ``"polynomial"``: the source's command at u = 1 (65535 for a 16-bit PWM); else 1.
    thrust_unit : float
        N per unit of the source's thrust, per rotor (``"voltage"``; 1 otherwise).
    max_thrust : float
        Thrust of one rotor at u = 1 (N) for ``"thr_mdl_fac"``; otherwise the model's own
        value at u = 1, informative only.
    source : str
        The publication or document the numbers come from.

    Raises
    ------
    InputError
        Naming the field and the bad value.
    """
    name: str
    kind: str
    signal: str
    coefficients: tuple[float, ...]
    source: str
    scale: float = 1.0
    thrust_unit: float = 1.0
    max_thrust: float = 0.0

    def __post_init__(self) -> None:
        where = f"rotor model {self.name!r}"
        if not isinstance(self.name, str) or not self.name:
            validate.fail("RotorModel.name", "a non-empty string", self.name)
        validate.choice(self.kind, f"{where}: kind", KINDS)
        validate.choice(self.signal, f"{where}: signal", SIGNALS_READ)
        n = {"polynomial": 3, "voltage": 3, "thr_mdl_fac": 1, "voltage_cubic": 4}[self.kind]
        c = validate.array(self.coefficients, f"{where}: coefficients", (n,))
        object.__setattr__(self, "coefficients", tuple(float(v) for v in c))
        for field in ("scale", "thrust_unit"):
            object.__setattr__(self, field, validate.positive(getattr(self, field),
                                                              f"{where}: {field}"))
        object.__setattr__(self, "max_thrust", validate.nonnegative(
            self.max_thrust, f"{where}: max_thrust", "N"))
        if self.kind == "thr_mdl_fac":
            validate.real(c[0], f"{where}: THR_MDL_FAC", lo=0.0, hi=1.0)
            if self.max_thrust <= 0:
                validate.fail(f"{where}: max_thrust", "a thrust > 0 N at full output",
                              self.max_thrust)
        if self.kind == "voltage" and not (c[1] > 0 and c[0] >= 0):
            validate.fail(f"{where}: coefficients", "c0 >= 0 V and a positive slope c1",
                          c.tolist())
        if self.kind == "voltage_cubic" and not (c[3] > 0 and 3 * c[3] * c[1] > c[2] ** 2):
            validate.fail(f"{where}: coefficients", "a cubic that rises everywhere (c3 > 0 and "
                          "3 c3 c1 > c2^2, so it has one inverse)", c.tolist())
        if not isinstance(self.source, str) or not self.source.strip():
            validate.fail(f"{where}: source", "the citation of the numbers", self.source)
        # the largest thrust any output (0..1) and battery voltage (up to
        # MAX_BATTERY_VOLTAGE) can give: a map that overflows there returned inf thrust
        with np.errstate(over="ignore", invalid="ignore"):
            if self.kind == "polynomial":
                top = abs(c[0]) + abs(c[1]) * self.scale + abs(c[2]) * self.scale * self.scale
            elif self.kind == "voltage_cubic":
                v = MAX_BATTERY_VOLTAGE
                top = abs(c[0]) + v * (abs(c[1]) + v * (abs(c[2]) + v * abs(c[3])))
            elif self.kind == "voltage":
                top = float(self._thrust(np.ones((1, 4)), np.array([[MAX_BATTERY_VOLTAGE]]))[0, 0])
            else:
                top = self.max_thrust
        if not np.isfinite(top):
            validate.fail(f"{where}: coefficients", "a map whose thrust stays within the float "
                          f"range for outputs in 0..1 and voltages up to {MAX_BATTERY_VOLTAGE:g} V",
                          c.tolist())

    @property
    def uses_voltage(self) -> bool:
        """bool: True when the thrust depends on the battery voltage (the ``"voltage"`` and
        ``"voltage_cubic"`` forms)."""
        return self.kind in ("voltage", "voltage_cubic")

    @property
    def signals(self) -> tuple[str, ...]:
        """tuple of str: The log signals the model reads, (signal,) or (signal,
        "battery_voltage")."""
        return (self.signal, "battery_voltage") if self.uses_voltage else (self.signal,)

    def _per_rotor(self, value: npt.ArrayLike, where: str) -> npt.NDArray[np.float64]:
        """``value`` as a float array of shape (..., 4) of finite real numbers, checked before
        any arithmetic (strings, bools, complex numbers, object arrays, ragged lists, integers
        beyond the float range refused by ``quadcog.validate.array``)."""
        where = f"rotor model {self.name!r}: {where}"
        a = validate.array(value, where, what="an array of shape (..., 4) (one per rotor)")
        if a.ndim < 1 or a.shape[-1] != 4:
            raise InputError(f"{where}: expected an array of shape (..., 4) (one per rotor), "
                             f"got shape {a.shape}")
        return a

    def _voltage(self, voltage: npt.ArrayLike | None,
                 shape: tuple[int, ...]) -> npt.NDArray[np.float64] | None:
        """The battery voltage as an array that broadcasts over outputs of ``shape`` (...,
        4): one number, or one per row (shape ``shape[:-1]``); None when the model does not
        use it (a voltage given then is not read)."""
        if not self.uses_voltage:
            return None
        if voltage is None:
            raise InputError(f"rotor model {self.name!r} needs the battery voltage (V), got "
                             "None")
        where = f"rotor model {self.name!r}: battery voltage"
        rows = shape[:-1]
        v = validate.array(voltage, where, finite=False,
                           what=f"a number or an array of shape {rows} (V)")
        if v.shape not in ((), rows):
            raise InputError(f"{where}: expected a number or an array of shape {rows} (one per "
                             f"row of outputs) (V), got shape {v.shape}")
        bad = ~((v > 0) & (v <= MAX_BATTERY_VOLTAGE))      # NaN too
        if bad.any():
            k = np.unravel_index(int(np.argmax(bad)), v.shape) if v.ndim else ()
            at = f"[{', '.join(str(int(i)) for i in k)}]" if k else ""
            raise InputError(f"{where}{at}: expected a voltage in (0, {MAX_BATTERY_VOLTAGE:g}] "
                             f"V, got {validate.plain(float(v[k]))}")
        return v[..., None]

    def thrust(self, u: npt.ArrayLike,
               voltage: npt.ArrayLike | None = None) -> npt.NDArray[np.float64]:
        """Thrust of each rotor (N) from logged outputs.

        Parameters
        ----------
        u : array_like, shape (..., 4)
            Motor outputs: finite real numbers (not bools), in 0..1 (finite values outside
            are clipped to 0..1).
        voltage : float or array_like, shape (...,), optional
            Battery voltage (V), one number or one per row of ``u``; required when
            ``uses_voltage``, not read otherwise.

        Returns
        -------
        numpy.ndarray, shape of u
            Thrust of each rotor (N), >= 0.

        Raises
        ------
        InputError
            When ``u`` is not an array of shape (..., 4) of finite real numbers, or the battery
            voltage is missing (``uses_voltage``), of another shape, or not in
            (0, ``MAX_BATTERY_VOLTAGE``] V; the message names the argument and the first bad
            value.
        """
        # checked before the clip, which would turn inf into full output
        u = self._per_rotor(u, "motor outputs u").clip(0.0, 1.0)
        return self._thrust(u, self._voltage(voltage, u.shape))

    def _thrust(self, u: npt.NDArray[np.float64],
                volts: npt.NDArray[np.float64] | None) -> npt.NDArray[np.float64]:
        """``thrust`` of checked outputs in 0..1 and checked voltages (..., 1)."""
        c = self.coefficients
        assert volts is not None or not self.uses_voltage      # _voltage gives them
        if self.kind == "polynomial":
            s = self.scale * u
            f = c[0] + c[1] * s + c[2] * s * s
        elif self.kind == "thr_mdl_fac":
            f = self.max_thrust * ((1.0 - c[0]) * u + c[0] * u * u)
        elif self.kind == "voltage_cubic":
            v = u * cast(npt.NDArray[np.float64], volts)
            f = c[0] + v * (c[1] + v * (c[2] + v * c[3]))
        else:
            across = u * cast(npt.NDArray[np.float64], volts) - c[0]
            if c[2] < 0:        # beyond the parabola's vertex the fit means nothing: saturate
                across = np.minimum(across, c[1] ** 2 / (-4.0 * c[2]))
            f = self.thrust_unit * _quadratic_root(c[2], c[1], -np.maximum(across, 0.0))
        return np.maximum(f, 0.0)

    def command(self, f: npt.ArrayLike,
                voltage: npt.ArrayLike | None = None) -> npt.NDArray[np.float64]:
        """The logged output u (0..1) that gives the rotor thrusts ``f``: the inverse of
        ``thrust``.

        Parameters
        ----------
        f : array_like, shape (..., 4)
            Thrust of each rotor (N): finite real numbers >= 0 (not bools).
        voltage : float or array_like, shape (...,), optional
            Battery voltage (V), one number or one per row of ``f``; required when
            ``uses_voltage``, not read otherwise.

        Returns
        -------
        numpy.ndarray, shape of f
            Outputs in 0..1.

        Raises
        ------
        InputError
            When ``f`` is not an array of shape (..., 4) of finite real numbers >= 0 N, a
            thrust needs more than full output, or the battery voltage is missing
            (``uses_voltage``), of another shape, or not in (0, ``MAX_BATTERY_VOLTAGE``] V.
        """
        f = self._per_rotor(f, "thrusts f")
        if (f < 0).any():
            k = np.unravel_index(int(np.argmax(f < 0)), f.shape)
            at = ", ".join(str(int(i)) for i in k)
            raise InputError(f"rotor model {self.name!r}: thrusts f[{at}]: expected a thrust "
                             f">= 0 N, got {validate.plain(float(f[k]))}")
        volts = self._voltage(voltage, f.shape)
        # a finite thrust far beyond the rotor's overflows below: refused as beyond full
        # output (the check after), with no numpy warning
        with np.errstate(over="ignore", invalid="ignore"):
            u = self._output(f, volts)
        beyond = ~(u <= 1.0 + 1e-9)          # NaN (inf - inf) too
        if beyond.any():
            k = np.unravel_index(int(np.argmax(beyond)), u.shape)
            needs = (f"output {u[k]:.4g} > 1" if np.isfinite(u[k]) else
                     "more than the model's largest thrust")
            raise InputError(f"rotor model {self.name!r}: a thrust of {f[k]:.4g} N needs "
                             f"{needs} (beyond full output)")
        return np.minimum(u, 1.0)

    def _output(self, f: npt.NDArray[np.float64],
                volts: npt.NDArray[np.float64] | None) -> npt.NDArray[np.float64]:
        """The outputs of checked thrusts ``f`` (``command`` without its checks), >= 0; inf
        for a thrust beyond the vertex of a falling parabola, which no output gives."""
        c = self.coefficients
        if self.kind == "polynomial":
            u = _quadratic_root(c[2], c[1], c[0] - f) / self.scale
            u = np.where(c[1] * c[1] - 4.0 * c[2] * (c[0] - f) < 0, np.inf, u)
        elif self.kind == "thr_mdl_fac":
            u = _quadratic_root(c[0], 1.0 - c[0], -f / self.max_thrust)
        elif self.kind == "voltage_cubic":
            u = np.where(f > 0, cubic_voltage(c, f), 0.0) / volts
        else:
            F = f / self.thrust_unit
            u = np.where(F > 0, c[0] + c[1] * F + c[2] * F * F, 0.0) / volts
            if c[2] < 0:        # thrust saturates at the vertex (see thrust)
                u = np.where(F > c[1] / (-2.0 * c[2]), np.inf, u)
        return np.maximum(u, 0.0)

    def describe(self) -> str:
        """One line: name, form and source.

        Returns
        -------
        str
            ``"<name> (<kind> of <signal>): <source>"``.
        """
        return f"{self.name} ({self.kind} of {self.signal}): {self.source}"


def cubic_voltage(c: tuple[float, ...], f: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The motor voltage v at which the rising cubic ``c0 + c1 v + c2 v^2 + c3 v^3`` is f.

    Cardano's formula in the form the Crazyflie firmware inverts its thrust map with
    (``motorsCompensateBatteryVoltage`` in src/drivers/src/motors.c): with
    ``p = -c2 / (3 c3)``, ``r = c1 / (3 c3)`` and
    ``q = p^3 + (c2 c1 - 3 c3 (c0 - f)) / (6 c3^2)``,
    ``v = cbrt(q + s) + cbrt(q - s) + p``, ``s = sqrt(q^2 + (r - p^2)^3)``.

    Parameters
    ----------
    c : tuple of 4 float
        (c0, c1, c2, c3) in N, N/V, N/V^2, N/V^3, with ``3 c3 c1 > c2^2`` (one real root).
    f : array_like
        Thrusts (N).

    Returns
    -------
    numpy.ndarray, shape of f
        Motor voltages (V).

    Raises
    ------
    InputError
        ``c`` not 4 finite numbers of a rising cubic, or ``f`` not finite real numbers.
    """
    coef = validate.array(c, "cubic_voltage: c", (4,), what="4 finite coefficients (c0, c1, c2, "
                          "c3) in N, N/V, N/V^2, N/V^3")
    c0, c1, c2, c3 = (float(x) for x in coef)
    if not (c3 > 0 and 3 * c3 * c1 > c2 * c2):
        validate.fail("cubic_voltage: c", "a cubic that rises everywhere (c3 > 0 and 3 c3 c1 > "
                      "c2^2, so it has one inverse)", coef.tolist())
    f = validate.array(f, "cubic_voltage: f", what="thrusts (N): finite real numbers")
    p, r = -c2 / (3 * c3), c1 / (3 * c3)
    q = p ** 3 + (c2 * c1 - 3 * c3 * (c0 - f)) / (6 * c3 * c3)
    s = np.sqrt(q * q + (r - p * p) ** 3)
    return np.cbrt(q + s) + np.cbrt(q - s) + p


def _quadratic_root(a, b, c):
    """The root of a x^2 + b x + c = 0 (elementwise, b > 0) that tends to -c / b as a -> 0:
    the physical branch of each map. The form 2c / (-b - sqrt(b^2 - 4ac)) loses no digits for
    small a; a negative discriminant (beyond the map's vertex) is taken as 0."""
    c = np.asarray(c, dtype=float)
    disc = np.maximum(b * b - 4.0 * a * c, 0.0)
    denom = -b - np.sqrt(disc)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.where(denom != 0, 2.0 * c / np.where(denom != 0, denom, 1.0), 0.0)
    return x


# --- Crazyflie 2.x -----------------------------------------------------------------------
# Bitcraze measured the thrust of the whole Crazyflie 2.X on a scale at 16 PWM steps with the
# supply voltage (wiki "PWM to Thrust", 2015 measurements) and fitted the voltage across the
# motors, PWM x supply, against the total thrust F (g) (crazyflie-firmware
# src/drivers/src/motors.c, comment above motorsCompensateBatteryVoltage, GNU Octave polyfit):
# V = 0.06865956 + 0.08835522 F - 0.00062390 F^2. Per rotor: F / 4 grams. The firmware's
# compensation drops the constant (zero thrust = zero PWM): CRAZYFLIE_FIRMWARE_COMMAND.
CRAZYFLIE_BITCRAZE_VOLTAGE = RotorModel(
    name="bitcraze-voltage", kind="voltage", signal="motor_pwm",
    coefficients=(0.06865956, 0.08835522, -0.00062390),
    thrust_unit=STANDARD_GRAVITY * 1e-3 / 4, max_thrust=60 / 4 * STANDARD_GRAVITY * 1e-3,
    source="Bitcraze, wiki 'PWM to Thrust' (2015 thrust-stand table) and its fit in "
           "crazyflie-firmware motors.c: motor voltage PWM * V_bat = 0.06865956 + 0.08835522 F "
           "- 0.00062390 F^2, F the Crazyflie 2.X total thrust (g), a quarter per rotor")
# J. Foerster, "System Identification of the Crazyflie 2.0 Nano Quadrocopter", BSc thesis,
# ETH Zurich (IDSC), 2015: thrust of one rotor f = 2.130295e-11 c^2 + 1.032633e-6 c +
# 5.484560e-4 N for the 16-bit PWM command c (0..65535), measured at a fixed supply: no
# voltage term. Read here with the logged PWM duty (pwm.m*_pwm), the motor's own input.
CRAZYFLIE_FOERSTER = RotorModel(
    name="foerster", kind="polynomial", signal="motor_pwm",
    coefficients=(5.484560e-4, 1.032633e-6, 2.130295e-11), scale=65535.0,
    max_thrust=5.484560e-4 + 1.032633e-6 * 65535 + 2.130295e-11 * 65535 ** 2,
    source="J. Foerster, 'System Identification of the Crazyflie 2.0 Nano Quadrocopter', "
           "BSc thesis, ETH Zurich 2015: f = 2.130295e-11 c^2 + 1.032633e-6 c + 5.484560e-4 N "
           "per rotor, c the 16-bit PWM (0..65535), no voltage term")
# The firmware's intent with battery compensation on: the thrust command (motor.m*) is linear
# in thrust, 65536 <==> 60 g total, i.e. 15 g per rotor at full command (same motors.c); the
# PWM it sets is (0.088 F - 0.0006239 F^2) / V_bat, the fit above without its constant, so
# this map reads about 0.0687 V / (dV/dF) more thrust than the measured fit (1.3 g of the
# vehicle's at a 27 g hover).
CRAZYFLIE_FIRMWARE_COMMAND = RotorModel(
    name="firmware-command", kind="polynomial", signal="motor_command",
    coefficients=(0.0, 60 / 4 * STANDARD_GRAVITY * 1e-3 / 65536, 0.0), scale=65535.0,
    max_thrust=60 / 4 * STANDARD_GRAVITY * 1e-3,
    source="Bitcraze, crazyflie-firmware motors.c: with battery compensation the thrust "
           "command maps 65536 <==> 60 g total (15 g per rotor), linearly")

# The Crazyflie firmware's thrust map for the Crazyflie 2.1 with its default 2.1+ propellers
# (Kconfig choice CRAZYFLIE_21_PLUS, the default when battery compensation is on), thrust of
# one rotor (N) a cubic of the motor voltage (V): crazyflie-firmware
# src/platform/interface/platform_defaults_cf2.h, VMOTOR2THRUST0..3 (commit 2a18fc29; Bitcraze
# blog "Keeping thrust consistent as the battery drains", 2025-10, firmware PR #1526).
# tests/test_crazyflie_preset.py reads them from the firmware tree.
CRAZYFLIE_21_PLUS_CUBIC = RotorModel(
    name="bitcraze-2.1plus", kind="voltage_cubic", signal="motor_pwm",
    coefficients=(-0.02476537915958403, 0.06523793527519485, -0.026792504967750107,
                  0.006776789303971145),
    max_thrust=0.12,
    source="Bitcraze, crazyflie-firmware platform_defaults_cf2.h (2.1+ propellers): thrust of "
           "one rotor = VMOTOR2THRUST0 + VMOTOR2THRUST1 v + VMOTOR2THRUST2 v^2 + "
           "VMOTOR2THRUST3 v^3 N, v = V_bat PWM / 65535; THRUST_MAX 0.12 N")

ROTOR_MODELS = {m.name: m for m in (CRAZYFLIE_BITCRAZE_VOLTAGE, CRAZYFLIE_FOERSTER,
                                    CRAZYFLIE_FIRMWARE_COMMAND, CRAZYFLIE_21_PLUS_CUBIC)}


def px4_thrust_curve(max_thrust: float, thr_mdl_fac: float, name: str = "px4",
                     source: str = "PX4 parameter THR_MDL_FAC (mc_att_control / control "
                                   "allocation: thrust = (1 - k) u + k u^2 of full thrust)"
                     ) -> RotorModel:
    """PX4's rotor model: normalized motor output u (0..1) to thrust
    ``max_thrust ((1 - k) u + k u^2)``.

    Parameters
    ----------
    max_thrust : float
        Thrust of one rotor at full output (N), > 0.
    thr_mdl_fac : float
        The vehicle's ``THR_MDL_FAC`` k in [0, 1] (0: thrust linear in u; 1: quadratic).
    name : str
        Identifier and citation of the numbers (the vehicle's own parameters).
    source : str
        Identifier and citation of the numbers (the vehicle's own parameters).

    Returns
    -------
    RotorModel
        Of kind ``"thr_mdl_fac"`` reading ``"motor_command"``.

    Raises
    ------
    InputError
        When ``max_thrust`` is not > 0 N or ``thr_mdl_fac`` is not in [0, 1].
    """
    return RotorModel(name=name, kind="thr_mdl_fac", signal="motor_command",
                      coefficients=(thr_mdl_fac,), max_thrust=max_thrust, source=source)



def px4_thrust_curve_from_log(log: Any, max_thrust: float) -> RotorModel:
    """PX4's rotor model with the ``THR_MDL_FAC`` that a ULog recorded.

    Parameters
    ----------
    log : quadcog.logs.FlightLog
        A ULog read by ``quadcog.logs.read_log`` (its ``meta["param.THR_MDL_FAC"]``).
    max_thrust : float
        Thrust of one rotor at full output (N): the vehicle's, PX4 does not log it.

    Returns
    -------
    RotorModel
        Of kind ``"thr_mdl_fac"`` reading ``"motor_command"``, named after the log's factor.

    Raises
    ------
    InputError
        ``max_thrust`` is not a positive number, ``log`` is not a flight log, it has no
        THR_MDL_FAC parameter, or it is not a number.
    """
    # checked first: it is written into the source with :g (a string raised ValueError)
    max_thrust = validate.positive(max_thrust, "px4_thrust_curve_from_log: max_thrust", "N")
    meta = getattr(log, "meta", None)
    if not isinstance(meta, Mapping):       # a FlightLog's meta is a read-only mapping
        validate.fail("px4_thrust_curve_from_log: log", "a flight log read by "
                      "quadcog.logs.read_log (a FlightLog with its meta)", log)
    text: Any = meta.get("param.THR_MDL_FAC")
    try:
        k = float(text)
    except (TypeError, ValueError):
        raise InputError(f"{getattr(log, 'source', 'the log')}: no numeric THR_MDL_FAC "
                         f"parameter in the log (got {validate.plain(text)}); pass "
                         "px4_thrust_curve(max_thrust, thr_mdl_fac)") from None
    return px4_thrust_curve(max_thrust, k, name=f"px4 (THR_MDL_FAC {k:g})",
                            source=f"PX4 THR_MDL_FAC = {k:g} from "
                                   f"{getattr(log, 'source', 'the log')}; "
                                   f"T_max = {max_thrust:g} N per rotor given")
