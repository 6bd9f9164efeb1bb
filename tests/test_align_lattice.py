"""The aligner's dynamic programmes score only what a whole cut can reach (speech/align.py `_forward`,
`_soft_forward`): on real recordings (Biaobei, ../shared/bench/zh) they give the same best cut, the
same lattice wherever a whole cut passes and the same posteriors to the bit as the recursions over
whole tables they replace, written out here as they were."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import cartoonface.speech.align as align
from cartoonface.speech.audio import Audio, load_audio
from cartoonface.speech.sentences import Span
from cartoonface.speech.textgrid import read_tiers

BIAOBEI = Path(__file__).resolve().parents[1].parent / "shared" / "bench" / "zh" / "biaobei"
SILENCE = {"", "sil", "sp"}


def whole_forward(evidence, silence, edges, means, penalty) -> align._Lattice:
    """`_forward` over every row of every table."""
    n, positions = evidence.shape
    total, cost, rates = positions - 1, align.rate_costs(), len(align.RATES)
    cum = np.concatenate([[0.0], np.cumsum(silence)])
    after_syllable = np.full((n + 1, rates, positions), align._NEG)
    after_pause = np.full((n + 1, positions), align._NEG)
    pause_from, rate_before = (np.zeros((n + 1, positions), dtype=int) for _ in range(2))
    length = np.zeros((n, rates, positions), dtype=int)
    fresh_won = np.zeros((n, rates, positions), dtype=bool)
    after_syllable[0, :, 0] = -cost
    k = np.arange(positions)
    for i in range(n + 1):
        rate_before[i] = after_syllable[i].argmax(axis=0)
        base = after_syllable[i].max(axis=0) + edges[0] - cum
        best = np.maximum.accumulate(base)
        gap = align.EDGE_MIN_PAUSE if i in (0, n) else align.MIN_PAUSE
        shifted = np.full(positions, align._NEG)
        shifted[gap:] = best[:-gap]
        after_pause[i] = shifted + cum - penalty[i] + edges[1]
        pause_from[i, gap:] = np.maximum.accumulate(np.where(base >= best, k, 0))[:-gap]
        if i == n:
            break
        for r in range(rates):
            direct, fresh = after_syllable[i, r] + evidence[i], after_pause[i] - cost[r]
            fresh_won[i, r] = fresh > direct
            mean = means[i] * align.RATES[r]
            d = np.arange(align.MIN_FRAMES, max(min(total, int(align.LONGEST_SHARE * mean) + align.MIN_FRAMES),
                                                align.MIN_FRAMES) + 1)
            cand = align._before(np.maximum(direct, fresh), k, d, align._NEG) + align._duration_score(d, mean)
            after_syllable[i + 1, r] = cand.max(axis=1)
            length[i, r] = d[cand.argmax(axis=1)]
    return align._Lattice(after_syllable, after_pause, pause_from, rate_before, length, fresh_won)


def whole_soft_forward(evidence, silence, edges, means, penalty, pace, temperature, starts, ends):
    """`_soft_forward` with its pauses summed over the whole part and every duration prior per cell."""
    n, positions = evidence.shape
    total = positions - 1
    evidence, silence, edges, penalty = (x / temperature for x in (evidence, silence, edges, penalty))
    cum = np.concatenate([[0.0], np.cumsum(silence)])
    after_syllable = np.full((n + 1, positions), align._NEG)
    after_pause = np.full((n + 1, positions), align._NEG)
    after_syllable[0, 0] = 0.0
    k = np.arange(positions)
    for i in range(n):
        summed = np.logaddexp.accumulate(after_syllable[i] + edges[0] - cum)
        gap = align.EDGE_MIN_PAUSE if i == 0 else align.MIN_PAUSE
        after_pause[i, gap:] = summed[:-gap] + cum[gap:] - penalty[i] + edges[1, gap:]
        start_score = np.logaddexp(after_syllable[i] + evidence[i], after_pause[i])
        longest = min(total, int(align.LONGEST_SHARE * means[i] * np.exp(pace.max())) + align.MIN_FRAMES)
        d = np.arange(align.MIN_FRAMES, max(longest, align.MIN_FRAMES) + 1)
        band = k[max(ends[i] - align.BAND, 0):ends[i] + align.BAND + 1]
        local = 0.5 * (pace[band][:, None] + align._before(pace, band, d, pace[0]))
        prior = -0.5 * ((np.log(np.maximum(d, 1) / means[i])[None, :] - local) / align.DURATION_SPREAD) ** 2
        cand = align._before(start_score, band, d, align._NEG) + prior / temperature
        top = cand.max(axis=1)
        after_syllable[i + 1, band] = top + np.log(np.exp(cand - top[:, None]).sum(axis=1))
    return after_syllable, after_pause[:n]


def biaobei_part(names: list[str]) -> tuple[Audio, float, float, list[str]]:
    """Biaobei recordings joined end to end, read as one part from their first syllable's start to
    their last's end: (audio, start s, end s, tone-numbered pinyin)."""
    samples, syllables, times, offset = [], [], [], 0.0
    for name in names:
        audio = load_audio(BIAOBEI / "wav" / f"{name}.wav")
        grid = BIAOBEI / "TextGrid" / f"{name}.TextGrid"
        _, tiers = read_tiers(grid.read_text(encoding="utf-8"), str(grid))
        spoken = [i for i in tiers["syllables_pinyin"] if i.text not in SILENCE]
        syllables += [i.text for i in spoken]
        times += [offset + spoken[0].start, offset + spoken[-1].end]
        samples.append(audio.samples)
        offset += audio.duration
    return Audio(np.concatenate(samples), audio.rate, "+".join(names)), times[0], times[-1], syllables


