"""The second process of generate (workers.py): same results as one process, falls back, never hangs."""

from __future__ import annotations

import dataclasses
import gc
import multiprocessing
import os
import subprocess
import sys
import time
from functools import partial
from pathlib import Path

import numpy as np
import pytest

from cartoonface.animate.frames import states_at
from cartoonface.animate.timeline import Keyframe, Timeline, build_timeline
from cartoonface.animate.behaviour import schedule, speech_pauses
from cartoonface.errors import OptionError
from cartoonface.face.state import FaceState, Pose
from cartoonface.speech.analyse import analyse
from cartoonface.speech.audio import load_audio
from cartoonface.workers import collector_paused, forked, from_both_ends, helper_pool, memory_file, offloaded, shares
from tests.conftest import ROOT
from tests.synthetic import synthetic_talk

STORY = ROOT / "samples" / "speech"


def _pid_and_square(x: float, wait: float = 0.0) -> tuple[int, float]:
    time.sleep(wait)
    return os.getpid(), x * x


def _signal_then_square(x: float, wait: float, flag: str) -> tuple[int, float]:
    Path(flag).touch()  # it has begun in the helper: the caller can no longer take it over
    return _pid_and_square(x, wait)


def _dies_in_a_child(parent: int) -> int:
    if os.getpid() != parent:
        os._exit(1)  # the helper process is lost (killed, out of memory)
    return parent


@pytest.mark.parametrize("besides", [0.0, 0.3])
@pytest.mark.parametrize("seed", range(5))
def test_shares_split_every_index_once_about_evenly(seed, besides):
    costs = np.random.default_rng(seed).uniform(0.1, 5.0, size=3 + 4 * seed).tolist()
    other = besides * sum(costs)  # work the second side does besides, counted with its share
    first, second = shares(costs, other)
    assert sorted(first + second) == list(range(len(costs)))
    assert first == sorted(first) and second == sorted(second)
    assert abs(sum(costs[i] for i in first) - sum(costs[i] for i in second) - other) <= max(costs)


def test_the_helper_is_forked_at_once_and_computes_the_same(tmp_path):
    before = len(multiprocessing.active_children())
    with helper_pool(2) as pool:
        assert pool is not None
        assert len(multiprocessing.active_children()) == before + 1  # before any pipe the caller opens later
        # a subprocess started now hands over its output: the helper holds none of its pipe
        out = subprocess.run([sys.executable, "-c", "print(7)"], stdout=subprocess.PIPE, timeout=60, check=True)
        assert out.stdout.strip() == b"7"
        flag = tmp_path / "begun"
        begun = offloaded(pool, _signal_then_square, 1.5, 1.0, str(flag))  # busy for 1 s: the next ones wait
        deadline = time.monotonic() + 60
        while not flag.exists() and time.monotonic() < deadline:  # a loaded machine may start it late
            time.sleep(0.01)
        queued = [offloaded(pool, _pid_and_square, x) for x in range(6)]
        # not begun there (at most two are handed to the process ahead of time): done here, the same
        assert queued[-1]() == (os.getpid(), 25)
        pid, value = begun()
        assert pid != os.getpid() and value == 2.25
        assert [getter()[1] for getter in queued] == [x * x for x in range(6)]
    with helper_pool(1) as none:
        assert none is None
        assert offloaded(none, _pid_and_square, 1.5)() == (os.getpid(), 2.25)


def test_jobs_from_both_ends_meet_once_each_in_order():
    """The pool's jobs are a run from the front, this process's the rest from the back, whatever the
    timing; each job once, the results in the jobs' order."""
    values = [float(x) for x in range(12)]
    jobs = [(_pid_and_square, (x, 0.02), partial(_pid_and_square, x, 0.02)) for x in values]
    with helper_pool(2) as pool:
        assert pool is not None
        pool.submit(time.sleep, 0.1)  # busy first, as the analysis helper with its pitch track
        fractions: list[float] = []
        results = from_both_ends(pool, jobs, fractions.append)
    assert [value for _, value in results] == [x * x for x in values]
    there = [pid != os.getpid() for pid, _ in results]
    assert there == sorted(there, reverse=True)  # a run from the front (maybe none), then this process's
    assert not there[-1] and fractions == sorted(fractions) and fractions[-1] < 1.0
    assert from_both_ends(None, jobs) == [(os.getpid(), x * x) for x in values]


def test_jobs_of_a_lost_helper_are_done_here():
    jobs = [(_dies_in_a_child, (os.getpid(),), partial(_dies_in_a_child, os.getpid())) for _ in range(4)]
    with helper_pool(2) as pool:
        assert from_both_ends(pool, jobs) == [os.getpid()] * 4


def test_a_lost_helper_is_done_here():
    with helper_pool(2) as pool:
        assert offloaded(pool, _dies_in_a_child, os.getpid())() == os.getpid()


def _pid_and_arrays(size: int, flag: str = "") -> tuple[int, dict[str, np.ndarray], list[str]]:
    if flag:
        Path(flag).touch()  # begun in the helper
    rng = np.random.default_rng(size)
    return os.getpid(), {"numbers": rng.integers(-1000, 1000, size)}, [f"part {n}" for n in range(size)]


