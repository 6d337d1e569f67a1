"""``make embedded``: export every controller in both precisions into generated/embedded/,
compile each with the strict flags on the host (and for the Cortex-M4), run each on the
Cortex-M4 in QEMU over a recorded flight, and print the cost table."""
from collections.abc import Sequence
import difflib
import os
from pathlib import Path
import tempfile
from typing import Any

import numpy as np
from numpy.typing import NDArray

from quadcog.controllers.registry import controller_names, make_controller
from quadcog.embedded import target
from quadcog.embedded.controller_export import render
from quadcog.embedded.emit import PRECISIONS
from quadcog.embedded.host import build_host_library
from quadcog.files import atomic_write, run_stamp, strict_json
from quadcog.paths import generated_dir

__all__ = ["CONTROLLERS", "RECORDING", "embedded_dir", "COMMAND", "render_all", "check",
           "write", "recording", "target_costs", "cost_table", "write_costs", "main"]

# The paper's three laws; controllers added to CONTROLLERS later export the same way.
CONTROLLERS = controller_names()
RECORDING = ("fig6", 900, 2900)      # scenario, first and end step: 2 s around the CoG step
COMMAND = "make embedded"            # what the committed modules name as their writer


def embedded_dir() -> Path:
    """The committed exported modules' folder.

    Returns
    -------
    pathlib.Path
        ``generated/embedded/`` (``quadcog/_generated/embedded/`` when installed).
    """
    return Path(generated_dir()) / "embedded"


def render_all(names: Sequence[str] = CONTROLLERS) -> dict[str, str]:
    """Every exported module, as committed in generated/embedded/.

    Parameters
    ----------
    names : sequence of str
        The controllers' short names.

    Returns
    -------
    dict of str to str
        {relative path (``<precision>/quadcog_<name>.h``): text}.
    """
    files = {}
    for name in names:
        ctl = make_controller(name)
        for precision in PRECISIONS:
            for fname, text in render(ctl, precision, name, COMMAND).items():
                files[f"{precision}/{fname}"] = text
    return files


def check(folder: str | os.PathLike[str] | None = None,
          files: dict[str, str] | None = None) -> str:
    """Whether a folder holds exactly what the exporter writes.

    Parameters
    ----------
    folder : str or os.PathLike, optional
        Default ``embedded_dir()``.
    files : dict of str to str, optional
        What the exporter writes (default ``render_all()``).

    Returns
    -------
    str
        '' when they agree, else a diff (at most 300 lines).
    """
    folder = Path(folder or embedded_dir())
    files = render_all() if files is None else files
    on_disk = {p.relative_to(folder).as_posix(): p for p in sorted(folder.rglob("*"))
               if p.is_file()} if folder.is_dir() else {}
    out = []
    for rel in sorted(set(files) | set(on_disk)):
        if rel not in files:
            out.append(f"only in {folder}: {rel}\n")
        elif rel not in on_disk:
            out.append(f"missing in {folder}: {rel}\n")
        else:
            old = on_disk[rel].read_text()
            if old != files[rel]:
                out.extend(difflib.unified_diff(old.splitlines(True), files[rel].splitlines(True),
                                                f"{folder}/{rel}", f"exporter/{rel}"))
    return "".join(out[:300])


def write(folder: str | os.PathLike[str] | None = None,
          files: dict[str, str] | None = None) -> Path:
    """Write the exported modules, and delete those no longer exported.

    Parameters
    ----------
    folder : str or os.PathLike, optional
        Default ``embedded_dir()``.
    files : dict of str to str, optional
        {relative path: text} (default ``render_all()``).

    Returns
    -------
    pathlib.Path
        The folder.
    """
    folder = Path(folder or embedded_dir())
    files = render_all() if files is None else files
    for rel, text in files.items():
        path = folder / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    for path in sorted(folder.rglob("*")):           # drop modules no longer exported
        if path.is_file() and path.relative_to(folder).as_posix() not in files:
            path.unlink()
    return folder


