"""quadcog's laws as Crazyflie out-of-tree controller apps: the app's files, its C compiled for
the host against the firmware's own struct headers and fed a quadcog flight in the firmware's
units (it must give quadcog's commands; a pitch-sign, quaternion-order or gyro-sign mutation
of the conversion must not), the firmware's rate, bad input, and (slow) cf2.elf built with
the app by the firmware's own Makefiles.

The firmware tree is firmware.VENDOR_TARBALL or $QUADCOG_CRAZYFLIE_FIRMWARE;
without either the tests that need its headers skip with how to get it.
"""
import os
from pathlib import Path
import re
import shutil
import subprocess

from conftest import background_job, background_result
import numpy as np
import pytest

from quadcog.cli import main as cli
from quadcog.controllers import make_controller
from quadcog.embedded import crazyflie_firmware as firmware
from quadcog.embedded.crazyflie_app import CONTROL_PERIOD, resolve_vehicle, write_crazyflie_app
from quadcog.embedded.crazyflie_host import (
    AGREEMENT_RTOL,
    MODE_ABS,
    MODE_DISABLE,
    MODE_VELOCITY,
    HostApp,
    agreement,
    build_host_app,
    firmware_units,
)
from quadcog.embedded.crazyflie_report import LAWS, agreement_flight, law_cost
from quadcog.embedded.target import missing_tools
from quadcog.errors import ExportError, FirmwareBuildError, FirmwareError, TargetError
from quadcog.model.conventions import rotation_matrix

HAVE_TREE = bool(os.environ.get(firmware.FIRMWARE_ENV)) or firmware.VENDOR_TARBALL.is_file()
needs_tree = pytest.mark.skipif(
    not HAVE_TREE, reason=f"needs the Crazyflie firmware: set ${firmware.FIRMWARE_ENV} to a "
                          "checkout (git clone --recursive https://github.com/bitcraze/"
                          f"crazyflie-firmware) or provide {firmware.VENDOR_TARBALL}")
HAVE_ARM = shutil.which("arm-none-eabi-gcc") is not None


@pytest.fixture(scope="module")
def tree():
    """The firmware copy in quadcog's cache (unpacked once)."""
    return firmware.firmware_tree()[0]


@pytest.fixture(scope="module")
def flights():
    """quadcog's own flight of each law on the app's vehicle, at the app's 500 Hz."""
    return {name: agreement_flight(name, resolve_vehicle(None)) for name in LAWS}


def _host(app, tree, tmp):
    host = HostApp(build_host_app(app, tree, Path(tmp) / "host.so"))
    assert host.init()
    return host


def test_app_files_follow_the_firmware_example(tmp_path):
    paths = write_crazyflie_app("payload_adaptive", tmp_path)
    rel = sorted(p.relative_to(tmp_path).as_posix() for p in paths)
    assert rel == ["Kbuild", "Makefile", "app-config", "src/Kbuild", "src/quadcog_cf_app.c",
                   "src/quadcog_cf_payload_adaptive.c", "src/quadcog_payload_adaptive.c",
                   "src/quadcog_payload_adaptive.h"]
    assert "include $(CRAZYFLIE_BASE)/tools/make/oot.mk" in (tmp_path / "Makefile").read_text()
    config = (tmp_path / "app-config").read_text().splitlines()
    assert "CONFIG_CONTROLLER_OOT=y" in config and "CONFIG_APP_ENABLE=y" in config
    c = (tmp_path / "src/quadcog_cf_payload_adaptive.c").read_text()
    assert "control->controlMode = controlModeForceTorque;" in c
    assert "RATE_DO_EXECUTE(ATTITUDE_RATE, stabilizerStep)" in c
    code = re.sub(r"/\*.*?\*/", "", c, flags=re.S)
    assert not re.search(r"\bdouble\b", code)
    assert all(f.endswith("f") for f in re.findall(r"(?<![\w.])\d+\.\d*(?:e[+-]?\d+)?f?", code))
    # the law is designed for the Crazyflie at the firmware's rate, and says so
    h = (tmp_path / "src/quadcog_payload_adaptive.h").read_text()
    assert f"m        = {resolve_vehicle(None).m:g} kg" in h and "(500 Hz)" in h


