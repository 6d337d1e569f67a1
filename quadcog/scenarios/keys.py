"""The one grammar of scenario keys, for ``--set KEY=VALUE`` and for sweep files.

A key names a value the way the scenario file spells it: table names joined by ``.``, an
entry of an array in brackets: ``vehicle.m``, ``trajectory.kind``, ``controller_params.gamma``,
``cog[0].r`` (a 3-vector), ``cog[0].r[1]`` (one component). The spelling ``cog.0.r`` of earlier
releases is refused with a message that shows the bracket form.

``--set`` VALUE is a TOML value (``0.8``, ``[0.06, 0, 0]``, ``true``,
``[{t = 1, r = [0.06, 0, 0]}]``) or, when it is not valid TOML, a plain string
(``controller=adaptive``). The result is validated exactly like a file, so a wrong type or an
unknown key is reported with the key's name.
"""
from collections.abc import Sequence
import copy
import re
import tomllib
from typing import Any

from quadcog.errors import OverrideError
from quadcog.scenarios.schema import controller_params

__all__ = ["parse_key", "format_key", "set_key", "parse_assignment", "apply_overrides",
           "KEY_EXAMPLE"]

KEY_EXAMPLE = "names joined by '.', with [index] for arrays, like 'vehicle.m' or 'cog[0].r[1]'"
_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]|\.")
_DOTTED_INDEX = re.compile(r"\.(\d+)(?=\.|$)")


def parse_key(key: object) -> list[str | int] | None:
    """The parts of a key: ``"cog[0].r[1]"`` -> ``["cog", 0, "r", 1]``.

    Parameters
    ----------
    key : object
        The key as written.

    Returns
    -------
    list of str and int, or None
        Names and array indices in order; None when ``key`` is not a well-formed key.
    """
    if not isinstance(key, str) or not key or key[0] in ".[":
        return None
    tokens: list[str | int] = []
    pos, expect_name = 0, True
    while pos < len(key):
        m = _TOKEN.match(key, pos)
        if m is None:
            return None
        if m.group(1) is not None:
            if not expect_name:
                return None
            tokens.append(m.group(1))
            expect_name = False
        elif m.group(2) is not None:
            if expect_name:
                return None
            tokens.append(int(m.group(2)))
        else:
            if expect_name:
                return None
            expect_name = True
        pos = m.end()
    return None if expect_name else tokens


def format_key(tokens: list[str | int]) -> str:
    """The key of its parts: ``["cog", 0, "r"]`` -> ``"cog[0].r"``.

    Parameters
    ----------
    tokens : list of str and int
        Names and array indices.

    Returns
    -------
    str
        The key in the accepted spelling.
    """
    out = ""
    for t in tokens:
        out += f"[{t}]" if isinstance(t, int) else (f".{t}" if out else t)
    return out


def _not_a_key(key: object) -> str:
    """Why ``key`` is refused, with the accepted spelling when it is the old dotted-index one."""
    if isinstance(key, str) and _DOTTED_INDEX.search(key):
        fixed = _DOTTED_INDEX.sub(r"[\1]", key)
        if parse_key(fixed) is not None:
            return f"array entries are written in brackets: {fixed!r}, not {key!r}"
    return f"not a key (expected {KEY_EXAMPLE})"


