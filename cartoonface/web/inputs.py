"""Check what the form sent, before a job is stored.

`check_submission(form, files, limits)` returns a `Submission` (the inputs as
bytes under names chosen here, with an edited TextGrid and actions.json when given, plus the
request as plain values) or a dict of
field -> message for the form. A photo becomes a face model here
(photo/model_from_photo.py), so a photo without a usable face is a message in the form. File types are decided from the bytes (magic
numbers), never from the file name; the user's file name is only ever shown
(escaped), never used in a path.
"""

from __future__ import annotations

import codecs
import json
import re
import tempfile
import threading
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from werkzeug.datastructures import FileStorage, MultiDict

from cartoonface.errors import InputError
from cartoonface.face.emotion import EMOTIONS
from cartoonface.face.model import face_from_dict, face_to_dict, json_with_long_numbers
from cartoonface.photo.model_from_photo import face_from_photo, load_photo
from cartoonface.animate.actions import load_actions
from cartoonface.pipeline import MAX_TITLE, edited_alignment
from cartoonface.speech.audio import load_audio
from cartoonface.video.clip import VideoError, probe
from cartoonface.speech.transcript import emotion_marks, parse_transcript

PAGES = {"audiobook": "Audio book", "announcer": "Virtual announcer"}
# The performance style (animate/style.py); "" leaves it to the page (audio book: storyteller).
STYLE_CHOICES = {"": "the page's own (audio book: storyteller, announcer: announcer)",
                 "announcer": "announcer (restrained)", "storyteller": "storyteller (livelier)"}
# The default mood (face/emotion.py EMOTIONS), where the transcript's [emotion] marks set none.
MOOD_CHOICES = {"": "neutral", **{name: name for name in EMOTIONS}}
# The language of the transcript and speech (speech/english.py LANGUAGES); "" finds it from the script.
LANGUAGE_CHOICES = {"": "found from the transcript (Chinese characters or English words)", "zh": "Mandarin",
                    "en": "English"}
MAX_FACE_BYTES = 1 << 20  # a face model is a few kB of JSON; 1 MiB is generous
MAX_PHOTO_BYTES = 20 << 20  # a 50-megapixel JPEG is ~15 MB
# An edited TextGrid: a 4-minute recording's is 0.3 MB in UTF-8, so 30 minutes in UTF-16 take ~4.4 MB.
MAX_TEXTGRID_BYTES = 8 << 20
# An edited actions.json: a 4-minute recording's is 27 kB, so 30 minutes take ~0.2 MB.
MAX_ACTIONS_BYTES = 2 << 20
# The job's names of the edited files (the worker hands them to pipeline.Options).
TEXTGRID_FILE = "alignment.TextGrid"
ACTIONS_FILE = "actions.json"
SHOWN_NAME_CHARS = 80
# Control characters refused in a title or transcript (tab, line feed and carriage return are kept).
CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")

# One photo is read at a time, by the form and by /photos alike (the face mesh is one model,
# ~0.5 s a photo, and a large photo takes a few hundred MB while it is read): a request that
# cannot start within DETECT_WAIT seconds is told the server is busy.
DETECT_WAIT = 20.0
DETECTING = threading.Lock()
PHOTO_BUSY = "The server is busy reading other photos; please try again in a minute."


@contextmanager
def photo_slot(wait: float) -> Iterator[bool]:
    """Whether this request may read a photo now: True when the one-photo-at-a-time lock was
    taken within `wait` seconds (then released when the block ends), False when it was not."""
    taken = DETECTING.acquire(timeout=wait)
    try:
        yield taken
    finally:
        if taken:
            DETECTING.release()


@dataclass(frozen=True)
class Limits:
    """What the form accepts: `upload_bytes` per recording, `transcript_chars`,
    and the sample faces (name -> JSON file), backgrounds and clothes on offer."""

    upload_bytes: int
    transcript_chars: int
    samples: Mapping[str, Path]
    backgrounds: tuple[str, ...]
    clothes: tuple[str, ...]


