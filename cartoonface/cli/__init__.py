"""The `cartoonface` command: a thin shell over the library.

Each subcommand lives in its own module in this package and exposes
`register(subparsers)`, which adds its parser and sets `func` to a function
taking the parsed arguments and returning an exit code. Bad input raises
`InputError`; it is printed as one line and the command exits 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from cartoonface import __version__
from cartoonface.errors import InputError

# Subcommand modules, in the order they appear in --help.
SUBCOMMANDS = ("face", "align", "generate", "serve")


def build_parser() -> argparse.ArgumentParser:
    """Return the top-level parser with every available subcommand registered."""
    parser = argparse.ArgumentParser(
        prog="cartoonface",
        description="Turn a face model, a speech recording and its transcript into a "
        "talking cartoon face (SVG animation and web pages).",
    )
    parser.add_argument("--version", action="version", version=f"cartoonface {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMANDS:
        try:
            module = importlib.import_module(f"cartoonface.cli.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"cartoonface.cli.{name}":
                raise
            continue
        module.register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the process exit code (0 ok, 2 bad input)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return 2
    try:
        return int(args.func(args) or 0)
    except InputError as exc:
        print(f"cartoonface: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("cartoonface: interrupted", file=sys.stderr)
        return 130
