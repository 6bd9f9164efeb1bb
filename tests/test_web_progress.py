"""The progress a job reports (and the job page shows): every stage, rising, and often enough
that the bar keeps moving, recorded from a real `pipeline.generate` of the sample story."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from cartoonface.pipeline import STAGES
from tests.conftest import ROOT

SPEECH = ROOT / "samples" / "speech"
# The longest wait between two reports, as a share of the whole job: the drawing stage alone
# takes ~80 % of it, and used to be reported only when it started and ended.
MAX_GAP_SHARE = 0.25
# How far the fraction reported may be from the share of the time gone by.
MAX_LAG = 0.25


# One generate in a fresh process (as a web job runs in its worker), printing every progress call
# as (processor seconds since the start, stage, fraction), then ("end", 1.0) when it returned.
# In the test's own process the heap that the suite's earlier tests leave makes the garbage
# collector's passes, and so the gaps, longer than any job's.
RECORDER = """
import json, sys, time
from pathlib import Path
from cartoonface.pipeline import Options, generate
seen = []
start = time.process_time()
generate(Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3]), Path(sys.argv[4]), Options(),
         lambda stage, fraction: seen.append((time.process_time() - start, stage, fraction)))
seen.append((time.process_time() - start, "end", 1.0))
print(json.dumps(seen))
"""


@pytest.fixture(scope="module")
def calls(tmp_path_factory: pytest.TempPathFactory) -> list[tuple[float, str, float]]:
    """(processor seconds since the start, stage, fraction) of every progress call of one real
    generate, and a last entry ("end") when it returned. Processor time, not wall time: on a
    busy machine the process may wait for a core between two reports, which is not work."""
    out = tmp_path_factory.mktemp("progress") / "site"
    done = subprocess.run([sys.executable, "-c", RECORDER, str(ROOT / "samples" / "faces" / "female.json"),
                           str(SPEECH / "story.wav"), str(SPEECH / "story.txt"), str(out)],
                          capture_output=True, text=True, timeout=300, check=True)
    return [(float(at), str(stage), float(fraction)) for at, stage, fraction in json.loads(done.stdout)]


def test_every_stage_is_reported_in_order(calls):
    stages = [stage for _, stage, _ in calls[:-1]]
    in_order = [stage for i, stage in enumerate(stages) if i == 0 or stages[i - 1] != stage]
    assert in_order == [name for name, _ in STAGES]


def test_fractions_rise_from_0_to_1(calls):
    fractions = [fraction for _, _, fraction in calls[:-1]]
    assert fractions == sorted(fractions)
    assert fractions[0] == 0.0 and fractions[-1] == 1.0
    assert all(0.0 <= fraction <= 1.0 for fraction in fractions)


def test_reports_come_often_and_follow_the_time(calls):
    total = calls[-1][0]
    gaps = [later[0] - earlier[0] for earlier, later in zip(calls, calls[1:])]
    assert max(gaps) <= MAX_GAP_SHARE * total, (max(gaps), total)
    lags = [abs(fraction - at / total) for at, _, fraction in calls[:-1]]
    assert max(lags) <= MAX_LAG, max(lags)


def test_the_drawing_stage_reports_within_itself(calls):
    inside = [fraction for _, stage, fraction in calls if stage == "svg"]
    assert len(set(inside)) >= 5, inside
