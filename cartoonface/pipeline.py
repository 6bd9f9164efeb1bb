"""The one library call behind `cartoonface generate` and the web app.

`generate` runs every stage: decode the audio, find the sentences and align the
syllables (or read an edited TextGrid), schedule the behaviour (or read an
edited actions.json), sample the face state of every frame, draw the SVG
animation and write the page folder (docs/output.md). The folder is built
under a temporary name and renamed into place (files.atomic_directory): it
appears complete or not at all.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import os
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import soundfile

from cartoonface.animate.actions import actions_to_json, load_actions
from cartoonface.animate.behaviour import emotion_actions, marked_spans, schedule, silences_of, speech_pauses, speech_spans
from cartoonface.animate.body import body_motion
from cartoonface.animate.frames import FPS_RANGE, frame_times, on_twos, sample_breaths, sample_frames, states_at
from cartoonface.animate.idle import sway
from cartoonface.animate.prosody import pitch_peaks, recording_pitch
from cartoonface.animate.style import PAGE_STYLES, STYLES
from cartoonface.animate.timeline import build_timeline
from cartoonface.errors import AlignmentError, OptionError, TranscriptError
from cartoonface.exports.captions import CAPTIONS_NAME, captions_vtt
from cartoonface.exports.cues import FORMATS as CUE_FORMATS
from cartoonface.exports.cues import cues_name, cues_text, mouth_cues
from cartoonface.face.emotion import EMOTIONS
from cartoonface.face.model import FaceModel, load_face
from cartoonface.files import atomic_directory, folder_size, read_user_text, write_text_atomic
from cartoonface.render.animation import DRAWN_SHARE, animation_svg
from cartoonface.render.pages import AUDIO_STEM, PAGES, check_links, compile_page, copy_audio, page_html, write_site
from cartoonface.render.scenery import BACKGROUNDS, CLOTHES
from cartoonface.speech.audio_only import AUDIO_ONLY_NOTE, transcribed
from cartoonface.speech.analyse import analyse
from cartoonface.speech.english import LANGUAGES
from cartoonface.speech.records import Alignment
from cartoonface.speech.audio import Audio, load_audio, page_copy_begun
from cartoonface.speech.textgrid import load_textgrid, write_textgrid
from cartoonface.speech.transcript import emotion_marks
from cartoonface.video.clip import Clip, VideoError, extract_audio, probe
from cartoonface.workers import collector_paused, helper_process, offloaded, processes

# Share of the whole job done when each stage starts (measured 2026-11-27, fourth session,
# processor time of the job's process, on the sample story and on bench/generate.py's 190 s input:
# the SVG takes ~60 % of it, the schedule's pitch track is computed meanwhile by the analysis
# helper process, workers.py; docs/web.md, "Progress"; docs/BENCHMARKS.md, "Issue 16, where it
# stands (end of the fourth session").
STAGES = (("decode", 0.0), ("segment", 0.03), ("align", 0.16), ("schedule", 0.32),
          ("frames", 0.33), ("svg", 0.35), ("pages", 0.96))
# An edited TextGrid may end this much after the audio (Praat rounds its times).
ALIGNMENT_SLACK = 0.05  # seconds
MAX_TITLE = 200  # characters
# Driven by a video: the scheduled actions kept (the video moves the head, eyes, brows and mouth).
VIDEO_KEEPS = ("emotion", "breath")
# Share of a video job spent decoding the clip and tracking the face (bench/video.py: about 1 of the 2.5
# CPU seconds of the joined GRID clips).
TRACK_SHARE = 0.4
SILENT_RATE = 16000  # Hz of the silence a clip without sound gets as the page's clock
SILENT_NOTE = "the video has no sound: the page is silent and its mouth follows the video alone"
VIDEO_MOUTH_NOTE = ("no transcript: the mouth follows the video; the TextGrid and mouth cues come from "
                    "the audio alone (loudness and formants)")


@dataclass(frozen=True)
class Options:
    """What to make: the page kind, its title and links, frame rate, seed, announcer
    scenery, and optional edited inputs (actions.json, TextGrid) replacing the automatic ones."""

    page: str = "audiobook"  # or "announcer"
    title: str = ""
    fps: int = 30  # 12..60
    seed: int = 0
    style: str | None = None  # performance style (animate/style.py); None: the page's default
    background: str = "studio"  # announcer backgrounds (scenery.BACKGROUNDS)
    clothes: str = "suit"  # announcer clothes (scenery.CLOTHES)
    actions: Path | None = None  # edited actions.json
    alignment: Path | None = None  # edited TextGrid: skips alignment
    pause: tuple[float, float] | None = None  # thesis mode of Alg. 3.1
    links: tuple[tuple[str, str], ...] = ()  # (label, url) for the audio-book page
    emotion: str | None = None  # default mood (face/emotion.py EMOTIONS) where the transcript marks none
    intensity: float = 1.0  # of the default mood, 0..1
    keep_original: bool = False  # also put the recording as given into the folder (recording.<ext>)
    cues: tuple[str, ...] = ()  # Rhubarb mouth-cue files to add: "tsv", "json", "xml" (exports/cues.py)
    language: str | None = None  # "zh" or "en" (speech/english.py LANGUAGES); None: from the transcript's script


@dataclass(frozen=True)
class Result:
    """What `generate` made: the folder, seconds of audio, frames, bytes written, wall seconds, notes."""

    out_dir: Path
    duration: float
    frames: int
    size: int
    seconds: float
    notes: tuple[str, ...]


def check_options(options: Options) -> None:
    """Raise OptionError naming the first option out of range (before any work is done)."""
    if options.page not in PAGES:
        raise OptionError(f"page {options.page!r}: expected one of {', '.join(PAGES)}")
    fps = options.fps
    if isinstance(fps, bool) or not isinstance(fps, int) or not FPS_RANGE[0] <= fps <= FPS_RANGE[1]:
        raise OptionError(f"fps {fps!r}: expected a whole number of frames per second from {FPS_RANGE[0]} to {FPS_RANGE[1]}")
    if options.style is not None and options.style not in STYLES:
        raise OptionError(f"style {options.style!r}: expected one of {', '.join(STYLES)}")
    if isinstance(options.seed, bool) or not isinstance(options.seed, int) or options.seed < 0:
        raise OptionError(f"seed {options.seed!r}: expected a whole number 0 or more")
    if options.background not in BACKGROUNDS:
        raise OptionError(f"background {options.background!r}: expected one of {', '.join(BACKGROUNDS)}")
    if options.clothes not in CLOTHES:
        raise OptionError(f"clothes {options.clothes!r}: expected one of {', '.join(CLOTHES)}")
    if len(options.title) > MAX_TITLE:
        raise OptionError(f"title: {len(options.title)} characters; expected at most {MAX_TITLE}")
    if options.pause is not None:
        start, end = options.pause
        if not 0 <= start < end:
            raise OptionError(f"pause {start},{end}: expected START,END seconds with 0 <= START < END")
    for fmt in options.cues:
        if fmt not in CUE_FORMATS:
            raise OptionError(f"cues {fmt!r}: expected one of {', '.join(CUE_FORMATS)}")
    check_links(options.links)
    if options.emotion is not None and options.emotion not in EMOTIONS:
        raise OptionError(f"emotion {options.emotion!r}: expected one of {', '.join(EMOTIONS)}")
    if options.language is not None and options.language not in LANGUAGES:
        raise OptionError(f"language {options.language!r}: expected one of {', '.join(LANGUAGES)}")
    intensity = options.intensity
    if isinstance(intensity, bool) or not isinstance(intensity, int | float) or not 0 <= intensity <= 1:
        raise OptionError(f"intensity {intensity!r}: expected a number from 0 to 1")


def edited_alignment(path: str | os.PathLike[str], duration: float) -> Alignment:
    """Read an edited TextGrid at `path` for audio of `duration` seconds.

    UTF-8 or, as Praat saves a TextGrid holding Chinese, UTF-16 with a byte order mark.
    Raises AlignmentError when it cannot be read or when speech in it ends after
    the audio does; its duration becomes the audio's.
    """
    alignment = load_textgrid(path)
    last = max((s.end for s in alignment.sentences), default=0.0)
    if last > duration + ALIGNMENT_SLACK:
        raise AlignmentError(
            f"{path}: a sentence ends at {last:.3f} s but the audio lasts {duration:.3f} s; "
            "expected the TextGrid made for this recording"
        )
    return dataclasses.replace(alignment, duration=duration)


def check_out_dir(out_dir: Path) -> None:
    """Refuse an output path that is a file, a folder with other content than a previous output,
    or one that cannot be made (its nearest existing ancestor is a file or not writable)."""
    if out_dir.exists() and not out_dir.is_dir():
        raise OptionError(f"{out_dir}: exists and is not a folder; expected a folder for the pages")
    if out_dir.is_dir() and any(out_dir.iterdir()) and not (out_dir / "animation.svg").is_file():
        raise OptionError(
            f"{out_dir}: the folder holds other files; choose a new or empty folder "
            "(a previous cartoonface output is replaced)"
        )
    ancestor = out_dir.absolute().parent
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir() or not os.access(ancestor, os.W_OK | os.X_OK):
        raise OptionError(f"{out_dir}: cannot write the output folder ({ancestor} is not a writable folder)")


def video_input(video: Path, text: str | None) -> Clip:
    """The probed clip at `video` (VideoError when unusable); VideoError when a transcript
    (`text`) is given for a clip without sound."""
    clip = probe(video)
    if not clip.has_audio and text is not None:
        raise VideoError(f"{video}: the clip has no sound track to align the transcript with; "
                         "expected a video with the speech, or no transcript")
    return clip


def clip_sound(clip: Clip, staging: Path) -> tuple[Path, Audio]:
    """(WAV path in `staging`, decoded Audio) of the clip's sound; for a clip without sound,
    silence as long as the clip (SILENT_RATE), which the page plays as its clock."""
    wav = staging / "clip-sound.wav"
    if clip.has_audio:
        extract_audio(clip, wav)
        return wav, load_audio(wav)
    samples = np.zeros(round(clip.duration * SILENT_RATE), dtype=np.float32)
    soundfile.write(wav, samples, SILENT_RATE, subtype="PCM_16")
    return wav, Audio(samples=samples, rate=SILENT_RATE, source=str(clip.path))


@collector_paused()  # the job's many containers hold no cycles (workers.collector_paused)
def generate(
    face: Path | FaceModel,
    audio: Path | None,
    transcript: Path | str | None,
    out_dir: Path,
    options: Options = Options(),
    progress: Callable[[str, float], None] | None = None,
    video: Path | None = None,
    pitch: Callable[[], tuple[np.ndarray, np.ndarray]] | None = None,
) -> Result:
    """Make the page folder `out_dir` from a face model, a recording and its transcript.

    `face`: a FaceModel or the path of its JSON. `audio`: the recording's path.
    `transcript`: a path (Path or os.PathLike) to a UTF-8 text file, or the text
    itself as a str; None: no transcript, the lip sync from the audio alone (speech/audio_only.py)
    and a page without text. `progress(stage, fraction)` is told when each stage of
    STAGES starts (and as segmentation and alignment go on) with the fraction
    0..1 of the whole job, and once more at ("pages", 1.0). Raises InputError (a
    subclass) for any bad input; then nothing is left at `out_dir`.

    `video`: a clip of a talking person (video/clip.py) instead of `audio` (then None): its
    sound is the recording, and the head, eyes, brows and mouth follow the face in it
    (video/track.py, video/drive.py; tracked during the "decode" stage); a clip without sound
    makes a silent page (said in the notes).

    `pitch`: a getter of `audio`'s prosody.recording_pitch begun elsewhere (the command begins it
    in a process of its own before its imports: cli/generate.py `begun`); None: the helper computes it.
    """
    started = time.perf_counter()
    names = [name for name, _ in STAGES]
    bounds = [share for _, share in STAGES] + [1.0]
    if video is not None:  # tracking the face is part of "decode": the other stages share the rest
        bounds = [0.0] + [TRACK_SHARE + (1 - TRACK_SHARE) * share for share in bounds[1:]]

    def report(stage: str, within: float = 0.0) -> None:
        """Tell `progress` that `stage` is `within` (0..1) done."""
        if progress is not None:
            index = names.index(stage)
            progress(stage, bounds[index] + within * (bounds[index + 1] - bounds[index]))

    check_options(options)
    target = Path(out_dir)
    check_out_dir(target)
    model = face if isinstance(face, FaceModel) else load_face(face)
    text = (transcript if transcript is None or isinstance(transcript, str)
            else read_user_text(transcript, TranscriptError, "transcript file"))
    source = "transcript" if transcript is None or isinstance(transcript, str) else str(transcript)
    marks = () if text is None else emotion_marks(text, source)
    clip = None if video is None else video_input(video, text)
    report("decode")
    # A forked helper (workers.py) computes the pitch track (unless `pitch` was begun before), then
    # aligns parts as this process does (none for a web job: its CPU-time limit counts per process),
    # then draws part of the frames (render/animation.py: no fork of this process, large by then).
    # The page's compressed audio is made by an ffmpeg begun as soon as the recording is known, at the
    # lowest priority: it takes the core time this job leaves idle (speech/audio.py page_copy_begun;
    # stopped, on leaving, before its folder is removed).
    with (helper_process(processes()) as helper,
          tempfile.TemporaryDirectory(prefix="cartoonface-audio-") as staging, contextlib.ExitStack() as stack):
        tracking = None
        decoded = None
        if clip is not None:
            from cartoonface.video.track import track  # video jobs only: not imported by an audio job's start

            tracking = track(clip, lambda done: report("decode", done))
            sound, decoded = clip_sound(clip, Path(staging))
        elif audio is not None:
            sound = audio
        else:
            raise OptionError("no recording: expected an audio file or a video")
        # the helper decodes the recording itself for the pitch track, while this process does,
        # rather than wait for it and be sent the samples (12 MB for 3 minutes, ~0.1 s of piping)
        if options.actions is not None:  # edited actions: no pitch peaks needed
            pitch = None
        elif pitch is None or clip is not None:  # none begun for this recording (a clip's sound is made here)
            pitch = None if helper.pool is None else offloaded(helper.pool, recording_pitch, sound)
        compressed = stack.enter_context(page_copy_begun(sound, staging, AUDIO_STEM))
        recording = load_audio(sound) if decoded is None else decoded
        duration = recording.duration
        if clip is not None and not clip.has_audio:
            alignment = Alignment((), duration, (SILENT_NOTE,))
        elif options.alignment is not None:
            report("segment")
            report("align")
            alignment = edited_alignment(options.alignment, duration)
        else:
            alignment = analyse(recording, text, pause=options.pause, progress=report, source=source,
                                language=options.language, pool=helper.pool)
        report("schedule")
        style = STYLES[options.style or PAGE_STYLES[options.page]]
        if options.actions is not None:
            actions = load_actions(options.actions, duration)
        else:
            actions = () if not alignment.sentences else schedule(  # a silent clip: nothing to schedule by
                duration, speech_pauses(alignment), options.seed, style=style, peaks=pitch_peaks(recording, alignment, None if pitch is None else pitch()),
                speech=speech_spans(alignment), breath_pauses=silences_of(alignment))
            spans = marked_spans(alignment, marks)
            if spans is None:
                alignment = dataclasses.replace(alignment, notes=alignment.notes + (
                    "the transcript's emotion marks were not used: the alignment holds other syllables",))
            default = None if options.emotion is None else (options.emotion, options.intensity)
            actions += emotion_actions(spans or (), duration, default)
        if tracking is not None:  # the video moves the head, eyes, brows and mouth: only moods and breaths stay
            actions = tuple(action for action in actions if action.kind in VIDEO_KEEPS)
            if AUDIO_ONLY_NOTE in alignment.notes:  # the face's mouth follows the video, not the audio
                alignment = dataclasses.replace(alignment, notes=tuple(
                    VIDEO_MOUTH_NOTE if note == AUDIO_ONLY_NOTE else note for note in alignment.notes))
        del recording, decoded  # the samples (12 MB for 3 minutes) let go before the frames and drawing: a lower peak
        report("frames")
        timeline = build_timeline(alignment, actions)
        if tracking is not None:
            from cartoonface.video.drive import drive  # video jobs only, as track above

            states = drive(tracking, sample_frames(timeline, options.fps), options.fps, model,
                           combine=transcribed(alignment))
        else:
            times = frame_times(timeline, options.fps)  # the idle sway added as the frames are sampled
            states = states_at(timeline, times, sway(times, options.seed, style.sway_peak))
        states = on_twos(states)
        body = body_motion(states, sample_breaths(timeline, options.fps), options.fps)

        def drawing(done: float) -> None:
            """Tell `progress` the svg stage's share `done`; once this process's part of the frames is
            drawn (render/animation.DRAWN_SHARE), the page's audio, if not made yet in the idle core
            time so far, is made at this process's priority: on a busy machine it then runs when it ran
            before it was begun early, not after everything (docs/BENCHMARKS.md, "early")."""
            report("svg", done)
            if done >= DRAWN_SHARE:
                compressed.hurry()

        @functools.cache
        def texts() -> tuple[str, str, str | None]:
            """The folder's texts that need no animation: the TextGrid, actions.json and the captions (None:
            no text, no captions); made, and the pages' templates compiled, while animation_svg would wait
            for its search's child (its `meanwhile`), not after it."""
            compile_page(options.page)
            return (write_textgrid(alignment), actions_to_json(actions),
                    captions_vtt(alignment) if transcribed(alignment) else None)

        report("svg")
        svg = animation_svg(model, states, options.fps, background=options.background, clothes=options.clothes,
                            wide=options.page == "announcer", title=options.title, body=body,
                            progress=drawing, workers=processes(), helper=helper, meanwhile=texts)
        if helper.pool is not None:  # shut down by animation_svg once it has drawn; not when it drew none
            helper.pool.shutdown(wait=False)  # (few frames): it ends on its own meanwhile
        report("pages")
        try:
            with atomic_directory(target) as folder:
                sources = copy_audio(sound, folder, keep_original=options.keep_original,
                                     compressed=compressed.finish())
                textgrid, actions_json, captions = texts()
                html = page_html(options.page, title=options.title, alignment=alignment, svg=svg, audio=sources,
                                 fps=options.fps, links=options.links, captions=captions)
                write_site(folder, html=html, svg=svg, textgrid=textgrid, actions=actions_json)
                if captions is not None:
                    write_text_atomic(folder / CAPTIONS_NAME, captions)
                cues = mouth_cues(alignment) if options.cues else ()  # asked for only
                for fmt in options.cues:
                    write_text_atomic(folder / cues_name(fmt), cues_text(cues, duration, fmt, sources[0].name))
                size = folder_size(folder)
        except OSError as exc:  # the place given for the output cannot be written (permissions, full disk, ...)
            raise OptionError(f"{target}: cannot write the output folder ({exc.strerror or exc})") from None
        if progress is not None:
            progress("pages", 1.0)
        return Result(out_dir=target, duration=duration, frames=len(states), size=size,
                      seconds=time.perf_counter() - started, notes=tuple(alignment.notes))