def set_key(data: dict, key: str, value: Any, *, append: bool = False,
            error: type[Exception] = OverrideError, where: str | None = None) -> None:
    """Set ``value`` at ``key`` in a parsed scenario (in place).

    Parameters
    ----------
    data : dict
        The parsed scenario (nested tables and arrays).
    key : str
        A key of this module's grammar.
    value : Any
        The TOML-like value to put there.
    append : bool
        Allow the index one past the end of an array, which appends an entry (``--set``);
        otherwise the array must already hold the index (a sweep's base scenario says how many
        CoG changes there are).
    error : type of Exception
        The class raised (an InputError subclass: OverrideError for ``--set``, SweepError for
        sweep files).
    where : str, optional
        What to name in the message (default: ``key``).

    Returns
    -------
    None

    Raises
    ------
    error
        When the key is malformed or leads through something that is not a table or array.
    """
    name = key if where is None else where
    tokens = parse_key(key)
    if tokens is None:
        raise error(f"{name}: {_not_a_key(key)}")
    node: Any = data
    for depth, (here, nxt) in enumerate(zip(tokens, tokens[1:])):
        path = format_key(tokens[:depth + 1])
        if isinstance(here, int):
            if not isinstance(node, list) or here >= len(node):
                raise error(f"{name}: the scenario has no entry {path!r}"
                            + (f" (it has {len(node)})" if isinstance(node, list) else ""))
            node = node[here]
        else:
            if not isinstance(node, dict):
                raise error(f"{name}: {format_key(tokens[:depth]) or 'the scenario'!r} is "
                            f"{node!r}, not a table")
            if here not in node:
                if isinstance(nxt, int):
                    raise error(f"{name}: the scenario has no array {path!r}")
                node[here] = {}
            node = node[here]
    last = tokens[-1]
    if isinstance(last, int):
        size = len(node) if isinstance(node, list) else None
        if size is None or last > size or (last == size and not append):
            raise error(f"{name}: the scenario has no entry {format_key(tokens)!r}"
                        + ("" if size is None else f" (expected an index 0..{size - 1 + append})"))
        if last == size:
            node.append(value)
        else:
            node[last] = value
    else:
        if not isinstance(node, dict):
            raise error(f"{name}: {format_key(tokens[:-1])!r} is {node!r}, not a table")
        node[last] = value


def parse_assignment(text: str) -> tuple[str, Any]:
    """One ``--set`` argument: ``"vehicle.m=0.8"`` -> ``("vehicle.m", 0.8)``.

    Parameters
    ----------
    text : str
        ``KEY=VALUE``.

    Returns
    -------
    tuple of (str, Any)
        The key, and the value parsed as TOML (a plain string when it is not TOML).

    Raises
    ------
    quadcog.errors.OverrideError
        Without ``=`` or with a malformed key.
    """
    key, sep, value = text.partition("=")
    key = key.strip()
    if not sep or parse_key(key) is None:
        if sep and key:         # the grammar's own reason names the accepted spelling
            raise OverrideError(f"--set {text!r}: {_not_a_key(key)}")
        raise OverrideError(f"--set {text!r}: expected KEY=VALUE (KEY: {KEY_EXAMPLE}; e.g. "
                            f"vehicle.m=0.8 or controller=adaptive)")
    try:
        parsed = tomllib.loads(f"v = {value.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        parsed = value.strip()          # a bare word: controller=adaptive, trajectory.kind=circle
    except ValueError:                  # tomllib's int() past Python's digit limit (4300)
        from quadcog.files import one_line
        digits = sum(ch.isdigit() for ch in value)
        raise OverrideError(f"--set {key}={one_line(value.strip()[:12])}...: key {key!r}: "
                            f"expected a finite real number, got an integer of {digits} "
                            "digits") from None
    return key, parsed


def apply_overrides(data: dict[str, Any], assignments: Sequence[str]
                    ) -> tuple[dict[str, Any], list[str]]:
    """A copy of a parsed scenario with each ``--set`` text applied in order.

    Parameters
    ----------
    data : dict
        The parsed scenario file.
    assignments : sequence of str
        ``KEY=VALUE`` texts.

    Returns
    -------
    tuple of (dict, list of str)
        The changed copy, and notes on what else changed, in words: when ``controller`` is
        changed, the file's ``controller_params`` that the new controller does not take are
        dropped (and named); the scenario validation reports any that a ``--set`` adds.

    Raises
    ------
    quadcog.errors.OverrideError
        For a malformed argument or a key through a value that is not a table.
    """
    data, notes = copy.deepcopy(data), []
    set_keys = []
    for text in assignments:
        key, value = parse_assignment(text)
        set_keys.append(parse_key(key))
        set_key(data, key, value, append=True, where=f"--set {text!r}")
    controller = data.get("controller")
    schema = controller_params()
    # a list or table given as the controller is reported by the scenario validation
    if any(k == ["controller"] for k in set_keys) and isinstance(controller, str) \
            and controller in schema:
        params = data.get("controller_params", {})
        explicit = {k[1] for k in set_keys if k and k[0] == "controller_params" and len(k) > 1}
        dropped = [k for k in params if k not in schema[controller] and k not in explicit]
        for k in dropped:
            del params[k]
        if dropped:
            notes.append(f"controller {controller!r} does not take controller_params "
                         f"{', '.join(dropped)} of the file: dropped")
    return data, notes
