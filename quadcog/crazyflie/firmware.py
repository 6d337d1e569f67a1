"""A Crazyflie firmware tree: where it is, what it defines, and its controllers, power
distribution, thrust map and battery compensation built for this machine with quadcog's loop.

The tree is the user's checkout (an argument, or ``$QUADCOG_CRAZYFLIE_FIRMWARE``), else the
vendor tarball ``crazyflie-firmware.tar.xz`` unpacked into the cache. It is only read: the
build (the firmware's C files compiled as they are, with ``-DCRAZYFLIE_FW -DUNIT_TEST_MODE``
as its Python bindings are) happens in ``quadcog.paths.cache_dir()/stacks``. Three firmware
functions live in files that the host cannot compile whole (``stabilizer.c`` and ``motors.c``
pull in FreeRTOS and the STM32 drivers), so they are cut from those files by name and compiled
on their own: ``controlMotors``, ``batteryCompensation`` (with the stabilizer's motor buffers)
and ``motorsCompensateBatteryVoltage``. What stands in for the hardware is quadcog's:
``pmGetBatteryVoltage`` returns the plant's battery voltage and ``motorsSetRatio`` records the
PWM (``motor.m1..m4``). No SWIG is needed. The firmware's ``autoconf.h`` is written by quadcog
from the Kconfig defaults of the cf2 platform (battery compensation on, the propellers chosen).
"""
from dataclasses import dataclass
import hashlib
import os
from pathlib import Path
import re
import subprocess
import tempfile

from quadcog import validate
from quadcog.codegen.compiler import find_compiler
from quadcog.errors import StackError
from quadcog.paths import cache_dir
from quadcog.stacks.build import Source, build_library, c_function, first_error_line
from quadcog.stacks.vendor import find_tree, tree_digest

__all__ = ["FIRMWARE_ENV", "MARKERS", "PROPELLERS", "CONTROLLERS", "INCLUDE_DIRS",
           "FIRMWARE_SOURCES", "GET_FIRMWARE", "firmware_tree", "autoconf", "constants",
           "check_structs", "extracted_source", "loop_source", "FirmwareBuild", "build_firmware"]

FIRMWARE_ENV = "QUADCOG_CRAZYFLIE_FIRMWARE"
GET_FIRMWARE = ("get one with `git clone --recursive https://github.com/bitcraze/"
                "crazyflie-firmware` and pass its folder as firmware=... or set "
                f"${FIRMWARE_ENV}")
MARKERS = ("src/modules/interface/stabilizer_types.h",
           "src/modules/src/controller/controller_pid.c",
           "src/platform/interface/platform_defaults_cf2.h",
           "src/modules/src/stabilizer.c", "src/drivers/src/motors.c")
# quadcog's name -> the Kconfig choice (Kconfig: "Crazyflie 2.X platform setup"); 2.1+ is the
# default of that choice
PROPELLERS = {"2.1+": "CONFIG_CRAZYFLIE_21_PLUS", "legacy": "CONFIG_CRAZYFLIE_LEGACY_PROPELLERS",
              "upgrade-kit": "CONFIG_CRAZYFLIE_THRUST_UPGRADE_KIT"}
# quadcog's name -> the firmware's ControllerType (controller.h), in its order
CONTROLLERS = {"pid": 1, "mellinger": 2, "indi": 3, "brescianini": 4, "lee": 5}
OUT_OF_TREE = 6
INCLUDE_DIRS = ("src/modules/interface", "src/modules/interface/controller",
                "src/modules/interface/kalman_core", "src/hal/interface", "src/utils/interface",
                "src/utils/interface/lighthouse", "src/config", "src/drivers/interface",
                "src/platform/interface", "vendor/CMSIS/CMSIS/DSP/Include",
                "vendor/CMSIS/CMSIS/Core/Include")
FIRMWARE_SOURCES = ("src/modules/src/controller/controller.c",
                    "src/modules/src/controller/controller_pid.c",
                    "src/modules/src/controller/position_controller_pid.c",
                    "src/modules/src/controller/attitude_pid_controller.c",
                    "src/modules/src/controller/controller_mellinger.c",
                    "src/modules/src/controller/controller_indi.c",
                    "src/modules/src/controller/position_controller_indi.c",
                    "src/modules/src/controller/controller_brescianini.c",
                    "src/modules/src/controller/controller_lee.c",
                    "src/modules/src/power_distribution_quadrotor.c",
                    "src/utils/src/pid.c", "src/utils/src/filter.c", "src/utils/src/num.c")
