"""video/clip.py: probing and decoding a real GRID clip, and clear errors for unusable files."""

from __future__ import annotations


import numpy as np
import pytest
import soundfile

from cartoonface.video.clip import MAX_FPS, MAX_SECONDS, MAX_SIZE, VideoError, extract_audio, frames, probe
from tests.clips import GRID, make_clip

def test_probe_reads_the_grid_clip_header():
    clip = probe(GRID)
    assert (clip.format, clip.width, clip.height, clip.has_audio) == ("MPEG-1", 360, 288, True)
    assert clip.fps == 25 and 2.9 < clip.duration < 3.1


def test_frames_are_rgb_pictures_at_the_clip_rate():
    clip = probe(GRID)
    pictures = list(frames(clip))
    assert abs(len(pictures) - clip.duration * clip.fps) <= 1
    assert all(p.shape == (288, 360, 3) and p.dtype == np.uint8 for p in pictures)
    # the speaker's face is lit: the frames are no blank decode
    assert 40 < float(np.mean(pictures[0])) < 220


def test_extract_audio_writes_the_sound_as_long_as_the_clip(tmp_path):
    clip = probe(GRID)
    samples, rate = soundfile.read(str(extract_audio(clip, tmp_path / "sound.wav")))
    assert samples.ndim == 1 and abs(len(samples) / rate - clip.duration) < 0.1
    assert np.max(np.abs(samples)) > 0.05


def test_fast_large_clips_are_decoded_at_the_caps(tmp_path):
    big = make_clip(tmp_path / "big.mp4", "-f", "lavfi", "-i", "testsrc=size=1920x1080:rate=60", "-t", "0.5",
                    "-c:v", "libx264", "-preset", "ultrafast")
    clip = probe(big)
    assert clip.fps == MAX_FPS and (clip.width, clip.height) == MAX_SIZE and not clip.has_audio
    pictures = list(frames(clip))
    assert abs(len(pictures) - 0.5 * MAX_FPS) <= 1 and pictures[0].shape == (MAX_SIZE[1], MAX_SIZE[0], 3)


def test_a_clip_without_sound_has_no_audio_to_extract(tmp_path):
    clip = probe(make_clip(tmp_path / "mute.webm", "-f", "lavfi", "-i", "color=c=gray:size=64x48:rate=10",
                           "-t", "1"))
    assert clip.format == "WebM" and not clip.has_audio
    with pytest.raises(VideoError, match="no sound track"):
        extract_audio(clip, tmp_path / "sound.wav")


@pytest.mark.parametrize("content, expected", [
    (None, "no such video file"),
    (b"", "empty"),
    (b"this is not a video at all" * 40, "not a readable video"),
])
def test_missing_empty_and_garbage_files_are_named(tmp_path, content, expected):
    path = tmp_path / "clip.mp4"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(VideoError, match=expected) as info:
        probe(path)
    assert str(path) in str(info.value)


def test_an_unsupported_container_is_refused(tmp_path):
    avi = make_clip(tmp_path / "clip.avi", "-f", "lavfi", "-i", "color=c=gray:size=64x48:rate=10", "-t", "1")
    with pytest.raises(VideoError, match="avi.*not supported.*MP4, WebM, MOV or MPEG-1"):
        probe(avi)


def test_a_recording_without_pictures_is_refused(tmp_path):
    sound = make_clip(tmp_path / "sound.m4a", "-f", "lavfi", "-i", "sine=frequency=220", "-t", "1")
    with pytest.raises(VideoError, match="no pictures"):
        probe(sound)


def test_a_clip_over_the_limit_is_refused(tmp_path):
    long = make_clip(tmp_path / "long.mp4", "-f", "lavfi", "-i", "color=c=gray:size=32x32:rate=1",
                     "-t", str(MAX_SECONDS + 5), "-c:v", "libx264", "-preset", "ultrafast")
    with pytest.raises(VideoError, match="at most 10 minutes"):
        probe(long)


def test_a_truncated_clip_yields_the_pictures_it_holds_or_a_clear_error(tmp_path):
    cut = tmp_path / "cut.mpg"
    cut.write_bytes(GRID.read_bytes()[:60_000])
    try:
        pictures = list(frames(probe(cut)))
    except VideoError as exc:
        assert str(cut) in str(exc)
    else:
        assert 0 < len(pictures) < 75


def test_a_phone_clip_turned_by_its_display_matrix_is_decoded_as_shown(tmp_path):
    plain = make_clip(tmp_path / "plain.mp4", "-i", str(GRID), "-c:v", "libx264", "-preset", "ultrafast")
    turned = make_clip(tmp_path / "turned.mp4", "-display_rotation", "90", "-i", str(plain), "-c", "copy")
    clip = probe(turned)
    assert (clip.width, clip.height) == (288, 360)
    picture = next(frames(clip))
    assert picture.shape == (360, 288, 3)
    # the picture is the plain one turned a quarter (ffmpeg's display matrix: counter-clockwise)
    first = next(frames(probe(plain))).astype(float)
    error = min(np.abs(np.rot90(first, k).astype(float) - picture).mean() for k in (1, 3))
    assert error < 12
