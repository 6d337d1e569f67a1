"""Tenth hostile pass: vehicle files and the payloads' timeline (quadcog.vehicles.description,
quadcog.vehicles.vehicle, quadcog.sim.timeline).

Each test names what the old code did with the input: a raw exception, an element or attribute
read silently as something else (the second ``<inertial>`` of a link left out, ``<mass
value="27" unit="g">`` flown as 27 kg, a xacro include of a battery dropped), a parse that
grew faster than the file, a CoG outside the rotors' polygon flown as if it could hover, or a
payload's position taken from the wrong place."""
from pathlib import Path
import shutil
import time

import numpy as np
import pytest

from quadcog import Vehicle
from quadcog.errors import VehicleFileError
from quadcog.sim.timeline import PayloadProfile

DATA = Path(__file__).parent / "data" / "vehicles"
CF2X = DATA / "gym-pybullet-drones" / "cf2x.urdf"
MODELS = DATA / "px4-gazebo-models"
BASE_INERTIAL = '<origin rpy="0 0 0" xyz="0 0 0"/>\n      <mass value="0.027"/>'
HEAD = '<?xml version="1.0" ?>'
XACRO = 'xmlns:xacro="http://www.ros.org/wiki/xacro"'


def _cf2x(tmp_path, old, new, data=None):
    text = CF2X.read_text()
    assert old in text, old
    path = tmp_path / "cf.urdf"
    if data is None:
        path.write_text(text.replace(old, new, 1))
    else:
        path.write_bytes(data)
    return path


# -- the XML itself --------------------------------------------------------------------------

LAUGHS = ('<!DOCTYPE robot [<!ENTITY a "aaaaaaaaaa">' + "".join(
    f'<!ENTITY {chr(98 + i)} "{("&" + chr(97 + i) + ";") * 10}">' for i in range(9)) + "]>")


@pytest.mark.parametrize("head, old, new", [
    (LAUGHS, 'name="cf2"', 'name="&j;"'),
    ('<!DOCTYPE robot [<!ENTITY m "5.0">]>', '<mass value="0.027"/>', '<mass value="&m;"/>'),
    ('<!DOCTYPE robot [<!ATTLIST inertia ixy CDATA "1e-6">]>', "", ""),
    ('<!DOCTYPE robot SYSTEM "http://example.com/robot.dtd">', "", ""),
])
def test_a_document_type_declaration_is_refused(tmp_path, head, old, new):
    """Entities and default attributes were expanded (a mass of 5 kg from '&m;', products of
    inertia from an ATTLIST) where PyBullet's and Gazebo's readers expand none."""
    path = _cf2x(tmp_path, HEAD, HEAD + head)
    path.write_text(path.read_text().replace(old, new, 1))
    with pytest.raises(VehicleFileError, match=r"cf\.urdf: <!DOCTYPE 'robot'>: a document type "
                                               "declaration; expected a URDF or SDF file "
                                               "without one"):
        Vehicle.from_urdf(path)


def test_an_unknown_encoding_is_a_vehicle_file_error(tmp_path):
    """A raw LookupError ('unknown encoding: x-bogus')."""
    path = _cf2x(tmp_path, HEAD, '<?xml version="1.0" encoding="x-bogus"?>')
    with pytest.raises(VehicleFileError, match=r"cf\.urdf: not readable as XML \(unknown "
                                               "encoding: x-bogus\\)"):
        Vehicle.from_urdf(path)


def test_a_long_attribute_is_parsed_in_time_linear_in_it(tmp_path):
    """ET.parse fed the file in 64 kB chunks and expat re-scanned a token that spans them:
    a 16 MB robot name took 3 s, 50 MB half a minute (quadratic)."""
    text = CF2X.read_text().replace('name="cf2"', 'name="' + "x" * 16_000_000 + '"')
    path = tmp_path / "cf.urdf"
    path.write_text(text)
    start = time.process_time()
    Vehicle.from_urdf(path, name="cf")
    assert time.process_time() - start < 1.0


