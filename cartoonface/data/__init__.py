"""Files the installed program needs, shipped in the wheel as package data.

`SAMPLE_FACES`: the folder of the sample face models (`*.json`, docs/face-model.md)
offered by the web form and used by `make demo`; samples/faces in a checkout links here.
"""

from __future__ import annotations

from pathlib import Path

SAMPLE_FACES = Path(__file__).resolve().parent / "faces"
