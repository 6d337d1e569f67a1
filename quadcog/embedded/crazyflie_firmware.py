"""Build a Crazyflie out-of-tree controller app inside the firmware, in quadcog's cache.

The firmware tree is the ``firmware`` argument (a folder or a tarball), else
``$QUADCOG_CRAZYFLIE_FIRMWARE``, else the vendored ``crazyflie-firmware.tar.xz`` of
``quadcog.codegen.third_party.vendor_dir()``, unpacked once into the cache: the one tree finder
that the firmware in the loop (``quadcog.crazyflie``) uses too. A user's tree is copied into
the cache (without ``.git`` and ``build`` folders) and built there, so it is never written.
The app (``write_crazyflie_app``) is copied into one workspace per firmware and built there
with the firmware's own Makefiles
(``make cf2_defconfig``, ``make``: its toolchain and flags, ``-Os -Werror``; incremental:
the next app rebuilds only its own objects); the ELF lands in
``<cache>/crazyflie/app/<firmware hash>-<app hash>/`` and is found there again. The plain
firmware (``make cf2_defconfig && make`` from the same copy, so that its ``__FILE__``
strings are as long) gives the sizes the app adds.
"""
from dataclasses import dataclass
import os
from pathlib import Path
import shutil
import subprocess
import tempfile

from quadcog.codegen.compiler import file_digest
from quadcog.codegen.third_party import SKIP_FOLDERS, locate_tree, locked, unpack_tarball, vendor_dir
from quadcog.codegen.third_party import check_tree as _check_tree
from quadcog.codegen.third_party import first_error_line as first_error
from quadcog.codegen.third_party import tree_hash as _tree_hash
from quadcog.embedded.target import ARM_GCC, ARM_SIZE
from quadcog.errors import FirmwareBuildError, FirmwareError, TargetError
from quadcog.paths import cache_dir

__all__ = ["FIRMWARE_ENV", "VENDOR_TARBALL", "ARM_INSTALL", "TREE_FILES", "FirmwareBuild",
           "GET_FIRMWARE", "TARBALL_NAME", "check_tree", "tree_hash", "firmware_tree",
           "require_arm_toolchain", "check_build_inputs", "first_error",
           "elf_size", "build_app", "build_plain"]

FIRMWARE_ENV = "QUADCOG_CRAZYFLIE_FIRMWARE"
TARBALL_NAME = "crazyflie-firmware.tar.xz"
VENDOR_TARBALL = vendor_dir() / TARBALL_NAME
GET_FIRMWARE = ("expected a checkout of github.com/bitcraze/crazyflie-firmware with its "
                "submodules: git clone --recursive https://github.com/bitcraze/crazyflie-firmware")
ARM_INSTALL = "apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi"
# what makes a folder a firmware tree for an out-of-tree app
TREE_FILES = ("Makefile", "tools/make/oot.mk", "configs/cf2_defconfig",
              "src/modules/interface/stabilizer_types.h",
              "src/modules/interface/controller/controller.h")
_SKIP = SKIP_FOLDERS
_BUILD_TIMEOUT = 1800.0            # s: a full firmware build is about 90 s on 2 cores


@dataclass(frozen=True)
class FirmwareBuild:
    """A finished firmware build.

    Parameters
    ----------
    elf : pathlib.Path
        ``cf2.elf``.
    text : int
        Its text (bytes, arm-none-eabi-size, Berkeley: code and constants).
    data : int
        Its initialized data (bytes; in flash and in RAM).
    bss : int
        Its zeroed data (bytes; RAM and the core-coupled memory).
    cached : bool
        Found in the cache rather than built by this call.
    """
    elf: Path
    text: int
    data: int
    bss: int
    cached: bool

    @property
    def flash(self) -> int:
        """Flash bytes (text + data)."""
        return self.text + self.data

    @property
    def ram(self) -> int:
        """Static RAM bytes (data + bss)."""
        return self.data + self.bss


