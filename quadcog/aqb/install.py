"""AdaptiveQuadBench set up in quadcog's cache: found, copied, patched for the CPU, located.

The tree comes from ``$QUADCOG_AQB`` (a user's own checkout, a folder, or a tarball) or else
from the vendor tarball ``shared/vendor/adaptivequadbench.tar.xz`` in the folder beside the checkout
(``shared/vendor/README.md``). It is unpacked or copied into
``quadcog.paths.cache_dir() / "aqb" / <sha256>`` (the tarball's sha256, or a hash of the
user's files), and only that copy is patched, never a user's tree. The three CPU fixes
(``PATCHES``) are the vendor README's: ``run_eval.py`` imports ``controller.*`` and
``experiments.*`` that now live under ``aqb.``, ``aqb/controller/__init__.py`` imports torch,
onnxruntime and acados unconditionally, and the plots ask for LaTeX (``text.usetex``). The
RotorPy fork is laid out as pip wants it (``rotorpy-pkg/pyproject.toml`` beside
``rotorpy-pkg/rotorpy/``) so that ``make aqb`` can ``pip install -e`` it.

    python -m quadcog.aqb setup   # the folders to pip install -e (make aqb does it)
"""
import hashlib
import json
import os
from pathlib import Path
import shutil
import tarfile
import tempfile

from quadcog.errors import InputError, MissingDependencyError
from quadcog.paths import cache_dir

__all__ = ["AQB_ENV", "TARBALL", "TARBALL_SHA256", "AQB_COMMIT", "ROTORPY_COMMIT", "PATCHES",
           "SETUP_LINE", "AqbTree", "vendor_tarball", "prepare", "installed_tree",
           "require_aqb"]

AQB_ENV = "QUADCOG_AQB"
TARBALL = "adaptivequadbench.tar.xz"
TARBALL_SHA256 = "8f341d69a6b072d0af228c48f3ad59cd78c8f3ff1b18095e221e55a1196e3204"
# the commits the vendor tarball holds (shared/vendor/README.md)
AQB_COMMIT, ROTORPY_COMMIT = "ee7df29", "6d2045d"
SETUP_LINE = ("make aqb   (or: pip install 'quadcog[aqb]', python -m quadcog.aqb setup, then "
              "pip install --no-deps -e each folder it prints)")
_STAMP = ".quadcog-aqb.json"
_ROOT = Path(__file__).resolve().parent.parent.parent

_OPTIONAL_IMPORTS = (
    "from .omnidrone_bridge import OmniDroneBridge\n"
    "from .omnidrone_direct import OmniDroneDirect\n")
_MPC_IMPORTS = (
    "from .quadrotor_control_mpc import ModelPredictiveControl\n"
    "from .quadrotor_control_mpc_l1 import L1_ModelPredictiveControl\n"
    "from .Xadap_NN_control import Xadap_NN_control\n")


def _guarded(lines: str) -> str:
    """Each import line inside try/except ImportError (torch, onnxruntime, acados absent)."""
    out = []
    for line in lines.splitlines():
        name = line.split(" import ")[1]
        out.append(f"try:\n    {line}\nexcept ImportError:   # quadcog: not installed on the CPU set-up\n"
                   f"    {name} = None\n")
    return "".join(out)


