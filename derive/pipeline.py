"""The stages of ``make derive``: derive, export, report, manifest; written atomically."""
from pathlib import Path
import shutil
import tempfile
import time

from derive.compare import FOREIGN
from derive.export import build_functions, write_c, write_casadi
from derive.latex import render
from derive.manifest import write_manifest
from derive.model import derive_model


def _log(stage, seconds, echo):
    if echo:
        echo(f"  {stage:<22s} {seconds:6.2f} s")


def generate(out_dir, echo=print):
    """Derive and write everything into ``out_dir`` (which should be empty or absent)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    model = derive_model(log=lambda n, t: _log(f"derive: {n}", t, echo))

    def stage(name, fn, *args):
        t0 = time.perf_counter()
        result = fn(*args)
        _log(name, time.perf_counter() - t0, echo)
        return result

    functions = stage("export: casadi build", build_functions, model)
    stage("export: .casadi files", write_casadi, functions, out_dir)
    stage("export: C code", write_c, functions, out_dir)
    stage("report: report.tex", lambda: (out_dir / "report.tex").write_text(render(model)))
    stage("manifest", write_manifest, out_dir, functions)
    return model, functions


def generate_atomically(target, echo=print):
    """Generate into a temporary sibling folder, then swap it in.

    If anything fails, ``target`` is left exactly as it was.
    """
    target = Path(target).resolve()
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".generated-new-", dir=target.parent))
    try:
        generate(tmp, echo)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    tmp.chmod(0o755)          # mkdtemp makes 0700; generated/ is shared, readable by all
    for name in FOREIGN:              # keep what other generators wrote into generated/
        if (target / name).exists():
            shutil.copytree(target / name, tmp / name)
    old = None
    if target.exists():
        old = Path(tempfile.mkdtemp(prefix=".generated-old-", dir=target.parent))
        old.rmdir()
        target.rename(old)
    tmp.rename(target)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