# -- elements and attributes quadcog does not read -------------------------------------------

ONE_LINK = '<link name="base_link"> '
BATTERY = ('<inertial><origin xyz="0.01 0 0"/><mass value="0.5"/><inertia ixx="1e-4" '
           'iyy="1e-4" izz="1e-4"/></inertial>')


@pytest.mark.parametrize("old, new, words", [
    (ONE_LINK, ONE_LINK + BATTERY, r"link 'base_link' has 2 <inertial> elements"),
    ('<mass value="0.027"/>', '<mass value="0.027"/><mass value="5"/>',
     r"link 'base_link' <inertial> has 2 <mass> elements"),
    ('<mass value="0.027"/>', '<mass value="0.027"/><origin xyz="0.03 0 0"/>',
     r"link 'base_link' <inertial> has 2 <origin> elements"),
    ('<mass value="0.027"/>', '<mass value="0.027"/><inertia ixx="1e-3" iyy="1e-3" izz="1e-3"/>',
     r"link 'base_link' <inertial> has 2 <inertia> elements"),
    ("</robot>", '<properties kf="1e-9" km="1e-11" thrust2weight="50"/></robot>',
     r"<robot> has 2 <properties> elements"),
    ('<joint name="prop0_joint" type="fixed">',
     '<joint name="prop0_joint" type="fixed"><origin xyz="0 0 0"/><origin xyz="1 0 0"/>',
     r"joint 'prop0_joint' has 2 <origin> elements"),
])
def test_an_element_given_twice_is_refused(tmp_path, old, new, words):
    """The first was read and the others dropped: a link's second <inertial> (a 0.5 kg battery
    written first left the 27 g airframe out), a second <mass>, <origin> or <properties>."""
    with pytest.raises(VehicleFileError, match=rf"cf\.urdf: {words}; expected at most one"):
        Vehicle.from_urdf(_cf2x(tmp_path, old, new))


@pytest.mark.parametrize("old, new, words", [
    ('<mass value="0.027"/>', '<mass value="27" unit="g"/>',
     r"<inertial>/mass has attribute\(s\) unit='g'; expected only value"),
    ('izz="2.17e-5"', 'izz="2.17e-5" units="g mm^2"',
     r"<inertial>/inertia has attribute\(s\) units='g mm\^2'; expected only ixx, iyy"),
    ('<origin rpy="0 0 0" xyz="0 0 0"/>\n      <mass',
     '<origin rpy="0 0 0" xyz="0 0 10" unit="mm"/>\n      <mass',
     r"<inertial>/origin has attribute\(s\) unit='mm'; expected only xyz, rpy"),
])
def test_an_attribute_quadcog_does_not_read_is_refused(tmp_path, old, new, words):
    """<mass value="27" unit="g"/> flew a 27 kg Crazyflie: the unit was never read."""
    with pytest.raises(VehicleFileError, match=rf"cf\.urdf: link 'base_link' {words}"):
        Vehicle.from_urdf(_cf2x(tmp_path, old, new))


@pytest.mark.parametrize("extra, tag", [
    ('<xacro:include filename="battery.xacro"/><xacro:battery parent="base_link" mass="0.5"/>',
     "include"),
    ('<xacro:macro name="b"><link name="bat"/></xacro:macro>', "macro"),
])
def test_an_unexpanded_xacro_file_is_refused(tmp_path, extra, tag):
    """The xacro elements (a battery included by a macro) were skipped and the rest flown."""
    path = _cf2x(tmp_path, '<robot name="cf2">', f'<robot name="cf2" {XACRO}>{extra}')
    with pytest.raises(VehicleFileError, match=rf"cf\.urdf: <xacro:{tag}> is a xacro macro; "
                                               "expected a URDF \\(expand it first"):
        Vehicle.from_urdf(path)