# (file, old text, new text): each old text must be found exactly once
PATCHES: tuple[tuple[str, str, str], ...] = (
    ("AdaptiveQuadBench/run_eval.py",
     "from controller.geometric_control import GeoControl\n"
     "from controller.geometric_adaptive_controller import GeometricAdaptiveController\n"
     "from controller.geometric_control_l1 import L1_GeoControl\n"
     "from controller.indi_adaptive_controller import INDIAdaptiveController\n"
     "from controller.quadrotor_control_mpc import ModelPredictiveControl\n"
     "from controller.quadrotor_control_mpc_l1 import L1_ModelPredictiveControl\n"
     "from controller.Xadap_NN_control import Xadap_NN_control\n"
     "from controller.omnidrone_bridge import OmniDroneBridge\n",
     "from aqb.controller import (GeoControl, GeometricAdaptiveController, L1_GeoControl,\n"
     "                            INDIAdaptiveController, ModelPredictiveControl,\n"
     "                            L1_ModelPredictiveControl, Xadap_NN_control, OmniDroneBridge)\n"),
    ("AdaptiveQuadBench/run_eval.py",
     "from experiments.config_manager import", "from aqb.experiments.config_manager import"),
    ("AdaptiveQuadBench/run_eval.py",
     "from experiments.experiment_runner import", "from aqb.experiments.experiment_runner import"),
    ("AdaptiveQuadBench/run_eval.py",
     "from experiments.results_manager import", "from aqb.experiments.results_manager import"),
    ("AdaptiveQuadBench/run_eval.py",
     "from experiments.visualizer import", "from aqb.experiments.visualizer import"),
    ("AdaptiveQuadBench/aqb/controller/__init__.py", _OPTIONAL_IMPORTS, _guarded(_OPTIONAL_IMPORTS)),
    ("AdaptiveQuadBench/aqb/controller/__init__.py", _MPC_IMPORTS, _guarded(_MPC_IMPORTS)),
    ("AdaptiveQuadBench/aqb/experiments/plotting_utils.py",
     "rcParams['text.usetex'] = True", "rcParams['text.usetex'] = False   # quadcog: no LaTeX"),
    ("AdaptiveQuadBench/aqb/experiments/plotting_utils.py",
     "rcParams['font.serif'] = ['cmr10']", "rcParams['font.serif'] = ['DejaVu Serif']"),
)


class AqbTree:
    """A patched AdaptiveQuadBench tree in the cache.

    Parameters
    ----------
    root : pathlib.Path
        The cache folder holding ``AdaptiveQuadBench/`` and ``rotorpy-pkg/``.
    """

    def __init__(self, root: Path) -> None:
        self.root = Path(root)

    @property
    def aqb(self) -> Path:
        """pathlib.Path: The AdaptiveQuadBench folder (``pip install -e`` it; holds ``run_eval.py``)."""
        return self.root / "AdaptiveQuadBench"

    @property
    def rotorpy(self) -> Path:
        """pathlib.Path: The folder whose ``pyproject.toml`` installs the RotorPy fork."""
        return self.root / "rotorpy-pkg"

    def stamp(self) -> dict:
        """What the set-up recorded: source, key, commits.

        Returns
        -------
        dict
            The JSON of the stamp file ({} when the tree is not complete).
        """
        f = self.root / _STAMP
        return json.loads(f.read_text()) if f.is_file() else {}


def vendor_tarball() -> Path:
    """Where the vendor tarball is: ``shared/vendor`` in the folder beside the checkout.

    Returns
    -------
    pathlib.Path
        The path (it may not exist).
    """
    return _ROOT.parent / "shared" / "vendor" / TARBALL


def _sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _sha256_tree(folder: Path) -> str:
    """A hash of a folder's files (relative paths and contents), .git and caches left out."""
    h = hashlib.sha256()
    for f in sorted(p for p in folder.rglob("*") if p.is_file()):
        rel = f.relative_to(folder)
        if rel.parts[0] == ".git" or "__pycache__" in rel.parts or rel.name == _STAMP:
            continue
        h.update(str(rel).encode() + b"\0" + f.read_bytes() + b"\0")
    return h.hexdigest()


def _layout(src: Path) -> tuple[Path, Path]:
    """(AdaptiveQuadBench folder, RotorPy package folder) of a source tree: the tarball's
    layout (``AdaptiveQuadBench/``, ``rotorpy-aqb/``) or a checkout with its submodule
    (``aqb/`` and a filled ``rotorpy/``)."""
    if (src / "AdaptiveQuadBench" / "aqb").is_dir() and (src / "rotorpy-aqb" / "simulate.py").is_file():
        return src / "AdaptiveQuadBench", src / "rotorpy-aqb"
    if (src / "aqb").is_dir() and (src / "rotorpy" / "simulate.py").is_file():
        return src, src / "rotorpy"
    raise InputError(f"${AQB_ENV} = {src}: expected an AdaptiveQuadBench checkout with its "
                     "rotorpy submodule filled (aqb/ and rotorpy/simulate.py), or the vendor "
                     "tarball's layout (AdaptiveQuadBench/ and rotorpy-aqb/), or the tarball")


def _patch(tree: Path) -> None:
    for rel, old, new in PATCHES:
        f = tree / rel
        text = f.read_text()
        if text.count(old) != 1:
            raise InputError(f"{f}: the CPU fix expects this text exactly once, found "
                             f"{text.count(old)} times (another AdaptiveQuadBench version?): "
                             f"{old.splitlines()[0]!r}")
        f.write_text(text.replace(old, new))


