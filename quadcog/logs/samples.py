"""Sample flight logs shipped inside the package, for the docs' examples and a first try.

Five real Crazyflie flights of the CrazyPAD data set (MIT licence, with the citation:
``quadcog/logs/sample_data/crazypad/README.md`` and ``LICENSE`` beside the files), so that
the examples run where quadcog was installed from a wheel, from any folder:

>>> from quadcog.logs import read_log
>>> from quadcog.logs.samples import sample
>>> log = read_log(sample("crazypad/motor_data/normal_flight/E8_log00"))

A sample's NAME is its path under ``sample_data/``; a folder's name stands for the logs in it
(``sample_logs``). ``quadcog identify`` takes ``sample:NAME`` where it takes a log file, and
``python -m quadcog.logs.samples`` prints every name.
"""
import os
from pathlib import Path
import sys

from quadcog.errors import LogError
from quadcog.validate import fail

__all__ = ["SAMPLE_FOLDER", "SAMPLE_PREFIX", "sample", "sample_logs", "sample_names",
           "resolve_log_argument"]

SAMPLE_FOLDER = Path(__file__).resolve().parent / "sample_data"
# the prefix of a command-line argument that names a sample instead of a file
SAMPLE_PREFIX = "sample:"
# beside the logs: their licence and citation, not logs
_NOT_LOGS = {"README.md", "LICENSE"}


def sample_names() -> list[str]:
    """The names of the shipped sample logs, sorted.

    Returns
    -------
    list of str
        Each log's path under ``SAMPLE_FOLDER``, with ``/`` separators.
    """
    return sorted(p.relative_to(SAMPLE_FOLDER).as_posix() for p in SAMPLE_FOLDER.rglob("*")
                  if p.is_file() and p.name not in _NOT_LOGS and "__pycache__" not in p.parts)


def _folders() -> set[str]:
    return {name.rsplit("/", k)[0] for name in sample_names() for k in range(1, name.count("/") + 1)}


def sample(name: str) -> Path:
    """The path of a shipped sample log, or of a folder of them.

    Parameters
    ----------
    name : str
        One of ``sample_names()`` (e.g. ``"crazypad/motor_data/normal_flight/E8_log00"``), or
        a folder of them (``"crazypad/motor_data/normal_flight"``).

    Returns
    -------
    pathlib.Path
        The file or folder inside the installed package.

    Raises
    ------
    LogError
        ``name`` is not a string or names no sample; the message lists the names.
    """
    names = sample_names()
    if not isinstance(name, str) or (name.strip("/") not in names
                                     and name.strip("/") not in _folders()):
        raise LogError(f"sample: {name!r} is no sample log of quadcog; expected one of "
                       f"{', '.join(names)} (or a folder of them)")
    return SAMPLE_FOLDER / name.strip("/")


def sample_logs(name: str) -> list[Path]:
    """The sample logs a name stands for: the file itself, or every log of a folder.

    Parameters
    ----------
    name : str
        A sample's name or a folder of samples, as for ``sample``.

    Returns
    -------
    list of pathlib.Path
        The log files, sorted by name.

    Raises
    ------
    LogError
        ``name`` names no sample.
    """
    path = sample(name)
    if path.is_file():
        return [path]
    return [SAMPLE_FOLDER / n for n in sample_names() if (SAMPLE_FOLDER / n).is_relative_to(path)]


def resolve_log_argument(argument: str | Path) -> list[Path]:
    """A command line's log argument as files: ``sample:NAME`` as ``sample_logs(NAME)``, any
    other argument as the one path it is.

    Parameters
    ----------
    argument : str or pathlib.Path
        A path, or ``SAMPLE_PREFIX`` followed by a sample's name.

    Returns
    -------
    list of pathlib.Path
        The files the argument stands for.

    Raises
    ------
    LogError
        ``sample:NAME`` with a NAME that names no sample, an empty argument (which ``Path``
        would read as the current folder), or one that is not a str or os.PathLike.
    """
    if isinstance(argument, bytes) or not isinstance(argument, (str, os.PathLike)) or \
            not isinstance(os.fspath(argument), str) or not os.fspath(argument):
        fail("log", "a log file's path or sample:NAME (a str or os.PathLike)", argument,
             LogError)
    text = os.fspath(argument)
    if text.startswith(SAMPLE_PREFIX):
        return sample_logs(text[len(SAMPLE_PREFIX):])
    return [Path(argument)]


if __name__ == "__main__":     # python -m quadcog.logs.samples [NAME ...]: names, or paths
    try:
        found = [p for arg in sys.argv[1:] for p in sample_logs(arg)]
    except LogError as e:
        sys.exit(f"error: {e}")
    print("\n".join(map(str, found)) if sys.argv[1:] else "\n".join(sample_names()))