@dataclass(frozen=True)
class Submission:
    """A checked request: `spec` (JSON-serialisable values for job.json) and `files`
    (our file name -> bytes: face.json, audio.<ext>, transcript.txt, and alignment.TextGrid and
    actions.json when edited ones were given)."""

    spec: Mapping[str, object]
    files: Mapping[str, bytes]


# Containers that may hold a video (sniffed extension), and the job's file extension of each
# video/clip.py format.
VIDEO_CONTAINERS = ("m4a", "webm", "mpg")
VIDEO_EXTENSIONS = {"MP4/MOV": "mp4", "WebM": "webm", "MPEG-1": "mpg"}


def megabytes(size: int) -> str:
    """A byte count in MB (2**20 bytes) for messages: '200', '0.5'."""
    return f"{size / 2**20:.3g}"


def sniff_audio(head: bytes) -> str | None:
    """The audio container that the first bytes of a file announce, as a file
    extension ("wav", "flac", "ogg", "mp3", "m4a"), or None when none matches."""
    if len(head) >= 12 and head[:4] in (b"RIFF", b"RF64") and head[8:12] == b"WAVE":
        return "wav"
    if head[:4] == b"fLaC":
        return "flac"
    if head[:4] == b"OggS":
        return "ogg"
    if head[:3] == b"ID3" or (len(head) >= 2 and head[0] == 0xFF and head[1] & 0xE0 == 0xE0):
        return "mp3"
    if len(head) >= 12 and head[4:8] == b"ftyp":
        return "m4a"
    return None


def sniff_video(head: bytes) -> str | None:
    """The video container the first bytes of a file announce that sniff_audio does not: "webm"
    (Matroska's EBML header) or "mpg" (an MPEG program stream's pack or sequence header), else None.
    (MP4 and MOV start as M4A does, "ftyp": check_audio tells them apart by their streams.)"""
    if head[:4] == b"\x1a\x45\xdf\xa3":
        return "webm"
    if head[:4] in (b"\x00\x00\x01\xba", b"\x00\x00\x01\xb3"):
        return "mpg"
    return None


def has_pictures(path: Path) -> bool:
    """Whether the file at `path` (an ftyp file: MP4, MOV or M4A) holds a video stream."""
    try:
        probe(path)
    except VideoError as exc:
        return "no pictures" not in str(exc)  # other problems: reported when it is read as a video
    return True


def sniff_image(head: bytes) -> str | None:
    """The image format the first bytes of a file announce ("jpg", "png", "webp"), or None."""
    if head[:3] == b"\xff\xd8\xff":
        return "jpg"
    if head[:8] == b"\x89PNG\r\n\x1a\n":
        return "png"
    if len(head) >= 12 and head[:4] == b"RIFF" and head[8:12] == b"WEBP":
        return "webp"
    return None


def shown_name(upload: FileStorage | None, fallback: str) -> str:
    """The user's file name for messages only: last path part, at most SHOWN_NAME_CHARS;
    `fallback` when there is no upload or it has no name."""
    filename = upload.filename if upload is not None else None
    name = (filename or "").replace("\\", "/").rsplit("/", 1)[-1].strip()
    return (name or fallback)[:SHOWN_NAME_CHARS]


def read_upload(upload: FileStorage | None, limit: int) -> tuple[bytes | None, bool]:
    """Read at most `limit` bytes of an upload; return (data or None when no file
    was chosen, True when the file is larger than `limit`)."""
    if upload is None or not upload.filename:
        return None, False
    data = upload.stream.read(limit + 1)
    return data[:limit], len(data) > limit


def _text(form: MultiDict[str, str], name: str) -> str:
    return form.get(name, "", type=str) or ""


def form_values(form: MultiDict[str, str]) -> dict[str, str]:
    """The plain fields as sent, to fill the form again when it comes back with errors."""
    return {name: _text(form, name) for name in ("face_sample", "face_draft", "page", "style", "mood", "language", "title",
                                                 "background", "clothes", "transcript", "mp4")}