def _assemble(aqb_src: Path, rotorpy_src: Path, target: Path) -> None:
    ignore = shutil.ignore_patterns(".git", "__pycache__")
    shutil.copytree(aqb_src, target / "AdaptiveQuadBench", ignore=ignore)
    shutil.rmtree(target / "AdaptiveQuadBench" / "rotorpy", ignore_errors=True)  # the submodule
    pkg = target / "rotorpy-pkg"
    shutil.copytree(rotorpy_src, pkg / "rotorpy", ignore=ignore)
    # pip wants the pyproject one level above the package folder (vendor README)
    shutil.move(str(pkg / "rotorpy" / "pyproject.toml"), pkg / "pyproject.toml")
    for name in ("README.md", "LICENSE.md"):
        if (pkg / "rotorpy" / name).is_file():
            shutil.copyfile(pkg / "rotorpy" / name, pkg / name)


def prepare(source: str | os.PathLike[str] | None = None) -> AqbTree:
    """Put a patched AdaptiveQuadBench tree into the cache (once per source) and return it.

    Parameters
    ----------
    source : path, optional
        A tarball or a folder; default ``$QUADCOG_AQB``, else ``vendor_tarball()``.

    Returns
    -------
    AqbTree
        The patched copy in ``cache_dir() / "aqb" / <sha256>``.

    Raises
    ------
    quadcog.MissingDependencyError
        When there is no source (names where it looked).
    quadcog.InputError
        A tarball whose sha256 is not the vendor's, or a folder of another layout.
    """
    src = Path(source if source is not None else os.environ.get(AQB_ENV) or vendor_tarball())
    if not src.exists():
        raise MissingDependencyError(
            f"AdaptiveQuadBench: {src} does not exist; set ${AQB_ENV} to a checkout or put "
            f"{TARBALL} into {vendor_tarball().parent}")
    if src.is_file():
        key = _sha256_file(src)
        if src.name == TARBALL and key != TARBALL_SHA256:
            raise InputError(f"{src}: sha256 {key}, expected the vendor tarball's "
                             f"{TARBALL_SHA256} (shared/vendor/README.md)")
    else:
        key = _sha256_tree(src)
    target = cache_dir() / "aqb" / key
    tree = AqbTree(target)
    if tree.stamp():
        return tree
    target.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=".aqb-", dir=target.parent))
    try:
        if src.is_file():
            with tarfile.open(src) as tar:
                tar.extractall(work / "src", filter="data")
            aqb_src, rotorpy_src = _layout(work / "src")
        else:
            aqb_src, rotorpy_src = _layout(src)
        _assemble(aqb_src, rotorpy_src, work / "tree")
        _patch(work / "tree")
        commits = ({"aqb": AQB_COMMIT, "rotorpy": ROTORPY_COMMIT} if key == TARBALL_SHA256
                   else {"aqb": "user tree", "rotorpy": "user tree"})
        (work / "tree" / _STAMP).write_text(json.dumps(
            {"source": str(src), "sha256": key, "commits": commits,
             "patches": [rel for rel, _, _ in PATCHES]}, indent=1))
        shutil.rmtree(target, ignore_errors=True)
        os.replace(work / "tree", target)       # complete or absent, never half-patched
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return tree


def installed_tree() -> AqbTree | None:
    """The patched tree the importable ``aqb`` package comes from, if any.

    Returns
    -------
    AqbTree or None
        None when ``aqb`` or ``rotorpy`` (the fork, with ``attach_payload``) is not importable.
    """
    try:
        import aqb  # noqa: F401
        from rotorpy.vehicles.multirotor import Multirotor
    except ImportError:
        return None
    if not hasattr(Multirotor, "attach_payload"):      # PyPI's RotorPy, not the fork
        return None
    return AqbTree(Path(aqb.__file__).resolve().parent.parent.parent)


def require_aqb() -> AqbTree:
    """The installed tree, or an error that says how to set it up.

    Returns
    -------
    AqbTree
        ``installed_tree()``.

    Raises
    ------
    quadcog.MissingDependencyError
        When AdaptiveQuadBench or its RotorPy fork is not installed (gives ``SETUP_LINE``).
    """
    tree = installed_tree()
    if tree is None:
        raise MissingDependencyError(f"AdaptiveQuadBench and its RotorPy fork are not installed: "
                                     f"{SETUP_LINE}")
    return tree