def test_a_result_handed_back_through_a_memory_file_is_the_one_computed_there(tmp_path):
    """Through a memory file, a large result (megabytes) comes from the helper as it was computed
    there; lost or not begun there, it is computed here; the helper may end on its own."""
    flag = tmp_path / "begun"
    with memory_file() as through, helper_pool(2, wait=False) as pool:
        assert pool is not None and through is not None  # Linux, as the tests run
        getter = offloaded(pool, _pid_and_arrays, 300_000, str(flag), through=through)
        deadline = time.monotonic() + 60
        while not flag.exists() and time.monotonic() < deadline:  # a loaded machine may start it late
            time.sleep(0.01)
        pid, arrays, texts = getter()
        assert pid != os.getpid()
        _, expected, expected_texts = _pid_and_arrays(300_000)
        assert np.array_equal(arrays["numbers"], expected["numbers"]) and texts == expected_texts
        assert offloaded(pool, _dies_in_a_child, os.getpid(), through=through)() == os.getpid()
    assert offloaded(None, _pid_and_arrays, 10, through=through)()[0] == os.getpid()


def test_a_result_that_cannot_be_read_from_its_memory_file_is_computed_here(tmp_path):
    """The helper writes its result into the file, but this process can no longer map it (its
    descriptor closed): the result is computed here, not an error."""
    flag = tmp_path / "begun"
    through = os.memfd_create("cartoonface-test")  # inherited by the helper forked next
    with helper_pool(2) as pool:
        assert pool is not None
        getter = offloaded(pool, _pid_and_arrays, 1000, str(flag), through=through)
        deadline = time.monotonic() + 60
        while not flag.exists() and time.monotonic() < deadline:  # begun there: its result goes to the file
            time.sleep(0.01)
        assert flag.exists()
        os.close(through)
        pid, arrays, _ = getter()
    assert pid == os.getpid() and len(arrays["numbers"]) == 1000


def _pid_and_call(fn) -> tuple[int, object]:
    return os.getpid(), fn()


def _fails(parent: int) -> int:
    raise ValueError(f"failed in {'the parent' if os.getpid() == parent else 'a child'}")


def test_forked_work_runs_in_a_child_holding_the_arguments_as_they_are():
    lines = [f"line {n}" for n in range(1000)]
    getter = forked(2, _pid_and_call, lambda: len(lines))  # a closure: it could not be pickled
    lines.append("added after the fork")  # the child's copy was taken at the fork
    pid, count = getter()
    assert pid != os.getpid() and count == 1000
    assert forked(1, _pid_and_call, lambda: len(lines))() == (os.getpid(), 1001)


def test_forked_work_whose_child_is_lost_or_fails_is_done_here():
    assert forked(2, _dies_in_a_child, os.getpid())() == os.getpid()
    with pytest.raises(ValueError, match="the parent"):  # the exception is the parent's own, with its traceback
        forked(2, _fails, os.getpid())()


def test_analyse_with_a_helper_gives_the_one_process_alignment():
    audio = load_audio(STORY / "story.wav")
    text = (STORY / "story.txt").read_text(encoding="utf-8")
    alone = analyse(audio, text)
    fractions = []
    with helper_pool(2) as pool:
        shared = analyse(audio, text, pool=pool, progress=lambda stage, done: fractions.append((stage, done)))
    assert shared == alone
    aligning = [done for stage, done in fractions if stage == "align"]
    assert aligning == sorted(aligning) and aligning[-1] == 1.0



def test_generate_with_its_helper_makes_what_one_process_makes(tmp_path, monkeypatch):
    """The helper decodes the recording itself for the pitch track and aligns parts: the
    page folder is the one a single process (a web job's) makes, byte for byte; so is the one
    made with the track begun elsewhere (the command's, cli/generate.py begun), taken once."""
    from cartoonface import pipeline
    from cartoonface.animate.prosody import recording_pitch

    if pipeline.processes() < 2:
        pytest.skip("no second process on this machine")
    inputs = (ROOT / "samples" / "faces" / "female.json", STORY / "story.wav", STORY / "story.txt")
    pipeline.generate(*inputs, tmp_path / "two")
    monkeypatch.setattr(pipeline, "processes", lambda: 1)
    pipeline.generate(*inputs, tmp_path / "one")
    taken = []
    begun = forked(2, recording_pitch, STORY / "story.wav")
    pipeline.generate(*inputs, tmp_path / "begun", pitch=lambda: taken.append(1) or begun())
    assert taken == [1]
    for name in ("alignment.TextGrid", "actions.json", "animation.svg", "index.html"):
        assert (tmp_path / "two" / name).read_bytes() == (tmp_path / "one" / name).read_bytes(), name
        assert (tmp_path / "begun" / name).read_bytes() == (tmp_path / "one" / name).read_bytes(), name

def test_sampled_states_out_of_range_are_still_refused():
    alignment = synthetic_talk(30.0, seed=2)
    timeline = build_timeline(alignment, schedule(alignment.duration, speech_pauses(alignment), seed=5))
    states = states_at(timeline, np.arange(50) / 10)
    for state in states:  # the states made without the checks pass them
        fields = {f.name: getattr(state, f.name) for f in dataclasses.fields(state)}
        assert state == FaceState(**{**fields, "pose": Pose(state.pose.tilt, state.pose.turn, state.pose.roll)})
    tracks = tuple(dataclasses.replace(track, keys=(Keyframe(0, 0.0), Keyframe(1000, 20.0)))
                   if track.name == "turn" else track for track in timeline.tracks)
    with pytest.raises(OptionError, match="turn"):
        states_at(Timeline(timeline.duration, tracks), np.arange(20) / 10)


def _collector_enabled() -> bool:
    return gc.isenabled()


def test_the_paused_collector_stays_paused_in_forked_children_and_runs_again_after():
    with collector_paused():
        assert not gc.isenabled()
        assert forked(2, _collector_enabled)() is False
    assert gc.isenabled()
    with pytest.raises(ValueError), collector_paused():
        raise ValueError("a failed job")
    assert gc.isenabled()
