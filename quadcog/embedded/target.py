"""Run an exported controller on a Cortex-M4 in QEMU (board mps2-an386, semihosting), and the
same harness on the host, over a recorded sequence of states and references.

The harness (``target/harness.c``) prints per step U and c as the hex of their bits, then the
SysTick ticks spent inside the step. QEMU runs with ``-icount shift=0``: the virtual clock
advances exactly 1 ns per instruction, and the SysTick, clocked at the board's 25 MHz, ticks
every 40 instructions, deterministically. A calibration loop of known length (2 x 100,000
instructions) is timed first, which checks that mapping on every run.
"""
from collections.abc import Sequence
import os
from pathlib import Path
import re
import shutil
import subprocess
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from quadcog.codegen.compiler import find_compiler
from quadcog.embedded.host import STRICT_FLAGS, compile_checked
from quadcog.errors import CompileError, TargetError

__all__ = ["TARGET_DIR", "ARM_GCC", "ARM_SIZE", "QEMU", "BOARD", "CORTEX_M4", "TARGET_OPT",
           "DEBIAN_PACKAGES", "TARGET_RTOL", "TARGET_RTOL_FLOAT32", "STRICT_FLAGS",
           "target_rtol", "relative_difference", "missing_tools", "write_data", "build_target",
           "build_host_harness", "run_qemu", "run_host", "parse_output", "object_cost"]

TARGET_DIR = Path(__file__).parent / "target"
ARM_GCC = "arm-none-eabi-gcc"
ARM_SIZE = "arm-none-eabi-size"
QEMU = "qemu-system-arm"
BOARD = "mps2-an386"
CORTEX_M4 = ("-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard")
TARGET_OPT = ("-O2",)
DEBIAN_PACKAGES = "gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm"
# Target vs host build of the same code: largest |difference| over the largest |value| of each
# output. Only the math libraries differ (newlib vs glibc sinf/cosf/atan2f, a couple of ulps),
# amplified by the law's conditioning; measured 9e-6 (float32) and 2e-14 (double).
TARGET_RTOL = {"float32": 1e-4, "double": 1e-11}
# The composite law's filters and least-squares recursion accumulate those float32 differences
# (no FMA on either side: -std=c99 keeps contraction off, checked with objdump): measured up to
# 3e-3 of the input's scale, bounded (the filters forget). The payload law has the same
# filters and recursion (4x4 covariance, mass and m r_G): measured 1.6e-3.
TARGET_RTOL_FLOAT32 = {"composite": 1e-2, "payload_adaptive": 1e-2}


def target_rtol(name: str, precision: str) -> float:
    """The tolerance of target vs host build.

    Parameters
    ----------
    name : str
        The controller's short name.
    precision : str
        'float32' or 'double'.

    Returns
    -------
    float
        The largest relative difference allowed (``relative_difference``).
    """
    if precision == "float32":
        return TARGET_RTOL_FLOAT32.get(name, TARGET_RTOL[precision])
    return TARGET_RTOL[precision]


def relative_difference(a: NDArray[Any], b: NDArray[Any], per_column: bool = True) -> float:
    """max |a - b| / max |b|, per column (the largest ratio) or over the whole array.

    Parameters
    ----------
    a : (N, k) numpy.ndarray
        One run's outputs.
    b : (N, k) numpy.ndarray
        The other's (the scale).
    per_column : bool
        Scale each column by its own largest value, else by the whole array's.

    Returns
    -------
    float
        The ratio; 0 for an empty array.
    """
    if not a.size:
        return 0.0
    axis = 0 if per_column else None
    scale = np.maximum(np.max(np.abs(b), axis=axis), np.finfo(float).tiny)
    return float(np.max(np.max(np.abs(a - b), axis=axis) / scale))


def missing_tools() -> list[str]:
    """Names of the tools (cross compiler, size, QEMU) not on PATH.

    Returns
    -------
    list of str
        Empty when all are there.
    """
    return [t for t in (ARM_GCC, ARM_SIZE, QEMU) if shutil.which(t) is None]


def _hex_literal(value, precision):
    if precision == "float32":
        return float(np.float32(value)).hex() + "f"
    return float(value).hex()


