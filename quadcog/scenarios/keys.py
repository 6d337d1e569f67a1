"""``--set KEY=VALUE``: change any key of a scenario before it is validated.

KEY is a dotted path into the scenario file (``vehicle.m``, ``trajectory.kind``,
``controller_params.gamma``, ``cog.0.r`` for an entry of an array of tables); VALUE is a TOML
value (``0.8``, ``[0.06, 0, 0]``, ``true``, ``[{t = 1, r = [0.06, 0, 0]}]``) or, when it is not
valid TOML, a plain string (``controller=adaptive``). The result is validated exactly like the
file, so a wrong type or an unknown key is reported with the key's name.
"""
import copy
import tomllib

from quadcog.errors import InputError


class OverrideError(InputError):
    """A ``--set`` argument is malformed (no ``=``, empty key, a path through a non-table)."""


def parse_assignment(text):
    """``"vehicle.m=0.8"`` -> (("vehicle", "m"), 0.8)."""
    key, sep, value = text.partition("=")
    parts = tuple(p.strip() for p in key.split("."))
    if not sep or not all(parts):
        raise OverrideError(f"--set {text!r}: expected KEY=VALUE with a dotted KEY such as "
                            f"vehicle.m=0.8 or controller=adaptive")
    try:
        parsed = tomllib.loads(f"v = {value.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        parsed = value.strip()          # a bare word: controller=adaptive, trajectory.kind=circle
    return parts, parsed


def apply_overrides(data, assignments):
    """A copy of the parsed scenario ``data`` (dict) with each ``--set`` text applied in order.

    Returns (data, notes): ``notes`` lists what else changed, in words. When ``controller`` is
    changed, the file's ``controller_params`` that the new controller does not take are dropped
    (and named in ``notes``); the scenario validation reports any that a ``--set`` adds.
    """
    from quadcog.scenarios.scenario import CONTROLLER_PARAMS
    data, notes = copy.deepcopy(data), []
    set_keys = []
    for text in assignments:
        parts, value = parse_assignment(text)
        set_keys.append(parts)
        node = data
        for depth, part in enumerate(parts[:-1]):
            where = ".".join(parts[:depth + 1])
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise OverrideError(f"--set {text!r}: {where!r} is not an entry of the "
                                        f"array (it has {len(node)})")
                node = node[int(part)]
            elif isinstance(node, dict):
                node = node.setdefault(part, {})
            else:
                raise OverrideError(f"--set {text!r}: {'.'.join(parts[:depth])!r} is "
                                    f"{node!r}, not a table")
        last = parts[-1]
        if isinstance(node, list):
            if not last.isdigit() or int(last) > len(node):
                raise OverrideError(f"--set {text!r}: expected an index 0..{len(node)}")
            if int(last) == len(node):
                node.append(value)
            else:
                node[int(last)] = value
        elif isinstance(node, dict):
            node[last] = value
        else:
            raise OverrideError(f"--set {text!r}: {'.'.join(parts[:-1])!r} is {node!r}, "
                                f"not a table")
    controller = data.get("controller")
    if any(k == ("controller",) for k in set_keys) and controller in CONTROLLER_PARAMS:
        params = data.get("controller_params", {})
        explicit = {k[1] for k in set_keys if k[0] == "controller_params" and len(k) > 1}
        dropped = [k for k in params if k not in CONTROLLER_PARAMS[controller]
                   and k not in explicit]
        for k in dropped:
            del params[k]
        if dropped:
            notes.append(f"controller {controller!r} does not take controller_params "
                         f"{', '.join(dropped)} of the file: dropped")
    return data, notes