def check_photo(name: str, data: bytes, too_big: bool,
                errors: dict[str, str]) -> tuple[bytes | None, str, tuple[str, ...]]:
    """A face model made from the photo bytes the user called `name`: (face JSON bytes,
    label, warnings about the photo)."""
    if too_big:
        errors["photo"] = f"{name}: a photo must be at most {megabytes(MAX_PHOTO_BYTES)} MB."
        return None, name, ()
    ext = sniff_image(data[:12])
    if ext is None:
        errors["photo"] = f"{name}: not a photo this app reads (by its content); expected JPEG, PNG or WebP."
        return None, name, ()
    with photo_slot(DETECT_WAIT) as free:
        if not free:
            errors["photo"] = PHOTO_BUSY
            return None, name, ()
        try:
            with tempfile.TemporaryDirectory(prefix="cartoonface-upload-") as tmp:
                path = Path(tmp) / f"photo.{ext}"
                path.write_bytes(data)
                made = face_from_photo(load_photo(path), "photo")
        except InputError as exc:
            errors["photo"] = str(exc).replace(str(path), name)
            return None, name, ()
    face = json.dumps(face_to_dict(made.face), ensure_ascii=False).encode("utf-8")
    return face, name, tuple(f"{name}: {warning}" for warning in made.warnings)


def check_face(form: MultiDict[str, str], files: MultiDict[str, FileStorage], limits: Limits,
               errors: dict[str, str], chosen: tuple[bytes, str, tuple[str, ...]] | None = None
               ) -> tuple[bytes | None, str, tuple[str, ...]]:
    """The face model JSON (bytes), its label and notes about it: an uploaded face model
    or a photo (not both) wins over `chosen` (a checked photo face: JSON bytes, label,
    notes), which wins over the sample chosen."""
    upload = files.get("face_file")
    data, too_big = read_upload(upload, MAX_FACE_BYTES)
    photo = files.get("photo")
    photo_data, photo_too_big = read_upload(photo, MAX_PHOTO_BYTES)
    if data is not None and photo_data is not None:
        errors["photo"] = "Give either a face model (JSON) or a photo, not both."
        return None, "", ()
    if photo_data is not None:
        return check_photo(shown_name(photo, "photo"), photo_data, photo_too_big, errors)
    if data is not None:
        name = shown_name(upload, "face model")
        if too_big:
            errors["face_file"] = f"{name}: a face model must be at most {MAX_FACE_BYTES >> 10} kB of JSON."
            return None, name, ()
        try:
            obj = json_with_long_numbers(data.decode("utf-8-sig"))
        except ValueError as exc:  # not UTF-8, not JSON
            errors["face_file"] = f"{name}: not a face model: expected UTF-8 JSON ({exc})."
            return None, name, ()
        except RecursionError:
            errors["face_file"] = f"{name}: not a face model: the JSON is nested too deeply."
            return None, name, ()
        try:
            face_from_dict(obj, name)
        except InputError as exc:
            errors["face_file"] = str(exc)
            return None, name, ()
        return data, name, ()
    if chosen is not None:
        return chosen
    sample = _text(form, "face_sample")
    if sample not in limits.samples:
        errors["face_sample"] = "Choose one of the sample faces, or upload a face model (JSON) or a photo."
        return None, sample, ()
    return limits.samples[sample].read_bytes(), sample, ()


