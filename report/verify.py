"""``python -m report.verify``: evaluate the identities of ``report/identities.py`` at random
admissible points and write the LaTeX table that the report includes (``verification.tex``).

Every number in the table comes from this run. Exit status 1 when any identity misses its
bound (the table is written all the same, with the failure marked), 2 on a usage error.

    python -m report.verify --out out/report/verification.tex --points 200
"""
import argparse
import datetime
from pathlib import Path
import platform
import sys
import time

import casadi as ca
import numpy as np

import quadcog
from quadcog.errors import QuadcogError
from quadcog.files import atomic_write, output_path, run_stamp, strict_json
from report.identities import SEED, run

ROOT = Path(__file__).resolve().parent.parent


def _sci(value):
    """A float in LaTeX: 0, or m \\times 10^{e}."""
    if value == 0:
        return "$0$"
    mantissa, exponent = f"{value:.1e}".split("e")
    return rf"${mantissa}\times10^{{{int(exponent)}}}$"


def _power(value):
    return "$0$" if value == 0 else rf"$10^{{{int(round(np.log10(value)))}}}$"


def table(results, seed, backend, seconds):
    """The LaTeX fragment: a caption paragraph and a longtable, one row per identity."""
    n = max(r.points for r in results)
    lines = [
        r"Each identity below was evaluated by \code{python -m report.verify} with the "
        rf"runtime (\code{{quadcog.load()}}, backend \code{{{backend}}}) at {n} random "
        rf"admissible points (seed {seed}): states with $|\phi|, |\theta| \le 1.2$, "
        r"parameters with $m$, $g$, $I_O > 0$, $c \ge 0$, each component of $r_G$ within "
        r"$\pm0.1$\,m and $I_G$ "
        r"positive definite (the samplers of \code{quadcog.model.sampling}). Error: "
        r"$\max|a - b| / \max(1, \max|b|)$, the largest over all points; the bound is the "
        r"test suite's tolerance.",
        "",
        r"{\small",
        r"\begin{longtable}{@{}>{\raggedright\arraybackslash}p{0.52\textwidth}rrrl@{}}",
        r"\toprule",
        r"identity & points & largest error & bound & \\",
        r"\midrule",
        r"\endhead",
        r"\bottomrule",
        r"\endfoot",
    ]
    group = None
    for r in results:
        if r.check.group != group:
            group = r.check.group
            lines.append(rf"\multicolumn{{5}}{{@{{}}l}}{{\emph{{{group}}}}} \\")
        if r.skipped:
            lines.append(rf"{r.check.tex} & -- & \multicolumn{{3}}{{l}}{{skipped: {r.skipped}}} \\")
            continue
        if r.check.kind == "min":
            value, bound = _sci(r.value), rf"$> {r.check.bound:g}$"
        else:
            value, bound = _sci(r.value), rf"$\le$ {_power(r.check.bound)}"
        verdict = "ok" if r.ok else r"\textbf{FAILED}"
        lines.append(rf"{r.check.tex} & {r.points} & {value} & {bound} & {verdict} \\")
    lines += [r"\end{longtable}", r"}", ""]
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    lines.append(
        rf"Run {stamp} in {seconds:.1f}\,s; quadcog {quadcog.__version__}, CasADi "
        rf"{ca.__version__}, NumPy {np.__version__}, Python {platform.python_version()}. "
        r"The test suite (\code{make test}) asserts the same identities, defined once in "
        r"\code{report/identities.py}, and also the agreement with SymPy's \code{lambdify} and "
        r"with an independent Kane derivation.")
    return "\n".join(lines) + "\n"


def summary(results, points, seed, seconds):
    """The run's figures as JSON data: each identity's error and bound, the largest error of
    the "max" kind and where the run was made (``quadcog.files.run_stamp``)."""
    errors = [r.value for r in results if not r.skipped and r.check.kind != "min"]
    return {"machine": f"run {run_stamp()}", "points": points, "seed": seed,
            "seconds": seconds, "n_identities": len(results),
            "largest_error": max(errors), "all_ok": all(r.ok for r in results),
            "identities": [{"identity": r.check.tex, "kind": r.check.kind, "value": r.value,
                            "bound": r.check.bound, "ok": r.ok, "skipped": r.skipped}
                           for r in results]}


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m report.verify", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "report" / "verification.tex",
                    help="LaTeX fragment to write (default: out/report/verification.tex)")
    ap.add_argument("--points", type=int, default=200, help="random points per identity")
    ap.add_argument("--seed", type=int, default=SEED)
    args = ap.parse_args(argv)
    if args.points < 1:
        ap.error("--points must be at least 1")
    figures = args.out.with_suffix(".json")      # the same figures for the docs (bench/publish.py)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    try:                # before the work: a folder, link, FIFO or device is never written through
        output_path(args.out, "--out")
        output_path(figures, "--out's .json")
    except QuadcogError as e:
        ap.error(str(e))
    t0 = time.perf_counter()
    model = quadcog.load()
    results = run(args.points, args.seed, model)
    seconds = time.perf_counter() - t0
    try:                # all or nothing
        atomic_write(args.out, table(results, args.seed, model.backend, seconds), "--out")
        atomic_write(figures, strict_json(summary(results, args.points, args.seed, seconds)),
                     "--out's .json")
    except QuadcogError as e:
        ap.error(str(e))
    failed = [r for r in results if not r.ok]
    for r in results:
        status = "skipped" if r.skipped else ("ok" if r.ok else "FAILED")
        print(f"  {status:<7s} {r.value:10.2e}  {r.check.tex}")
    print(f"wrote {args.out} ({len(results)} identities, {args.points} points each, "
          f"{seconds:.1f} s)")
    if failed:
        sys.stderr.write(f"report.verify: {len(failed)} identities missed their bound:\n"
                         + "".join(f"  {r.check.tex}: {r.value:.3e}\n" for r in failed))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
