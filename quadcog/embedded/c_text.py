"""Text that reaches generated C from the caller: identifiers checked, comment text escaped.

``export_controller(..., name=..., command=...)`` puts ``name`` into file, function and macro
names and ``command`` into a ``/* ... */`` comment. A name must be a plain ASCII C identifier
(so it can neither break a declaration nor a file name); a comment text is reduced to one
line of printable ASCII in which no ``*/`` (which would end the comment and let the rest be
compiled) and no ``/*`` (a nested-comment warning) can appear: every other byte is written as
``\\xNN``, which in a comment is inert text.
"""
import re

from quadcog.errors import ExportError

__all__ = ["MAX_NAME", "MAX_COMMENT", "c_identifier", "comment_text"]

MAX_NAME = 48           # characters of <name>: quadcog_<name>_step stays below C99's 63
MAX_COMMENT = 400       # characters of a caller's text in a comment
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def c_identifier(name: object, where: str = "name") -> str:
    """``name`` when it is an ASCII C identifier of at most MAX_NAME characters.

    Parameters
    ----------
    name : object
        The caller's value.
    where : str
        The argument it came from, first in the message.

    Returns
    -------
    str
        ``name`` unchanged.

    Raises
    ------
    ExportError
        Not a string, not an identifier (spaces, punctuation, non-ASCII, a leading digit),
        or too long.
    """
    if not isinstance(name, str):
        raise ExportError(f"{where}: expected a C identifier (a string of ASCII letters, digits "
                          f"and _, not starting with a digit), got {name!r} "
                          f"({type(name).__name__})")
    if not _IDENTIFIER.match(name) or len(name) > MAX_NAME:
        raise ExportError(f"{where} {name!r} is not a C identifier of at most {MAX_NAME} "
                          f"characters (ASCII letters, digits and _, not starting with a digit)")
    return name


def comment_text(text: object, where: str = "command") -> str:
    """``text`` made safe inside a C block comment, on one line.

    Parameters
    ----------
    text : object
        The caller's text (must be a string).
    where : str
        The argument it came from, first in the message.

    Returns
    -------
    str
        Printable ASCII without ``*/`` or ``/*``; other characters as ``\\xNN``
        (``\\uNNNN`` beyond Latin-1); only the first MAX_COMMENT characters of ``text``
        (then ``...``).

    Raises
    ------
    ExportError
        ``text`` is not a string.
    """
    if not isinstance(text, str):
        raise ExportError(f"{where}: expected a string, got {text!r} ({type(text).__name__})")
    cut = len(text) > MAX_COMMENT
    out = []
    for ch in text[:MAX_COMMENT]:
        code = ord(ch)
        if 32 <= code < 127 and ch != "\\":
            out.append(ch)
        elif code < 256:
            out.append(f"\\x{code:02x}")
        else:
            out.append(f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}")
    safe = "".join(out)
    # "*/" and "/*" in either order and overlapping ("/*/"): break every star next to a slash
    safe = safe.replace("*/", "*\\x2f").replace("/*", "\\x2f*")
    return safe + ("..." if cut else "")