def check_audio(files: MultiDict[str, FileStorage], limits: Limits,
                errors: dict[str, str]) -> tuple[bytes | None, str, str, float]:
    """The recording: (bytes, extension by content, shown name, duration in seconds)."""
    upload = files.get("audio")
    data, too_big = read_upload(upload, limits.upload_bytes)
    if data is None:
        errors["audio"] = "Choose a recording (WAV, MP3, OGG, M4A or FLAC)."
        return None, "", "", 0.0
    name = shown_name(upload, "recording")
    if too_big:
        errors["audio"] = f"{name}: the recording is larger than {megabytes(limits.upload_bytes)} MB."
        return None, "", name, 0.0
    ext = sniff_audio(data[:16]) or sniff_video(data[:16])
    if ext is None:
        errors["audio"] = (f"{name}: not a recording this app reads (by its content); "
                           "expected WAV, MP3, OGG, M4A or FLAC, or a video (MP4, MOV, WebM or MPEG-1).")
        return None, "", name, 0.0
    with tempfile.TemporaryDirectory(prefix="cartoonface-upload-") as tmp:
        path = Path(tmp) / f"recording.{ext}"
        path.write_bytes(data)
        try:
            if ext in VIDEO_CONTAINERS:  # an MP4 may hold only sound (M4A): then it is a recording
                clip = probe(path) if ext != "m4a" or has_pictures(path) else None
                if clip is not None:
                    return data, VIDEO_EXTENSIONS[clip.format], name, clip.duration
            audio = load_audio(path)
        except InputError as exc:
            errors["audio"] = str(exc).replace(str(path), name)
            return None, ext, name, 0.0
    return data, ext, name, len(audio.samples) / audio.rate


def check_transcript(form: MultiDict[str, str], files: MultiDict[str, FileStorage], limits: Limits,
                     errors: dict[str, str]) -> str | None:
    """The transcript text: an uploaded UTF-8 text file wins over the pasted text; "" when neither
    holds any (the lip sync then comes from the audio alone, speech/audio_only.py)."""
    upload = files.get("transcript_file")
    data, too_big = read_upload(upload, 4 * limits.transcript_chars + 3)
    field, name = "transcript", "transcript"
    if data is not None:
        field, name = "transcript_file", shown_name(upload, "transcript")
        if b"\x00" in data:
            errors[field] = f"{name}: not a text file (it holds NUL bytes): expected UTF-8 text."
            return None
        try:  # a file cut at the limit may end inside a character: only a whole file must end well
            text = codecs.getincrementaldecoder("utf-8-sig")().decode(data, final=not too_big)
        except UnicodeDecodeError:
            errors[field] = f"{name}: not a text file: expected UTF-8 text."
            return None
        if too_big:
            errors[field] = f"{name}: the transcript is longer than {limits.transcript_chars} characters."
            return None
    else:
        text = _text(form, "transcript")
    control = CONTROL.search(text)
    if control:
        errors[field] = (f"{name}: holds the control character U+{ord(control.group()):04X}; "
                         "expected plain text (tabs and line breaks are fine).")
        return None
    text = text.replace("\r\n", "\n").strip()
    if not text:
        return ""
    if len(text) > limits.transcript_chars:
        errors[field] = (f"{name}: the transcript has {len(text)} characters; "
                         f"at most {limits.transcript_chars} are accepted.")
        return None
    try:
        parse_transcript(text, name)
        emotion_marks(text, name)
    except InputError as exc:
        errors[field] = str(exc)
        return None
    return text


def check_edited(files: MultiDict[str, FileStorage], field: str, limit: int, duration: float | None,
                 errors: dict[str, str]) -> bytes | None:
    """An edited file of the advanced section (`field` "textgrid_file" or "actions_file"), checked
    as the pipeline reads it for a recording of `duration` seconds (None: the recording itself
    was refused, so only the size is checked). Returns its bytes, or None when none was chosen
    or it is refused (then errors[field] says why, naming the user's file)."""
    upload = files.get(field)
    data, too_big = read_upload(upload, limit)
    if data is None:
        return None
    name = shown_name(upload, TEXTGRID_FILE if field == "textgrid_file" else ACTIONS_FILE)
    if too_big:
        errors[field] = f"{name}: larger than {megabytes(limit)} MB; expected the file this app made, edited."
        return None
    if duration is None:
        return data
    with tempfile.TemporaryDirectory(prefix="cartoonface-upload-") as tmp:
        path = Path(tmp) / (TEXTGRID_FILE if field == "textgrid_file" else ACTIONS_FILE)
        path.write_bytes(data)
        try:
            if field == "textgrid_file":
                edited_alignment(path, duration)
            else:
                load_actions(path, duration)
        except InputError as exc:
            errors[field] = str(exc).replace(str(path), name)
            return None
        except (ValueError, RecursionError):  # a JSON integer of 4300+ digits, nesting too deep
            errors[field] = f"{name}: not an actions file: a number is too long or the JSON is nested too deeply."
            return None
    return data