# the firmware build's own flags that change code (tools/make/targets or Makefile), as the
# bindings use them
FIRMWARE_FLAGS = ("-O2", "-std=gnu11", "-fno-strict-aliasing", "-Wno-address-of-packed-member",
                  "-DCRAZYFLIE_FW", "-DUNIT_TEST_MODE")
# struct fields quadcog's loop reads or writes (stabilizer_types.h)
STRUCT_FIELDS = {
    "state_t": ("attitude", "attitudeQuaternion", "position", "velocity", "acc"),
    "setpoint_t": ("timestamp", "attitude", "attitudeRate", "attitudeQuaternion", "thrust",
                   "position", "velocity", "acceleration", "jerk", "velocity_body", "mode"),
    "sensorData_t": ("acc", "gyro", "mag", "baro", "interruptTimestamp"),
    "control_t": ("roll", "pitch", "yaw", "thrust", "thrustSi", "torqueX", "torqueY",
                  "torqueZ", "controlMode"),
}
_C_DIR = Path(__file__).with_name("c")


def firmware_tree(firmware: str | os.PathLike[str] | None = None) -> Path:
    """The Crazyflie firmware tree to build from.

    Parameters
    ----------
    firmware : str or os.PathLike, optional
        The root of a checkout; default ``$QUADCOG_CRAZYFLIE_FIRMWARE``, else the vendor
        tarball unpacked into the cache.

    Returns
    -------
    pathlib.Path
        Its root.

    Raises
    ------
    quadcog.StackError
        A folder that is not a firmware tree (the first missing file named), none at all, or
        ``firmware`` not a path (an empty one would name the current folder).
    """
    return find_tree(firmware, FIRMWARE_ENV, "crazyflie-firmware.tar.xz", "crazyflie-firmware",
                     MARKERS, "Crazyflie firmware tree", GET_FIRMWARE, argument_name="firmware")


def autoconf(propellers: str = "2.1+", out_of_tree: bool = False) -> str:
    """The ``autoconf.h`` quadcog builds the firmware with: the cf2 platform's Kconfig defaults.

    Parameters
    ----------
    propellers : str
        A key of ``PROPELLERS`` (default ``"2.1+"``, the Kconfig default).
    out_of_tree : bool
        Define ``CONFIG_CONTROLLER_OOT`` (an out-of-tree controller is linked in).

    Returns
    -------
    str
        The header's text.
    """
    validate.choice(propellers, "propellers", tuple(PROPELLERS))
    lines = ["/* written by quadcog: the cf2 platform's Kconfig defaults */",
             "#define CONFIG_PLATFORM_CF2 1", "#define CONFIG_ENABLE_THRUST_BAT_COMPENSATED 1",
             f"#define {PROPELLERS[propellers]} 1"]
    if out_of_tree:
        lines.append("#define CONFIG_CONTROLLER_OOT 1")
    return "\n".join(lines) + "\n"


def _config_dir(text: str) -> Path:
    """A folder in the cache holding autoconf.h of this text."""

    d = cache_dir() / "stacks" / f"crazyflie-config-{hashlib.sha256(text.encode()).hexdigest()[:16]}"
    if not (d / "autoconf.h").is_file():
        d.mkdir(parents=True, exist_ok=True)
        tmp = d / f".autoconf-{os.getpid()}.h"
        tmp.write_text(text)
        os.replace(tmp, d / "autoconf.h")
    return d


def _include_flags(tree: Path, config: Path, extra: tuple[Path, ...] = ()) -> list[str]:
    # quadcog's shims first: their log.h, param.h and debug.h include the firmware's
    # (#include_next) and register the log and parameter tables with the loop
    return ([f"-I{_C_DIR / 'include'}", f"-I{config}"] + [f"-I{p}" for p in extra]
            + [f"-I{tree / d}" for d in INCLUDE_DIRS])