def recording() -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """States and references of a host flight, for the target runs.

    Returns
    -------
    tuple of (numpy.ndarray, numpy.ndarray, float)
        x (N, 12) [m, rad, m/s, rad/s], ref (N, 14) and dt [s] of the steps of ``RECORDING``
        (the compiled path of its scenario).
    """
    from quadcog.scenarios.scenario import load_scenario
    scenario, first, end = RECORDING
    sc = load_scenario(scenario)
    res = sc.run()
    return res.x[first:end], res.ref[first:end], sc.dt


def target_costs(folder: str | os.PathLike[str] | None = None,
                 names: Sequence[str] = CONTROLLERS,
                 work: str | os.PathLike[str] | None = None) -> list[dict[str, Any]]:
    """Run every module of ``folder`` on the Cortex-M4 in QEMU and on the host.

    Parameters
    ----------
    folder : str or os.PathLike, optional
        The exported modules (default ``embedded_dir()``).
    names : sequence of str
        The controllers' short names.
    work : str or os.PathLike, optional
        Build folder (default: a temporary one).

    Returns
    -------
    list of dict
        One row per controller and precision: {controller, precision, flash, ram (B),
        stack_static, stack_measured (B), instructions_mean, instructions_max, max_U_diff
        (N, N m), max_c_diff, rel_diff, calibration}.

    Raises
    ------
    quadcog.errors.TargetError
        When the cross tools are missing or a run fails.
    """
    folder = Path(folder or embedded_dir())
    x, ref, dt = recording()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(work or tmp)
        for precision in PRECISIONS:
            data = work / precision
            data.mkdir(parents=True, exist_ok=True)
            target.write_data(data / "harness_data.h", x, ref, dt, precision)
            for name in names:
                nc = int(make_controller(name).n_state)
                module = folder / precision
                elf = target.build_target(module, name, nc, data, data)
                exe = target.build_host_harness(module, name, nc, data, data)
                U, c, info = target.parse_output(target.run_qemu(elf), precision, nc)
                U_h, c_h, _ = target.parse_output(target.run_host(exe), precision, nc)
                size = target.object_cost(data / f"quadcog_{name}.o")
                rows.append(dict(
                    controller=name, precision=precision, flash=size["text"] + size["data"],
                    ram=size["data"] + size["bss"], stack_static=size["stack"],
                    stack_measured=info["stack_bytes"],
                    instructions_mean=info["instructions_mean"],
                    instructions_max=info["instructions_max"],
                    max_U_diff=float(abs(U - U_h).max()),
                    max_c_diff=float(abs(c - c_h).max()) if nc else 0.0,
                    rel_diff=max(target.relative_difference(U, U_h),
                                 target.relative_difference(c, c_h, per_column=False)),
                    calibration=(info["calibration_counted"], info["calibration_true"])))
    return rows