def check_tree(path: str | os.PathLike[str], where: str) -> Path:
    """``path`` when it is a Crazyflie firmware tree.

    Parameters
    ----------
    path : str or os.PathLike
        The folder.
    where : str
        Where it came from (an argument, the environment variable), first in the message.

    Returns
    -------
    pathlib.Path
        The folder, resolved.

    Raises
    ------
    quadcog.errors.FirmwareError
        Not a folder, or a file of ``TREE_FILES`` is missing.
    """
    return _check_tree(path, where, TREE_FILES, "Crazyflie firmware tree", GET_FIRMWARE,
                       FirmwareError)


def tree_hash(tree: str | os.PathLike[str]) -> str:
    """The hex SHA-256 of a tree's file names and contents (``.git`` and ``build`` left out).

    Parameters
    ----------
    tree : str or os.PathLike
        The folder.

    Returns
    -------
    str
        64 hex digits.
    """
    return _tree_hash(tree, _SKIP)


def _root():
    return cache_dir() / "crazyflie"


def _publish(tmp, final):
    """Move a finished folder into place; another process may have been first."""
    try:
        os.rename(tmp, final)
    except OSError:
        if not final.is_dir():
            raise
        shutil.rmtree(tmp, ignore_errors=True)


def firmware_tree(firmware: str | os.PathLike[str] | None = None) -> tuple[Path, str]:
    """The firmware copy in the cache that the builds use, and its key.

    Parameters
    ----------
    firmware : str or os.PathLike, optional
        A firmware tree, or a tarball of one in a ``crazyflie-firmware/`` folder (default:
        ``$QUADCOG_CRAZYFLIE_FIRMWARE``, else ``VENDOR_TARBALL``).

    Returns
    -------
    tuple of (pathlib.Path, str)
        The copy's folder (``<cache>/crazyflie/firmware/<key>/crazyflie-firmware``) and the
        key: 16 hex digits of the tree's (or the tarball's) SHA-256.

    Raises
    ------
    quadcog.errors.FirmwareError
        The tree named is not a firmware tree, or none is named and the tarball is absent.
    """
    source, is_tarball = locate_tree(firmware, FIRMWARE_ENV, TARBALL_NAME, TREE_FILES,
                                     "Crazyflie firmware tree", GET_FIRMWARE,
                                     tarball_argument=True, argument_name="firmware",
                                     error=FirmwareError)
    where = "tarball" if is_tarball else "firmware"
    key = (file_digest(source) if where == "tarball" else tree_hash(source))[:16]
    final = _root() / "firmware" / key
    tree = final / "crazyflie-firmware"
    if where == "tarball":
        unpack_tarball(source, final.parent, name=key, error=FirmwareError)
        if not tree.is_dir():
            raise FirmwareError(f"{source}: no crazyflie-firmware/ folder in the tarball")
    elif not tree.is_dir():
        final.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f"{key}.", dir=final.parent))
        shutil.copytree(source, tmp / "crazyflie-firmware", symlinks=True,
                        ignore=lambda d, names: [n for n in names if n in _SKIP])
        _publish(tmp, final)
    check_tree(tree, f"the cached copy of {source}")
    return tree, key


def require_arm_toolchain() -> None:
    """Refuse to build without the ARM cross compiler.

    Raises
    ------
    quadcog.errors.TargetError
        ``arm-none-eabi-gcc`` or ``arm-none-eabi-size`` is not on PATH (with the install line).
    """
    missing = [t for t in (ARM_GCC, ARM_SIZE) if shutil.which(t) is None]
    if missing:
        raise TargetError(f"{', '.join(missing)} not found on PATH: the Crazyflie firmware "
                          f"builds with the GNU Arm toolchain (Debian, as root: {ARM_INSTALL})")


