"""Decode a speech recording to mono float samples.

WAV (8/16/24/32-bit integer or float, any rate) and FLAC are read by
soundfile (libsndfile); every other format (MP3, OGG Vorbis/Opus, M4A/AAC,
...) is decoded by the ffmpeg that imageio-ffmpeg bundles, to a temporary
float WAV first (pydub would need ffprobe, which is not bundled). Stereo and
multichannel audio is mixed to mono by averaging the channels. The sample
rate is kept as recorded.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import tempfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import soundfile

from cartoonface.errors import AudioError

# Longest recording accepted: 30 minutes (README, "Limits").
MAX_SECONDS = 30 * 60
# A recording whose peak is below this is silent: -70 dBFS, far below the
# noise floor of any microphone recording.
SILENT_PEAK = 10 ** (-70 / 20)
# Digital silence: a stretch whose samples span at most this (peak to peak) holds no recorded
# sound, only a constant (zeros, a DC offset, the resting code of 8-bit audio) or the last
# bit of a 16-bit file flickering (2 steps of 2 / 65536: about -84 dBFS). Edited recordings,
# joined files, noise gates and TTS put such stretches between sentences; they are no noise
# floor (thesis 002, 3.2.1: silence is normally *not* zero, because of environment noise).
DIGITAL_SILENCE = 2 * 2 / 65536
# When fewer than this share of a recording's frames hold recorded (non-digital-silence) sound, the
# segmenter and the aligner take their floor over all frames (a recording nearly all digital silence).
MIN_RECORDED = 0.05
# Integer sample formats of 8 to 16 bits: a recording whose samples all lie on the grid of one
# of them (steps of 2 / 2**bits, offset by a removed DC) flickers over QUANTUM_STEPS steps of that
# grid where it is digital silence; 8-bit audio turns the quietest sounds and noise into such
# flicker (1 step = -42 dBFS). Chosen on Biaobei 000001-000035 stored as 8-bit (bench/silence.py:
# 1, 2, 3 steps tried; 2 best).
GRID_BITS = range(8, 17)
QUANTUM_STEPS = 2
GRID_TOLERANCE = 0.01  # share of a step a sample may lie off the grid (float32 rounding)
GRID_CHUNK = 1 << 16   # samples checked at a time
GRID_PROBE = 1 << 10   # samples checked first: float audio is off every grid within them
# A mean (DC offset) larger than this (-60 dBFS) is subtracted from the samples when reading:
# a faulty converter or sound card adds it; smaller means are what speech itself averages to.
DC_OFFSET = 1e-3
# The page's audio (page_copy): AAC at this bit rate, mono, is 0.48 MB per minute, so a 3-minute
# book's sound stays far under issue 14's 3 MB; speech at 64 kbit/s AAC sounds like the recording.
PAGE_BITRATE = "64k"
# ffmpeg's "fast" AAC coder: 0.29 s of CPU for 190 s of speech against 1.71 s for its default
# "twoloop", the same size, and no less faithful on speech (waveform SNR of the decoded copy
# 29.1 dB against 27.7 dB on bench/generate.py's input; docs/BENCHMARKS.md, "Speed of the SVG stage").
PAGE_CODER = ("-aac_coder", "fast")
# page_copy_begun's niceness: the lowest CPU priority, so that ffmpeg runs on core time the job's own
# processes leave idle (the start, the analysis's waits, the drawing's joins, the tail) rather than
# beside them (docs/BENCHMARKS.md, "early": the command 0.96x on the 190 s book).
BEGUN_NICENESS = 19
# Containers libsndfile reads exactly (sample count from the header); the rest go through ffmpeg.
_SOUNDFILE_MAGIC = (b"RIFF", b"RIFX", b"RF64", b"fLaC", b"FORM")


@dataclass(frozen=True, eq=False)
class Audio:
    """A decoded recording: `samples` (n,) float32 mono in [-1, 1] at `rate` Hz, read from `source`."""

    samples: np.ndarray
    rate: int
    source: str

    @property
    def duration(self) -> float:
        """Length in seconds."""
        return len(self.samples) / self.rate


def digital_silence(samples: np.ndarray, rate: int, hop: float, step: float | None = None) -> np.ndarray:
    """(n,) samples at `rate` Hz -> (n // block,) bool per block of `hop` seconds (at least one
    sample): True where the block's samples span at most DIGITAL_SILENCE, or QUANTUM_STEPS times
    `step` (their integer grid's step; None: `quantum(samples)`) when that is more (no recorded sound)."""
    block = max(1, round(rate * hop))
    count = len(samples) // block
    if count == 0:
        return np.zeros(0, dtype=bool)
    blocks = np.asarray(samples[: count * block]).reshape(count, block)
    limit = max(DIGITAL_SILENCE, QUANTUM_STEPS * (quantum(samples) if step is None else step))
    return (blocks.max(axis=1) - blocks.min(axis=1)) <= limit


def quantum(samples: np.ndarray) -> float:
    """(n,) samples in [-1, 1] -> the step 2 / 2**bits of the integer format (GRID_BITS) whose
    grid all of them lie on, up to a common offset (a removed DC), the coarsest that fits;
    0.0 when none fits (float audio, or a format finer than 16 bits)."""
    x = np.asarray(samples)
    if x.size < 2:
        return 0.0
    origin = float(x[0])
    # chunk by chunk, a short one first: float audio fails on its first samples (each of GRID_BITS
    # tried), and no copy of a long file is made
    edges = [0, *range(GRID_PROBE, x.size, GRID_CHUNK), x.size]
    for bits in GRID_BITS:
        step = 2.0 / 2**bits
        if all(_on_grid(x[a:b], origin, step) for a, b in zip(edges, edges[1:])):
            return step
    return 0.0


def _on_grid(chunk: np.ndarray, origin: float, step: float) -> bool:
    """Whether every sample of (m,) `chunk` lies within GRID_TOLERANCE of origin + j * step."""
    position = (np.asarray(chunk, dtype=np.float64) - origin) / step
    return bool(np.all(np.abs(position - np.round(position)) <= GRID_TOLERANCE))


def ffmpeg_exe() -> str:
    """Path of the ffmpeg executable bundled by imageio-ffmpeg."""
    import imageio_ffmpeg

    return imageio_ffmpeg.get_ffmpeg_exe()


def load_audio(path: str | os.PathLike[str]) -> Audio:
    """Decode the audio file at `path` to an `Audio` (mono float32, original rate).

    Raises AudioError naming the file when it is missing, empty (0 bytes or no
    samples), not audio, truncated or corrupt, silent, or longer than 30 minutes.
    """
    file = Path(path)
    if not file.is_file():
        raise AudioError(f"{file}: no such audio file")
    size = file.stat().st_size
    if size == 0:
        raise AudioError(f"{file}: the file is empty (0 bytes); expected a recording (WAV, MP3, OGG, M4A, FLAC)")
    with file.open("rb") as handle:
        head = handle.read(12)
    if head[:4] in _SOUNDFILE_MAGIC:
        samples, rate = _read_soundfile(file, head)
    else:
        samples, rate = _read_ffmpeg(file)
    if len(samples) == 0:
        raise AudioError(f"{file}: the recording holds no samples; expected speech")
    if len(samples) > MAX_SECONDS * rate:
        raise AudioError(
            f"{file}: the recording is longer than {MAX_SECONDS // 60} minutes; "
            "split it into parts of at most 30 minutes"
        )
    # Float files may hold NaN or infinities (a broken encoder): read them as silence / full scale.
    if not np.isfinite(samples).all():  # one pass to check; nan_to_num makes four
        np.nan_to_num(samples, copy=False, nan=0.0, posinf=1.0, neginf=-1.0)
    offset = float(np.mean(samples, dtype=np.float64))
    if abs(offset) > DC_OFFSET:
        samples -= np.float32(offset)  # a DC offset is no sound: it would hide a silent file
    low, high = float(samples.min()), float(samples.max())
    if low < -1.0 or high > 1.0:
        np.clip(samples, -1.0, 1.0, out=samples)
        low, high = max(low, -1.0), min(high, 1.0)
    peak = max(high, -low)
    if peak < SILENT_PEAK:
        level = "digital silence" if peak == 0 else f"peak {20 * np.log10(peak):.0f} dBFS"
        raise AudioError(f"{file}: the recording is silent ({level}); expected audible speech")
    return Audio(samples=samples, rate=int(rate), source=str(file))


def _read_soundfile(file: Path, head: bytes) -> tuple[np.ndarray, int]:
    """Read a WAV/FLAC/AIFF file with libsndfile; return (mono float32 samples, rate)."""
    if head[:4] == b"RIFF" and head[8:12] == b"WAVE":
        _check_wav_complete(file)
    try:
        sound = soundfile.SoundFile(str(file))
    except (soundfile.LibsndfileError, RuntimeError) as exc:
        if head[:4] in (b"RIFF", b"RF64"):
            # A WAV codec libsndfile lacks (e.g. MP3 inside WAV): let ffmpeg try.
            return _read_ffmpeg(file)
        raise AudioError(f"{file}: not a readable audio file ({exc})") from None
    with sound:
        if sound.frames > (MAX_SECONDS + 1) * sound.samplerate:
            raise AudioError(
                f"{file}: the recording lasts {sound.frames / sound.samplerate / 60:.1f} minutes; "
                f"at most {MAX_SECONDS // 60} minutes are accepted"
            )
        try:
            mono = np.empty(sound.frames, dtype=np.float32)
            if sound.channels == 1:  # read in place: the mean of one channel is that channel
                return sound.read(out=mono), sound.samplerate
            filled = 0
            for block in sound.blocks(blocksize=1 << 20, dtype="float32", always_2d=True):
                mono[filled : filled + len(block)] = block.mean(axis=1)
                filled += len(block)
        except (soundfile.LibsndfileError, RuntimeError) as exc:
            raise AudioError(f"{file}: corrupt audio data ({exc})") from None
    return mono[:filled], sound.samplerate


def _check_wav_complete(file: Path) -> None:
    """Raise AudioError when a RIFF/WAVE file's data chunk is shorter than its header declares.

    Sizes of 0 or 0xFFFFFFFF are streaming placeholders and accepted.
    """
    size = file.stat().st_size
    with file.open("rb") as handle:
        pos = 12
        while pos + 8 <= size:
            handle.seek(pos)
            chunk = handle.read(8)
            length = int.from_bytes(chunk[4:8], "little")
            if chunk[:4] == b"data":
                available = size - pos - 8
                if 0 < length < 0xFFFFFFFF and available < length:
                    raise AudioError(
                        f"{file}: truncated WAV file: the header declares {length} bytes of samples "
                        f"but only {available} are present"
                    )
                return
            pos += 8 + length + (length & 1)
    raise AudioError(f"{file}: truncated or corrupt WAV file: no sample data (no 'data' chunk)")


def _read_ffmpeg(file: Path) -> tuple[np.ndarray, int]:
    """Decode any format ffmpeg knows to a temporary float WAV; return (mono float32 samples, rate)."""
    with tempfile.TemporaryDirectory(prefix="cartoonface-audio-") as tmp:
        wav = Path(tmp) / "decoded.wav"
        command = [
            ffmpeg_exe(), "-nostdin", "-v", "error", "-i", str(file),
            "-map", "0:a:0", "-vn", "-ac", "1", "-c:a", "pcm_f32le",
            # Decode a little past the limit only: enough to know it is too long.
            "-t", str(MAX_SECONDS + 1), "-f", "wav", str(wav),
        ]  # fmt: skip
        done = subprocess.run(command, capture_output=True, text=True, errors="replace")
        if done.returncode != 0 or not wav.is_file():
            reason = ffmpeg_reason(done.stderr)
            raise AudioError(f"{file}: not a readable audio file ({reason}); expected WAV, MP3, OGG, M4A or FLAC")
        samples, rate = soundfile.read(str(wav), dtype="float32", always_2d=True)
    return np.ascontiguousarray(samples.mean(axis=1), dtype=np.float32), int(rate)


def ffmpeg_reason(stderr: str) -> str:
    """The most telling line of ffmpeg's error output, without the file path."""
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    if any("matches no streams" in line for line in lines):
        return "it contains no audio stream"
    if not lines:
        return "ffmpeg could not decode it"
    reason = lines[-1].split(": ", 1)[-1] if ": " in lines[-1] else lines[-1]
    return reason[:200]


def page_copy(path: str | os.PathLike[str], out_dir: str | os.PathLike[str], stem: str = "audio") -> Path:
    """Put the recording at `path` into `out_dir` compressed for the page (by ffmpeg at this process's
    priority, written beside as `stem`.begun.m4a and renamed); return the file's path.

    Any format ffmpeg reads becomes `stem`.m4a: AAC-LC, mono, PAGE_BITRATE (every browser plays it;
    the MP4 edit list tells players to skip the encoder's priming, so times stay those of the
    recording). Raises AudioError when the conversion fails.
    """
    with page_copy_begun(path, out_dir, stem, niceness=None) as copy:
        return copy.finish()


@dataclass(frozen=True)
class BegunCopy:
    """page_copy_begun's handle. `hurry()`: from now on the copy is made at this process's priority;
    `finish()`: hurry, wait, and return the file's path (AudioError when ffmpeg fails)."""

    hurry: Callable[[], None]
    finish: Callable[[], Path]


@contextlib.contextmanager
def page_copy_begun(path: str | os.PathLike[str], out_dir: str | os.PathLike[str], stem: str = "audio",
                    niceness: int | None = BEGUN_NICENESS) -> Iterator[BegunCopy]:
    """page_copy of the recording at `path` into `out_dir` (`stem`.m4a, the same bytes), begun now in
    an ffmpeg at the lowest CPU priority (BEGUN_NICENESS; `niceness` None: this process's): it takes
    core time the caller leaves idle.

    Yields a BegunCopy. Its `hurry` gives that ffmpeg this process's priority; where that is not
    allowed (only root may lower a niceness) it is stopped and begun again at this process's
    priority. Hurried at the latest by `finish`, it never waits long behind other work. On leaving
    the block an unfinished ffmpeg is stopped and its part removed, so nothing is written into
    `out_dir` after it; a failed one leaves no part either.
    """
    source, folder = Path(path), Path(out_dir)
    partial = folder / f"{stem}.begun.m4a"
    folder.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryFile() as log:

        def begin(niceness: int | None) -> subprocess.Popen[bytes]:
            log.seek(0)
            log.truncate()
            ffmpeg = subprocess.Popen(_page_command(source, partial), stdin=subprocess.DEVNULL,
                                      stdout=subprocess.DEVNULL, stderr=log)
            if niceness is not None:  # lowered at once, before it starts its threads (they inherit it)
                with contextlib.suppress(ProcessLookupError):
                    os.setpriority(os.PRIO_PROCESS, ffmpeg.pid, niceness)
            return ffmpeg

        running, hurried = [begin(niceness)], [False]

        def hurry() -> None:
            if not hurried[0] and running[-1].poll() is None and not _raised(running[-1].pid):
                _stopped(running[-1], partial)
                running.append(begin(None))
            hurried[0] = True

        def finish() -> Path:
            hurry()
            if running[-1].wait() != 0 or not partial.is_file():
                partial.unlink(missing_ok=True)
                log.seek(0)
                reason = ffmpeg_reason(log.read().decode("utf-8", "replace"))
                raise AudioError(f"{source}: cannot compress for the page ({reason})")
            return partial.replace(folder / f"{stem}.m4a")

        try:
            yield BegunCopy(hurry, finish)
        finally:
            if running[-1].poll() is None:
                _stopped(running[-1], partial)


def _stopped(ffmpeg: subprocess.Popen[bytes], partial: Path) -> None:
    """Stop the running `ffmpeg` and remove the file it was writing, `partial`."""
    ffmpeg.kill()
    ffmpeg.wait()
    partial.unlink(missing_ok=True)


def _raised(pid: int) -> bool:
    """Give every thread of process `pid` this process's niceness; False when that is not allowed.
    A process or thread that has ended meanwhile counts as raised."""
    niceness = os.getpriority(os.PRIO_PROCESS, 0)
    try:
        threads = os.listdir(f"/proc/{pid}/task")
    except FileNotFoundError:  # ended (and reaped)
        return True
    for thread in threads:
        try:
            os.setpriority(os.PRIO_PROCESS, int(thread), niceness)
        except ProcessLookupError:  # this thread ended meanwhile
            continue
        except PermissionError:
            return False
    return True


def _page_command(source: Path, m4a: Path) -> list[str]:
    """ffmpeg's arguments making page_copy's AAC file `m4a` of the recording `source`."""
    return [
        ffmpeg_exe(), "-nostdin", "-v", "error", "-i", str(source),
        "-map", "0:a:0", "-vn", "-ac", "1", "-c:a", "aac", *PAGE_CODER, "-b:a", PAGE_BITRATE,
        "-movflags", "+faststart", str(m4a),
    ]  # fmt: skip
