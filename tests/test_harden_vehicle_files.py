"""Hostile vehicle files and rotor-model arguments (fifth hostile-input pass): the readers of
quadcog.vehicles.description cost time linear in the files (an SDF include fan-out, a URDF
joint chain), refuse a URDF that is not one tree of uniquely named links, and refuse rotor
numbers no rotor has; ``RotorModel.thrust`` / ``.command`` refuse what is not a finite real
array of their shape before computing. Every refusal is a typed error whose message names the
value and where it came from."""
from pathlib import Path
import re
import shutil

from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
import pytest

from quadcog import Vehicle
from quadcog.errors import InputError, VehicleFileError
from quadcog.vehicles import description
from quadcog.vehicles.rotor_model import ROTOR_MODELS, RotorModel, px4_thrust_curve

DATA = Path(__file__).parent / "data" / "vehicles"
MODELS = DATA / "px4-gazebo-models"
CF2X = DATA / "gym-pybullet-drones" / "cf2x.urdf"


# -- SDF: includes --------------------------------------------------------------------------

def _fan(folder, k, levels, leaf=""):
    """levels + 1 files f0 .. f<levels>, each including the next k times; the last holds
    ``leaf``. Expanded naively that is k^levels copies of the last file."""
    folder.mkdir(exist_ok=True)
    for i in range(levels):
        inc = f"<include><uri>f{i + 1}.sdf</uri></include>" * k
        (folder / f"f{i}.sdf").write_text(f'<sdf version="1.9"><model name="m{i}">{inc}'
                                          "</model></sdf>")
    (folder / f"f{levels}.sdf").write_text(f'<sdf version="1.9"><model name="leaf">{leaf}'
                                           "</model></sdf>")
    return folder / "f0.sdf"


@pytest.mark.parametrize("k", [2, 3])
def test_each_included_file_is_parsed_once(tmp_path, monkeypatch, k):
    """The rule: one parse per distinct file, however often and deeply it is included (the
    old reader parsed each include twice per copy: 2 * 3^8 parses for k = 3)."""
    parsed = []
    real_parse = description._parse
    monkeypatch.setattr(description, "_parse", lambda p: parsed.append(p) or real_parse(p))
    top = _fan(tmp_path, k, 8)
    with pytest.raises(VehicleFileError, match="0 MulticopterMotorModel"):
        Vehicle.from_sdf(top)
    assert len(parsed) == 9 and len(set(parsed)) == 9


def test_includes_that_copy_too_many_elements_are_refused(tmp_path):
    """A model included many times over multiplies its links at every level: past
    MAX_INCLUDED_ELEMENTS copies the read stops with the including file named."""
    links = "".join(f'<link name="l{i}"/>' for i in range(60))
    top = _fan(tmp_path, 200, 1, leaf=links)       # 12,000 link copies from two small files
    with pytest.raises(VehicleFileError, match=r"f0\.sdf: <include><uri>f1\.sdf</uri>: the "
                       r"includes copy more than 10,000 links, joints and plugins"):
        Vehicle.from_sdf(top)


@pytest.mark.parametrize("length", [1, 2, 3])
def test_an_include_loop_is_named_as_a_loop(tmp_path, length):
    """f0 -> f1 -> ... -> f0: refused as a loop that lists the chain (any length)."""
    for i in range(length):
        (tmp_path / f"f{i}.sdf").write_text(
            f'<sdf version="1.9"><model name="m{i}"><include><uri>f{(i + 1) % length}.sdf'
            "</uri></include></model></sdf>")
    with pytest.raises(VehicleFileError, match=r"includes a model that includes this one "
                       r"\(.*f0\.sdf -> .*f0\.sdf\)"):
        Vehicle.from_sdf(tmp_path / "f0.sdf")


# -- SDF: the motor plugins -----------------------------------------------------------------

@pytest.fixture
def x500(tmp_path):
    shutil.copytree(MODELS, tmp_path / "models")
    return tmp_path / "models" / "x500" / "model.sdf"


def _set_all(sdf, tag, value):
    text = re.sub(rf"<{tag}>[^<]*</{tag}>", f"<{tag}>{value}</{tag}>", sdf.read_text())
    sdf.write_text(text)