def elf_size(elf: str | os.PathLike[str]) -> tuple[int, int, int]:
    """text, data, bss of an ELF (arm-none-eabi-size, Berkeley format).

    Parameters
    ----------
    elf : str or os.PathLike
        The ELF.

    Returns
    -------
    tuple of (int, int, int)
        Bytes.
    """
    res = subprocess.run([ARM_SIZE, str(elf)], capture_output=True, text=True, check=True)
    text, data, bss = (int(v) for v in res.stdout.splitlines()[1].split()[:3])
    return text, data, bss


def _make(args, cwd, log_path):
    env = dict(os.environ, PWD=str(cwd))      # oot.mk reads $(PWD): the app folder
    with open(log_path, "a") as log:
        log.write(f"$ make {' '.join(args)}  (in {cwd})\n")
        log.flush()
        try:
            res = subprocess.run(["make", *args], cwd=cwd, env=env, stdout=log,
                                 stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                 timeout=_BUILD_TIMEOUT)
        except subprocess.TimeoutExpired:
            raise FirmwareBuildError(f"`make {' '.join(args)}` in {cwd} did not finish within "
                                     f"{_BUILD_TIMEOUT:g} s; log: {log_path}") from None
    if res.returncode != 0:
        text = Path(log_path).read_text(errors="replace")
        raise FirmwareBuildError(f"the firmware build failed (`make {' '.join(args)}` in {cwd}, "
                                 f"exit {res.returncode}): {first_error(text)}; log: {log_path}")


def _build_info(build, key):
    # without .git the firmware's versionTemplate.py reads build_info.json from the build folder
    build.mkdir(parents=True, exist_ok=True)
    (build / "build_info.json").write_text(f'{{"tag": "quadcog-{key}"}}\n')


def _finished(folder, cached):
    elf = folder / "build" / "cf2.elf"
    return FirmwareBuild(elf, *elf_size(elf), cached=cached)


def _sync_app(app, ws):
    """The workspace's app files become ``app``'s; its build/ folder stays (incremental)."""
    ws.mkdir(parents=True, exist_ok=True)
    for entry in ws.iterdir():
        if entry.name not in ("build", "build.log"):
            shutil.rmtree(entry) if entry.is_dir() else entry.unlink()
    shutil.copytree(app, ws, dirs_exist_ok=True,
                    ignore=lambda d, names: [n for n in names if n in _SKIP])


def check_build_inputs(firmware: str | os.PathLike[str] | None = None) -> None:
    """Refuse, before anything is written, a build that ``build_app`` would refuse: the ARM
    toolchain missing, or no firmware tree (named, in the environment, or the tarball).

    Parameters
    ----------
    firmware : str or os.PathLike, optional
        The firmware tree or tarball (see ``firmware_tree``).

    Raises
    ------
    quadcog.errors.TargetError
        The ARM toolchain is missing.
    quadcog.errors.FirmwareError
        The tree named is not a firmware tree, or none is named and the tarball is absent.
    """
    require_arm_toolchain()
    locate_tree(firmware, FIRMWARE_ENV, TARBALL_NAME, TREE_FILES, "Crazyflie firmware tree",
                GET_FIRMWARE, tarball_argument=True, argument_name="firmware",
                error=FirmwareError)


