"""Export a controller as a self-contained C99 module (``quadcog_<name>.h`` and ``.c``).

The exported step is one control period of the law that ``quadcog.simulate`` flies: U from
(x, ref, c) at the start of the period, then the controller state c takes one Euler step of
length dt and is mapped through the controller's projection. Works for any controller that
provides the public interface of ``quadcog.controllers.base.Controller``:

- ``function()``: CasADi SX Function (t, x (12), ref (14), c (n_state)) -> (U (4), c_dot),
  which must not depend on t (time enters through the reference);
- ``n_state``, ``initial_state()`` (numbers) and ``project(c)`` (SX -> SX);
- ``nominal`` (14,): the vehicle parameters the law was built for.
"""
from contextlib import ExitStack
import os
from pathlib import Path

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from quadcog import config
from quadcog.controllers.base import Controller
from quadcog.controllers.registry import CONTROLLERS, make_controller
from quadcog.embedded.c_text import c_identifier, comment_text
from quadcog.embedded.emit import C_TYPE, PRECISIONS, body, literal
from quadcog.errors import ExportError, QuadcogError
from quadcog.files import RunFiles, output_path
from quadcog.model.conventions import N_STATE, PARAM_NAMES, STATE_NAMES
from quadcog.trajectories.analytic import REF_SIZE

__all__ = ["NOTICE", "PARAM_UNITS", "file_names", "out_folder", "write_files", "short_name",
           "step_function", "documented_constants", "render", "export_controller"]

# {command}: what wrote the file (`make embedded`, the `quadcog export` line, the Python call)
NOTICE = ("DO NOT EDIT: written by `{command}` from the controllers in quadcog/controllers/; "
          "change those and re-export.")
PARAM_UNITS = {"m": "kg", "g": "m/s^2", "Ixx": "kg m^2", "Iyy": "kg m^2", "Izz": "kg m^2",
               "c_x": "N s/m", "c_y": "N s/m", "c_z": "N s/m", "c_phi": "N m s/rad",
               "c_theta": "N m s/rad", "c_psi": "N m s/rad", "x_G": "m", "y_G": "m", "z_G": "m"}


def short_name(controller: Controller) -> str:
    """The short name of a controller ('pd', 'fl', 'adaptive', ...).

    Parameters
    ----------
    controller : quadcog.Controller
        The controller.

    Returns
    -------
    str
        Its key in ``quadcog.controllers.CONTROLLERS``, else its ``name`` attribute (else its
        class name).
    """
    for key, cls in CONTROLLERS.items():
        if type(controller) is cls:
            return key
    return str(getattr(controller, "name", type(controller).__name__))


def step_function(controller: Controller) -> ca.Function:
    """One control period of a controller as an SX Function.

    Parameters
    ----------
    controller : quadcog.Controller
        The controller (see the module docstring for what it must provide).

    Returns
    -------
    casadi.Function
        step(x (12), ref (14), c (n_state), dt) -> (U (4), c_next (n_state)) with x in
        [m, rad, m/s, rad/s], ref as ``quadcog.trajectories.analytic``, dt [s], U [N, N m];
        c_next = project(c + dt c_dot): the Euler update of ``quadcog.sim.closed_loop``.

    Raises
    ------
    quadcog.errors.ExportError
        When the law depends on the time t.
    """
    nc = int(controller.n_state)
    law = controller.function()
    t = ca.SX.sym("t")
    x, ref = ca.SX.sym("x", N_STATE), ca.SX.sym("ref", REF_SIZE)
    c, dt = ca.SX.sym("c", nc), ca.SX.sym("dt")
    U, c_dot = law(t, x, ref, c)
    if ca.depends_on(ca.vertcat(U, c_dot), t):
        raise ExportError(f"controller {short_name(controller)!r}: its law depends on the time "
                          "t, which the exported step does not take; feed time-varying "
                          "terms through the reference")
    U, c_dot = law(0.0, x, ref, c)
    c_next = controller.project(c + dt * c_dot) if nc else ca.SX(0, 1)
    U, c_next = ca.cse([ca.SX(U), ca.SX(c_next)])
    return ca.Function("step", [x, ref, c, dt], [U, c_next],
                       ["x", "ref", "c", "dt"], ["U", "c_next"])