def constants(firmware: str | os.PathLike[str] | None = None, propellers: str = "2.1+"
              ) -> dict[str, float]:
    """The physical constants of ``platform_defaults.h`` for the cf2 platform, as the
    firmware's preprocessor sees them.

    Parameters
    ----------
    firmware : str or os.PathLike, optional
        The tree (see ``firmware_tree``).
    propellers : str
        A key of ``PROPELLERS``.

    Returns
    -------
    dict of str to float
        ``CF_MASS`` (kg), ``ARM_LENGTH`` (m), ``VMOTOR2THRUST0..3`` (N, N/V, N/V^2, N/V^3),
        ``THRUST_MIN``, ``THRUST_MAX`` (N per motor), ``THRUST2TORQUE`` (m).

    Raises
    ------
    quadcog.StackError
        No tree, no compiler, or a constant that is not a number.
    """
    tree = firmware_tree(firmware)
    cc = find_compiler()
    if cc is None:
        raise StackError("reading the firmware's constants: no C compiler found (looked for "
                         "$CC or `cc` on PATH); install one, e.g. `apt-get install gcc`")
    # once per process and header state: the preprocessor run costs tens of ms per flight
    headers = sorted((tree / "src/platform/interface").glob("platform_defaults*.h"))
    key = (str(tree), propellers, cc, tuple((h.name, h.stat().st_mtime_ns, h.stat().st_size)
                                            for h in headers))
    if key not in _CONSTANTS:
        _CONSTANTS[key] = _read_constants(tree, cc, propellers)
    return dict(_CONSTANTS[key])


_CONSTANTS: dict[tuple, dict[str, float]] = {}


def _read_constants(tree: Path, cc: str, propellers: str) -> dict[str, float]:
    """The constants of ``constants`` from the preprocessor."""
    names = ("CF_MASS", "ARM_LENGTH", "VMOTOR2THRUST0", "VMOTOR2THRUST1", "VMOTOR2THRUST2",
             "VMOTOR2THRUST3", "THRUST_MIN", "THRUST_MAX", "THRUST2TORQUE")
    config = _config_dir(autoconf(propellers))
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "constants.c"
        src.write_text('#include "platform_defaults.h"\n')
        res = subprocess.run([cc, "-E", "-dM", *_include_flags(tree, config), str(src)],
                             capture_output=True, text=True)
    if res.returncode:
        raise StackError(f"reading platform_defaults.h of {str(tree)!r} failed: "
                         f"{first_error_line(res.stderr)}")
    macros = dict(re.findall(r"^#define (\w+) (.*)$", res.stdout, re.M))
    out = {}
    for name in names:
        text = macros.get(name, "").strip()
        m = re.fullmatch(r"\(?\s*([-+0-9.eE]+)f?\s*\)?(\s*//.*)?", text)
        if not m:
            raise StackError(f"platform_defaults.h of {str(tree)!r}: {name} is {text!r}, "
                             "expected a number")
        out[name] = float(m.group(1))
    return out


def check_structs(tree: Path) -> None:
    """Check that the firmware's structs have the fields quadcog's loop uses.

    Parameters
    ----------
    tree : pathlib.Path
        The firmware tree.

    Raises
    ------
    quadcog.StackError
        Naming the struct and the first missing field.
    """
    header = tree / "src/modules/interface/stabilizer_types.h"
    text = re.sub(r"//[^\n]*|/\*.*?\*/", "", header.read_text(errors="replace"), flags=re.S)
    for struct, fields in STRUCT_FIELDS.items():
        m = re.search(r"typedef struct \w*\s*\{(.*?)\}\s*" + re.escape(struct) + r"\s*;",
                      text, re.S)
        if m is None:
            raise StackError(f"{header}: no `typedef struct ... {struct};`; this firmware's "
                             "structs differ from those quadcog knows (crazyflie-firmware "
                             "2a18fc29 and its neighbours)")
        body = m.group(1)
        for field in fields:
            if not re.search(r"\b" + field + r"\b", body):
                raise StackError(f"{header}: {struct} has no field `{field}`; this firmware's "
                                 "structs differ from those quadcog knows (crazyflie-firmware "
                                 "2a18fc29 and its neighbours)")