@needs_tree
def test_signature_is_the_firmware_s(tree, tmp_path):
    """controllerOutOfTree of the app has the parameter types of the firmware's controller.h."""
    header = (tree / "src/modules/interface/controller/controller.h").read_text()
    write_crazyflie_app("composite", tmp_path)
    c = (tmp_path / "src/quadcog_cf_composite.c").read_text()
    types = lambda text: [re.sub(r"\s*\w+$", "", a.strip()).replace(" ", "")
                          for a in re.search(r"void controllerOutOfTree\(([^)]*)\)",
                                             text).group(1).split(",")]
    assert types(c) == types(header)


def test_firmware_units_are_the_estimator_s():
    """firmware_units against the firmware's formulas, written out here: kalmanCoreExternalize
    State's Euler angles from the quaternion (attitude = roll, -pitch, yaw in degrees), the
    quaternion's rotation (x, y, z, w) equal to quadcog's R, the velocity in world axes."""
    rng = np.random.default_rng(5)
    x = np.zeros((50, 12))
    x[:, 3:6] = rng.uniform(-1.2, 1.2, (50, 3)) * [1, 1, 2.5]
    x[:, 6:12] = rng.normal(size=(50, 6))
    ref = rng.normal(size=(50, 14))
    state, gyro, sp = (a.astype(float) for a in firmware_units(x, ref, 0.002))
    qx, qy, qz, qw = state[:, 3:7].T
    q0, q1, q2, q3 = qw, qx, qy, qz                      # the estimator's q[0..3] = w, x, y, z
    yaw = np.arctan2(2 * (q1 * q2 + q0 * q3), q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3)
    pitch = np.arcsin(-2 * (q1 * q3 - q0 * q2))
    roll = np.arctan2(2 * (q2 * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3)
    assert np.allclose(state[:, 0:3], np.degrees(np.column_stack([roll, -pitch, yaw])),
                       atol=1e-4)
    for k in range(50):
        R = rotation_matrix(*x[k, 3:6])
        Rq = np.array([[1 - 2 * (qy[k]**2 + qz[k]**2), 2 * (qx[k] * qy[k] - qw[k] * qz[k]),
                        2 * (qx[k] * qz[k] + qw[k] * qy[k])],
                       [2 * (qx[k] * qy[k] + qw[k] * qz[k]), 1 - 2 * (qx[k]**2 + qz[k]**2),
                        2 * (qy[k] * qz[k] - qw[k] * qx[k])],
                       [2 * (qx[k] * qz[k] - qw[k] * qy[k]), 2 * (qy[k] * qz[k] + qw[k] * qx[k]),
                        1 - 2 * (qx[k]**2 + qy[k]**2)]])
        assert np.allclose(Rq, R, atol=1e-6)
        assert np.allclose(state[k, 10:13], R @ x[k, 6:9], atol=1e-5)
    assert np.allclose(gyro, np.degrees(x[:, 9:12]), rtol=1e-6)
    assert np.allclose(sp[:, 12], np.degrees(np.angle(np.exp(1j * ref[:, 12]))), atol=1e-4)


@needs_tree
@pytest.mark.parametrize("name", LAWS)
def test_host_build_gives_quadcog_s_commands(tree, flights, tmp_path, name):
    """The app's C (float32, the firmware's structs), fed quadcog's flight in the firmware's
    units, commands what quadcog's double law commanded, within AGREEMENT_RTOL."""
    write_crazyflie_app(name, tmp_path / "app")
    res = flights[name]
    assert not res.metrics.diverged and np.abs(res.r_hat[-1]).max() > 3e-3   # it adapted
    out = _host(tmp_path / "app", tree, tmp_path).run(*firmware_units(res.x, res.ref,
                                                                     CONTROL_PERIOD))
    assert (out[:, 4] == 1).all()                        # controlModeForceTorque
    got = agreement(out[:, :4], res.U)
    assert got["thrust"] <= AGREEMENT_RTOL["thrust"], got
    assert got["torque"] <= AGREEMENT_RTOL["torque"], got


MUTATIONS = {
    "pitch sign": [("x[4] = -QC_DEG_TO_RAD * state->attitude.pitch",
                    "x[4] = QC_DEG_TO_RAD * state->attitude.pitch")],
    "quaternion as w x y z": [
        ("qx = state->attitudeQuaternion.x, qy = state->attitudeQuaternion.y",
         "qx = state->attitudeQuaternion.y, qy = state->attitudeQuaternion.z"),
        ("qz = state->attitudeQuaternion.z, qw = state->attitudeQuaternion.w",
         "qz = state->attitudeQuaternion.w, qw = state->attitudeQuaternion.x")],
    "gyro y sign": [("x[10] = QC_DEG_TO_RAD * sensors->gyro.y",
                     "x[10] = -QC_DEG_TO_RAD * sensors->gyro.y")],
}


@needs_tree
@pytest.mark.parametrize("mutation", MUTATIONS)
def test_a_conversion_mistake_fails_the_agreement(tree, flights, tmp_path, mutation):
    app = tmp_path / "app"
    write_crazyflie_app("composite", app)
    src = app / "src/quadcog_cf_composite.c"
    text = src.read_text()
    for old, new in MUTATIONS[mutation]:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    src.write_text(text)
    res = flights["composite"]
    out = _host(app, tree, tmp_path).run(*firmware_units(res.x, res.ref, CONTROL_PERIOD))
    got = agreement(out[:, :4], res.U)
    assert got["torque"] > 100 * AGREEMENT_RTOL["torque"], (mutation, got)


@needs_tree
def test_rate_and_idle(tree, flights, tmp_path):
    """Off the 500 Hz ticks the app leaves control_t alone; without a z setpoint it commands
    zero in force-torque mode and restarts its state (the next flight starts as the first)."""
    write_crazyflie_app("composite", tmp_path / "app")
    host = _host(tmp_path / "app", tree, tmp_path)
    res = flights["composite"]
    rows = [a[:200] for a in firmware_units(res.x, res.ref, CONTROL_PERIOD)]
    odd = host.run(*rows, tick0=1)
    assert (odd == 0).all()                               # never written: the zeroed struct
    idle = host.run(*rows, modes=(MODE_ABS, MODE_ABS, MODE_DISABLE, MODE_ABS))
    assert (idle[:, :4] == 0).all() and (idle[:, 4] == 1).all()
    first = host.run(*rows)
    host.run(*rows, modes=(MODE_ABS, MODE_ABS, MODE_DISABLE, MODE_ABS))
    assert np.array_equal(host.run(*rows), first)


@needs_tree
def test_velocity_setpoints(tree, flights, tmp_path):
    """An axis in modeVelocity holds the current position; a body (hover) velocity is turned
    by the yaw: at yaw 90 deg, body x is world y."""
    write_crazyflie_app("composite", tmp_path / "app")
    host = _host(tmp_path / "app", tree, tmp_path)
    res = flights["composite"]
    state, gyro, sp = (a[:100].copy() for a in firmware_units(res.x, res.ref, CONTROL_PERIOD))
    state[:, 2] = 90.0
    state[:, 3:7] = [0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)]      # yaw 90 deg, x y z w
    sp[:, 12] = 90.0
    velocity = (MODE_VELOCITY, MODE_VELOCITY, MODE_ABS, MODE_ABS)
    held = sp.copy()
    held[:, 0:2] = state[:, 7:9]                  # a position setpoint at the current position
    host.init()
    expected = host.run(state, gyro, held)
    host.init()
    assert np.array_equal(host.run(state, gyro, sp, modes=velocity), expected)
    body = sp.copy()
    body[:, 3], body[:, 4] = sp[:, 4], -sp[:, 3]   # world (vx, vy) in the frame turned by 90 deg
    host.init()
    got = host.run(state, gyro, body, modes=velocity, velocity_body=True)
    assert np.allclose(got, expected, rtol=1e-5, atol=1e-9)


