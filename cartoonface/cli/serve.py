"""`cartoonface serve`: run the web app under waitress (a production WSGI server, no debug mode)."""

from __future__ import annotations

import argparse
import signal
import sys
from pathlib import Path

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 5000
THREADS = 8  # waitress request threads; jobs run in the app's own worker pool


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `serve` subcommand."""
    parser = subparsers.add_parser(
        "serve", help="run the web app (upload, progress, results)",
        description="Run the cartoonface web app with waitress. Settings: docs/web.md "
                    "(CARTOONFACE_* environment variables or <instance>/config.py).")
    parser.add_argument("--host", default=DEFAULT_HOST, help=f"address to listen on (default {DEFAULT_HOST})")
    parser.add_argument("--port", type=int, default=DEFAULT_PORT, help=f"port (default {DEFAULT_PORT})")
    parser.add_argument("--instance", type=Path, default=None,
                        help="instance folder holding jobs and settings (default: $CARTOONFACE_INSTANCE_PATH "
                             "or instance/ beside the package)")
    parser.set_defaults(func=run)


def stop(signum: int, frame: object) -> None:
    """SIGTERM handler: leave the server loop the way Ctrl-C does."""
    raise KeyboardInterrupt


def run(args: argparse.Namespace) -> int:
    """Build the app and serve it until interrupted; the worker pool is closed on the way out."""
    import waitress

    from cartoonface.web import create_app

    app = create_app({"INSTANCE_PATH": str(args.instance)} if args.instance else None)
    print(f"cartoonface: serving on http://{args.host}:{args.port}/ (instance {app.instance_path})",
          file=sys.stderr, flush=True)
    signal.signal(signal.SIGTERM, stop)
    try:
        waitress.serve(app, host=args.host, port=args.port, threads=THREADS, ident="cartoonface")
    finally:
        app.extensions["cartoonface"].runner.close()
    return 0
