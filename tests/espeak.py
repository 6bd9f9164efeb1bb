"""Mandarin speech synthesised by espeak-ng, with the exact start time of every syllable.

libespeak-ng (Debian package libespeak-ng1) is driven through ctypes with the voice
`cmn-latn-pinyin`, which reads tone-numbered pinyin; the library reports one WORD event per
syllable (see /work/shared/DEPENDENCIES.md). Tests use it as speech with known syllable
onsets; bench/align.py as the template of the espeak+DTW baseline (the aligner does not use it).

Each synthesis runs in a fresh process (this file run as a script): the library keeps state
from one synthesis to the next (the pitch-flutter position, a static counter in its wave
generator that no call resets), so in one process the same syllables came out differently
depending on what had been spoken before, and a test passed or failed with the tests run
before it.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import json
import subprocess
import sys
import threading
from dataclasses import dataclass
from typing import Sequence

import numpy as np

VOICE = b"cmn-latn-pinyin"
_SYNCHRONOUS = 2          # espeak_AUDIO_OUTPUT AUDIO_OUTPUT_SYNCHRONOUS
_PHONEME_EVENTS = 1       # espeakINITIALIZE_PHONEME_EVENTS
_WORD = 1                 # espeakEVENT_WORD
_CHARACTER = 1            # espeak_POSITION_TYPE POS_CHARACTER
_UTF8 = 1                 # espeakCHARS_UTF8
_RATE, _PITCH = 1, 3      # espeak_PARAMETER espeakRATE (words a minute), espeakPITCH (0-100, 50 normal)


@dataclass(frozen=True, eq=False)
class Synthesis:
    """samples (n,) float32 in [-1, 1] at `rate` Hz; onsets (N,) seconds, one per syllable."""

    samples: np.ndarray
    rate: int
    onsets: tuple[float, ...]


class _Event(ctypes.Structure):
    # espeak_EVENT of speak_lib.h (the id union is 8 bytes: int, const char * or char[8])
    _fields_ = [("type", ctypes.c_int), ("unique_identifier", ctypes.c_uint),
                ("text_position", ctypes.c_int), ("length", ctypes.c_int),
                ("audio_position", ctypes.c_int), ("sample", ctypes.c_int),
                ("user_data", ctypes.c_void_p), ("id", ctypes.c_char * 8)]


_CALLBACK = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_short), ctypes.c_int, ctypes.POINTER(_Event))
_lock = threading.Lock()


class _Engine:
    """The loaded library (None until loaded or when missing), its sample rate, the callback
    object (kept alive while the library holds it), and what one synthesis collects."""

    def __init__(self) -> None:
        self.tried = False
        self.lib: ctypes.CDLL | None = None
        self.rate = 0
        self.callback: object = None
        self.chunks: list[np.ndarray] = []
        self.words: list[int] = []


_engine = _Engine()


def _library() -> ctypes.CDLL | None:
    """The initialised library, or None when espeak-ng or the voice is missing."""
    if not _engine.tried:
        _engine.tried = True
        name = ctypes.util.find_library("espeak-ng") or "libespeak-ng.so.1"
        try:
            lib = ctypes.CDLL(name)
        except OSError:
            return None
        rate = lib.espeak_Initialize(_SYNCHRONOUS, 0, None, _PHONEME_EVENTS)
        if rate <= 0 or lib.espeak_SetVoiceByName(VOICE) != 0:
            return None
        callback = _CALLBACK(_collect)
        lib.espeak_SetSynthCallback(callback)
        _engine.lib, _engine.rate, _engine.callback = lib, int(rate), callback
    return _engine.lib


def _collect(wav: ctypes._Pointer, count: int, events: ctypes._Pointer) -> int:
    """The synthesis callback: keep `count` samples of `wav` and the sample of each WORD event
    that covers some text."""
    if wav and count > 0:
        _engine.chunks.append(np.ctypeslib.as_array(wav, (count,)).copy())
    i = 0
    while events[i].type != 0:
        if events[i].type == _WORD and events[i].length > 0:  # a sentence break gives an empty word
            _engine.words.append(events[i].sample)
        i += 1
    return 0


@dataclass(frozen=True)
class Voice:
    """How espeak-ng reads: `variant` one of its voice variants ("f3", "m1", ...; "" the plain
    voice), `rate` words (syllables) a minute, `pitch` 0-100 (None: espeak-ng's defaults, 175
    and 50)."""

    variant: str = ""
    rate: int | None = None
    pitch: int | None = None

    def __str__(self) -> str:
        return f"{self.variant or 'plain'}, {self.rate or 175} words a minute, pitch {self.pitch or 50}"


def _speak_here(text: bytes, voice: Voice = Voice()) -> tuple[np.ndarray, int, list[int]] | None:
    """Speak `text` in this process with `voice` -> (int16 samples, rate, sample of each WORD
    event), or None when the library or the voice is missing (espeak-ng reads an unknown variant
    with the plain voice)."""
    with _lock:
        lib = _library()
        if lib is None:
            return None
        if voice.variant and lib.espeak_SetVoiceByName(VOICE + b"+" + voice.variant.encode()) != 0:
            return None
        for parameter, value in ((_RATE, voice.rate), (_PITCH, voice.pitch)):
            if value is not None:
                lib.espeak_SetParameter(parameter, value, 0)
        _engine.chunks, _engine.words = [], []
        lib.espeak_Synth(text, len(text) + 1, 0, _CHARACTER, 0, _UTF8, None, None)
        chunks, words, rate = _engine.chunks, _engine.words, _engine.rate
    samples = np.concatenate(chunks) if chunks else np.zeros(0, dtype=np.int16)
    return samples.astype(np.int16), rate, words


def synthesize(syllables: Sequence[str], voice: Voice = Voice()) -> Synthesis | None:
    """Speak tone-numbered pinyin syllables with `voice` (in a fresh process, so the result does
    not depend on earlier syntheses); None when espeak-ng is unavailable or does not report
    exactly one syllable per item (odd spellings it reads as letters). A syllable may carry
    punctuation ("hao3,", "ma5."): espeak-ng pauses after it as after a clause or a sentence."""
    text = " ".join(s for s in syllables if s.strip())
    if not text or len(text.split()) != len(syllables):
        return None
    spoken = read(text, voice)
    return spoken if spoken is not None and len(spoken.onsets) == len(syllables) else None


def read(text: str, voice: Voice = Voice()) -> Synthesis | None:
    """Speak any `text` (pinyin or Hanzi, as samples/speech/make_speech.py does) with `voice` in a
    fresh process; its onsets are espeak-ng's WORD events (one per Hanzi or pinyin syllable). None
    when espeak-ng is unavailable or says nothing."""
    options = json.dumps([voice.variant, voice.rate, voice.pitch])
    done = subprocess.run([sys.executable, __file__, text, options], capture_output=True, check=False)
    header, _, raw = done.stdout.partition(b"\n")
    if done.returncode != 0 or not header or not raw:
        return None
    head = json.loads(header)
    samples = np.frombuffer(raw, dtype=np.int16).astype(np.float32) / 32768.0
    return Synthesis(samples, head["rate"], tuple(w / head["rate"] for w in head["words"]))


def story() -> Synthesis | None:
    """The project's sample story as samples/speech/make_speech.py reads it (story.txt, its voice and
    rate): the samples of samples/speech/story.wav (which ends with a little more of the last sound)
    and the onset of every syllable; None without espeak-ng."""
    from samples.speech import make_speech  # here: this file also runs as a script, outside the checkout's path

    text = (make_speech.HERE / "story.txt").read_text(encoding="utf-8")
    sentences = " ".join(line.strip() for line in text.splitlines() if line.strip())
    return read(sentences, Voice(make_speech.VOICE.partition("+")[2], make_speech.RATE))


if __name__ == "__main__":
    # one synthesis: argv[1] the text, argv[2] the Voice as a JSON list; stdout a JSON line
    # {"rate", "words"} then the int16 samples
    spoken = _speak_here(sys.argv[1].encode("utf-8"), Voice(*json.loads(sys.argv[2])))
    if spoken is None:
        sys.exit(1)
    pcm, hertz, events = spoken
    sys.stdout.buffer.write(json.dumps({"rate": hertz, "words": events}).encode() + b"\n" + pcm.tobytes())