@pytest.mark.parametrize("tag, value, expected", [
    ("maxRotVelocity", "1e200", r"maxRotVelocity 1e\+200 rad/s.*thrust-to-weight ratio of inf"),
    ("maxRotVelocity", "-1000", r"motor 0/maxRotVelocity = -1000; expected a number > 0 \(rad/s\)"),
    ("maxRotVelocity", "0", r"motor 0/maxRotVelocity = 0; expected"),
    ("maxRotVelocity", "400", r"maxRotVelocity 400 rad/s.*ratio of 0\.2.*expected a ratio in "
                              r"\(1, 100\]"),
    ("maxRotVelocity", "1e5", r"maxRotVelocity 100000 rad/s.*ratio of 1\.689e\+04.*expected a ratio in \(1, 100\]"),
    ("timeConstantUp", "1e300", r"motor 0/timeConstantUp = 1e\+300; expected a number in "
                                r"\[0, 10\] \(s\)"),
    ("timeConstantUp", "-0.01", r"motor 0/timeConstantUp = -0\.01; expected"),
    ("momentConstant", "-0.016", r"motor 0/momentConstant = -0\.016; expected a number in "
                                 r"\(0, 1\] \(m\)"),
    ("momentConstant", "5", r"motor 0/momentConstant = 5; expected"),
    ("motorConstant", "0", r"motor 0/motorConstant = 0; expected a number in \(0, "),
    ("motorConstant", "-8.5e-6", r"motor 0/motorConstant = -8\.5e-06; expected"),
    ("motorConstant", "1_0", r"motor 0/motorConstant = '1_0'; expected 1 finite number"),
])
def test_sdf_motor_constants_out_of_range_are_refused(x500, tag, value, expected):
    """Every constant read from the plugins: its sign, its scale, and the largest thrust
    they give against the weight (neither a raw OverflowError nor a squared-away sign)."""
    _set_all(x500, tag, value)
    with pytest.raises(VehicleFileError, match=rf"model\.sdf: .*{expected}"):
        Vehicle.from_sdf(x500)


@pytest.mark.parametrize("numbers, expected", [
    (("0", "1", "2", "0.5"), r"motorNumber = '0\.5'; expected an integer 0\.\.3"),
    (("0", "1", "2", "1e300"), r"motorNumber = '1e300'; expected an integer 0\.\.3"),
    (("0", "1", "2", "4"), r"motorNumber = '4'; expected an integer 0\.\.3"),
    (("-1", "1", "2", "3"), r"motorNumber = '-1'; expected an integer 0\.\.3"),
    (("0", "1", "2", "three"), r"motorNumber = 'three'; expected"),
    (("0", "1", "1", "3"), r"link 'rotor_2': motorNumber = 1 is also the motorNumber of another"),
    (("3", "3", "3", "3"), r"motorNumber = 3 is also the motorNumber of another"),
])
def test_sdf_motor_numbers_must_be_0_to_3_each_once(x500, numbers, expected):
    """The numbers order the rotors (and so their spin directions): fractions, numbers no
    command has and duplicates would each give a vehicle whose order is a guess."""
    text = x500.read_text()
    for i, n in enumerate(numbers):
        text = text.replace(f"<motorNumber>{i}</motorNumber>", f"<motorNumber>#{n}</motorNumber>")
    x500.write_text(text.replace("#", ""))
    with pytest.raises(VehicleFileError, match=rf"model\.sdf: MulticopterMotorModel of .*{expected}"):
        Vehicle.from_sdf(x500)


def test_sdf_motor_numbers_order_the_rotors(x500):
    """Renumbered 3, 2, 1, 0 the rotors come in the reverse order (what the check keeps)."""
    plain = Vehicle.from_sdf(x500)
    text = x500.read_text()
    for i in range(4):
        text = text.replace(f"<motorNumber>{i}</motorNumber>", f"<motorNumber>#{3 - i}</motorNumber>")
    x500.write_text(text.replace("#", ""))
    reversed_ = Vehicle.from_sdf(x500)
    assert reversed_.rotor_positions == plain.rotor_positions[::-1]
    assert reversed_.rotor_directions == plain.rotor_directions[::-1]


