"""Finding a PX4-Autopilot tree and building ``px4_sitl_default`` in quadcog's cache.

Where the tree comes from, first found wins: the argument (a source folder or a ``.tar.xz``
of one), the environment variable ``QUADCOG_PX4`` (the same), else the shared tarball
``shared/vendor/px4-autopilot.tar.xz`` next to the checkout. Every build happens in
``cache_dir()/px4/<key>/PX4-Autopilot``, never in the user's tree: a tarball is unpacked there
(key: the first 16 hex digits of its sha256); a folder is copied there (key: ``tree-`` and a
sha256 of its files' names and contents, ``build/`` left out), because PX4's version script
needs the tree to be a git repository with a tag, which would mean writing ``.git`` folders
into the user's tree, and PX4's Makefile puts its build folder inside the tree.

The build (``build``): each submodule folder without ``.git`` and the top folder become git
repositories with one commit (the top one tagged ``v1.17.0-dev`` when it has no tag), then
``make px4_sitl_default`` with ``GIT_SUBMODULES_ARE_EVIL=1`` (no submodule updates) and this
interpreter as ``PYTHON_EXECUTABLE``, its output in ``<key>/build.log``; a finished build
leaves ``<key>/built.json``. A second process waits on ``<key>/lock`` instead of building
the same tree twice. The build needs cmake, ninja, a C++ compiler and the Python packages of
``BUILD_MODULES`` in this interpreter (``make px4-build`` installs them).
"""
import contextlib
from dataclasses import dataclass
import hashlib
import importlib.util
import json
import os
from pathlib import Path
import re
import shutil
import signal
import subprocess
import sys
import tarfile
import time
from typing import Iterator

from quadcog.codegen.compiler import file_digest
from quadcog.codegen.third_party import locked
from quadcog.errors import MissingDependencyError, Px4Error
from quadcog.paths import cache_dir

__all__ = ["TREE_ENV", "TARBALL_NAME", "TARGET", "VERSION_TAG", "BUILD_MODULES",
           "BUILD_PACKAGES", "SUBMODULES", "Px4Build", "shared_tarball", "find_source",
           "tree_key", "build_dir", "cached_build", "build", "first_error_line"]

TREE_ENV = "QUADCOG_PX4"
TARBALL_NAME = "px4-autopilot.tar.xz"
TARGET = "px4_sitl_default"
VERSION_TAG = "v1.17.0-dev"     # what `git describe` must find (PX4's version script)
# module -> the pip requirement (of Tools/setup/requirements.txt) a SITL build imports
BUILD_MODULES = {"em": "empy>=3.3,<4", "genmsg": "pyros-genmsg", "kconfiglib": "kconfiglib",
                 "jinja2": "jinja2", "yaml": "pyyaml", "jsonschema": "jsonschema",
                 "future": "future", "lxml": "lxml"}
BUILD_PACKAGES = tuple(BUILD_MODULES.values())
# the submodules a px4_sitl_default build reads (each must be a git repository)
SUBMODULES = ("src/modules/mavlink/mavlink", "src/modules/mavlink/mavlink/pymavlink",
              "src/drivers/gps/devices", "src/lib/events/libevents",
              "src/lib/heatshrink/heatshrink",
              "src/modules/uxrce_dds_client/Micro-XRCE-DDS-Client")
_GIT = ["git", "-c", "user.name=quadcog", "-c", "user.email=quadcog@localhost",
        "-c", "init.defaultBranch=main", "-c", "advice.addEmbeddedRepo=false"]
_ERROR = re.compile(r"(error:|Error:|FAILED:|CMake Error|No such file or directory|"
                    r"ModuleNotFoundError|make: \*\*\*)")


@dataclass(frozen=True)
class Px4Build:
    """A built ``px4_sitl_default``.

    Parameters
    ----------
    key : str
        The cache key of its tree.
    source : pathlib.Path
        The source tree in the cache.
    origin : str
        Where the tree came from (a tarball or a folder).
    """
    key: str
    source: Path
    origin: str

    @property
    def build_folder(self) -> Path:
        """``build/px4_sitl_default`` of the tree."""
        return self.source / "build" / TARGET

    @property
    def binary(self) -> Path:
        """The ``px4`` executable."""
        return self.build_folder / "bin" / "px4"

    @property
    def etc(self) -> Path:
        """The ROMFS folder (``etc``) that PX4's start-up scripts run from."""
        return self.build_folder / "etc"

    def commit(self) -> str:
        """What the tree says it is: ``git describe --always --tags`` of its top folder.

        Returns
        -------
        str
            E.g. ``v1.17.0-dev``; ``unknown`` when git cannot tell.
        """
        try:
            return subprocess.run(["git", "-C", str(self.source), "describe", "--always",
                                   "--tags"], capture_output=True, text=True, timeout=30,
                                  check=True).stdout.strip() or "unknown"
        except (OSError, subprocess.SubprocessError):
            return "unknown"


