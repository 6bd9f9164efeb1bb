"""Exports: the page's weight per minute of speech with the compressed audio (issue 14).

Input: bench/generate.py's 3-minute recording of THCHS-30 speech (16 kHz 16-bit WAV, made at
bench time in a temporary folder) and the sample story (samples/speech/story.wav, 22.05 kHz).
One `generate` with keep_original=True writes both the page audio (audio.m4a) and the
recording as given (recording.wav), so the folder is measured before (the recording as the
page's audio, as until now) and after (audio.m4a) without generating twice.
Target (issue 14): a 3-minute book weighs at most 3 MB besides its SVG.

The MP4 (exports/video.py) of the sample story's announcer page at 1280x720, 30 fps: frames
rendered and encoded per second of wall time (target: at least the frame rate, real time, on
2 cores), distinct frames put together, CPU seconds of this process and its children (the
worker processes and ffmpeg), MB per minute. Then x264's presets on the same frames (the
video decoded to raw RGB, PRESET_FRAMES of them): ffmpeg's CPU seconds per frame and MB per
minute of picture, for the choice of VIDEO_CODEC's preset.
"""

from __future__ import annotations

import os
import subprocess
import tempfile
import time
from pathlib import Path

from bench.generate import build_input
from cartoonface.data import SAMPLE_FACES
from cartoonface.exports.video import VIDEO_CODEC, write_video
from cartoonface.pipeline import Options, generate
from cartoonface.speech.audio import ffmpeg_exe

ROOT = Path(__file__).resolve().parents[1]
STORY = ROOT / "samples" / "speech" / "story"
PRESETS = ("ultrafast", "superfast", "veryfast", "faster")
PRESET_FRAMES = 300  # 10 s at 30 fps


def page_weights(name: str, audio: Path, transcript: Path, folder: Path) -> None:
    """Generate the page for `audio` and print its weight per minute before and after, with and without the SVG."""
    result = generate(sorted(SAMPLE_FACES.glob("*.json"))[0], audio, transcript, folder / name, Options(keep_original=True))
    files = {p.relative_to(result.out_dir).as_posix(): p.stat().st_size for p in result.out_dir.rglob("*") if p.is_file()}
    minutes = result.duration / 60
    svg = files["animation.svg"] + files["index.html"]  # the SVG is in the page too
    original = files[f"recording{audio.suffix}"]
    compressed = files["audio.m4a"]
    rest = sum(files.values()) - svg - original - compressed
    before, after = rest + original, rest + compressed
    print(f"{name}: {result.duration:.1f} s; per minute: audio {original / 1e6 / minutes:.2f} MB -> "
          f"{compressed / 1e6 / minutes:.2f} MB (x{original / compressed:.1f} smaller); page besides its SVG "
          f"{before / 1e6 / minutes:.2f} -> {after / 1e6 / minutes:.2f} MB; with the SVG (animation.svg + "
          f"index.html) {(before + svg) / 1e6 / minutes:.2f} -> {(after + svg) / 1e6 / minutes:.2f} MB; "
          f"besides the SVG for 3 minutes: {after / minutes * 3 / 1e6:.2f} MB (target <= 3)")


def video_speed(folder: Path) -> Path:
    """Make the sample story's announcer page and its 720p30 MP4; print the speed and size. Returns the video."""
    story = STORY.with_suffix(".wav")
    result = generate(sorted(SAMPLE_FACES.glob("*.json"))[0], story, STORY.with_suffix(".txt"), folder / "announcer",
                      Options(page="announcer"))
    video = folder / "story.mp4"
    started, cpu = time.perf_counter(), os.times()
    drawn = write_video((result.out_dir / "animation.svg").read_bytes(), 30, result.duration, story, video)
    wall, after = time.perf_counter() - started, os.times()
    used = sum(after[:4]) - sum(cpu[:4])
    print(f"MP4 1280x720 30 fps, announcer, {result.duration:.1f} s ({result.frames} frames, {drawn} put together): "
          f"{wall:.1f} s wall = {result.frames / wall:.1f} frames/s ({result.duration / wall:.2f}x real time), "
          f"{used:.1f} CPU s = {result.frames / used:.1f} frames per CPU second ({used / result.frames * 1000:.0f} ms "
          f"a frame); {video.stat().st_size / 1e6 / (result.duration / 60):.2f} MB per minute")
    return video


def presets(video: Path, folder: Path) -> None:
    """Encode the first PRESET_FRAMES frames of `video` again with each of PRESETS (VIDEO_CODEC
    otherwise); print ffmpeg's CPU time per frame and the picture's MB per minute."""
    raw = folder / "frames.rgb"
    subprocess.run([ffmpeg_exe(), "-v", "error", "-y", "-i", str(video), "-frames:v", str(PRESET_FRAMES),
                    "-f", "rawvideo", "-pix_fmt", "rgb24", str(raw)], check=True)
    preset = VIDEO_CODEC.index("-preset") + 1
    for name in PRESETS:
        codec = [*VIDEO_CODEC[:preset], name, *VIDEO_CODEC[preset + 1:]]
        out = folder / f"{name}.mp4"
        cpu = os.times()
        subprocess.run([ffmpeg_exe(), "-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", "1280x720",
                        "-framerate", "30", "-i", str(raw), *codec, str(out)], check=True)
        used = sum(os.times()[2:4]) - sum(cpu[2:4])
        print(f"x264 -preset {name}: {used / PRESET_FRAMES * 1000:.1f} ms CPU a frame, "
              f"{out.stat().st_size / 1e6 / (PRESET_FRAMES / 30 / 60):.2f} MB per minute of picture")
    raw.unlink()


def main() -> None:
    """Print the page weights of the two recordings and the video's speed."""
    with tempfile.TemporaryDirectory(prefix="cartoonface-bench-exports-") as tmp:
        folder = Path(tmp)
        audio, transcript, _ = build_input(folder)
        page_weights("THCHS-30 3 min 16 kHz", audio, transcript, folder)
        page_weights("sample story 22.05 kHz", STORY.with_suffix(".wav"), STORY.with_suffix(".txt"), folder)
        presets(video_speed(folder), folder)


if __name__ == "__main__":
    main()
