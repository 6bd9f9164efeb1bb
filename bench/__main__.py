"""Run every benchmark module in this folder (or those named on the command line). Options
("--profile", "--minutes 30") are left for the modules, which read sys.argv themselves."""

from __future__ import annotations

import importlib
import pkgutil
import sys
import time
from pathlib import Path


def main(argv: list[str]) -> int:
    """Import bench/<name>.py for each name in `argv` (default: all) and call its main(); the
    names come first, the options (from the first "--x" on) are not names."""
    here = Path(__file__).parent
    options = next((index for index, arg in enumerate(argv) if arg.startswith("--")), len(argv))
    names = argv[:options] or sorted(m.name for m in pkgutil.iter_modules([str(here)]) if not m.name.startswith("_"))
    for name in names:
        module = importlib.import_module(f"bench.{name}")
        if not hasattr(module, "main"):
            continue
        print(f"== bench {name}", flush=True)
        started = time.perf_counter()
        module.main()
        print(f"== bench {name} took {time.perf_counter() - started:.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
