"""The command line every scripts.* test shares, and the unittest run behind it.

ctest passes each of them `--cli <latentbench> --tmp <scratch folder>` (tests/CMakeLists.txt);
anything it does not recognise goes on to unittest (a test name, -k PATTERN, ...).
"""
import argparse
import os
import sys
import unittest


def arguments(description=None, required=True, extra=None):
    """Parse --cli and --tmp (both made absolute; --tmp created), plus what `extra(parser)` adds.

    Returns (namespace, the arguments left for unittest)."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--cli", required=required, help="the latentbench executable")
    parser.add_argument("--tmp", required=required, help="a scratch folder")
    if extra is not None:
        extra(parser)
    args, rest = parser.parse_known_args()
    if args.cli:
        args.cli = os.path.abspath(args.cli)
    if args.tmp:
        args.tmp = os.path.abspath(args.tmp)
        os.makedirs(args.tmp, exist_ok=True)
    return args, rest


def run(rest):
    """Run the calling script's tests; the exit status for sys.exit."""
    result = unittest.main(module="__main__", argv=[sys.argv[0], *rest], exit=False, verbosity=2).result
    return 0 if result.wasSuccessful() else 1
