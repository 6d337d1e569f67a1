"""The shipped sweep files by name (``quadcog sweeps``), and any shipped file's text
(``quadcog scenarios --show NAME``, ``quadcog sweeps --show NAME``)."""
from quadcog.files import one_line
from quadcog.scenarios.lookup import SHIPPED, SUFFIX, read_toml, shipped_folder, shipped_names
from quadcog.validate import plain

__all__ = ["shipped_sweeps", "shipped_text"]


def shipped_sweeps() -> dict[str, str]:
    """The shipped sweep files with their descriptions.

    Returns
    -------
    dict of str to str
        {name: description}, in name order.
    """
    error = SHIPPED["sweep"][1]
    return {name: str(read_toml(shipped_folder("sweep") / f"{name}{SUFFIX}", error)
                      .get("description", ""))
            for name in shipped_names("sweep")}


def shipped_text(name: str, kind: str) -> str:
    """The text of a shipped file, to copy and edit.

    Parameters
    ----------
    name : str
        A shipped name (``"fig6"``, ``"failure-map"``).
    kind : str
        'scenario' or 'sweep'.

    Returns
    -------
    str
        The file's TOML text.

    Raises
    ------
    quadcog.errors.ScenarioError or quadcog.errors.SweepError
        When ``name`` is not a shipped name of ``kind``; the message lists them.
    """
    error = SHIPPED[kind][1]
    stem = name.removesuffix(SUFFIX) if isinstance(name, str) else None
    if stem not in shipped_names(kind):     # the name as given, shortened (it may be anything)
        shown = one_line(name, word=60) if isinstance(name, str) else plain(name)
        raise error(f"{shown}: no shipped {kind} of that name (shipped: "
                    f"{', '.join(shipped_names(kind))})")
    return (shipped_folder(kind) / f"{stem}{SUFFIX}").read_text(encoding="utf-8-sig")