def shared_tarball() -> Path | None:
    """The shared tarball, ``shared/vendor/px4-autopilot.tar.xz`` next to the checkout
    (or beside the current folder).

    Returns
    -------
    pathlib.Path or None
        The file, None when it is not there.
    """
    here = Path(__file__).resolve().parents[2]
    for base in (here, Path.cwd()):
        path = base.parent / "shared" / "vendor" / TARBALL_NAME
        if path.is_file():
            return path
    return None


def find_source(tree: str | os.PathLike[str] | None = None) -> Path:
    """The PX4 tree to use: ``tree``, else $QUADCOG_PX4, else the shared tarball.

    Parameters
    ----------
    tree : str or os.PathLike, optional
        A PX4-Autopilot source folder or a ``.tar.xz`` of one.

    Returns
    -------
    pathlib.Path
        The folder or tarball.

    Raises
    ------
    quadcog.Px4Error
        When the one named does not exist or is not a PX4 tree, or none is found (the
        message says where it looked and how to get one).
    """
    named, where = (tree, "argument --px4") if tree is not None else (
        os.environ.get(TREE_ENV) or None, f"${TREE_ENV}")
    if named is None:
        path = shared_tarball()
        if path is None:
            raise Px4Error(f"no PX4 tree: none given (--px4 PATH), ${TREE_ENV} is not set and "
                           f"there is no shared/vendor/{TARBALL_NAME} next to the checkout; "
                           f"expected a PX4-Autopilot source folder or a .tar.xz of one")
        return path
    if isinstance(named, bytes) or not isinstance(named, (str, os.PathLike)) or not str(named):
        # Path("") is the current folder, which would be named '.'
        raise Px4Error(f"{where} = {named!r}: expected the path of a PX4-Autopilot source "
                       "folder or a .tar.xz of one")
    path = Path(named).expanduser()
    if path.is_file() and path.name.endswith((".tar.xz", ".tar.gz", ".tar")):
        return path
    if path.is_dir():
        if not (path / "Makefile").is_file() or not (path / "ROMFS").is_dir():
            raise Px4Error(f"{where} = {str(path)!r}: not a PX4-Autopilot source folder (no "
                           f"Makefile and ROMFS/ in it)")
        return path
    from quadcog.files import path_kind
    kind = path_kind(path)
    found = (f"is {kind}" if kind is not None else
             "is a file, not a tarball (.tar.xz, .tar.gz, .tar)" if path.is_file() else
             "no such folder or tarball")
    raise Px4Error(f"{where} = {str(path)!r}: {found}; expected a PX4-Autopilot source folder "
                   "or a .tar.xz of one")


def _tree_files(root: Path) -> Iterator[Path]:
    for folder, dirs, files in os.walk(root):
        here = Path(folder)
        dirs[:] = sorted(d for d in dirs if d != ".git" and not (here == root and d == "build"))
        for name in sorted(files):
            yield here / name


def tree_key(source: Path) -> str:
    """The cache key of a tree: its tarball's sha256 (16 hex digits), or ``tree-`` and the
    sha256 of a folder's file names and contents (``build/`` and ``.git`` left out).

    Parameters
    ----------
    source : pathlib.Path
        A tarball or a folder (``find_source``).

    Returns
    -------
    str
        The key.
    """
    if source.is_file():
        return file_digest(source)[:16]
    h = hashlib.sha256()
    for path in _tree_files(source):
        rel = path.relative_to(source).as_posix().encode()
        h.update(len(rel).to_bytes(4, "little") + rel)
        if path.is_symlink():
            h.update(b"L" + os.readlink(path).encode())
        elif path.is_file():
            h.update(b"F" + file_digest(path).encode())
    return "tree-" + h.hexdigest()[:16]


def build_dir(key: str) -> Path:
    """The cache folder of a tree: ``cache_dir()/px4/<key>``.

    Parameters
    ----------
    key : str
        ``tree_key``'s.

    Returns
    -------
    pathlib.Path
        The folder (it may not exist).
    """
    return cache_dir() / "px4" / key