@pytest.mark.parametrize("g", [float("nan"), -9.81, 0.0, True, "9.81", 1e300])
def test_g_is_checked_as_an_argument(x500, g):
    with pytest.raises(InputError, match=r"g \(Vehicle\.from_sdf\): expected a number in"):
        Vehicle.from_sdf(x500, g=g)
    with pytest.raises(InputError, match=r"g \(Vehicle\.from_urdf\): expected a number in"):
        Vehicle.from_urdf(CF2X, g=g)


# -- URDF: the link tree --------------------------------------------------------------------

def _urdf(tmp_path, old, new, count=1):
    text = CF2X.read_text()
    assert text.count(old) >= count
    path = tmp_path / "cf2x.urdf"
    path.write_text(text.replace(old, new, count))
    return path


PROP0_JOINT = '<parent link="base_link"/>\n    <child link="prop0_link"/>'
PROP1_JOINT = '<parent link="base_link"/>\n    <child link="prop1_link"/>'
HEAVY = ('<link name="base_link"><inertial><mass value="5"/><inertia ixx="1" iyy="1" '
         'izz="1"/></inertial></link>\n')


@pytest.mark.parametrize("old, new, expected", [
    ('<link name="base_link">', HEAVY + '<link name="base_link">',
     r"link 'base_link' is declared twice"),
    ('<link name="prop3_link">', '<link name="prop0_link"/><link name="prop3_link">',
     r"link 'prop0_link' is declared twice"),
    ('<link name="prop3_link">', '<link/>\n<link name="prop3_link">', r"<link> number \d+ has no name"),
    ('<child link="prop0_link"/>', '<child link="prop9_link"/>',
     r"joint 'prop0_joint'/child@link = 'prop9_link' is not a link"),
    ('<parent link="base_link"/>', '<parent link="world"/>',
     r"joint 'prop0_joint'/parent@link = 'world' is not a link"),
    ('<parent link="base_link"/>', '', r"joint 'prop0_joint'/parent@link is missing"),
    ('<joint name="prop3_joint"', '<joint name="prop2_joint"', r"joint 'prop2_joint' is declared twice"),
    ('</robot>', '<joint name="x" type="fixed"><parent link="center_of_mass_link"/>'
                 '<child link="prop0_link"/></joint></robot>',
     r"link 'prop0_link' is the child of two joints \('prop0_joint' and 'x'\)"),
    ('</robot>', '<link name="stray"/></robot>',
     r"links 'base_link' and 'stray' have no parent joint; expected one root link"),
    (PROP0_JOINT, '<parent link="prop1_link"/>\n    <child link="prop0_link"/>',
     None),                                     # with the next edit: a two-link loop
])
def test_urdf_that_is_not_one_tree_is_refused(tmp_path, old, new, expected):
    """Duplicate names (the last silently won), joints to links that do not exist, two
    parents, several roots, loops: each refused with the element named."""
    path = _urdf(tmp_path, old, new)
    if expected is None:
        path.write_text(path.read_text().replace(
            PROP1_JOINT, '<parent link="prop0_link"/>\n    <child link="prop1_link"/>'))
        expected = r"the joints make a loop: link '(prop0_link|prop1_link)' -> '.*' -> '\1'"
    with pytest.raises(VehicleFileError, match=rf"cf2x\.urdf: {expected}"):
        Vehicle.from_urdf(path)


@pytest.mark.parametrize("n", [1, 7])
def test_urdf_loop_of_any_length_is_named(tmp_path, n):
    """A ring of n extra links hanging off nothing: refused as a loop (the old reader walked
    each link's parents until it met one it had seen and took the pose it had reached)."""
    ring = "".join(f'<link name="r{i}"/><joint name="rj{i}" type="fixed"><parent link='
                   f'"r{(i + 1) % n}"/><child link="r{i}"/></joint>' for i in range(n))
    path = _urdf(tmp_path, "</robot>", ring + "</robot>")
    with pytest.raises(VehicleFileError, match=rf"the joints make a loop: link 'r\d+' .*"
                       rf"{n} link\(s\)\)"):
        Vehicle.from_urdf(path)


