"""``python -m quadcog.aqb setup [SOURCE]``: put the patched AdaptiveQuadBench tree into the
cache and print the two folders to ``pip install -e`` (the RotorPy fork, then AdaptiveQuadBench);
``make aqb`` does both."""
import sys

from quadcog.aqb.install import prepare

__all__: list[str] = []

if __name__ == "__main__":
    if len(sys.argv) not in (2, 3) or sys.argv[1] != "setup":
        raise SystemExit(__doc__)
    tree = prepare(sys.argv[2] if len(sys.argv) == 3 else None)
    print(tree.rotorpy)
    print(tree.aqb)