def cost_table(rows: Sequence[dict[str, Any]]) -> str:
    """The cost table as Markdown.

    Parameters
    ----------
    rows : sequence of dict
        The rows of ``target_costs``.

    Returns
    -------
    str
        The table, with the time per step at 168 MHz [us].
    """
    head = ("| controller | precision | flash (B) | RAM (B) | stack, -fstack-usage (B) | "
            "stack, measured (B) | instructions per step, mean | max | at 168 MHz (us) |\n"
            "|---|---|---|---|---|---|---|---|---|\n")
    lines = [f"| {r['controller']} | {r['precision']} | {r['flash']} | {r['ram']} | "
             f"{r['stack_static']} | {r['stack_measured']} | {r['instructions_mean']:.0f} | "
             f"{r['instructions_max']:.0f} | {r['instructions_mean'] / 168:.1f} |"
             for r in rows]
    return head + "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m quadcog.embedded`` (``make embedded``).

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments (default: the command line's).

    Returns
    -------
    int
        The exit status: 0, or 1 when generated/embedded/ is stale (``--check``) or a target
        run is off its tolerance.
    """
    import argparse
    import sys
    import time
    ap = argparse.ArgumentParser(prog="python -m quadcog.embedded", description=__doc__)
    ap.add_argument("--check", action="store_true",
                    help="only compare generated/embedded/ with the exporter; write nothing")
    ap.add_argument("--no-target", action="store_true",
                    help="skip the Cortex-M4 build and the QEMU runs")
    ap.add_argument("--out", type=Path, default=Path("out") / "embedded",
                    help="folder for costs.json, the cost table and the target-vs-host "
                         "differences (default out/embedded; bench/publish.py embedded copies "
                         "them into the docs)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    files = render_all()
    if args.check:
        diff = check(files=files)
        if diff:
            sys.stderr.write(f"generated/embedded/ is stale; run `make embedded`:\n{diff}")
            return 1
        print("generated/embedded/ is up to date")
        return 0
    folder = write(files=files)
    print(f"exported {len(files) // 2} modules into {folder} ({time.perf_counter() - t0:.1f} s)")
    with tempfile.TemporaryDirectory() as tmp:
        for precision in PRECISIONS:
            build_host_library(folder / precision, CONTROLLERS, Path(tmp) / f"{precision}.so")
    print("host: every module compiles with " + " ".join(target.STRICT_FLAGS))
    if args.no_target:
        return 0
    missing = target.missing_tools()
    if missing:
        print(f"no Cortex-M4 run: missing {', '.join(missing)}; install (as root): "
              f"apt-get install -y --no-install-recommends {target.DEBIAN_PACKAGES}")
        return 0
    rows = target_costs(folder)
    x_steps = RECORDING[2] - RECORDING[1]
    print(f"Cortex-M4 (QEMU {target.BOARD}, -icount shift=0), {x_steps} recorded steps of "
          f"{RECORDING[0]}; calibration loop counted "
          f"{rows[0]['calibration'][0]} of {rows[0]['calibration'][1]} instructions:")
    print(cost_table(rows), end="")
    bad = 0
    for r in rows:
        tol = target.target_rtol(r["controller"], r["precision"])
        ok = r["rel_diff"] <= tol
        bad += not ok
        print(f"  {r['controller']:>8s} {r['precision']:>7s}: target vs host build, max |dU| = "
              f"{r['max_U_diff']:.3g} N (N m), max |dc| = {r['max_c_diff']:.3g}, relative "
              f"{r['rel_diff']:.2g} (tolerance {tol:g})"
              + ("" if ok else "  FAILED"))
    if rows[0]["calibration"][0] != rows[0]["calibration"][1]:
        print("the instruction count is not exact: the calibration loop was miscounted")
        bad += 1
    write_costs(rows, args.out / "costs.json")
    print(f"wrote {args.out / 'costs.json'}")
    return 1 if bad else 0


def write_costs(rows: Sequence[dict[str, Any]], path: str | os.PathLike[str]) -> None:
    """Write the target run's figures as JSON: the machine, the cost table (Markdown), each
    row, and per precision the largest target-vs-host difference (the figures the docs quote).

    Parameters
    ----------
    rows : sequence of dict
        The rows of ``target_costs``.
    path : str or os.PathLike
        The JSON file (its folder is created).
    """
    # the laws with a float32 tolerance of their own (their filters accumulate) apart
    apart = tuple(target.TARGET_RTOL_FLOAT32)

    def largest(precision, key, which):
        """Over the law ``which``, or (None) over every law not kept apart."""
        chosen = ((lambda name: name not in apart) if which is None
                  else (lambda name: name == which))
        return max(r[key] for r in rows if r["precision"] == precision and chosen(r["controller"]))

    summary = {
        "machine": f"QEMU {target.BOARD} (-icount shift=0), run {run_stamp()}",
        "table": cost_table(rows),
        "rows": [{k: v for k, v in r.items()} for r in rows],
        # the same rows by law and precision, so that a page names the row it quotes
        "cost": {name: {r["precision"]: r for r in rows if r["controller"] == name}
                 for name in dict.fromkeys(r["controller"] for r in rows)},
        "largest": {precision: {key: largest(precision, key, None)
                                for key in ("max_U_diff", "max_c_diff", "rel_diff")}
                    for precision in PRECISIONS},
        **{name: {precision: {key: largest(precision, key, name)
                              for key in ("max_U_diff", "max_c_diff", "rel_diff")}
                  for precision in PRECISIONS} for name in apart},
    }
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, strict_json(summary))
