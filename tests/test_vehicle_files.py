"""Vehicles from URDF and SDF files (quadcog.vehicles.description): PX4's gz X500 gives back the
preset that was taken from it, gym-pybullet-drones' Crazyflies and racer give the geometry and
rotor directions of that project's BaseAviary, and broken files fail with the value and the
file named."""
import dataclasses
import math
from pathlib import Path
import shutil
import subprocess
import sys

import numpy as np
import pytest

from quadcog import X500, Vehicle
from quadcog.errors import PhysicalConsistencyError, VehicleFileError

DATA = Path(__file__).parent / "data" / "vehicles"
X500_SDF = DATA / "px4-gazebo-models" / "x500" / "model.sdf"
GYM = DATA / "gym-pybullet-drones"


def test_x500_sdf_round_trip_gives_the_preset():
    """The preset came from these two files (base link only): every field comes back, the
    model:// include found beside the including model's folder."""
    v = Vehicle.from_sdf(X500_SDF, rotor_links=False)
    assert dataclasses.replace(v, name=X500.name) == X500


def test_x500_with_rotor_links_adds_their_mass_by_the_parallel_axis_theorem():
    """The oracle: four 16 g point-like rotor links at (+-0.174, +-0.174, 0.06) m, each with
    its own inertia, added by hand to the base link about the common CoG."""
    v = Vehicle.from_sdf(X500_SDF)
    m_r, base = 0.016076923076923075, 2.0
    own = np.array([3.8464910483993325e-07, 2.6115851691700804e-05, 2.649858234714004e-05])
    m = base + 4 * m_r
    z_c = 4 * m_r * 0.06 / m                  # the CoG rises above the base link's origin
    a, h = 0.174, 0.06 - z_c
    Ixx = 0.02166666666666667 + base * z_c**2 + 4 * (own[0] + m_r * (a**2 + h**2))
    Izz = 0.04000000000000001 + 4 * (own[2] + m_r * 2 * a**2)
    assert v.m == pytest.approx(m, rel=1e-12)
    assert v.Ixx == pytest.approx(Ixx, rel=1e-12)
    assert v.Izz == pytest.approx(Izz, rel=1e-12)
    assert v.r_G.tolist() == [0.0, 0.0, 0.0]


def test_model_path_is_searched_and_a_missing_include_is_named(tmp_path):
    lone = tmp_path / "models" / "x500"
    shutil.copytree(X500_SDF.parent, lone)
    with pytest.raises(VehicleFileError, match=r"model://x500_base.*no folder 'x500_base'"):
        Vehicle.from_sdf(lone / "model.sdf")
    v = Vehicle.from_sdf(lone / "model.sdf", model_paths=(X500_SDF.parent.parent,),
                         rotor_links=False)
    assert v.m == X500.m


def _base_aviary_mixer(kind, L, k):
    """gym-pybullet-drones BaseAviary._dynamics (written out here): rows thrust, roll, pitch,
    yaw of forces f_i; roll as the URDF's rotor positions give it (see the test below)."""
    h = L / math.sqrt(2)
    if kind == "cf2x":       # props at (+h,-h), (-h,-h), (-h,+h), (+h,+h)
        roll, pitch = [-h, -h, h, h], [-h, h, h, -h]
    elif kind == "cf2p":     # props at +x, +y, -x, -y
        roll, pitch = [0, L, 0, -L], [-L, 0, L, 0]
    else:                    # racer: x layout with the first two on +y
        roll, pitch = None, None
    yaw = [-k, k, -k, k]     # z_torque = -t0 + t1 - t2 + t3
    return np.array([[1, 1, 1, 1], roll, pitch, yaw], dtype=float)


@pytest.mark.parametrize("kind", ["cf2x", "cf2p"])
def test_gym_pybullet_crazyflies_match_base_aviary(kind):
    """Mixer rows against BaseAviary's torque formulas; kf, km per rpm^2 converted to rad/s.
    (BaseAviary._dynamics writes the CF2X roll as (f0 + f1 - f2 - f3) L/sqrt 2, the opposite
    of its own URDF's rotor positions, which PyBullet's physics, the default, uses; quadcog
    follows the positions.)"""
    v = Vehicle.from_urdf(GYM / f"{kind}.urdf")
    assert v.m == 0.027
    kf, km, arm = 3.16e-10, 7.94e-12, 0.0397
    assert v.thrust_constant == pytest.approx(kf * (60 / (2 * math.pi)) ** 2, rel=1e-14)
    assert v.moment_constant == pytest.approx(km / kf, rel=1e-14)
    # BaseAviary: MAX_RPM = sqrt(t2w m g / (4 kf)), the largest thrust kf MAX_RPM^2
    assert v.max_rotor_thrust == pytest.approx(2.25 * 0.027 * 9.81 / 4, rel=1e-14)
    expected = _base_aviary_mixer(kind, arm, km / kf)
    np.testing.assert_allclose(v.mixer(), expected, atol=2e-4 if kind == "cf2x" else 1e-15)
    assert v.rotor_directions == (-1, 1, -1, 1)


def test_racer_spins_the_other_way():
    """BaseAviary negates the racer's torques (DroneModel.RACE), which the file cannot say."""
    v = Vehicle.from_urdf(GYM / "racer.urdf")
    assert v.rotor_directions == (1, -1, 1, -1)
    assert v.rotor_positions[0] == (0.085, 0.0675) and v.m == 0.83


def test_urdf_lacking_a_value_names_it_and_the_file(tmp_path):
    text = (GYM / "cf2x.urdf").read_text()
    bad = tmp_path / "cf.urdf"
    bad.write_text(text.replace(' kf="3.16e-10"', ""))
    with pytest.raises(VehicleFileError, match=r"cf\.urdf: <properties>@kf is missing"):
        Vehicle.from_urdf(bad)
    bad.write_text(text.replace('<mass value="0.027"/>', '<mass value="heavy"/>'))
    with pytest.raises(VehicleFileError, match=r"link 'base_link' <inertial>/mass@value"):
        Vehicle.from_urdf(bad)
    bad.write_text(text.replace('izz="2.17e-5"', 'izz="3e-5"'))       # > ixx + iyy
    with pytest.raises(PhysicalConsistencyError, match=r"cf\.urdf: link 'base_link'.*triangle"):
        Vehicle.from_urdf(bad)


def test_sdf_lacking_a_motor_constant_names_it(tmp_path):
    folder = tmp_path / "x500"
    shutil.copytree(X500_SDF.parent, folder)
    sdf = folder / "model.sdf"
    sdf.write_text(sdf.read_text().replace("<motorConstant>8.54858e-06</motorConstant>", "", 1))
    with pytest.raises(VehicleFileError, match=r"motor 0/motorConstant is missing"):
        Vehicle.from_sdf(sdf, model_paths=(X500_SDF.parent.parent,))


def test_quadcog_run_vehicle_flies_the_file(tmp_path):
    out = tmp_path / "run"
    done = subprocess.run([sys.executable, "-m", "quadcog", "run", "fig3b", "--set",
                           "duration=1", "--vehicle", str(X500_SDF), "--out", str(out),
                           "--quiet", "--no-plot"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert '"m": 2.064307692307' in (out / "vehicle.json").read_text()
