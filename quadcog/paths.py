"""Where generated/ and the compile cache are."""
import os
from pathlib import Path

GENERATED_ENV = "QUADCOG_GENERATED"
CACHE_ENV = "QUADCOG_CACHE_DIR"


def generated_dir():
    """generated/ beside the package (a repository checkout), or $QUADCOG_GENERATED."""
    env = os.environ.get(GENERATED_ENV)
    return Path(env) if env else Path(__file__).resolve().parent.parent / "generated"


def cache_dir():
    """$QUADCOG_CACHE_DIR, else $XDG_CACHE_HOME/quadcog, else ~/.cache/quadcog."""
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "quadcog"