@pytest.fixture
def x500_base(tmp_path):
    shutil.copytree(MODELS, tmp_path / "models")
    return tmp_path / "models" / "x500_base" / "model.sdf"


ROTOR_0_POSE = "<pose>0.174 -0.174 0.06 0 0 0</pose>"
MODEL_POSE = "<pose>0 0 .24 0 0 0</pose>"


@pytest.mark.parametrize("old, new, words", [
    (ROTOR_0_POSE, '<pose relative_to="base_link">0.174 -0.174 0.06 0 0 0</pose>',
     r"link 'rotor_0'/pose has attribute\(s\) relative_to='base_link'; expected only degrees"),
    ("</model>", '<model name="battery"><link name="bat"><inertial><mass>1.5</mass><inertia>'
                 "<ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz></inertia></inertial></link>"
                 "</model></model>",
     r"<model> holds a nested <model name='battery'>"),
    (MODEL_POSE, '<pose degrees="yes">0 0 .24 0 0 0</pose>',
     r"<model>/pose@degrees = 'yes'; expected true, 1, false or 0"),
    ("<inertial>", '<inertial auto="true">', r"<inertial> has attribute\(s\) auto='true'; "
                                             "expected none"),
    (ROTOR_0_POSE, ROTOR_0_POSE + "<pose>1 1 0 0 0 0</pose>",
     r"link 'rotor_0' has 2 <pose> elements"),
    ("</sdf>", '<model name="x"/></sdf>', r"<sdf> has 2 <model> elements"),
])
def test_sdf_elements_and_attributes_quadcog_does_not_read_are_refused(x500_base, old, new,
                                                                       words):
    """A pose relative_to another frame was read in its parent's, a nested model's links
    left out, degrees="yes" read as radians, <inertial auto="true"> (Gazebo computes it from
    the collisions) read as written, a second <pose> or <model> dropped."""
    text = x500_base.read_text()
    assert old in text, old
    x500_base.write_text(text.replace(old, new, 1))
    with pytest.raises(VehicleFileError, match=words):
        Vehicle.from_sdf(x500_base.parent.parent / "x500" / "model.sdf")


def test_sdf_degrees_as_sdformat_reads_them(x500_base):
    """sdformat's bool is true or 1: degrees="1" was read as radians (a 90 degree yaw as 90
    radians)."""
    text = x500_base.read_text()
    turned = "<pose>0.174 -0.174 0.06 0 0 90</pose>"
    one, true = (text.replace(ROTOR_0_POSE, turned.replace("<pose>", f'<pose degrees="{d}">'))
                 for d in ("1", "true"))
    x500_base.write_text(one)
    by_one = Vehicle.from_sdf(x500_base.parent.parent / "x500" / "model.sdf", name="x")
    x500_base.write_text(true)
    by_true = Vehicle.from_sdf(x500_base.parent.parent / "x500" / "model.sdf", name="x")
    assert by_one == by_true


def test_sdf_inertial_auto_false_is_the_numbers_as_written(x500_base):
    """auto="false" (and "0") is SDF 1.11's default, the inertia as written: read, the same
    vehicle as without it (auto="true" is refused above)."""
    path = x500_base.parent.parent / "x500" / "model.sdf"
    plain = Vehicle.from_sdf(path, name="x")
    text = x500_base.read_text()
    for value in ("false", "0", " False "):
        x500_base.write_text(text.replace("<inertial>", f'<inertial auto="{value}">'))
        assert Vehicle.from_sdf(path, name="x") == plain


# -- a vehicle that cannot hover -------------------------------------------------------------

