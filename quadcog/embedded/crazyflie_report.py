"""``make crazyflie-app``: quadcog's laws as Crazyflie out-of-tree controllers, built into
``cf2.elf``, with the flash and RAM they add, their instructions per call on a Cortex-M4 in
QEMU against the 500 Hz budget, and their host agreement with quadcog's own law.

The flight that both the agreement and the QEMU recording use (``agreement_flight``): the
default trajectory ``circle`` for 5 s at the app's 500 Hz, with the CoG ramped 4 mm forward
and 4 mm left over 0.5 s from t = 1 s, on the app's vehicle.
"""
import argparse
from collections.abc import Sequence
import os
from pathlib import Path
import tempfile
from typing import Any

from quadcog.controllers.registry import make_controller
from quadcog.embedded import crazyflie_firmware as firmware
from quadcog.embedded import target
from quadcog.embedded.crazyflie_app import CONTROL_PERIOD, RATE, resolve_vehicle, write_crazyflie_app
from quadcog.embedded.crazyflie_host import HOST_INCLUDES, HostApp, agreement, build_host_app, firmware_units
from quadcog.embedded.host import compile_checked
from quadcog.sim.flight import simulate
from quadcog.sim.result import SimulationResult
from quadcog.sim.timeline import CogProfile
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["LAWS", "CLOCK_HZ", "BUDGET_CYCLES", "FIRMWARE_OPT", "COG_RAMP", "STABILIZER_STACK",
           "agreement_flight", "host_agreement", "law_cost", "boundary_frame", "report", "table",
           "main"]

LAWS = ("composite", "payload_adaptive")
CLOCK_HZ = 168_000_000                    # the Crazyflie 2.x's STM32F405
BUDGET_CYCLES = CLOCK_HZ // RATE           # 336,000 per call at 500 Hz
FIRMWARE_OPT = ("-Os",)                    # the firmware's optimization (its Makefile)
COG_RAMP = (1.0, (0.004, 0.004, 0.0), 0.5)  # t (s), r_G step (m, body), ramp (s)
# bytes of the stabilizer task's stack, on which the controller runs: config.h's
# STABILIZER_TASK_STACKSIZE, 3 * configMINIMAL_STACK_SIZE (150) words of 4 bytes
STABILIZER_STACK = 3 * 150 * 4


def agreement_flight(name: str, vehicle: Vehicle) -> SimulationResult:
    """quadcog's flight of a law that its Crazyflie app is compared with.

    Parameters
    ----------
    name : str
        The law's short name.
    vehicle : quadcog.vehicles.Vehicle
        The vehicle the law is designed for and flies.

    Returns
    -------
    SimulationResult
        5 s of ``circle`` at dt = ``CONTROL_PERIOD`` with ``COG_RAMP``.
    """
    return simulate(make_controller(name, vehicle=vehicle), "circle", duration=5.0,
                    dt=CONTROL_PERIOD, vehicle=vehicle, cog=CogProfile([COG_RAMP]))


def host_agreement(app: str | os.PathLike[str], flight: SimulationResult,
                   firmware_tree: str | os.PathLike[str],
                   work: str | os.PathLike[str]) -> dict[str, float]:
    """The app's C, built for the host with the firmware's headers, over a quadcog flight.

    Parameters
    ----------
    app : str or os.PathLike
        The app folder.
    flight : SimulationResult
        quadcog's flight of the same law (``agreement_flight``).
    firmware_tree : str or os.PathLike
        A firmware tree (headers).
    work : str or os.PathLike
        Where the host library goes.

    Returns
    -------
    dict of str to float
        ``crazyflie_host.agreement`` of the app's commands with ``flight.U``.
    """
    host = HostApp(build_host_app(app, firmware_tree, Path(work) / "host_app.so"))
    host.init()
    out = host.run(*firmware_units(flight.x, flight.ref, CONTROL_PERIOD))
    return agreement(out[:, :4], flight.U)


def law_cost(app: str | os.PathLike[str], name: str, nc: int, flight: SimulationResult,
             work: str | os.PathLike[str], steps: int = 2000) -> dict[str, Any]:
    """Instructions per call of the app's law on the Cortex-M4 (QEMU), built with ``-Os``.

    Parameters
    ----------
    app : str or os.PathLike
        The app folder (its ``src/quadcog_<name>.c``).
    name : str
        The law's short name.
    nc : int
        Size of its state.
    flight : SimulationResult
        The recording (its first ``steps`` states and references).
    work : str or os.PathLike
        Build folder.
    steps : int
        Steps of the recording.

    Returns
    -------
    dict
        ``quadcog.embedded.target.parse_output``'s costs.
    """
    work = Path(work)
    work.mkdir(parents=True, exist_ok=True)
    target.write_data(work / "harness_data.h", flight.x[:steps], flight.ref[:steps],
                      CONTROL_PERIOD, "float32")
    elf = target.build_target(Path(app) / "src", name, nc, work, work, opt=FIRMWARE_OPT)
    return target.parse_output(target.run_qemu(elf), "float32", nc)[2]


