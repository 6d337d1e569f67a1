"""The `quadcog` command."""
import argparse
import sys

from .errors import QuadcogError


def main(argv=None):
    ap = argparse.ArgumentParser(prog="quadcog", description="quadrotor with a moving CoG")
    sub = ap.add_subparsers(dest="command", required=True)
    sub.add_parser("tour", help="evaluate the generated functions at hover and print them")
    args = ap.parse_args(argv)
    try:
        if args.command == "tour":
            from .tour import tour
            tour()
    except QuadcogError as e:
        print(f"quadcog: error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
