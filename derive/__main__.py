"""``python -m derive``: regenerate generated/ (``--check`` only compares)."""
import argparse
from pathlib import Path
import sys
import tempfile
import time

from derive.compare import diff_trees
from derive.manifest import is_fresh
from derive.pipeline import generate, generate_atomically
from derive.to_casadi import UnsupportedAtomError

ROOT = Path(__file__).resolve().parent.parent


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m derive", description=__doc__)
    ap.add_argument("--out", type=Path, default=ROOT / "generated",
                    help="folder to (re)write; default: generated/ of this repository")
    ap.add_argument("--check", action="store_true",
                    help="derive into a temporary folder and diff against --out; write nothing")
    ap.add_argument("--if-stale", action="store_true",
                    help="regenerate only when derive/ sources or generated files do not "
                         "match the manifest")
    ap.add_argument("--quiet", action="store_true", help="no per-stage timings")
    args = ap.parse_args(argv)
    echo = (lambda s: None) if args.quiet else (lambda s: print(s, flush=True))
    t0 = time.perf_counter()
    try:
        if args.if_stale and is_fresh(args.out):
            echo(f"{args.out} is up to date with derive/ (manifest hashes match)")
            return 0
        if args.check:
            with tempfile.TemporaryDirectory() as tmp:
                generate(tmp, echo)
                diff = diff_trees(args.out, tmp)
            if diff:
                sys.stderr.write(f"{args.out} is stale; run `make derive`:\n{diff}")
                return 1
            echo(f"{args.out} is up to date")
        else:
            generate_atomically(args.out, echo)
    except UnsupportedAtomError as e:
        sys.stderr.write(f"derive: error: {e}\n{args.out} was left as it was.\n")
        return 2
    echo(f"  {'total':<22s} {time.perf_counter() - t0:6.2f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