def same_where_reached(mine: np.ndarray, theirs: np.ndarray) -> bool:
    """Whether two score tables are equal to the bit wherever the whole table holds a cut's score,
    and both near _NEG (no cut) elsewhere."""
    reached = theirs > align._NEG / 2
    return bool(np.array_equal(mine[reached], theirs[reached]) and np.all(mine[~reached] < align._NEG / 2))


@pytest.mark.skipif(not BIAOBEI.is_dir(), reason="the bench recordings (../shared/bench) are not here")
@pytest.mark.parametrize("names", [["000001"], ["000002", "000003"], [f"{k:06d}" for k in range(16, 21)]])
def test_the_programmes_cut_to_whole_cuts_give_what_the_whole_tables_give(names, monkeypatch):
    audio, start, end, syllables = biaobei_part(names)
    forwards, posteriors, priors = [], [], []
    forward, onset_posteriors, duration_scores = align._forward, align._onset_posteriors, align._duration_scores

    def noted_forward(*args):
        forwards.append(args)
        return forward(*args)

    def noted_posteriors(*args):
        posteriors.append(args)
        return onset_posteriors(*args)

    def noted_priors(*args):
        priors.append(duration_scores(*args).shape[0])
        return duration_scores(*args)

    monkeypatch.setattr(align, "_forward", noted_forward)
    monkeypatch.setattr(align, "_onset_posteriors", noted_posteriors)
    monkeypatch.setattr(align, "_duration_scores", noted_priors)
    align.align_details(audio, Span(start, end), syllables)
    monkeypatch.undo()
    (args,), (soft_args,) = forwards, posteriors
    n, positions = args[0].shape
    cut, whole = align._forward(*args), whole_forward(*args)
    for mine, theirs in zip(align._best_cut(cut), align._best_cut(whole)):
        assert np.array_equal(mine, theirs)
    for i in range(n + 1):  # i syllables done where a whole cut can be: after theirs, before the rest's
        on_cuts = slice(i * align.MIN_FRAMES, positions - (n - i) * align.MIN_FRAMES)
        assert same_where_reached(cut.after_syllable[i, :, on_cuts], whole.after_syllable[i, :, on_cuts])
        assert same_where_reached(cut.after_pause[i, on_cuts], whole.after_pause[i, on_cuts])
    posterior = align._onset_posteriors(*soft_args)
    monkeypatch.setattr(align, "_soft_forward", whole_soft_forward)
    assert np.array_equal(posterior, align._onset_posteriors(*soft_args))
    # the paragraph is read at more than one pace: some priors were scored per cell, not on one row
    assert (max(priors) > 1) == (len(names) == 5)


def test_the_candidates_view_reads_each_start_or_the_fill_before_the_part():
    x = np.random.default_rng(3).standard_normal(40)
    for ends, d in ((np.arange(0, 40), np.arange(3, 9)), (np.arange(12, 30), np.arange(3, 20)), (np.arange(39, 40), np.arange(1, 3))):
        view = align._before(x, ends, d, -7.0)
        start = ends[:, None] - d[None, :]
        assert np.array_equal(view, np.where(start >= 0, x[np.maximum(start, 0)], -7.0))


def test_on_random_parts_down_to_three_frames_a_syllable_the_cut_programmes_agree_with_the_whole_ones(monkeypatch):
    rng = np.random.default_rng(7)
    for _ in range(60):  # 1-11 syllables, 0-200 frames to spare, scores of any scale
        n = int(rng.integers(1, 12))
        positions = n * align.MIN_FRAMES + int(rng.integers(0, 200)) + 1
        evidence = rng.normal(0.0, rng.choice([0.1, 1.0, 3.0]), (n, positions))
        evidence[0] = 0.0
        args = (evidence, np.clip(rng.normal(-0.5, 1.5, positions - 1), -3.0, 1.0),
                np.abs(rng.normal(0.0, 1.0, (2, positions))), rng.uniform(2.0, 40.0, n), rng.uniform(1.0, 6.0, n + 1))
        cut = align._best_cut(align._forward(*args))
        for mine, theirs in zip(cut, align._best_cut(whole_forward(*args))):
            assert np.array_equal(mine, theirs)
        starts, ends, rate = cut
        pace = np.zeros(positions)
        for a, b, r in zip(starts, ends, rate):
            pace[a:b + 1] = np.log(align.RATES[r])
        posterior = align._onset_posteriors(*args, pace, starts, ends, align.TEMPERATURE)
        with monkeypatch.context() as patched:
            patched.setattr(align, "_soft_forward", whole_soft_forward)
            assert np.array_equal(posterior, align._onset_posteriors(*args, pace, starts, ends, align.TEMPERATURE))
