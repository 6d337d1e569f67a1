"""What `make bench` ran on, and the arithmetic bound of its vector unit.

``machine()`` names the CPU (model, vector features from /proc/cpuinfo), the compiler and the
batch kernel's instruction set and flags, and ``loadavg()`` the load; ``fma_roofline()``
measures a C loop of independent fused multiply-adds compiled with the kernel's own flags
(the ISA's widest vectors, ``quadcog.codegen.vector_kernel.vector_flags``): the peak floating-point rate of one
thread that the kernel's rate is set against.
"""
import ctypes
import os
from pathlib import Path
import platform
import subprocess
import time

from quadcog.codegen.compiler import _compiler_identity, compile_library, find_compiler
import quadcog.codegen.vector_kernel as qk
from quadcog.files import cpu_model

__all__ = ["VECTOR_FEATURES", "cpu_identity", "fma_roofline", "loadavg", "machine"]

# the /proc/cpuinfo flags that matter to the kernel (the rest are not vector features)
VECTOR_FEATURES = ("sse2", "sse4_2", "avx", "avx2", "fma", "avx512f", "avx512dq", "avx512vl",
                   "avx512bw", "avx512_fp16", "avx512_bf16", "amx_tile", "asimd", "sve")
CHAINS = 12    # independent accumulator vectors: latency (4 cycles) x 2 FMA pipes, and more


def loadavg():
    """The 1, 5 and 15 minute load averages as /proc/loadavg gives them.

    Returns
    -------
    str
        E.g. "0.52 0.61 0.40", or "unknown" where there is no /proc/loadavg.
    """
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "unknown"


def cpu_identity(cc=None):
    """What tells two CPUs of one model name apart: /proc/cpuinfo's vendor, family, model and
    stepping and the clock it lists, and the target gcc reads ``-march=native`` as.

    Parameters
    ----------
    cc : str, optional
        The C compiler (default ``find_compiler()``), asked gcc's ``-march=native -Q
        --help=target``; a compiler that does not answer it in gcc's form is left out.

    Returns
    -------
    str
        E.g. "AuthenticAMD family 26 model 2 stepping 1, 2596 MHz listed; gcc -march=native:
        znver3"; the parts that cannot be read are left out ("unknown" when none can).
    """
    info = {}
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            info.setdefault(key.strip(), value.strip())
    except OSError:
        pass
    parts = []
    if "cpu family" in info:
        parts.append(f"{info.get('vendor_id', '')} family {info['cpu family']} model "
                     f"{info.get('model', '?')} stepping {info.get('stepping', '?')}".strip())
    if info.get("cpu MHz", "").replace(".", "", 1).isdigit():
        parts.append(f"{float(info['cpu MHz']):.0f} MHz listed")
    cc = find_compiler() if cc is None else cc
    if cc:
        try:
            out = subprocess.run([cc, "-march=native", "-Q", "--help=target"],
                                 capture_output=True, text=True, timeout=30).stdout
            march = [ln.split()[-1] for ln in out.splitlines()
                     if ln.strip().startswith("-march=") and len(ln.split()) > 1]
            if march:
                parts.append(f"gcc -march=native: {march[0]}")
        except (OSError, subprocess.SubprocessError):
            pass
    return "; ".join(parts) or "unknown"


def machine():
    """The machine, compiler and kernel build of this run.

    Returns
    -------
    dict
        cpu (model name), identity (``cpu_identity``), cores (os.cpu_count), features (the
        VECTOR_FEATURES it has, space separated), compiler (first line of ``cc --version``),
        isa (``kernel_isa()``), native (``detect_isa()``: the CPU's widest), isa_env (the
        variable that pins the ISA), lanes (flights per float64 block), flags (the kernel's
        compiler flags).
    """
    feats = qk.cpu_features()
    cc = find_compiler()
    isa = qk.kernel_isa()
    return {"cpu": cpu_model(), "identity": cpu_identity(cc), "cores": os.cpu_count(),
            "machine": platform.machine(),
            "features": " ".join(f for f in VECTOR_FEATURES if f in feats) or "none listed",
            "compiler": _compiler_identity(cc) if cc else "none", "isa": isa,
            "native": qk.detect_isa(), "isa_env": qk.ISA_ENV,
            "lanes": qk.lanes_for(isa),
            "flags": " ".join(f for f in qk.vector_flags(isa) if f not in ("-shared", "-fPIC"))}


def _loop_source(isa, chains=CHAINS):
    width = qk.VECTOR_BITS[isa] // 64
    fused = isa in ("avx2", "avx512")        # the FMA instruction is there (-mfma)
    # acc = acc * m + c converges to c / (1 - m): no overflow, no subnormals
    update = "__builtin_fma(a[i][j], m, c)" if fused else "a[i][j] * m + c"
    kind = "FMA" if fused else "mul+add"
    return f"""/* quadcog roofline: {chains} x {width} independent {kind} chains */
#define K {chains}
#define W {width}
double qc_fma_loop(long n) {{
  double a[K][W] __attribute__((aligned(64)));
  const double m = 0.999999, c = 1e-6;
  for (int i = 0; i < K; ++i) for (int j = 0; j < W; ++j) a[i][j] = 1.0 + 0.01 * (i * W + j);
  for (long k = 0; k < n; ++k) {{
    for (int i = 0; i < K; ++i) {{
      #pragma omp simd
      for (int j = 0; j < W; ++j) a[i][j] = {update};
    }}
  }}
  double s = 0.0;
  for (int i = 0; i < K; ++i) for (int j = 0; j < W; ++j) s += a[i][j];
  return s;
}}
""", 2 * chains * width


def fma_roofline(isa=None, seconds=0.5):
    """Peak floating-point rate of one thread, measured.

    Parameters
    ----------
    isa : str, optional
        One of ``quadcog.codegen.vector_kernel.ISAS`` (default ``kernel_isa()``): the loop is compiled with
        the kernel's flags for it.
    seconds : float
        About how long to measure (CPU time of this thread).

    Returns
    -------
    dict
        flops (floating-point operations per second, an FMA counted as 2), ns (CPU time of
        the measured call), isa, kind ("FMA" or "mul+add").
    """
    isa = qk.kernel_isa() if isa is None else isa
    source, flops_per_iter = _loop_source(isa)
    flags = qk.vector_flags(isa)
    lib = compile_library(source.encode(), f"roofline_{isa}", find_compiler(), flags=flags)
    fn = ctypes.CDLL(str(lib)).qc_fma_loop
    fn.restype, fn.argtypes = ctypes.c_double, [ctypes.c_long]
    n = 1 << 16
    while True:
        t0 = time.thread_time()
        fn(n)
        t = time.thread_time() - t0
        if t > seconds / 4 or n > 1 << 34:
            break
        n *= 4
    n = int(n * seconds / max(t, 1e-6))
    t0 = time.thread_time()
    fn(n)
    t = time.thread_time() - t0
    return {"flops": n * flops_per_iter / t, "seconds": t, "isa": isa,
            "kind": "FMA" if isa in ("avx2", "avx512") else "mul+add"}