@pytest.mark.parametrize("x", ["0.03", "0.1"])
def test_a_file_whose_cog_leaves_no_hover_is_refused(tmp_path, x):
    """cf2x's CoG moved 3 cm or 10 cm forward, past its front rotors (2.8 cm): the back
    rotors would have to pull down to hover, and the file was accepted and flown."""
    path = _cf2x(tmp_path, BASE_INERTIAL, BASE_INERTIAL.replace('xyz="0 0 0"', f'xyz="{x} 0 0"'))
    with pytest.raises(VehicleFileError, match=rf"cf\.urdf: the links' CoG at \({x}, 0\) m "
                                               r"from the rotors' centre needs rotor thrusts "
                                               r"\[.*-.*\] N to hover; expected each in \[0, "):
        Vehicle.from_urdf(path)
    inside = _cf2x(tmp_path, BASE_INERTIAL, BASE_INERTIAL.replace('xyz="0 0 0"', 'xyz="0.01 0 0"'))
    assert Vehicle.from_urdf(inside).x_G == pytest.approx(0.01)


# -- the payloads' timeline ------------------------------------------------------------------

MOVES = [dict(t=0.0, action="attach", name="a", mass=0.1, position=[0, 0, 0]),
         dict(t=1.0, action="move", name="a", position=[0.1, 0, 0], ramp=1.0),
         dict(t=3.0, action="move", name="a", position=[0.1, 0.1, 0], ramp=1.0)]


def test_on_board_starts_a_move_where_the_last_one_ended():
    """on_board(3.5) put the payload at (0.05, 0.05, 0): the second move started from where
    it was attached, not from where the first move left it."""
    (p,) = PayloadProfile(MOVES).on_board(3.5)
    assert p.position == pytest.approx((0.1, 0.05, 0.0), abs=1e-15)


def test_payloads_at_times_out_of_order_are_those_at_the_times_in_order():
    """Sampled at times out of order, a move started from the sample found by a search of
    the unsorted times (there: the middle of the first move's ramp)."""
    profile = PayloadProfile(MOVES)
    t = np.array([0.0, 1.5, 2.5, 3.5, 4.5])
    np.testing.assert_allclose(profile.sample(t[::-1])[::-1], profile.sample(t), rtol=0,
                               atol=1e-15)


# -- no airframe denser than osmium ------------------------------------------------------------

def test_an_airframe_lighter_in_inertia_than_a_ball_of_osmium_is_refused(tmp_path):
    """A solid ball has I = 2/5 m R^2 about each axis (the textbook formula, written here);
    of all bodies of a mass and a largest density it has the least trace. cf2x.urdf with its
    27 g written as 27 (read as kg) has 3e-4 of the trace a ball of osmium of 27 kg has, and
    passed every other check (its thrust is read per mass)."""
    from quadcog import HUMMINGBIRD
    from quadcog.errors import ParameterError
    from quadcog.vehicles.vehicle import DENSEST, least_inertia_trace
    for m in (0.027, 1.0, 27.0):
        radius = (m / DENSEST / (4.0 / 3.0 * np.pi)) ** (1.0 / 3.0)
        assert least_inertia_trace(m) == pytest.approx(3 * 0.4 * m * radius ** 2, rel=1e-12)
    assert DENSEST == 22_590.0                                # osmium, kg/m^3
    path = _cf2x(tmp_path, '<mass value="0.027"', '<mass value="27"')
    with pytest.raises(ParameterError, match=r"Ixx \+ Iyy \+ Izz: expected at least 0.14 kg "
                                             r"m\^2, .* m = 27 kg .*\(a mass in grams\?\), "
                                             r"got 4.97e-05"):
        Vehicle.from_urdf(path)
    least = least_inertia_trace(HUMMINGBIRD.m)
    with pytest.raises(ParameterError, match="a ball of osmium"):
        HUMMINGBIRD.replace(Ixx=0.1 * least, Iyy=0.1 * least, Izz=0.15 * least)
    kept = HUMMINGBIRD.replace(Ixx=0.3 * least, Iyy=0.3 * least, Izz=0.45 * least)
    assert kept.Ixx + kept.Iyy + kept.Izz > least