def extracted_source(tree: Path) -> bytes:
    """The firmware's motor pipeline cut from ``stabilizer.c`` and ``motors.c``, as one C file.

    Parameters
    ----------
    tree : pathlib.Path
        The firmware tree.

    Returns
    -------
    bytes
        C text: the stabilizer's motor buffers, ``batteryCompensation``, ``setMotorRatios``,
        ``logCapWarning`` and ``controlMotors`` (stabilizer.c), ``motorsCompensateBatteryVoltage``
        (motors.c), and ``qc_control_motors`` calling ``controlMotors``.

    Raises
    ------
    quadcog.StackError
        A function or buffer that is not in those files.
    """
    stab_path = tree / "src/modules/src/stabilizer.c"
    motors_path = tree / "src/drivers/src/motors.c"
    stab = stab_path.read_text(errors="replace")
    motors = motors_path.read_text(errors="replace")
    buffers = re.findall(r"^static motors_thrust_\w+ \w+;", stab, re.M)
    if len(buffers) != 3:
        raise StackError(f"{stab_path}: expected the three motor buffers `static "
                         f"motors_thrust_... ...;`, found {len(buffers)}; this firmware differs "
                         "from the one quadcog knows")
    parts = [c_function(stab, sig, str(stab_path)) for sig in (
        "static void batteryCompensation(", "static void setMotorRatios(",
        "static void logCapWarning(", "static void controlMotors(")]
    parts.append(c_function(motors, "float motorsCompensateBatteryVoltage(", str(motors_path)))
    preamble = (_C_DIR / "motors_preamble.h").read_text()
    tail = ("\nvoid qc_control_motors(const control_t *control) { controlMotors(control); }\n")
    return (preamble + "\n".join(buffers) + "\n\n" + "\n\n".join(parts) + tail).encode()


@dataclass(frozen=True)
class FirmwareBuild:
    """A built firmware loop library.

    Parameters
    ----------
    library : pathlib.Path
        The shared library in the cache (copy it before loading: one copy per flight).
    tree : pathlib.Path
        The firmware tree it was built from.
    propellers : str
        The propeller configuration it was built for.
    out_of_tree : pathlib.Path or None
        The out-of-tree controller's folder, if one is linked in.
    """
    library: Path
    tree: Path
    propellers: str
    out_of_tree: Path | None


def loop_source() -> bytes:
    """The C text of quadcog's driver loop (``c/loop.c``; the tests mutate it here).

    Returns
    -------
    bytes
        The file's bytes.
    """
    return (_C_DIR / "loop.c").read_bytes()


def _oot_sources(folder: Path) -> tuple[list[Source], tuple[Path, ...]]:
    src = folder / "src" if (folder / "src").is_dir() else folder
    files = sorted(src.glob("*.c"))
    if not files:
        raise StackError(f"controller: the folder {str(folder)!r} has no C sources (*.c in "
                         "it or in its src/); expected an out-of-tree controller app that "
                         "defines controllerOutOfTreeInit, controllerOutOfTreeTest and "
                         "controllerOutOfTree (examples/app_out_of_tree_controller)")
    sources = [(f"oot_{f.name}", f.read_bytes()) for f in files]
    headers = tuple(sorted({p.parent for p in folder.rglob("*.h")}))
    return sources, (src, *headers)


def build_firmware(firmware: str | os.PathLike[str] | None = None, propellers: str = "2.1+",
                   out_of_tree: str | os.PathLike[str] | None = None) -> FirmwareBuild:
    """Build (or find in the cache) the firmware loop library.

    Parameters
    ----------
    firmware : str or os.PathLike, optional
        The tree (see ``firmware_tree``).
    propellers : str
        A key of ``PROPELLERS``.
    out_of_tree : str or os.PathLike, optional
        A folder of an out-of-tree controller's C sources (compiled in with
        ``CONFIG_CONTROLLER_OOT``).

    Returns
    -------
    FirmwareBuild
        The library and what it was built from.

    Raises
    ------
    quadcog.StackError
        No tree or not one, structs that differ, no compiler, or a compile error (its first
        line).
    """
    tree = firmware_tree(firmware)
    check_structs(tree)
    oot = Path(out_of_tree).resolve() if out_of_tree is not None else None
    config = _config_dir(autoconf(propellers, oot is not None))
    sources: list[Source] = [(Path(f).name, (tree / f).read_bytes()) for f in FIRMWARE_SOURCES]
    sources.append(("qc_motors.c", extracted_source(tree)))
    sources.append(("qc_loop.c", loop_source()))
    extra: tuple[Path, ...] = ()
    if oot is not None:
        oot_sources, extra = _oot_sources(oot)
        sources += oot_sources
    headers = [p for d in INCLUDE_DIRS for p in (tree / d).glob("*.h")]
    own = sorted((_C_DIR / "include").glob("*.h")) + [_C_DIR / "motors_preamble.h"]
    key = [tree_digest(tree, headers), tree_digest(_C_DIR, own), autoconf(propellers, oot is not None)]
    key += [tree_digest(d, d.glob("*.h")) for d in extra]
    flags = [*FIRMWARE_FLAGS, *_include_flags(tree, config, extra)]
    name = "crazyflie-loop" + ("-oot" if oot is not None else "")
    lib = build_library(name, sources, flags, key)
    return FirmwareBuild(lib, tree, propellers, oot)
