"""The sensors PX4 reads, made from the truth state: IMU, magnetometer, barometer, GPS.

Everything PX4 receives is in its frames (FRD body, NED ground: ``quadcog.px4.frames``):

- accelerometer: the specific force at the body origin O, ``R^T (a_O - g)`` with ``g`` =
  (0, 0, -g) in the z-up ground frame (a level vehicle at rest reads +g along its z axis,
  -g along FRD's z), m/s^2;
- gyroscope: the body rates, rad/s;
- magnetometer: the Earth's field at the home position from PX4's own World Magnetic Model
  tables (``src/lib/world_magnetic_model/geo_magnetic_tables.hpp`` of the tree: declination,
  inclination, strength, interpolated as PX4 does), in body axes, gauss. A field that
  disagrees with those tables makes PX4's arming checks refuse (``COM_ARM_MAG_STR``);
- barometer: the International Standard Atmosphere's pressure at the altitude, hPa;
- GPS: latitude, longitude (a flat Earth about the home position, radius 6371 km),
  altitude, NED velocity, at ``GPS_RATE``.

The IMU is quadcog's sensing model (``quadcog.sim.sensing.Sensing``, the scenario's
``[sensing]`` table): white noise of its densities per sample at the IMU rate
(``Sensing.imu_sigmas``: ``density sqrt(rate / 2)``) and its constant biases of the seed
(``Sensing.bias`` on the gyroscope, ``Sensing.accel_offset`` on the accelerometer), both in
quadcog's body axes before the turn to FRD; without ``noise`` the IMU reads the truth. Its
``position``, ``velocity`` and ``attitude`` accuracies are not used: PX4 estimates those
itself (EKF2) from these sensors. Its ``delay`` holds PX4's answer one lockstep period
(``quadcog.px4.lockstep``).

The magnetometer, the barometer and the GPS are PX4's additions (``Px4Sensing``), always
noisy: PX4 calls a barometer or magnetometer whose reading does not change stale and refuses
to arm.
"""
from dataclasses import dataclass
import math
from pathlib import Path
import re

import numpy as np
import numpy.typing as npt

from quadcog.errors import Px4Error
from quadcog.px4.frames import FLIP
from quadcog.sim.sensing import Sensing

__all__ = ["HOME", "EARTH_RADIUS", "GPS_RATE", "Px4Sensing", "earth_field", "isa_pressure",
           "Sensors"]

# PX4's default SITL home (SIH_LOC_LAT0, SIH_LOC_LON0; Zurich): lat, lon (deg), altitude (m)
HOME = (47.397742, 8.545594, 488.0)
EARTH_RADIUS = 6371000.0          # m, mean (PX4's CONSTANTS_RADIUS_OF_EARTH)
GPS_RATE = 10.0                    # Hz
_TABLES = "src/lib/world_magnetic_model/geo_magnetic_tables.hpp"