def check_choice(form: MultiDict[str, str], name: str, allowed: tuple[str, ...] | Mapping[str, str],
                 what: str, errors: dict[str, str]) -> str:
    """A select field whose value must be one of `allowed`."""
    value = _text(form, name)
    if value not in allowed:
        errors[name] = f"Choose one of the {what} offered."
    return value


# A yes/no field (the form's checkbox sends its value "1"; the API's `mp4: true`): these values
# mean yes, FLAG_NO no (an absent field is no).
FLAG_YES = ("1", "on", "true", "yes")
FLAG_NO = ("", "0", "off", "false", "no")


def check_flag(form: MultiDict[str, str], name: str, errors: dict[str, str]) -> bool:
    """A checkbox `name`: True for FLAG_YES, False for FLAG_NO or when absent (case ignored);
    an error for anything else."""
    value = _text(form, name).strip().lower()
    if value not in FLAG_YES + FLAG_NO:
        errors[name] = f"{name} is {value[:20]!r}; expected true or false."
    return value in FLAG_YES


def check_submission(form: MultiDict[str, str], files: MultiDict[str, FileStorage], limits: Limits,
                     chosen: tuple[bytes, str, tuple[str, ...]] | None = None) -> Submission | dict[str, str]:
    """Check every field (`chosen`: a face from a photo draft, see check_face); return the
    Submission, or field -> message for each problem."""
    errors: dict[str, str] = {}
    title = " ".join(_text(form, "title").split())
    control = CONTROL.search(title)
    if control:
        errors["title"] = f"The title holds the control character U+{ord(control.group()):04X}; expected plain text."
    elif len(title) > MAX_TITLE:
        errors["title"] = f"The title has {len(title)} characters; at most {MAX_TITLE} are accepted."
    page = check_choice(form, "page", PAGES, "page kinds", errors)
    style = check_choice(form, "style", STYLE_CHOICES, "styles", errors)
    mood = check_choice(form, "mood", MOOD_CHOICES, "moods", errors)
    language = check_choice(form, "language", LANGUAGE_CHOICES, "languages", errors)
    background = check_choice(form, "background", limits.backgrounds, "backgrounds", errors)
    clothes = check_choice(form, "clothes", limits.clothes, "clothes", errors)
    mp4 = check_flag(form, "mp4", errors)
    face, face_label, face_notes = check_face(form, files, limits, errors, chosen)
    transcript = check_transcript(form, files, limits, errors)
    audio, ext, audio_label, duration = check_audio(files, limits, errors)
    known = duration if audio is not None else None
    textgrid = check_edited(files, "textgrid_file", MAX_TEXTGRID_BYTES, known, errors)
    actions = check_edited(files, "actions_file", MAX_ACTIONS_BYTES, known, errors)
    if errors or face is None or audio is None or transcript is None:
        return errors
    spec = {
        "title": title,
        "page": page,
        "style": style,
        "mood": mood,
        "language": language,
        "background": background,
        "clothes": clothes,
        "face_label": face_label,
        "face_notes": list(face_notes),
        "audio_label": audio_label,
        "audio_file": f"audio.{ext}",
        "video": ext in VIDEO_EXTENSIONS.values(),  # a video of the speaker (pipeline.generate's video=)
        "duration": duration,
        "transcript_chars": len(transcript),
        "mp4": mp4,  # also make the MP4 video (worker.py VIDEO_NAME)
    }
    files_out = {"face.json": face, f"audio.{ext}": audio}
    if transcript:  # without one the job is made from the audio alone
        files_out["transcript.txt"] = transcript.encode("utf-8")
    for field, name, data in (("textgrid", TEXTGRID_FILE, textgrid), ("actions", ACTIONS_FILE, actions)):
        if data is not None:
            spec[f"{field}_file"] = name
            spec[f"{field}_label"] = shown_name(files.get(f"{field}_file"), name)
            files_out[name] = data
    return Submission(spec, files_out)