def boundary_frame(app: str | os.PathLike[str], name: str,
                   firmware_tree: str | os.PathLike[str], work: str | os.PathLike[str]) -> int:
    """The stack frame of the app's ``controllerOutOfTree`` (bytes, -fstack-usage at -Os).

    Parameters
    ----------
    app : str or os.PathLike
        The app folder.
    name : str
        The law's short name.
    firmware_tree : str or os.PathLike
        A firmware tree (headers).
    work : str or os.PathLike
        Where the object goes.

    Returns
    -------
    int
        Bytes of its own frame (the law's step is measured apart, ``law_cost``).
    """
    work = Path(work)
    work.mkdir(parents=True, exist_ok=True)
    obj = work / f"quadcog_cf_{name}.o"
    includes = [a for d in HOST_INCLUDES for a in ("-I", str(Path(firmware_tree) / d))]
    compile_checked([target.ARM_GCC, "-std=gnu11", *target.CORTEX_M4, *FIRMWARE_OPT,
                     "-fno-math-errno", "-DCONFIG_CONTROLLER_OOT=1", "-fstack-usage",
                     "-I", Path(app) / "src", *includes, "-c",
                     Path(app) / "src" / f"quadcog_cf_{name}.c", "-o", obj])
    for line in obj.with_suffix(".su").read_text().splitlines():
        if ":controllerOutOfTree\t" in line:
            return int(line.split("\t")[1])
    return 0


def report(laws: Sequence[str] = LAWS, vehicle: str | Vehicle | None = None,
           firmware_path: str | os.PathLike[str] | None = None,
           jobs: int = 2) -> list[dict[str, Any]]:
    """Build and measure each law's app.

    Parameters
    ----------
    laws : sequence of str
        Short names.
    vehicle : str or Vehicle, optional
        As ``write_crazyflie_app``.
    firmware_path : str or os.PathLike, optional
        The firmware tree (see ``crazyflie_firmware.firmware_tree``).
    jobs : int
        ``make -j``.

    Returns
    -------
    list of dict
        One row per law: controller, vehicle, flash and RAM added to cf2.elf (B), the plain
        and the app's cf2.elf sizes, instructions per call (mean, max), the stack (the
        law's measured in QEMU plus controllerOutOfTree's frame), the budget, the host
        agreement and whether the builds came from the cache.
    """
    v = resolve_vehicle(vehicle)
    plain = firmware.build_plain(firmware_path, jobs)
    tree, _ = firmware.firmware_tree(firmware_path)
    rows = []
    for name in laws:
        with tempfile.TemporaryDirectory() as tmp:
            app = Path(tmp) / f"app_{name}"
            write_crazyflie_app(name, app, vehicle=v,
                                command=f"quadcog export --target crazyflie --controller "
                                        f"{name} --out DIR")
            built = firmware.build_app(app, firmware_path, jobs)
            flight = agreement_flight(name, v)
            nc = int(make_controller(name, vehicle=v).n_state)
            cost = law_cost(app, name, nc, flight, Path(tmp) / "qemu")
            frame = boundary_frame(app, name, tree, Path(tmp) / "frame")
            agree = host_agreement(app, flight, tree, tmp)
        rows.append(dict(controller=name, vehicle=v.name, flash_added=built.flash - plain.flash,
                         ram_added=built.ram - plain.ram, plain=(plain.text, plain.data,
                                                                 plain.bss),
                         app=(built.text, built.data, built.bss),
                         instructions_mean=cost["instructions_mean"],
                         instructions_max=cost["instructions_max"],
                         stack_bytes=cost["stack_bytes"] + frame, budget=BUDGET_CYCLES,
                         agreement=agree, cached=(plain.cached, built.cached)))
    return rows


def table(rows: Sequence[dict[str, Any]]) -> str:
    """The rows as Markdown.

    Parameters
    ----------
    rows : sequence of dict
        ``report``'s.

    Returns
    -------
    str
        The table.
    """
    head = ("| law | flash added (B) | RAM added (B) | instructions per call, mean | max | "
            f"of the 500 Hz budget | stack (B, of the stabilizer's {STABILIZER_STACK}) | "
            "host agreement, thrust | torque |\n"
            "|---|---|---|---|---|---|---|---|---|\n")
    lines = [f"| {r['controller']} | {r['flash_added']} | {r['ram_added']} | "
             f"{r['instructions_mean']:.0f} | {r['instructions_max']:.0f} | "
             f"{100 * r['instructions_max'] / r['budget']:.2f} % | {r['stack_bytes']} | "
             f"{r['agreement']['thrust']:.1e} | {r['agreement']['torque']:.1e} |"
             for r in rows]
    return head + "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m quadcog.embedded.crazyflie_report`` (``make crazyflie-app``).

    Parameters
    ----------
    argv : sequence of str, optional
        ``[--firmware PATH] [--vehicle NAME] [--jobs N]``.

    Returns
    -------
    int
        0.
    """
    p = argparse.ArgumentParser(prog="python -m quadcog.embedded.crazyflie_report")
    p.add_argument("--firmware", help=f"firmware tree (default ${firmware.FIRMWARE_ENV}, else "
                                      "the vendored tarball)")
    p.add_argument("--vehicle", help="vehicle preset (default the Crazyflie's)")
    p.add_argument("--jobs", type=int, default=2, help="make -j (default 2)")
    args = p.parse_args(argv)
    rows = report(LAWS, args.vehicle, args.firmware, args.jobs)
    r0 = rows[0]
    # the header lines fit the docs' 88-column code blocks, where the output is republished
    print(f"cf2.elf (arm-none-eabi-size, text data bss), vehicle {r0['vehicle']}:")
    print(f"  plain: {r0['plain']}")
    for r in rows:
        print(f"  with {r['controller']}: {r['app']}")
    print(f"instructions per call: QEMU mps2-an386 -icount, law built with "
          f"{' '.join(FIRMWARE_OPT)},\n  2000 calls of the agreement flight; budget "
          f"{BUDGET_CYCLES} cycles per call ({CLOCK_HZ // 10**6} MHz / {RATE} Hz)")
    print(table(rows), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