def write_data(path: str | os.PathLike[str], x: ArrayLike, ref: ArrayLike, dt: float,
               precision: str) -> Path:
    """Write harness_data.h: a recorded sequence as exact hexadecimal literals.

    Parameters
    ----------
    path : str or os.PathLike
        The header to write.
    x : (N, 12) array_like
        Recorded states [m, rad, m/s, rad/s].
    ref : (N, 14) array_like
        Recorded references.
    dt : float
        Control period [s].
    precision : str
        'float32' (rounded once, as the host does) or 'double'.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    x, ref = np.asarray(x, float), np.asarray(ref, float)
    rows = lambda a: ",\n".join("    {" + ", ".join(_hex_literal(v, precision) for v in r) + "}"
                                for r in a)
    text = (f"/* recorded sequence: {len(x)} steps (written by quadcog.embedded.target) */\n"
            f"#define HARNESS_N {len(x)}u\n"
            f"static const qc_real harness_dt = {_hex_literal(dt, precision)};\n"
            f"static const qc_real harness_x[{len(x)}][12] = {{\n{rows(x)}\n}};\n"
            f"static const qc_real harness_ref[{len(x)}][14] = {{\n{rows(ref)}\n}};\n")
    Path(path).write_text(text)
    return Path(path)


def _defines(name, nc):
    return [f'-DQC_HEADER="quadcog_{name}.h"', f"-DQC_STEP=quadcog_{name}_step",
            f"-DQC_INIT=quadcog_{name}_init", f"-DQC_NC={nc}"]


def build_target(module_dir: str | os.PathLike[str], name: str, nc: int,
                 data_dir: str | os.PathLike[str], out_dir: str | os.PathLike[str],
                 opt: Sequence[str] = TARGET_OPT) -> Path:
    """Cross-compile the controller with the harness for the Cortex-M4.

    The controller also gets a .su file (-fstack-usage) and an object for arm-none-eabi-size.

    Parameters
    ----------
    module_dir : str or os.PathLike
        The folder of ``quadcog_<name>.c``.
    name : str
        The controller's short name.
    nc : int
        Size of its state c.
    data_dir : str or os.PathLike
        The folder of harness_data.h.
    out_dir : str or os.PathLike
        Where the object and the ELF go (created if needed).
    opt : sequence of str
        The optimization flags of the controller's object (default ``TARGET_OPT``; the
        Crazyflie firmware builds with ``-Os``).

    Returns
    -------
    pathlib.Path
        The ELF.

    Raises
    ------
    quadcog.errors.TargetError
        When the cross tools are missing.
    quadcog.errors.CompileError
        When a compile fails.
    """
    if missing_tools():
        raise TargetError(f"missing {', '.join(missing_tools())}; install the Debian packages "
                          f"{DEBIAN_PACKAGES} (as root, apt-get install)")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    module_dir = Path(module_dir)
    obj = out_dir / f"quadcog_{name}.o"
    compile_checked([ARM_GCC, *STRICT_FLAGS, *CORTEX_M4, *opt, "-fstack-usage",
                     "-ffunction-sections", "-c", module_dir / f"quadcog_{name}.c", "-o", obj])
    elf = out_dir / f"harness_{name}.elf"
    compile_checked([ARM_GCC, "-std=c99", "-Wall", "-Wextra", "-Werror", *CORTEX_M4,
                     *TARGET_OPT, "-I", module_dir, "-I", data_dir, "-I", TARGET_DIR,
                     *_defines(name, nc), "-nostartfiles", "-T", TARGET_DIR / "mps2.ld",
                     "-Wl,--gc-sections", TARGET_DIR / "startup.c", TARGET_DIR / "harness.c",
                     obj, "-o", elf, "-lm", "-lc", "-lgcc"])
    return elf


def build_host_harness(module_dir: str | os.PathLike[str], name: str, nc: int,
                       data_dir: str | os.PathLike[str], out_dir: str | os.PathLike[str]) -> Path:
    """The same harness and controller source built for the host.

    Parameters
    ----------
    module_dir : str or os.PathLike
        The folder of ``quadcog_<name>.c``.
    name : str
        The controller's short name.
    nc : int
        Size of its state c.
    data_dir : str or os.PathLike
        The folder of harness_data.h.
    out_dir : str or os.PathLike
        Where the executable goes.

    Returns
    -------
    pathlib.Path
        The executable.

    Raises
    ------
    quadcog.errors.CompileError
        Without a C compiler, or when the compile fails.
    """
    cc = find_compiler()
    if cc is None:
        raise CompileError("no C compiler found (looked for $CC or `cc` on PATH)")
    exe = Path(out_dir) / f"harness_{name}_host"
    compile_checked([cc, *STRICT_FLAGS, "-O2", "-I", module_dir, "-I", data_dir, "-I", TARGET_DIR,
                     *_defines(name, nc), TARGET_DIR / "harness.c", TARGET_DIR / "host_io.c",
                     Path(module_dir) / f"quadcog_{name}.c", "-o", exe, "-lm"])
    return exe


def run_qemu(elf: str | os.PathLike[str], timeout: float = 120) -> str:
    """Run an ELF on mps2-an386 with semihosting and icount.

    The semihosting console goes to a file next to the ELF (a chardev), apart from QEMU's
    own messages.

    Parameters
    ----------
    elf : str or os.PathLike
        The program (``build_target``).
    timeout : float
        Wall-clock limit [s].

    Returns
    -------
    str
        The harness's output.

    Raises
    ------
    quadcog.errors.TargetError
        When QEMU times out or exits with an error.
    """
    log = Path(elf).with_suffix(".out")
    cmd = [QEMU, "-M", BOARD, "-display", "none", "-monitor", "none", "-serial", "none",
           "-chardev", f"file,id=semihosting,path={log}",
           "-semihosting-config", "enable=on,target=native,chardev=semihosting",
           "-icount", "shift=0", "-kernel", str(elf)]
    try:
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                             stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        raise TargetError(f"QEMU did not finish within {timeout} s: {' '.join(cmd)}") from None
    text = log.read_text() if log.is_file() else ""
    if res.returncode != 0:
        raise TargetError(f"`{' '.join(cmd)}` exited with {res.returncode}:\n"
                          f"{text[-2000:]}{res.stderr[-2000:]}")
    return text


def run_host(exe: str | os.PathLike[str], timeout: float = 60) -> str:
    """Run the host build of the harness.

    Parameters
    ----------
    exe : str or os.PathLike
        The executable (``build_host_harness``).
    timeout : float
        Wall-clock limit [s].

    Returns
    -------
    str
        The harness's output.

    Raises
    ------
    quadcog.errors.TargetError
        When it exits with an error.
    """
    res = subprocess.run([str(exe)], capture_output=True, text=True, timeout=timeout)
    if res.returncode != 0:
        raise TargetError(f"{exe} exited with {res.returncode}: {res.stderr[-2000:]}")
    return res.stdout


def parse_output(text: str, precision: str,
                 nc: int) -> tuple[NDArray[np.float64], NDArray[np.float64], dict[str, Any]]:
    """The values and costs of a harness output.

    Parameters
    ----------
    text : str
        The output (``run_qemu``, ``run_host``).
    precision : str
        'float32' or 'double': how the hex of the bits is read.
    nc : int
        Size of the controller state c.

    Returns
    -------
    tuple of (numpy.ndarray, numpy.ndarray, dict)
        U (N, 4) [N, N m], c (N, nc), and the costs: calibration counts, timer overhead,
        instructions per step (mean, max), steps and stack bytes.

    Raises
    ------
    quadcog.errors.TargetError
        When the output ends early.
    """
    dtype = np.dtype(">f4") if precision == "float32" else np.dtype(">f8")
    values: list[bytes] = []
    info: dict[str, Any] = {}
    for line in text.splitlines():
        head = line.split(" ", 1)[0]
        if head in ("calibration", "cost"):
            info[head] = [int(v) for v in line.split()[1:]]
        elif re.fullmatch(r"[0-9a-f]+", head):
            values.append(bytes.fromhex(line.replace(" ", "")))
    if "cost" not in info:
        raise TargetError(f"harness output ends early:\n{text[-1000:]}")
    a = np.frombuffer(b"".join(values), dtype=dtype).astype(float).reshape(len(values), 4 + nc)
    cal_counted, cal_true, empty, n_empty = info["calibration"]
    total, worst, n, stack = info["cost"]
    overhead = empty / n_empty if n_empty else 0.0
    info = {"calibration_counted": cal_counted, "calibration_true": cal_true,
            "timer_overhead": overhead,
            "instructions_mean": total / n - overhead if n else 0.0,
            "instructions_max": worst - overhead, "steps": n, "stack_bytes": stack}
    return a[:, :4], a[:, 4:], info


def object_cost(obj: str | os.PathLike[str]) -> dict[str, int]:
    """The sizes of a controller object.

    Parameters
    ----------
    obj : str or os.PathLike
        The object file (its .su file next to it).

    Returns
    -------
    dict of str to int
        {'text', 'data', 'bss', 'stack'} in bytes (arm-none-eabi-size, and the largest frame
        in the .su file).
    """
    res = subprocess.run([ARM_SIZE, str(obj)], capture_output=True, text=True, check=True)
    text, data, bss = (int(v) for v in res.stdout.splitlines()[1].split()[:3])
    su = Path(obj).with_suffix(".su")
    frames = [int(line.split("\t")[1]) for line in su.read_text().splitlines() if line.strip()]
    return {"text": text, "data": data, "bss": bss, "stack": max(frames, default=0)}