def test_bad_input(tmp_path, monkeypatch):
    with pytest.raises(FirmwareError, match=r"firmware = .*not a Crazyflie firmware tree: "
                                            r"it has no Makefile, tools/make/oot.mk"):
        firmware.firmware_tree(tmp_path)
    monkeypatch.setenv(firmware.FIRMWARE_ENV, str(tmp_path / "nowhere"))
    with pytest.raises(FirmwareError, match=r"\$QUADCOG_CRAZYFLIE_FIRMWARE = .*nowhere.*not a "
                                            "folder"):
        firmware.firmware_tree()
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(TargetError, match="arm-none-eabi-gcc.*apt-get install gcc-arm-none-eabi"):
        firmware.require_arm_toolchain()
    with pytest.raises(FirmwareError, match="no Makefile and Kbuild"):
        firmware.build_app(tmp_path)
    with pytest.raises(ExportError, match="vehicle 'cf3'"):
        write_crazyflie_app("composite", tmp_path / "a", vehicle="cf3")
    with pytest.raises(ExportError, match="controller 'lqr'"):
        write_crazyflie_app("lqr", tmp_path / "a")


@needs_tree
def test_a_user_tree_is_copied_not_written(tree, tmp_path, monkeypatch):
    """A tree named by the environment variable is copied into the cache (the builds run in
    the copy), and is the same tree afterwards."""
    monkeypatch.setenv("QUADCOG_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv(firmware.FIRMWARE_ENV, str(tree))
    before = firmware.tree_hash(tree)
    copy, key = firmware.firmware_tree()
    assert copy != tree and copy.is_relative_to(tmp_path / "cache")
    assert key == before[:16] and firmware.tree_hash(copy) == before == firmware.tree_hash(tree)


@pytest.mark.skipif(not firmware.VENDOR_TARBALL.is_file(), reason="needs the vendored tarball")
def test_a_tarball_is_a_firmware(monkeypatch):
    """A tarball named as the firmware is unpacked into the cache as the vendored one is."""
    monkeypatch.delenv(firmware.FIRMWARE_ENV, raising=False)
    assert firmware.firmware_tree(firmware.VENDOR_TARBALL) == firmware.firmware_tree()


def test_first_error_line():
    log = ("  CC      src/modules/src/crtp.o\n"
           "In file included from app/src/quadcog_cf_x.c:9:\n"
           "app/src/quadcog_cf_x.c:42:5: error: 'qc_state' undeclared (first use in this "
           "function)\n"
           "app/src/quadcog_cf_x.c:50:1: error: expected ';'\n"
           "make[3]: *** [scripts/Makefile.build:197: app/src/quadcog_cf_x.o] Error 1\n")
    assert firmware.first_error(log) == ("app/src/quadcog_cf_x.c:42:5: error: 'qc_state' "
                                         "undeclared (first use in this function)")
    assert firmware.first_error("make: *** No rule to make target 'x'.  Stop.\n").startswith(
        "make: ***")


def test_cli(tmp_path, capsys):
    assert cli(["export", "--target", "crazyflie", "--controller", "composite",
                "--out", str(tmp_path)]) == 0
    first = (tmp_path / "src/quadcog_cf_composite.c").read_text().splitlines()[0]
    assert "quadcog export --target crazyflie --controller composite --out DIR" in first
    assert cli(["export", "--target", "crazyflie", "--controller", "composite", "--vehicle",
                "cf3", "--out", str(tmp_path)]) == 2
    assert "cf3" in capsys.readouterr().err
    assert cli(["export", "--controller", "pd", "--vehicle", "crazyflie",
                "--out", str(tmp_path)]) == 2
    assert "--vehicle needs --target crazyflie" in capsys.readouterr().err
    assert cli(["export", "--target", "crazyflie", "--controller", "composite", "--firmware",
                str(tmp_path), "--out", str(tmp_path / "never")]) == 2
    assert "--firmware needs --build" in capsys.readouterr().err
    assert not (tmp_path / "never").exists()


# ---- the firmware build (slow: about 90 s on 2 cores, once per firmware and app source) ----

def _start_build():
    """The app of composite built into cf2.elf, and a broken copy built after it (found
    again by the hashes of the firmware and the app when they are in the cache)."""
    if not (HAVE_TREE and HAVE_ARM):
        return lambda: None
    import tempfile
    work = Path(tempfile.mkdtemp(prefix="quadcog-cf-app-"))
    write_crazyflie_app("composite", work / "app",
                        command="quadcog export --target crazyflie --controller composite "
                                "--out DIR")

    broken = work / "broken"
    shutil.copytree(work / "app", broken)
    src = broken / "src" / "quadcog_cf_composite.c"
    src.write_text(src.read_text().replace("return true;", "return true"))

    def build():
        """Files and subprocesses only; the broken app builds in the same workspace, so
        only its objects are compiled."""
        first = firmware.build_app(work / "app")
        again = firmware.build_app(work / "app")
        try:
            firmware.build_app(broken)
            failed = None
        except FirmwareBuildError as e:
            failed = e
        return work, first, again, failed
    return build


background_job("crazyflie: cf2.elf with the app", __file__, "test_firmware_build_with_the_app",
               _start_build, lane="crazyflie")


@pytest.mark.slow
@pytest.mark.skipif(not (HAVE_TREE and HAVE_ARM),
                    reason=f"needs the firmware tree and {firmware.ARM_INSTALL} (CI installs "
                           "it: .ci/run)")
def test_firmware_build_with_the_app(capsys):
    """The firmware's own Makefiles build cf2.elf with the app (its -Os -Werror, its arm-none-
    eabi-gcc); the ELF has the app's controller and law; the second call finds it cached; a
    broken app fails with the compiler's first error line."""
    work, first, again, failed = background_result("crazyflie: cf2.elf with the app")
    assert first.elf.is_file() and again.cached and again.elf == first.elf
    assert (again.text, again.data, again.bss) == (first.text, first.data, first.bss)
    syms = subprocess.run(["arm-none-eabi-nm", str(first.elf)], capture_output=True, text=True,
                          check=True).stdout
    for sym in ("controllerOutOfTree", "controllerOutOfTreeInit", "quadcog_composite_step",
                "appMain"):
        assert re.search(rf" T {sym}\n", syms), sym
    # the app's objects were compiled with the firmware's own flags (Kbuild's command line)
    cmd = (first.elf.parent.parent / "src" / ".quadcog_cf_composite.o.cmd").read_text()
    assert cmd.startswith("cmd_") and "arm-none-eabi-gcc" in cmd
    for flag in ("-Os -Werror", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard", "-Wdouble-promotion"):
        assert f" {flag} " in cmd, flag
    # the command line finds the same app in the cache (same files: same hash)
    assert cli(["export", "--target", "crazyflie", "--controller", "composite", "--out",
                str(work / "cli"), "--build"]) == 0
    assert f"found {first.elf}: flash {first.flash} B" in capsys.readouterr().out
    # a broken app: the compiler's first error line, naming the file and line
    assert failed is not None
    assert re.search(r"quadcog_cf_composite\.c:\d+:\d+: error: expected ';'", str(failed)), failed
    shutil.rmtree(work, ignore_errors=True)


@pytest.mark.slow
@pytest.mark.skipif(bool(missing_tools()), reason="needs gcc-arm-none-eabi "
                    "libnewlib-arm-none-eabi qemu-system-arm (CI installs them: .ci/run)")
@pytest.mark.parametrize("name", LAWS)
def test_published_instructions_are_this_app_s(flights, tmp_path, name):
    """The instructions per call in docs/tour/crazyflie.md (from `make crazyflie-app`) are what
    QEMU counts for the app's law now (-icount: the same on any host): a change of the law or
    of the export that is not republished fails here."""
    page = (Path(__file__).resolve().parent.parent / "docs/tour/crazyflie.md").read_text()
    row = re.search(rf"^\| {name} \| \d+ \| \d+ \| (\d+) \| (\d+) \|", page, re.M)
    assert row, f"no row of {name} in docs/tour/crazyflie.md"
    app = tmp_path / "app"
    write_crazyflie_app(name, app)
    nc = int(make_controller(name, vehicle=resolve_vehicle(None)).n_state)
    cost = law_cost(app, name, nc, flights[name], tmp_path / "qemu")
    assert (f"{cost['instructions_mean']:.0f}", f"{cost['instructions_max']:.0f}") == row.groups(), (
        "run make crazyflie-app and republish its output in docs/tour/crazyflie.md")
