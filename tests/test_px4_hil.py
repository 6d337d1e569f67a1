"""PX4 in the loop, lean: the MAVLink 2 frames of the simulator link packed with struct, against
the CRC's textbook check value, a hand-laid HIL_SENSOR, and pymavlink's generated codec (an
independent implementation from the same XML); the frame splitter on torn, noisy and damaged
streams; PX4's x500 airframe against quadcog's X500 (motor order, spin, thrust curve)."""
import functools
import math
import struct
import tarfile

import numpy as np
import pytest

from quadcog.errors import Px4Error
from quadcog.px4.airframe import AIRFRAME, X500_AIRFRAME, check_rotors, read_airframe, rotor_map
from quadcog.px4.mavlink import (
    HIL_SENSOR_ALL_FIELDS,
    MESSAGES,
    FrameReader,
    frame,
    pack_hil_gps,
    pack_hil_sensor,
    unpack_hil_actuator_controls,
    x25_crc,
    x25_crc_python,
)
from quadcog.px4.tree import shared_tarball
from quadcog.vehicles.vehicle import X500

SENSOR = dict(time_usec=123456789, acc=(0.25, -0.5, -9.75), gyro=(0.01, -0.02, 0.03),
              mag=(0.21, 0.013, 0.43), abs_pressure=955.98, diff_pressure=0.0,
              pressure_alt=488.0, temperature=11.8)


def test_crc_textbook_check_value():
    for crc in (x25_crc, x25_crc_python):            # fastcrc's (when installed) and ours
        assert crc(b"123456789") == 0x6F91            # CRC-16/MCRF4XX check value
        assert crc(b"") == 0xFFFF
        assert crc(b"56789", crc(b"1234")) == 0x6F91  # running


def test_hil_sensor_bytes_laid_by_hand():
    p = pack_hil_sensor(**SENSOR)
    assert len(p) == 65
    assert p[:8] == (123456789).to_bytes(8, "little")
    assert struct.unpack("<f", p[8:12])[0] == 0.25
    assert struct.unpack("<f", p[16:20])[0] == -9.75
    assert struct.unpack("<I", p[60:64])[0] == 0x1FFF == HIL_SENSOR_ALL_FIELDS
    f = frame(MESSAGES["HIL_SENSOR"], p, seq=7, sysid=1, compid=200)
    # 0xFD, length, flags, seq, sys, comp, id 107 in 3 bytes; the length is 62: the id byte
    # (0) and the two high bytes of fields_updated (0x00001FFF) are trailing zeros, cut
    assert f[:10] == bytes([0xFD, 62, 0, 0, 7, 1, 200, 107, 0, 0])
    crc = x25_crc(bytes([108]), x25_crc(f[1:10 + 62]))
    assert f[-2:] == crc.to_bytes(2, "little") and len(f) == 10 + 62 + 2


def test_frames_match_pymavlink():
    c = pytest.importorskip("pymavlink.dialects.v20.common")
    mav = c.MAVLink(None, srcSystem=1, srcComponent=200)
    for name, m in MESSAGES.items():
        cls = getattr(c, f"MAVLink_{name.lower()}_message")
        assert (cls.id, cls.crc_extra) == (m.msgid, m.crc_extra), name
        assert cls.unpacker.size == m.size, name        # the wire layout, extensions too
    mav.seq = 5
    ref = c.MAVLink_hil_sensor_message(
        SENSOR["time_usec"], *SENSOR["acc"], *SENSOR["gyro"], *SENSOR["mag"],
        SENSOR["abs_pressure"], 0.0, 488.0, 11.8, 0x1FFF, 0).pack(mav)
    assert ref == frame(MESSAGES["HIL_SENSOR"], pack_hil_sensor(**SENSOR), 5, 1, 200)
    mav.seq = 6
    ref = c.MAVLink_hil_gps_message(99, 3, 473977420, 85455940, 488000, 30, 40, 100, -10, 20,
                                    -30, 9000, 10, 0, 0).pack(mav)
    ours = frame(MESSAGES["HIL_GPS"], pack_hil_gps(99, 473977420, 85455940, 488000, 30, 40,
                                                   100, -10, 20, -30, 9000), 6, 1, 200)
    assert ref == ours
    decoded = mav.decode(bytearray(ours))
    assert (decoded.lat, decoded.vd, decoded.fix_type) == (473977420, -30, 3)
    # PX4's answer, as pymavlink packs it, read back by ours (trailing zeros cut)
    mav.seq = 9
    controls = [0.7, 0.71, 0.69, 0.72] + [0.0] * 12
    raw = c.MAVLink_hil_actuator_controls_message(4000, controls, 129, 1).pack(mav)
    (out,) = list(FrameReader().feed(raw))
    t, flags, got, mode = unpack_hil_actuator_controls(out[3])
    assert (t, flags, mode) == (4000, 1, 129)
    assert np.allclose(got, controls, atol=1e-7)


def _controls_frame(t_us, u, seq=0):
    payload = struct.pack("<2Q16fB", t_us, 1, *u, *([0.0] * 12), 129)
    return frame(MESSAGES["HIL_ACTUATOR_CONTROLS"], payload, seq)


def test_reader_on_torn_noisy_and_damaged_streams():
    a, b = _controls_frame(4000, [0.1] * 4), _controls_frame(8000, [0.2] * 4, 1)
    bad = bytearray(_controls_frame(12000, [0.3] * 4, 2))
    bad[20] ^= 0xFF                                   # a flipped payload byte: wrong CRC
    stream = b"\x00\x01garbage" + a + bytes(bad) + b    # bytes before a frame: skipped
    r = FrameReader({93})
    got = []
    for i in range(0, len(stream), 7):                # 7-byte pieces: frames torn anywhere
        got += [unpack_hil_actuator_controls(p)[0] for _, _, _, p, _ in r.feed(stream[i:i + 7])]
    assert got == [4000, 8000]
    assert r.bad_crc >= 1