def _chain(tmp_path, n):
    """cf2x with n tiny links in one chain of fixed joints under base_link."""
    links, joints, prev = [], [], "base_link"
    for i in range(n):
        links.append(f'<link name="l{i}"><inertial><mass value="1e-6"/><inertia ixx="1e-12" '
                     'iyy="1e-12" izz="1e-12"/></inertial></link>')
        joints.append(f'<joint name="j{i}" type="fixed"><origin xyz="0 0 0.001"/><parent '
                      f'link="{prev}"/><child link="l{i}"/></joint>')
        prev = f"l{i}"
    return _urdf(tmp_path, "</robot>", "".join(links + joints) + "</robot>")


@pytest.mark.parametrize("n", [50, 400])
def test_urdf_poses_cost_one_joint_origin_per_joint(tmp_path, monkeypatch, n):
    """Linear cost: each joint's origin is read once, however long the chain (the old
    reader walked to the root from every link: n^2 / 2 origins)."""
    calls = []
    real_origin = description._urdf_origin
    monkeypatch.setattr(description, "_urdf_origin",
                        lambda e, what, p: calls.append(what) or real_origin(e, what, p))
    v = Vehicle.from_urdf(_chain(tmp_path, n))
    joints = sum(1 for w in calls if w.startswith("joint "))
    assert joints == n + 5                          # the chain's and cf2x's five
    # the chain's links sit 1 mm apart above base_link: their CoG is at the mean height
    assert v.m == pytest.approx(0.027 + n * 1e-6, rel=1e-12)


# -- URDF: properties -----------------------------------------------------------------------

@pytest.mark.parametrize("attribute, value, expected", [
    ("thrust2weight", "1e300", r"<properties>@thrust2weight = 1e\+300; expected a number in \(1, 100\]"),
    ("thrust2weight", "0.5", r"<properties>@thrust2weight = 0\.5; expected a number in \(1, 100\]"),
    ("thrust2weight", "1", r"<properties>@thrust2weight = 1; expected"),
    ("thrust2weight", "-2.25", r"<properties>@thrust2weight = -2\.25; expected"),
    ("km", "0", r"<properties>@km = 0; expected a number in \(0, "),
    ("km", "-7.94e-12", r"<properties>@km = -7\.94e-12; expected"),
    ("km", "1e-3", r"<properties>@km / @kf = .* m; expected a drag moment per thrust in "
                   r"\(0, 1\] m"),
    ("kf", "1e300", r"<properties>@kf = 1e\+300; expected a number in \(0, "),
    ("kf", "1_0", r"<properties>@kf = '1_0'; expected 1 finite number"),
])
def test_urdf_properties_out_of_range_are_refused(tmp_path, attribute, value, expected):
    text = CF2X.read_text()
    old = re.search(rf' {attribute}="[^"]*"', text).group(0)
    path = _urdf(tmp_path, old, f' {attribute}="{value}"')
    with pytest.raises(VehicleFileError, match=rf"cf2x\.urdf: {expected}"):
        Vehicle.from_urdf(path)


# -- RotorModel.thrust / .command -----------------------------------------------------------

MODELS_ALL = list(ROTOR_MODELS.values()) + [px4_thrust_curve(0.2, 0.6)]
HOSTILE = ["0.5", b"0.5", 0.5 + 0j, 10 ** 400, True, None, {"u": 1}, object(),
           (x for x in [0.5] * 4), [[0.5] * 4, [0.5] * 3], np.array([object()] * 4),
           np.array([0.5 + 0j] * 4), np.array([True] * 4), [10 ** 400, 0, 0, 0],
           [0.5, "0.5", 0.5, 0.5], 0.5, np.zeros(3), np.zeros((2, 5)),
           [np.inf, 0, 0, 0], [0, 0, 0, -np.inf], np.full((3, 4), np.nan), [True] * 4]


@pytest.mark.parametrize("model", MODELS_ALL, ids=lambda m: m.name)
@pytest.mark.parametrize("method", ["thrust", "command"])
@pytest.mark.parametrize("value", HOSTILE, ids=lambda v: type(v).__name__)
def test_rotor_model_refuses_what_is_not_a_finite_array_of_four(model, method, value):
    """Never a raw ValueError/TypeError/OverflowError, never a thrust: an InputError naming
    the model and the argument (old: raw errors, and inf clipped to full output)."""
    with pytest.raises(InputError, match=rf"rotor model '{re.escape(model.name)}': "
                       rf"(motor outputs u|thrusts f)"):
        getattr(model, method)(value, 3.7)