@dataclass(frozen=True)
class Px4Sensing:
    """The sensors of a PX4 flight: quadcog's IMU model and PX4's additions (GPS, barometer,
    magnetometer), one standard deviation per axis and sample.

    Parameters
    ----------
    imu : Sensing
        The accelerometer and gyroscope (noise densities, biases, seed, delay: see the module
        docstring); the seed also seeds the additions' noise.
    mag : float
        Magnetometer noise (gauss); 0.002 G is a few tenths of a degree of heading.
    baro : float
        Barometer noise (hPa); 0.01 hPa is about 8 cm of altitude.
    gps_position : float
        GPS position noise (m), horizontal and vertical.
    gps_velocity : float
        GPS velocity noise (m/s).

    Raises
    ------
    quadcog.Px4Error
        ``imu`` not a Sensing, or a noise not a number >= 0.
    """
    imu: Sensing = Sensing()
    mag: float = 0.002
    baro: float = 0.01
    gps_position: float = 0.05
    gps_velocity: float = 0.02

    def __post_init__(self) -> None:
        if not isinstance(self.imu, Sensing):
            raise Px4Error(f"Px4Sensing.imu must be a quadcog Sensing, got {self.imu!r}")
        for name in ("mag", "baro", "gps_position", "gps_velocity"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not v >= 0 \
                    or not math.isfinite(v):
                raise Px4Error(f"Px4Sensing.{name} must be a number >= 0, got {v!r}")

    @property
    def seed(self) -> int:
        """The noise's seed (``imu.seed``)."""
        return int(self.imu.seed)


def _table(text: str, name: str) -> tuple[npt.NDArray[np.float64], float]:
    scale = re.search(rf"WMM_{name.upper()}_SCALE_TO_\w+ = ([-0-9.eE]+)f?;", text)
    body = re.search(rf"{name}_table\[(\d+)\]\[(\d+)\]\s*\{{(.*?)\n\}};", text, re.S)
    if scale is None or body is None:
        raise Px4Error(f"{_TABLES}: no {name} table found (PX4's World Magnetic Model)")
    rows, cols = int(body.group(1)), int(body.group(2))
    lines = [re.sub(r"/\*.*?\*/|//.*", "", line) for line in body.group(3).splitlines()]
    values = [int(v) for v in re.findall(r"-?\d+", " ".join(lines))]
    if len(values) != rows * cols:
        raise Px4Error(f"{_TABLES}: the {name} table has {len(values)} numbers, expected "
                       f"{rows} x {cols}")
    return np.array(values, float).reshape(rows, cols), float(scale.group(1))


def _lookup(table: npt.NDArray[np.float64], lat: float, lon: float) -> float:
    """PX4's bilinear look-up on the 10-degree grid (geo_mag_declination.cpp)."""
    res = 10.0
    lat = min(max(lat, -90.0), 90.0)
    lon = lon - 360.0 if lon > 180.0 else lon + 360.0 if lon < -180.0 else lon
    lat0 = min(max(math.floor(lat / res) * res, -90.0), 90.0 - res)
    lon0 = min(max(math.floor(lon / res) * res, -180.0), 180.0 - res)
    i, j = int((lat0 + 90.0) / res), int((lon0 + 180.0) / res)
    a = min(max((lat - lat0) / res, 0.0), 1.0)
    b = min(max((lon - lon0) / res, 0.0), 1.0)
    south = table[i, j] + b * (table[i, j + 1] - table[i, j])
    north = table[i + 1, j] + b * (table[i + 1, j + 1] - table[i + 1, j])
    return float(south + a * (north - south))


def earth_field(tree: Path, lat: float, lon: float) -> npt.NDArray[np.float64]:
    """The Earth's magnetic field at (lat, lon) by PX4's World Magnetic Model tables.

    Parameters
    ----------
    tree : pathlib.Path
        The PX4-Autopilot source folder.
    lat : float
        Latitude (deg).
    lon : float
        Longitude (deg).

    Returns
    -------
    (3,) numpy.ndarray
        The field in NED (gauss): strength ``B``, inclination ``I`` (down positive),
        declination ``D`` (east of north): ``B [cos I cos D, cos I sin D, sin I]``.

    Raises
    ------
    quadcog.Px4Error
        When the tables are not in the tree or not as expected.
    """
    path = tree / _TABLES
    try:
        text = path.read_text()
    except OSError as e:
        raise Px4Error(f"{path}: cannot read PX4's World Magnetic Model tables "
                       f"({e.strerror})") from None
    dec_t, dec_s = _table(text, "declination")
    inc_t, inc_s = _table(text, "inclination")
    str_t, str_s = _table(text, "totalintensity")
    D = math.radians(_lookup(dec_t, lat, lon) * dec_s)
    incl = math.radians(_lookup(inc_t, lat, lon) * inc_s)
    B = _lookup(str_t, lat, lon) * str_s * 1e-9 * 1e4          # nT -> T -> gauss
    return B * np.array([math.cos(incl) * math.cos(D), math.cos(incl) * math.sin(D),
                         math.sin(incl)])


def isa_pressure(altitude: float) -> tuple[float, float]:
    """Pressure and temperature of the International Standard Atmosphere (troposphere).

    Parameters
    ----------
    altitude : float
        Geopotential altitude above mean sea level (m).

    Returns
    -------
    pressure : float
        hPa: ``1013.25 (1 - 0.0065 h / 288.15) ^ 5.2559``.
    temperature : float
        deg C: ``15 - 0.0065 h``.
    """
    return 1013.25 * (1.0 - 0.0065 * altitude / 288.15) ** 5.25588, 15.0 - 0.0065 * altitude


class Sensors:
    """The sensor readings of one flight, drawn step by step.

    Parameters
    ----------
    field_ned : (3,) array_like
        The Earth's field at home (gauss, NED; ``earth_field``).
    g : float
        Gravity (m/s^2) of the plant.
    rate : float
        IMU rate (Hz): the rate HIL_SENSOR is sent at, which sets the per-sample noise.
    sensing : Px4Sensing, optional
        The sensors' models (default ``Px4Sensing()``).
    home : tuple of 3 float
        lat, lon (deg), altitude (m) of the plant's origin.
    """

    _BLOCK = 4096            # noise samples drawn at a time

    def __init__(self, field_ned: npt.ArrayLike, g: float, rate: float,
                 sensing: Px4Sensing | None = None, home: tuple[float, float, float] = HOME
                 ) -> None:
        self.sensing = sensing or Px4Sensing()
        self.field_up = np.asarray(field_ned, float) * FLIP      # ground z-up components
        self.g = float(g)
        self.home = home
        self._rng = np.random.default_rng(self.sensing.seed)
        s, imu = self.sensing, self.sensing.imu
        accel_std, gyro_std = imu.imu_sigmas(1.0 / rate) if imu.noise else (0.0, 0.0)
        self._imu_std = np.array([accel_std] * 3 + [gyro_std] * 3 + [s.mag] * 3 + [s.baro])
        # the constant biases, drawn in quadcog's body axes (FLU), turned to FRD and added to
        # each block of noise (no cost per sample)
        self.accel_bias = imu.accel_offset() if imu.noise else np.zeros(3)
        self.gyro_bias = imu.bias() if imu.noise else np.zeros(3)
        self._imu_offset = np.r_[self.accel_bias * FLIP, self.gyro_bias * FLIP, np.zeros(4)]
        self._gps_std = np.array([s.gps_position] * 3 + [s.gps_velocity] * 3)
        self._imu_noise = np.empty((0, 10))
        self._gps_noise = np.empty((0, 6))
        self._k = self._kg = 0
        self._cols = np.empty((3, 2))                   # [a + g, field] in ground axes
        self._cols[:, 1] = self.field_up

    def _imu(self) -> npt.NDArray[np.float64]:
        if self._k >= len(self._imu_noise):
            self._imu_noise = (self._rng.standard_normal((self._BLOCK, 10)) * self._imu_std
                               + self._imu_offset)
            self._k = 0
        self._k += 1
        return self._imu_noise[self._k - 1]

    def _gps(self) -> npt.NDArray[np.float64]:
        if self._kg >= len(self._gps_noise):
            self._gps_noise = self._rng.standard_normal((self._BLOCK, 6)) * self._gps_std
            self._kg = 0
        self._kg += 1
        return self._gps_noise[self._kg - 1]

    def imu(self, R: npt.NDArray[np.float64], rates: npt.ArrayLike, accel_ground: npt.ArrayLike,
            altitude: float) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...],
                                      float, float, float]:
        """One HIL_SENSOR's readings (PX4's frames, noise added).

        Parameters
        ----------
        R : (3, 3) numpy.ndarray
            Rotation FLU body -> z-up ground.
        rates : (3,) array_like
            Body rates p, q, r (rad/s, FLU).
        accel_ground : (3,) array_like
            Acceleration of the body origin (m/s^2, z-up ground axes).
        altitude : float
            Height above home (m).

        Returns
        -------
        acc, gyro, mag : tuple of 3 float
            Specific force (m/s^2), rates (rad/s), field (gauss), FRD.
        pressure : float
            Static pressure (hPa).
        pressure_alt : float
            Altitude above mean sea level from the pressure (m).
        temperature : float
            deg C.
        """
        n = self._imu()
        cols = self._cols
        cols[:, 0] = accel_ground
        cols[2, 0] += self.g
        f_body, m_body = (R.T @ cols).T                 # specific force and field, body axes
        h = self.home[2] + altitude
        pressure, temperature = isa_pressure(h)
        pressure += n[9]
        acc = (f_body[0] + n[0], -f_body[1] + n[1], -f_body[2] + n[2])
        w = np.asarray(rates, float)
        gyro = (w[0] + n[3], -w[1] + n[4], -w[2] + n[5])
        mag = (m_body[0] + n[6], -m_body[1] + n[7], -m_body[2] + n[8])
        alt = 288.15 / 0.0065 * (1.0 - (pressure / 1013.25) ** (1 / 5.25588))
        return acc, gyro, mag, pressure, alt, temperature

    def gps(self, position: npt.ArrayLike, velocity_ground: npt.ArrayLike
            ) -> tuple[int, int, int, int, int, int, int]:
        """One HIL_GPS's readings.

        Parameters
        ----------
        position : (3,) array_like
            Position (m; ground x north, y west, z up) relative to home.
        velocity_ground : (3,) array_like
            Velocity (m/s, the same axes).

        Returns
        -------
        lat, lon : int
            degrees * 1e7.
        alt : int
            Altitude above mean sea level (mm).
        vn, ve, vd : int
            NED velocity (cm/s).
        cog : int
            Course over ground (cdeg).
        """
        n = self._gps()
        north, east, down = (np.asarray(position, float) * FLIP) + n[:3]
        vn, ve, vd = (np.asarray(velocity_ground, float) * FLIP) + n[3:]
        lat0, lon0, alt0 = self.home
        lat = lat0 + math.degrees(north / EARTH_RADIUS)
        lon = lon0 + math.degrees(east / (EARTH_RADIUS * math.cos(math.radians(lat0))))
        cog = int(round(math.degrees(math.atan2(ve, vn)) * 100)) % 36000
        return (int(round(lat * 1e7)), int(round(lon * 1e7)), int(round((alt0 - down) * 1000)),
                int(round(vn * 100)), int(round(ve * 100)), int(round(vd * 100)), cog)
