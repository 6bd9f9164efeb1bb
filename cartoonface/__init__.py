"""cartoonface: talking cartoon faces from a face model, speech and its transcript.

The data flows one way (see docs/ARCHITECTURE.md):
inputs -> face model and speech analysis -> timeline -> frames -> SVG -> pages.
"""

import os

__version__ = "0.1.0"

# One OpenBLAS thread per process, set before numpy loads it (a value set by the user is kept):
# a job works in two processes of its own on two cores (workers.py), and the BLAS threads each
# started spun against the other process: the reuse search's matrix products took ~1.45x the
# CPU time (docs/BENCHMARKS.md, "One BLAS thread").
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