WMM = "src/lib/world_magnetic_model/geo_magnetic_tables.hpp"
WANTED = (f"{AIRFRAME}/{X500_AIRFRAME}", WMM)


@functools.lru_cache(maxsize=1)
def _tree_files():
    """The files of WANTED from the built tree in the cache, else from the shared tarball
    (one pass through it)."""
    from quadcog.px4.tree import cached_build
    try:
        found = cached_build()
    except Px4Error:
        found = None
    if found is not None:
        return {rel: (found.source / rel).read_text() for rel in WANTED}
    tarball = shared_tarball()
    if tarball is None:
        return None
    out = {}
    with tarfile.open(tarball) as tar:
        for member in tar:
            rel = member.name.partition("/")[2]
            if rel in WANTED:
                out[rel] = tar.extractfile(member).read().decode()
                if len(out) == len(WANTED):
                    break
    return out


def _tree_file(relative):
    files = _tree_files()
    if files is None:
        pytest.skip("no PX4 tree: shared/vendor/px4-autopilot.tar.xz next to the checkout, or `make px4-build`")
    return files[relative]


@pytest.fixture(scope="module")
def x500_params(tmp_path_factory):
    text = _tree_file(f"{AIRFRAME}/{X500_AIRFRAME}")
    root = tmp_path_factory.mktemp("px4")
    (root / AIRFRAME).mkdir(parents=True)
    (root / AIRFRAME / X500_AIRFRAME).write_text(text)
    return read_airframe(root)


def test_x500_preset_is_px4s_x500(x500_params):
    check_rotors(x500_params, X500)                   # motor order and spin
    swapped = X500.replace(rotor_positions=X500.rotor_positions[::-1])
    with pytest.raises(Px4Error, match="rotor 1"):
        check_rotors(x500_params, swapped)
    flipped = X500.replace(rotor_directions=tuple(-d for d in X500.rotor_directions))
    with pytest.raises(Px4Error, match="turns"):
        check_rotors(x500_params, flipped)


def test_thrust_curve_of_the_gz_x500(x500_params):
    m = rotor_map(x500_params, X500)
    k = 8.54858e-06                                  # the gz x500's motorConstant
    assert m.thrust([0.0] * 4, armed=True) == pytest.approx([k * 150.0 ** 2] * 4)
    assert m.thrust([1.0] * 4, armed=True) == pytest.approx([X500.max_rotor_thrust] * 4)
    assert m.thrust([1.0] * 4, armed=False).tolist() == [0.0] * 4
    # hover of the 2 kg X500: 4 k (150 + 850 u)^2 = m g
    u = (math.sqrt(X500.m * X500.g / 4 / k) - 150.0) / 850.0
    assert m.thrust([u] * 4, armed=True).sum() == pytest.approx(X500.m * X500.g)
    assert 0.6 < u < 0.8


def test_world_magnetic_model_at_zurich(tmp_path):
    from quadcog.px4.sensors import HOME, earth_field
    rel = WMM
    (tmp_path / rel).parent.mkdir(parents=True)
    (tmp_path / rel).write_text(_tree_file(rel))
    B = earth_field(tmp_path, HOME[0], HOME[1])
    strength = np.linalg.norm(B)
    # NOAA's WMM for Zurich (2024): about 48 uT, inclination about 63 deg, declination about
    # 3 deg east; PX4's 10-degree grid is coarse, hence the tolerances
    assert 0.47 < strength < 0.49
    assert 62.5 < math.degrees(math.asin(B[2] / strength)) < 64.0
    assert 2.0 < math.degrees(math.atan2(B[1], B[0])) < 4.5
    with pytest.raises(Px4Error, match="World Magnetic Model"):
        earth_field(tmp_path / "nowhere", HOME[0], HOME[1])


def test_airframe_file_missing_is_named(tmp_path):
    with pytest.raises(Px4Error, match="4001_gz_x500"):
        read_airframe(tmp_path)


def test_px4_rotor_model_is_the_thrust_curve_expanded(x500_params):
    from quadcog.px4.identify import rotor_model
    rotors = rotor_map(x500_params, X500)
    model = rotor_model(rotors)
    u = np.linspace(0.0, 1.0, 11)
    k = 8.54858e-06
    # the gz motor model written out: thrust = k omega^2, omega = 150 + 850 u
    expected = k * (150.0 + 850.0 * u) ** 2
    got = model.thrust(np.repeat(u[:, None], 4, axis=1))
    assert np.allclose(got, expected[:, None], rtol=1e-12)
    assert np.allclose(rotors.thrust([0.3] * 4, armed=True), model.thrust([[0.3] * 4])[0])
    assert model.signal == "motor_command" and model.command(got).max() == pytest.approx(1.0)


def test_log_order_is_the_ulog_readers_quadrants():
    from quadcog.px4.identify import log_order
    v = log_order(X500)
    signs = [(np.sign(x), np.sign(y)) for x, y in v.rotor_positions]
    # the ULog reader's order: front-right, back-right, back-left, front-left (FLU)
    assert signs == [(1, -1), (-1, -1), (-1, 1), (1, 1)]
    # PX4's motors 1 (FR, ccw), 4 (BR, cw), 2 (BL, ccw), 3 (FL, cw): the spins follow
    assert v.rotor_directions == (X500.rotor_directions[0], X500.rotor_directions[3],
                                  X500.rotor_directions[1], X500.rotor_directions[2])