def _numbers(value):
    """A real array of at most 64 entries, or None for anything else."""
    if isinstance(value, bool) or value is None:
        return None
    if isinstance(value, (int, float, np.floating, np.integer, tuple, list, np.ndarray)):
        try:
            a = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            return None
        return a if a.size <= 64 else None
    return None


def documented_constants(controller: Controller) -> list[tuple[str, NDArray[np.float64]]]:
    """The controller's public numeric settings, for the header's comment.

    Parameters
    ----------
    controller : quadcog.Controller
        The controller.

    Returns
    -------
    list of (str, numpy.ndarray)
        [(name, array)] by name (generic: any public attribute that is a number or a real
        array of at most 64 entries, and dicts of those as ``name[key]``), in SI units.
    """
    out = []
    for name in sorted(vars(controller)):
        if name.startswith("_") or name in ("nominal", "model"):
            continue
        value = getattr(controller, name)
        items = value.items() if isinstance(value, dict) else [(None, value)]
        for key, v in items:
            a = _numbers(v)
            if a is not None:
                out.append((name if key is None else f"{name}[{key}]", a))
    return out


def _fmt(a):
    a = a + 0.0                # no "-0" in the text
    if a.ndim == 0:
        return f"{float(a):.6g}"
    if a.ndim == 1:
        return "[" + ", ".join(f"{v:.6g}" for v in a) + "]"
    return "[" + "; ".join(", ".join(f"{v:.6g}" for v in row) for row in a) + "]"


def _header(name, controller, precision, command, nc, dt=None):
    N = name.upper()
    c_type = C_TYPE[precision]
    is_float = 1 if precision == "float32" else 0
    dt = config.get("simulate.dt", dt)
    p = controller.nominal
    params = [f" *   {n:<8s} = {v:.6g} {PARAM_UNITS[n]}" for n, v in zip(PARAM_NAMES, p)]
    consts = []
    for cname, a in documented_constants(controller):
        text = f" *   {cname} = {_fmt(a)}"
        while len(text) > 96:              # wrap long matrices
            cut = text.rfind(", ", 0, 96) + 1
            consts.append(text[:cut])
            text = " *       " + text[cut:].lstrip()
        consts.append(text)
    init = controller.initial_state()
    lines = [
        f"/* {NOTICE.format(command=command)} */",
        f"/* quadcog_{name}: {type(controller).__name__} ({type(controller).__module__}) as a",
        f" * C99 module in {c_type} ({precision})",
        " *",
        f" * Designed for: a control period of dt = {dt:g} s ({1 / dt:g} Hz), fed the state "
        "estimate",
        " * at the start of the period; U is held over the period. Frames and signs: ground frame",
        " * {G} inertial, z up,",
        " * gravity -g e_z; body frame {A} with origin O at the rotor-plane centre, x forward, "
        "z up",
        " * along the thrust (a z-down NED/FRD estimate must be converted: see the README, "
        "\"On a",
        " * flight controller\"); ZYX Euler angles, R = Rz(psi) Ry(theta) Rx(phi) maps body to "
        "ground.",
        f" * x (12) = [{', '.join(STATE_NAMES)}]: position of O (m, ground),",
        " *   Euler angles (rad), body velocities u, v, w (m/s, body axes), body rates p, q, r "
        "(rad/s).",
        " * ref (14) = position (3, m), velocity (3, m/s), acceleration (3, m/s^2), "
        "jerk (3, m/s^3),",
        " *   all in the ground frame, then yaw (rad) and yaw rate (rad/s).",
        " * U (4) = [U1 thrust along body z (N), U2, U3, U4 body moments about O (N m)]; "
        "map to rotor",
        " *   thrusts with the inverse of the vehicle's mixer.",
        f" * c ({max(nc, 1)}) = the controller state"
        + (" (NC = 0: unused, pass any 1-entry array)." if nc == 0 else
           f" ({nc} entries; the adaptive laws: r_hat, the CoG estimate, m, body axes)."),
        f" *   quadcog_{name}_init sets it to [{', '.join(f'{v:g}' for v in init)}]"
        if nc else " *   quadcog_" + name + "_init writes 0.",
        " *",
        " * Nominal vehicle parameters baked into the code (the controller's model):",
        *params,
        " * Gains and settings baked into the code (SI units: m, s, rad, N):",
        *consts,
        " *",
        " * No heap, no globals, no I/O; only <math.h>. Re-entrant: all state is in c[].",
        " */",
        f"#ifndef QUADCOG_{N}_H",
        f"#define QUADCOG_{N}_H",
        "",
        "#ifndef QUADCOG_REAL_IS_FLOAT",
        f"#define QUADCOG_REAL_IS_FLOAT {is_float}",
        f"typedef {c_type} qc_real;",
        f"#elif QUADCOG_REAL_IS_FLOAT != {is_float}",
        "#error \"quadcog modules of different precisions included in one translation unit\"",
        "#endif",
        "",
        "/* size of the controller state c */",
        f"#define QUADCOG_{N}_NC {nc}",
        "",
        "#ifdef __cplusplus",
        "extern \"C\" {",
        "#endif",
        "",
        f"/* c has max(QUADCOG_{N}_NC, 1) entries */",
        f"void quadcog_{name}_init(qc_real c[]);",
        "",
        "/* One control period: state x (12), reference ref (14), controller state c (updated in",
        "   place by one Euler step of length dt, projection included), output U (4). */",
        f"void quadcog_{name}_step(const qc_real x[12], const qc_real ref[14], qc_real c[],",
        f"{' ' * (len(name) + 19)}qc_real dt, qc_real U[4]);",
        "",
        "#ifdef __cplusplus",
        "}",
        "#endif",
        "",
        f"#endif /* QUADCOG_{N}_H */",
    ]
    return "\n".join(lines) + "\n"