def cached_build(tree: str | os.PathLike[str] | None = None) -> Px4Build | None:
    """The finished build of the tree ``find_source(tree)`` names, if the cache has it.

    Nothing is unpacked or built: tests ask this and skip without a build.

    Parameters
    ----------
    tree : str or os.PathLike, optional
        As for ``find_source``.

    Returns
    -------
    Px4Build or None
        None when no finished build of that tree is in the cache.

    Raises
    ------
    quadcog.Px4Error
        As ``find_source``.
    """
    source = find_source(tree)
    key = tree_key(source)
    folder = build_dir(key)
    found = Px4Build(key, folder / "PX4-Autopilot", str(source))
    if (folder / "built.json").is_file() and found.binary.is_file():
        return found
    return None


def _missing_modules() -> list[str]:
    return [pkg for module, pkg in BUILD_MODULES.items()
            if importlib.util.find_spec(module) is None]


def _unpack(source: Path, folder: Path) -> Path:
    """The tree's copy in the cache: a tarball unpacked, a folder copied (once)."""
    target = folder / "PX4-Autopilot"
    if target.is_dir():
        return target
    tmp = folder / "unpacking"
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    try:
        if source.is_file():
            try:
                with tarfile.open(source) as tar:
                    tar.extractall(tmp, filter="data")
            except (tarfile.TarError, OSError, EOFError) as e:
                raise Px4Error(f"{source}: cannot unpack ({e})") from None
            tops = [p for p in tmp.iterdir() if p.is_dir()]
            if len(tops) != 1 or not (tops[0] / "Makefile").is_file():
                raise Px4Error(f"{source}: expected one PX4-Autopilot folder in the tarball, "
                               f"found {sorted(p.name for p in tmp.iterdir())}")
            tops[0].rename(target)
        else:
            try:
                shutil.copytree(source, tmp / "PX4-Autopilot", symlinks=True,
                                ignore=lambda d, names: _not_copied(source, Path(d), names))
            except (shutil.Error, OSError) as e:
                raise Px4Error(f"{source}: cannot copy the tree into the cache "
                               f"({str(e)[:300]})") from None
            (tmp / "PX4-Autopilot").rename(target)
    finally:        # a failed or interrupted copy leaves nothing half-made in the cache
        shutil.rmtree(tmp, ignore_errors=True)
    return target


def _not_copied(source: Path, folder: Path, names: list[str]) -> list[str]:
    """What a tree's copy leaves out: its top ``build/`` and what ``tree_key`` does not hash,
    i.e. all but folders, regular files and links (a FIFO would be read without end)."""
    return [n for n in names if (n == "build" and folder == source)
            or not ((folder / n).is_symlink() or (folder / n).is_dir()
                    or (folder / n).is_file())]


def _git(args: list[str], cwd: Path) -> None:
    subprocess.run(_GIT + args, cwd=cwd, check=True, capture_output=True, timeout=600)


def _make_git_repositories(tree: Path) -> None:
    """Each submodule folder and the top folder as a git repository (PX4's version script
    runs ``git describe``; the build checks the submodules are repositories)."""
    try:
        for sub in SUBMODULES:
            d = tree / sub
            if d.is_dir() and not (d / ".git").exists():
                _git(["init", "-q"], d)
                _git(["add", "-A"], d)
                _git(["commit", "-qm", "snapshot", "--allow-empty"], d)
        if not (tree / ".git").exists():
            _git(["init", "-q"], tree)
            _git(["add", "-A"], tree)
            _git(["commit", "-qm", "snapshot"], tree)
        described = subprocess.run(["git", "describe", "--tags"], cwd=tree, capture_output=True,
                                   timeout=60)
        if described.returncode != 0:
            _git(["tag", VERSION_TAG], tree)
    except FileNotFoundError:
        raise Px4Error("git not found: the PX4 build needs git (its version script runs "
                       "`git describe`); install it (apt-get install git)") from None
    except subprocess.CalledProcessError as e:
        raise Px4Error(f"{tree}: git {' '.join(e.cmd[len(_GIT):])} failed: "
                       f"{(e.stderr or b'').decode(errors='replace').strip()[:300]}") from None


