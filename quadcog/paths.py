"""Where the generated code and the compile cache are."""
import os
from pathlib import Path

__all__ = ["GENERATED_ENV", "CACHE_ENV", "shipped_generated_dir", "generated_dir", "cache_dir"]

GENERATED_ENV = "QUADCOG_GENERATED"
CACHE_ENV = "QUADCOG_CACHE_DIR"
_PACKAGE = Path(__file__).resolve().parent


def shipped_generated_dir() -> Path:
    """The copy of generated/ inside an installed package (wheel or sdist install).

    Returns
    -------
    pathlib.Path
        ``quadcog/_generated`` beside this module (it may not exist in a checkout).
    """
    return _PACKAGE / "_generated"


def generated_dir() -> Path:
    """Where the generated code is read from.

    Returns
    -------
    pathlib.Path
        $QUADCOG_GENERATED when set; else the copy shipped inside the package (an installed
        wheel); else generated/ beside the package (a checkout or an editable install).
    """
    env = os.environ.get(GENERATED_ENV)
    if env:
        return Path(env)
    shipped = shipped_generated_dir()
    return shipped if shipped.is_dir() else _PACKAGE.parent / "generated"


def cache_dir() -> Path:
    """The folder of the compile cache.

    Returns
    -------
    pathlib.Path
        $QUADCOG_CACHE_DIR, else $XDG_CACHE_HOME/quadcog, else ~/.cache/quadcog.
    """
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "quadcog"