def _source(name, controller, precision, command, fn):
    nc = int(controller.n_state)
    decls, stmts, read = body(fn, precision, ["x", "ref", "c", "dt"], ["U", "c_next"])
    init = controller.initial_state()
    lines = [f"/* {NOTICE.format(command=command)} */",
             f"/* quadcog_{name} ({precision}): see quadcog_{name}.h. {fn.n_instructions()} "
             "straight-line operations. */",
             "#include <math.h>",
             "",
             f"#include \"quadcog_{name}.h\"",
             "",
             f"void quadcog_{name}_init(qc_real c[])",
             "{"]
    if nc:
        lines += [f"    c[{k}] = {literal(v, precision)};" for k, v in enumerate(init)]
    else:
        lines.append(f"    c[0] = {literal(0.0, precision)};")
    lines += ["}", "",
              f"void quadcog_{name}_step(const qc_real x[12], const qc_real ref[14], qc_real c[],",
              f"{' ' * (len(name) + 19)}qc_real dt, qc_real U[4])",
              "{",
              # c is read while c_next is written: keep the new state apart until the end
              *([f"    qc_real c_next[{nc}];"] if nc else []),
              *decls]
    lines += [f"    (void){arg};" for k, arg in enumerate(("x", "ref", "c", "dt"))
              if k not in read]
    lines += stmts
    lines += [f"    c[{k}] = c_next[{k}];" for k in range(nc)]
    lines += ["}"]
    return "\n".join(lines) + "\n"


def render(controller: Controller, precision: str = "float32", name: str | None = None,
           command: str | None = None, dt: float | None = None) -> dict[str, str]:
    """The exported module's files as text.

    Parameters
    ----------
    controller : quadcog.Controller
        The controller.
    precision : str
        'float32' or 'double'.
    name : str, optional
        The C name part ``quadcog_<name>`` (default: ``short_name(controller)``).
    command : str, optional
        What wrote the files, named in their first line (default: the Python call
        ``quadcog.embedded.export_controller(<class>(...), precision=...)``).
    dt : float, optional
        The control period the header says the law is designed for (s; default
        ``quadcog.config.defaults["simulate.dt"]``).

    Returns
    -------
    dict of str to str
        {file name: text} of the header and the source.

    Raises
    ------
    quadcog.errors.ExportError
        For an unknown precision, something that is not a Controller, a name that is not a
        C identifier, or a law that depends on t.
    """
    if precision not in PRECISIONS:
        raise ExportError(f"precision must be one of {PRECISIONS}, got {precision!r}")
    if not isinstance(controller, Controller):
        raise ExportError(f"controller must be a quadcog Controller or one of "
                          f"{tuple(CONTROLLERS)}, got {controller!r}")
    name = c_identifier(short_name(controller) if name is None else name, "name")
    command = comment_text(command, "command") if command is not None else (
        f"quadcog.embedded.export_controller({type(controller).__name__}(...), "
        f"precision={precision!r})")
    fn = step_function(controller)
    header, source = file_names(name)
    return {header: _header(name, controller, precision, command, int(controller.n_state), dt),
            source: _source(name, controller, precision, command, fn)}