def first_error_line(log: Path) -> str:
    """The first line of a build log that reports an error (compiler, CMake, make).

    Parameters
    ----------
    log : pathlib.Path
        The build's output.

    Returns
    -------
    str
        The line, stripped; the log's last line when none looks like an error.
    """
    last = ""
    with open(log, errors="replace") as fh:
        for line in fh:
            if line.strip():
                last = line.strip()
            if _ERROR.search(line):
                return line.strip()
    return last


def build(tree: str | os.PathLike[str] | None = None, jobs: int | None = None,
          quiet: bool = False) -> Px4Build:
    """Find the tree, copy it into the cache and build ``px4_sitl_default`` there (once).

    Parameters
    ----------
    tree : str or os.PathLike, optional
        As for ``find_source``.
    jobs : int, optional
        Parallel compile jobs (default: ninja's choice).
    quiet : bool
        No progress lines on stderr.

    Returns
    -------
    Px4Build
        The finished build.

    Raises
    ------
    quadcog.Px4Error
        No tree (``find_source``), a tree that cannot be unpacked, or a build that fails
        (the compiler's first error line and the log's path).
    quadcog.errors.MissingDependencyError
        A Python package the build imports is not installed (the pip line).
    """
    source = find_source(tree)
    key = tree_key(source)
    folder = build_dir(key)
    folder.mkdir(parents=True, exist_ok=True)
    with locked(folder / "lock"):           # another build of this tree: wait for it
        done = Px4Build(key, folder / "PX4-Autopilot", str(source))
        if (folder / "built.json").is_file() and done.binary.is_file():
            return done
        missing = _missing_modules()
        if missing:
            raise MissingDependencyError(
                f"the PX4 build imports Python packages that are not installed in "
                f"{sys.executable}: install them with: {Path(sys.executable).name} -m pip "
                f"install {' '.join(repr(m) if '<' in m else m for m in missing)} "
                f"(or `make px4-build`)")
        for tool in ("cmake", "ninja", "make", "c++"):
            if shutil.which(tool) is None:
                raise Px4Error(f"{tool} not found: the PX4 build needs cmake, ninja, make and a "
                               f"C++ compiler (apt-get install cmake ninja-build g++)")
        if not quiet:
            print(f"quadcog: building PX4 ({TARGET}) from {source} in {folder} (first time "
                  f"only; several minutes)", file=sys.stderr)
        tree_copy = _unpack(source, folder)
        _make_git_repositories(tree_copy)
        env = dict(os.environ, GIT_SUBMODULES_ARE_EVIL="1", PYTHON_EXECUTABLE=sys.executable,
                   PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""))
        if jobs:
            env["CMAKE_BUILD_PARALLEL_LEVEL"] = str(jobs)
        log = folder / "build.log"
        t0 = time.monotonic()
        with open(log, "w") as fh:
            try:
                proc = subprocess.Popen(["make", TARGET], cwd=tree_copy, env=env, stdout=fh,
                                        stderr=subprocess.STDOUT, start_new_session=True)
            except OSError as e:
                raise Px4Error(f"cannot run make in {tree_copy}: {e.strerror}") from None
            try:
                code = proc.wait()
            except BaseException:       # Ctrl-C: make, ninja and the compilers all go
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
                raise
        if code != 0 or not done.binary.is_file():
            raise Px4Error(f"the PX4 build of {source} failed (make {TARGET} exited {code}): "
                           f"{first_error_line(log)} (full log: {log})")
        seconds = time.monotonic() - t0
        (folder / "built.json").write_text(json.dumps(
            {"origin": str(source), "key": key, "target": TARGET, "seconds": round(seconds, 1),
             "built": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}, indent=1))
        return done


def main(argv: list[str] | None = None) -> int:
    """``make px4-build [PX4=PATH]``: install the build's Python packages
    (``BUILD_PACKAGES``) into this interpreter where missing, then build.

    Parameters
    ----------
    argv : list of str, optional
        ``[PATH]`` or ``[]`` (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0 when built; 2 with one line on stderr otherwise.
    """
    from quadcog.errors import QuadcogError
    missing = _missing_modules()
    if missing:
        print(f"quadcog: installing the PX4 build's Python packages: {' '.join(missing)}",
              file=sys.stderr)
        if subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", *missing]).returncode:
            print("quadcog: error: pip could not install them", file=sys.stderr)
            return 2
    try:
        args = sys.argv[1:] if argv is None else argv
        done = build(args[0] if args else None)
    except QuadcogError as e:
        print(f"quadcog: error: {e}", file=sys.stderr)
        return 2
    print(f"PX4 {done.commit()} built: {done.binary}")
    return 0