def build_app(app: str | os.PathLike[str], firmware: str | os.PathLike[str] | None = None,
              jobs: int = 2) -> FirmwareBuild:
    """Build ``cf2.elf`` with an out-of-tree app, or find the build in the cache.

    The build runs in one workspace per firmware, ``<cache>/crazyflie/workspace/<firmware
    key>/app`` (the firmware's objects name their build folder in their command lines, so a
    fixed folder lets Kbuild rebuild only the app's objects for the next app: the first
    build takes the firmware's full time, about 90 s on 2 cores, the next a few seconds).
    The ELF, the log and the app objects' command lines (``src/.*.o.cmd``: the firmware's
    flags) are then copied to the app's keyed folder.

    Parameters
    ----------
    app : str or os.PathLike
        The app folder (``write_crazyflie_app``); copied, never written.
    firmware : str or os.PathLike, optional
        The firmware tree (see ``firmware_tree``).
    jobs : int
        ``make -j``.

    Returns
    -------
    FirmwareBuild
        The ELF in ``<cache>/crazyflie/app/<firmware key>-<app key>/build/``.

    Raises
    ------
    quadcog.errors.FirmwareError
        Not a firmware tree, or ``app`` has no Makefile.
    quadcog.errors.TargetError
        The ARM toolchain is missing.
    quadcog.errors.FirmwareBuildError
        The build failed (the compiler's first error line and the log's path).
    """
    app = Path(app)
    if not (app / "Makefile").is_file() or not (app / "Kbuild").is_file():
        raise FirmwareError(f"app = {str(app)!r}: no Makefile and Kbuild; expected a folder "
                            "written by write_crazyflie_app (quadcog export --target crazyflie)")
    require_arm_toolchain()
    tree, fw_key = firmware_tree(firmware)
    key = f"{fw_key}-{tree_hash(app)[:16]}"
    final = _root() / "app" / key
    if (final / "build" / "cf2.elf").is_file():
        return _finished(final, cached=True)
    ws = _root() / "workspace" / fw_key / "app"
    ws.parent.mkdir(parents=True, exist_ok=True)
    with locked(ws.parent / "lock"):
        if (final / "build" / "cf2.elf").is_file():          # built while we waited
            return _finished(final, cached=True)
        _sync_app(app, ws)
        _build_info(ws / "build", fw_key)
        log = ws / "build.log"
        log.write_text("")
        base = f"CRAZYFLIE_BASE={tree}"
        if not (ws / "build" / ".config").is_file():
            _make([base, "cf2_defconfig"], ws, log)
        (ws / "build" / "cf2.elf").unlink(missing_ok=True)
        _make([base, f"-j{jobs}"], ws, log)
        if not (ws / "build" / "cf2.elf").is_file():
            raise FirmwareBuildError(f"the build in {ws} finished without build/cf2.elf; "
                                     f"log: {log}")
        final.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f"{key}.", dir=final.parent))
        (tmp / "build").mkdir()
        (tmp / "src").mkdir()
        shutil.copy2(ws / "build" / "cf2.elf", tmp / "build" / "cf2.elf")
        shutil.copy2(log, tmp / "build.log")
        for cmd in (ws / "src").glob(".*.o.cmd"):
            shutil.copy2(cmd, tmp / "src" / cmd.name)
        _publish(tmp, final)
    return _finished(final, cached=False)


def build_plain(firmware: str | os.PathLike[str] | None = None, jobs: int = 2) -> FirmwareBuild:
    """Build the firmware without an app (``make cf2_defconfig && make``), or find it.

    Parameters
    ----------
    firmware : str or os.PathLike, optional
        The firmware tree (see ``firmware_tree``).
    jobs : int
        ``make -j``.

    Returns
    -------
    FirmwareBuild
        The ELF in ``<cache>/crazyflie/plain/<firmware key>/build/``.

    Raises
    ------
    quadcog.errors.FirmwareError, quadcog.errors.TargetError, quadcog.errors.FirmwareBuildError
        As ``build_app``.
    """
    require_arm_toolchain()
    tree, fw_key = firmware_tree(firmware)
    final = _root() / "plain" / fw_key
    if (final / "build" / "cf2.elf").is_file():
        return _finished(final, cached=True)
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f"{fw_key}.", dir=final.parent))
    _build_info(tmp / "build", fw_key)
    args = [f"KBUILD_OUTPUT={tmp / 'build'}"]
    log = tmp / "build.log"
    _make(["-C", str(tree), *args, "cf2_defconfig"], tree, log)
    _make(["-C", str(tree), *args, f"-j{jobs}"], tree, log)
    if not (tmp / "build" / "cf2.elf").is_file():
        raise FirmwareBuildError(f"the build in {tmp} finished without build/cf2.elf; log: {log}")
    _publish(tmp, final)
    return _finished(final, cached=False)