def file_names(name: str) -> tuple[str, str]:
    """The names of the header and the source exported for a law named ``name``.

    Parameters
    ----------
    name : str
        The law's C name part (``<name>`` of ``quadcog_<name>_step``).

    Returns
    -------
    (str, str)
        ``quadcog_<name>.h`` and ``quadcog_<name>.c``.
    """
    return f"quadcog_{name}.h", f"quadcog_{name}.c"


def export_controller(controller: str | Controller, precision: str = "float32",
                      out: str | os.PathLike[str] = ".", name: str | None = None,
                      command: str | None = None) -> list[Path]:
    """Write ``quadcog_<name>.h`` and ``.c`` into the folder ``out``; returns their paths.

    Parameters
    ----------
    controller : str or Controller
        A short name ('pd', 'fl', 'adaptive', or any key of ``quadcog.controllers.CONTROLLERS``;
        built with its default settings) or a controller object.
    precision : {'float32', 'double'}
        The C type of every quantity.
    out : path
        Folder to write into (created when missing).
    name : str, optional
        ``<name>`` in the file and function names; default the controller's short name.
    command : str, optional
        What wrote the files, named in their first line (``quadcog export`` passes its command
        line; default: this Python call).

    Returns
    -------
    list of Path
        The header and the source.

    Raises
    ------
    quadcog.errors.ExportError
        For an unknown precision, a name that is not a C identifier, or a folder that cannot
        be made.
    quadcog.errors.InputError
        For an unknown controller name.
    """
    out = out_folder(out)
    if name is not None:
        c_identifier(name, "name")
    if isinstance(controller, str):
        if controller not in CONTROLLERS:
            raise ExportError(f"controller {controller!r}: expected one of "
                              f"{tuple(CONTROLLERS)} or a quadcog Controller")
        if command is None:                     # the call that wrote it (the CLI passes its line)
            command = f"quadcog.embedded.export_controller({controller!r}, {precision!r})"
        name = name if name is not None else c_identifier(controller, "controller")
        controller = make_controller(controller)
    return write_files(render(controller, precision, name, command), out, "exported file")


def out_folder(out: object) -> Path:
    """``out`` checked as the folder of an export: a non-empty str or os.PathLike without a
    null byte (``''`` wrote into the working folder; ``'.'`` says so).

    Parameters
    ----------
    out : object
        What the caller passed.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    quadcog.errors.ExportError
        Naming the value.
    """
    if not isinstance(out, (str, os.PathLike)) or "\0" in os.fspath(out) or not os.fspath(out):
        raise ExportError(f"out: expected a folder path (str or os.PathLike; '.' for the "
                          f"working folder), got {out!r:.60} ({type(out).__name__})")
    return Path(out)


def write_files(files: dict[str, str], out: Path, what: str) -> list[Path]:
    """Write ``files`` into ``out`` together or not at all.

    Every file goes to a temporary name first (``quadcog.files.RunFiles``, one per folder),
    then all are renamed: a failure or Ctrl-C leaves what was there, never a new header
    beside an old source. A folder, link, FIFO or device in a file's place is refused
    before anything is written (never written through).

    Parameters
    ----------
    files : dict of str to str
        {path relative to ``out``: text}.
    out : pathlib.Path
        The folder (made when missing).
    what : str
        What a file is, for messages ("exported file", "app file").

    Returns
    -------
    list of pathlib.Path
        The files written, in the order of ``files``.

    Raises
    ------
    quadcog.errors.ExportError
        Naming the file or folder that could not be written, and why.
    """
    for rel in files:
        if os.path.lexists(out / rel):
            output_path(out / rel, what, ExportError)
    try:
        with ExitStack() as stack:
            folders: dict[Path, RunFiles] = {}
            for rel, text in files.items():
                folder = (out / rel).parent
                if folder not in folders:
                    folders[folder] = stack.enter_context(RunFiles(folder, owned=()))
                folders[folder].path(rel).write_text(text)
    except OSError as e:
        raise ExportError(f"{e.filename or out}: cannot write the {what} ({e.strerror})") from None
    except QuadcogError as e:
        if isinstance(e, ExportError):
            raise
        raise ExportError(f"out = {str(out)!r}: {e}") from None
    return [out / rel for rel in files]
