"""The `cartoonface` command: a thin shell over the library.

Each subcommand lives in its own module in this package and exposes `HELP`
(its one-line help) and `register(subparsers)`, which adds its parser and sets
`func` to a function taking the parsed arguments and returning an exit code.
Subcommand modules import the library (numpy, scipy, lxml, flask, ...) only in
`register` and in their command functions, and only the chosen subcommand is
registered, so `cartoonface --help` starts without them. Bad input raises
`InputError`; it is printed as one line and the command exits 2.
"""

from __future__ import annotations

import argparse
import gc
import multiprocessing
import signal
import sys
from types import FrameType

from cartoonface import __version__
from cartoonface.cli import align, batch, face, generate, serve, worker
from cartoonface.errors import InputError

# Subcommand name -> module, in the order they appear in --help.
SUBCOMMANDS = {"face": face, "align": align, "generate": generate, "batch": batch, "serve": serve,
               "worker": worker}


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """Return the top-level parser. The subcommand named `command` is registered with all
    its options; the others (all of them for None) only with their name and help line."""
    parser = argparse.ArgumentParser(
        prog="cartoonface",
        description="Turn a face model, a speech recording and its transcript into a "
        "talking cartoon face (SVG animation and web pages).",
    )
    parser.add_argument("--version", action="version", version=f"cartoonface {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, module in SUBCOMMANDS.items():
        if name == command:
            module.register(subparsers)
        else:
            subparsers.add_parser(name, help=module.HELP)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the process exit code (0 ok, 2 bad input)."""
    argv = sys.argv[1:] if argv is None else argv
    # generate's pitch track begun before the parser imports the library (cli/generate.py begun)
    early = generate.begun(argv[1:]) if argv[:1] == ["generate"] else None
    parser = build_parser(argv[0] if argv else None)
    args = parser.parse_args(argv, namespace=argparse.Namespace(begun=early))
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


def command() -> int:
    """The `cartoonface` command (and `python -m cartoonface`): main() on sys.argv, its exit code.
    The heap is frozen (gc.freeze) before the process exits, so the interpreter's last collection
    skips what the job left behind: ~0.05 s of CPU after a 3-minute book (docs/BENCHMARKS.md,
    "Issue 16, where it stands (end of the fourth session of 2026-11-27)").

    SIGTERM (`kill`, `timeout`) ends the command as an exception does (_terminated), so its helper
    processes end with it and nothing half-written is left; `serve` and `worker` set their own."""
    signal.signal(signal.SIGTERM, _terminated)
    code = main()
    gc.freeze()
    return code


def _terminated(signum: int, frame: FrameType | None) -> None:
    """SIGTERM's handler: exit 143 (128 + 15) through the interpreter's exit, not the signal's
    default. The default ended this process alone: the helpers that `generate` forks (workers.py)
    then waited forever to send their results, and its staging folder stayed behind. Said by the
    command itself only: its helper processes inherit the handler, and a helper ended by the
    command's own exit (an error before its result was taken) is no news to the user."""
    if multiprocessing.parent_process() is None:
        print("cartoonface: terminated", file=sys.stderr)
    raise SystemExit(128 + signum)
