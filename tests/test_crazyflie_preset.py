"""The Crazyflie 2.1 preset against the firmware's own header, read from a firmware tree."""
import numpy as np
import pytest

from quadcog.errors import StackError
from quadcog.vehicles.rotor_model import CRAZYFLIE_21_PLUS_CUBIC, cubic_voltage
from quadcog.vehicles.vehicle import CRAZYFLIE, CRAZYFLIE_21, PRESETS

INSTALL = ("no Crazyflie firmware tree: set QUADCOG_CRAZYFLIE_FIRMWARE to a `git clone "
           "--recursive https://github.com/bitcraze/crazyflie-firmware` or put "
           "crazyflie-firmware.tar.xz in the vendor folder ($QUADCOG_VENDOR_DIR)")


@pytest.fixture(scope="module")
def header():
    from quadcog.crazyflie.firmware import constants
    try:
        return constants()
    except StackError as e:
        if "no Crazyflie firmware tree" in str(e):
            pytest.skip(INSTALL)
        raise


def test_preset_is_the_firmware_header(header):
    # the preprocessor's values of platform_defaults.h with the 2.1+ propellers (the default)
    assert CRAZYFLIE_21.m == header["CF_MASS"] == 0.029
    assert CRAZYFLIE_21.arm_length == pytest.approx(header["ARM_LENGTH"], rel=1e-15)
    assert CRAZYFLIE_21.moment_constant == header["THRUST2TORQUE"]
    assert CRAZYFLIE_21.max_rotor_thrust == header["THRUST_MAX"]
    assert CRAZYFLIE_21.rotor_model is CRAZYFLIE_21_PLUS_CUBIC
    assert CRAZYFLIE_21_PLUS_CUBIC.coefficients == tuple(
        header[f"VMOTOR2THRUST{k}"] for k in range(4))
    assert PRESETS["crazyflie21"] is CRAZYFLIE_21 and PRESETS["crazyflie"] is CRAZYFLIE


def test_other_propellers_differ(header):
    from quadcog.crazyflie.firmware import constants
    kit = constants(propellers="upgrade-kit")
    assert kit["CF_MASS"] == 0.0325     # the thrust upgrade kit changes CF_MASS too
    assert kit["THRUST_MAX"] == 0.18 and kit["VMOTOR2THRUST0"] != header["VMOTOR2THRUST0"]


def test_cubic_inverse_against_the_roots():
    # an independent oracle: numpy's roots of the cubic
    c = CRAZYFLIE_21_PLUS_CUBIC.coefficients
    for f in (0.013, 0.07, 0.12):
        real = [r.real for r in np.roots([c[3], c[2], c[1], c[0] - f]) if abs(r.imag) < 1e-9]
        assert cubic_voltage(c, f) == pytest.approx(real[0], rel=1e-12)
    u = CRAZYFLIE_21_PLUS_CUBIC.command(np.full(4, 0.07), 4.0)
    assert CRAZYFLIE_21_PLUS_CUBIC.thrust(u, 4.0) == pytest.approx(0.07, rel=1e-12)
