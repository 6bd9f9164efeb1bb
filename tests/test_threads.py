"""cartoonface keeps numpy's OpenBLAS to one thread a process unless the user says otherwise."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

# A fresh interpreter that imports cartoonface, then multiplies matrices large enough for OpenBLAS
# to use its threads, and prints how many threads the process has.
PROBE = """
import os
import cartoonface
import numpy as np
a = np.ones((600, 600))
a @ a
print(len(os.listdir('/proc/self/task')))
"""


def _threads(env: dict[str, str]) -> int:
    done = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, timeout=120, check=True)
    return int(done.stdout)


@pytest.mark.skipif(not os.path.isdir("/proc/self/task") or (os.cpu_count() or 1) < 2, reason="needs Linux /proc, 2 cores")
def test_openblas_runs_one_thread_unless_the_user_sets_more():
    env = {name: value for name, value in os.environ.items() if name != "OPENBLAS_NUM_THREADS"}
    assert _threads(env) == 1
    assert _threads({**env, "OPENBLAS_NUM_THREADS": "2"}) == 2  # the user's own setting is kept