@pytest.mark.parametrize("model", [m for m in MODELS_ALL if m.uses_voltage],
                         ids=lambda m: m.name)
@pytest.mark.parametrize("method", ["thrust", "command"])
@pytest.mark.parametrize("voltage", ["3.7", True, 3.7 + 0j, 10 ** 400, np.zeros(3) + 3.7,
                                     [[3.7, 3.7]], np.full((2, 4), 3.7), [3.7, np.nan],
                                     [3.7, -1.0], 1e300, np.inf, (v for v in [3.7, 3.7])])
def test_rotor_model_refuses_a_voltage_of_another_shape_or_out_of_range(model, method,
                                                                          voltage):
    with pytest.raises(InputError, match=rf"rotor model '{re.escape(model.name)}': battery "
                       r"voltage(\[\d+\])?: expected"):
        getattr(model, method)(np.full((2, 4), 0.01), voltage)


@settings(max_examples=60, deadline=None)
@given(model=st.sampled_from(MODELS_ALL), rows=st.integers(1, 5), data=st.data())
def test_property_a_non_finite_output_anywhere_is_refused(model, rows, data):
    """Wherever a NaN or an infinity sits, thrust refuses it and names its index."""
    u = np.full((rows, 4), 0.4)
    i, j = data.draw(st.integers(0, rows - 1)), data.draw(st.integers(0, 3))
    u[i, j] = data.draw(st.sampled_from([np.inf, -np.inf, np.nan]))
    with pytest.raises(InputError, match=rf"motor outputs u\[{i}, {j}\]: expected a finite"):
        model.thrust(u, np.full(rows, 3.7))


@pytest.mark.parametrize("model", [m for m in MODELS_ALL if m.kind in ("voltage",
                                                                       "voltage_cubic")],
                         ids=lambda m: m.name)
@pytest.mark.parametrize("factor", [1.001, 10.0, 1e300])
def test_command_refuses_a_thrust_beyond_full_output(model, factor):
    """A thrust above what u = 1 gives is refused, never answered with an output below 1
    (old: beyond the falling parabola's vertex the voltage model returned 0.76, and 0 for
    1e300 N)."""
    full = float(model.thrust([1.0] * 4, 4.2)[0])
    with pytest.raises(InputError, match="beyond full output"):
        model.command([full * factor] + [0.0] * 3, 4.2)
    assert model.command([full * 0.99] + [0.0] * 3, 4.2)[0] <= 1.0


def test_valid_arguments_still_round_trip():
    """What the checks keep: one number or one voltage per row, (4,) or (n, 4) outputs."""
    for model in MODELS_ALL:
        u = np.array([[0.2, 0.4, 0.6, 0.7], [0.3, 0.3, 0.5, 0.6]])
        for v in (4.0, [3.8, 4.0], np.array([3.8, 4.0])):
            assert np.allclose(model.command(model.thrust(u, v), v), u, atol=1e-12)
        assert model.thrust(u[0], 4.0).shape == (4,)
    assert isinstance(MODELS_ALL[0], RotorModel)


@pytest.mark.parametrize("options, expected", [
    ({"model_paths": "models"}, r"model_paths \(Vehicle\.from_sdf\): expected a tuple of folders"),
    ({"model_paths": 5}, r"model_paths \(Vehicle\.from_sdf\): expected a tuple of folders"),
    ({"model_paths": (b"models",)}, r"model_paths \(Vehicle\.from_sdf\): expected"),
    ({"rotor_links": "no"}, r"rotor_links \(Vehicle\.from_sdf\): expected true or false"),
    ({"rotor_links": 0}, r"rotor_links \(Vehicle\.from_sdf\): expected true or false"),
])
def test_sdf_options_of_the_wrong_type_are_refused(x500, options, expected):
    """A str's letters were searched as model folders, an int raised a raw TypeError, and
    0 read as False."""
    with pytest.raises(InputError, match=expected):
        Vehicle.from_sdf(x500, **options)
