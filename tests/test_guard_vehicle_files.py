"""Guards of the URDF/SDF reader (quadcog.vehicles.description) with a CoG off the rotors'
axis and a turned inertial frame, against oracles written here: the URDF inertia is about the
link's CoG in the axes of its <inertial> origin (fixed-axis roll, pitch, yaw: SciPy's
extrinsic "xyz" rotation), turned to the body as R I R^T, then moved to O on the rotors' axis
by the parallel-axis theorem I_O = I_G + m (|r|^2 1 - r r^T). The preset files all have their
CoG on the axis and an unturned inertia, where neither step shows.
(bench/mutations.py: vehicle_file_inertia_not_moved_to_O, vehicle_file_inertia_rotated_backwards.)"""
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from quadcog import Vehicle

CF2X = Path(__file__).parent / "data" / "vehicles" / "gym-pybullet-drones" / "cf2x.urdf"
BASE = ('<origin rpy="0 0 0" xyz="0 0 0"/>\n      <mass value="0.027"/>\n      '
        '<inertia ixx="1.4e-5" ixy="0.0" ixz="0.0" iyy="1.4e-5" iyz="0.0" izz="2.17e-5"/>')


def _file(tmp_path, xyz, rpy, I):
    text = CF2X.read_text()
    assert text.count(BASE) == 1
    (ixx, ixy, ixz), (_, iyy, iyz), (_, _, izz) = np.asarray(I).tolist()
    inertial = (f'<origin rpy="{rpy[0]!r} {rpy[1]!r} {rpy[2]!r}" xyz="{xyz[0]!r} {xyz[1]!r} '
                f'{xyz[2]!r}"/>\n      <mass value="0.027"/>\n      <inertia ixx="{ixx!r}" '
                f'ixy="{ixy!r}" ixz="{ixz!r}" iyy="{iyy!r}" iyz="{iyz!r}" izz="{izz!r}"/>')
    path = tmp_path / "cf2x.urdf"
    path.write_text(text.replace(BASE, inertial))
    return path


@pytest.mark.parametrize("xyz, rpy", [
    ((0.004, -0.003, 0.01), (0.0, 0.0, 0.0)),          # off the axis, unturned
    ((0.0, 0.0, 0.0), (0.3, 0.5, 0.7)),                # on the axis, turned
    ((-0.002, 0.005, -0.004), (-0.4, 0.2, 1.1)),       # both
])
def test_inertia_is_turned_and_moved_to_o(tmp_path, xyz, rpy):
    m = 0.027
    I_frame = np.array([[1.4e-5, 1.0e-6, -0.5e-6], [1.0e-6, 1.6e-5, 0.8e-6],
                        [-0.5e-6, 0.8e-6, 2.17e-5]])
    v = Vehicle.from_urdf(_file(tmp_path, xyz, rpy, I_frame))
    R = Rotation.from_euler("xyz", rpy).as_matrix()    # fixed axes: Rz(yaw) Ry(pitch) Rx(roll)
    I_G = R @ I_frame @ R.T
    r = np.array([xyz[0], xyz[1], 0.0])                # O: on the rotors' axis, at the CoG's height
    I_O = I_G + m * (r @ r * np.eye(3) - np.outer(r, r))
    assert v.m == m
    np.testing.assert_allclose(v.r_G, r, rtol=0, atol=1e-15)
    np.testing.assert_allclose([v.Ixx, v.Iyy, v.Izz], np.diag(I_O), rtol=1e-12, atol=0)
    # and the off-axis CoG really moves the inertia here (a check of the check)
    if r.any():
        assert np.abs(np.diag(I_O) - np.diag(I_G)).max() > 1e-3 * np.abs(np.diag(I_G)).max()
    if any(rpy):
        assert np.abs(np.diag(R @ I_frame @ R.T) - np.diag(R.T @ I_frame @ R)).max() > 1e-8
