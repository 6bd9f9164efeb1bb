"""The talking-face animation as one SVG document (thesis 002, ch. 6).

Spatial domain (6.3.1): four layers, background, hair, clothes and face, drawn
in that order; the face's gradients live once in `<defs>`. A part's clip path
(the eye outline clipping the eyeball, the mouth opening clipping the teeth)
is written just before the part, inside the same drawing, where gzip finds the
clip's outline next to the same outline drawn by the part. A clip path that several
drawings hold alike (an eye's outline under different gazes of a still head) is
written once in the document's `<defs>` instead (render/compact.py).

Temporal domain (6.3.2): the thesis shows each frame as
`<g visibility="hidden"><set attributeName="visibility" to="visible" begin=".." dur=".."/>...</g>`.
We show a track's frames with one `<use>` whose `href` one discrete `<animate>` points at
the drawing of each frame (10 % fewer bytes than a `<set>` per drawing, and Chromium plays a long
animation about three times as fast: docs/BENCHMARKS.md, "Frames by one <use>"):

- the face of render/svg.py is split into part tracks (TRACK_OF): hair, ears,
  face (outline, cheeks and mouth, which follow the jaw), features (nose and
  brows), eyes. Each track has its own frames, so a moving mouth does not
  repeat the eyes, and a still head does not repeat the hair;
- each distinct drawing of a track is written once, as a `<g id>` in the track's own
  `<defs>` (a drawing of one element: that element with the id, no `<g>`); consecutive
  frames showing the same drawing are one value of the animation;
- a track whose drawing never changes is written once, with no `<use>`;
- every frame's state is drawn (no pose held over frames); the head's roll is
  not drawn into the parts but is a rotation of the hair and face layers (one
  discrete `<animateTransform>` each, and a skew of the neck about the collar),
  so a sideways lean redraws nothing;
- a drawing (or a part of one) within the tolerance of a transform of an earlier one is a `<use>`
  of it with the transform (render/reuse.py); one shown unmoved is that drawing (_aliased): its
  frames show the earlier one;
- the part drawings are written by the compactor of render/compact.py:
  coordinates are whole pixels in relative path commands (render/pathdata.py);
- a part shown in several drawings of its track (the face outline under
  different mouths) is defined once and drawn with `<use>`; a path with the
  outline of its part's clip path (the mouth's opening, an eye's white and
  outline) is a `<use>` of the clip path's outline; consecutive paths of one opaque
  style lying apart (the brows) are one path (compact.merge_alike);
- repeated presentation attributes become CSS classes, the most used ones
  named by one letter; ids are short (base 36).

Frame i shows time i / fps, from its boundary round(i * 1000 / fps) ms. Every discrete
animation (_discrete) lasts a power of ten of milliseconds and writes each key time a
little before its boundary (KEY_TIME_LEAD), so Chromium, which compares in single
precision and whole microseconds, shows the new frame at the boundary itself. The last
value is frozen (`fill="freeze"`) so the face stays after the end. SMIL starts at 0 when
the document loads: animation.svg opened on its own plays silently; the pages drive its
clock from the audio (static/cartoonface.js).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import operator
import re
from collections.abc import Callable, Iterator, Sequence
from contextlib import nullcontext
from dataclasses import dataclass
from itertools import chain
from typing import NamedTuple

import numpy as np
from lxml import etree

from cartoonface.animate.body import BodyMotion
from cartoonface.face.lift import lift
from cartoonface.face.model import FaceModel
from cartoonface.face.pose import pose_faces, rig, unroll_faces
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.compact import Drawn, Formed, RawPart, Writer, bare, drawn_parts, merge_all_alike, share, short_ids, with_id
from cartoonface.render.elements import DECIMALS, Part, attributes_text, element, markup, svg_root
from cartoonface.render.numbers import decimal_text, distinct_rows, fraction_texts
from cartoonface.render.pathdata import Compacted, merged
from cartoonface.render.reuse import (IDENTITY, TOLERANCE, Layouts, Readings, Reuse, Shape, find, find_alike, joined, read_parts, shapes_from,
                                      shapes_of)
from cartoonface.render.scenery import (LEAN_DECIMALS, Figure, background_layer, clothes_layer, desk_layer, figure_of, lean,
                                        neck_pivot, torso_pivot, torso_shift)
from cartoonface.render.svg import all_face_parts, face_defs
from cartoonface.workers import Helper, collector_paused, forked, helper_process, offloaded, shares

# The track of each part of render/svg.py's face_parts (by its name), in drawing order.
# Parts that change together share a track; a part of another class gets a track of its own.
# The mouth and the jaw's shadow on the neck move with the jaw, so they share the track of the
# face outline; the mouth is then drawn before the nose, brows and eyes rather than after them,
# which changes nothing on screen
# (they never overlap; where a nodding nose tip comes near the upper lip, the nose in front is right).
TRACK_OF = {"hair": "hair", "ear-l": "ears", "ear-r": "ears", "chin-shadow": "face", "face": "face", "fringe": "fringe",
            "cheeks": "face",
            "nose": "features", "brow-l": "features", "brow-r": "features", "eye-l": "eyes", "eye-r": "eyes",
            "mouth": "face"}
MOUTH_TRACK = TRACK_OF["mouth"]  # its frames carry data-shape
# The parts reused on their own (_reuse), by how render/svg.py's face_parts begins them: those
# that pay (docs/BENCHMARKS.md, "Mouths reused"; the chin's shadow, an ellipse, is as short as a <use>).
ALONE = ('<g class="mouth"', '<g class="eye-', '<path class="face"')
# ... and those searched the same way but taken only unmoved (reuse.IDENTITY: then the earlier part
# itself, which makes more drawings equal, _aliased): the hair and fringe, a few hundred long
# outlines (-1.7 KB a minute gzipped; every other part too: no more gained, ~0.2 s more search on
# the 3-minute bench book: docs/BENCHMARKS.md, "Gzipped weight").
UNMOVED = ('<path class="hair"', '<path class="fringe"')
HAIR_TRACKS = ("hair",)  # drawn in the hair layer, behind the clothes; every other track in the face layer
# Discrete animations (the tracks' drawings, the head's roll, the body) last a power of ten of
# milliseconds, the first at or above the frames' end (the last value is frozen after that), so that a
# key time is a frame boundary's milliseconds shifted in decimals and keeps their steps for gzip; key
# times have KEY_TIME_DECIMALS decimals (units of 10 us in 100 s, 0.1 ms in 1000 s) and are written
# KEY_TIME_LEAD units early: Chromium compares them with the time as a share of the whole in single
# precision (24 bits), so a key time written exactly can fall either side of a time on the boundary;
# 5 units are 8 steps of single precision near the end (0.5 ms early in a 1000 s animation). They are
# also at least KEY_TIME_MIN_LEAD ms early: Chromium's clock counts whole microseconds, cut down from
# the seconds given to setCurrentTime (0.033 -> 32.999 ms).
KEY_TIME_DECIMALS = 7
KEY_TIME_LEAD = 5
KEY_TIME_MIN_LEAD = 0.01
# The ids of the tracks' drawings: this letter and a number in base 36 (compact.short_id).
FRAME_LETTER = "f"
PARTS_ID = "cf-parts"  # the <defs> of the parts several drawings show (compact.share)
SPLICE = "cf-text-"  # the comments animation_svg splices the texts of the tracks and shared parts in for
UID = "u"  # the one uid every state is drawn with; definitions are then renamed by content
WIDE = 16 / 9  # the announcer's stage: a 16:9 picture with the face in the middle,
STAGE_DEPTH = 1.3  # reaching this many canvas heights down, so the shoulders show under the chin
# The head's roll (Pose.roll, a sideways lean) is drawn as a rotation of the hair and face
# layers, in steps of this many decimals of a degree: 0.01 degree moves a point 250 px from
# the centre by 0.04 px.
ROLL_DECIMALS = 2
# animation_svg draws the distinct states this many at a time (array operations over all of them),
# telling its progress after each batch (a state takes ~0.3 ms to draw: a report every ~0.1 s);
# fewer states are drawn in at least BATCHES batches (a short recording's drawing is most of its
# job: three batches of the sample story made a progress bar stand still for a quarter of it), never
# under MIN_BATCH. The batch's size changes no byte (tests/test_batches.py).
BATCH = 256
BATCHES = 8
MIN_BATCH = 32
# animation_svg draws in two processes (workers.processes) from this many distinct states (~1 ms
# each to draw; starting the process and sending the drawings back take ~0.1 s), and searches the
# reused drawings in two (_reuse) from this many distinct drawings of all tracks.
POOL_STATES = 400
# _reuse splits the tracks by their distinct parts (the search's cost grows with them); this process
# also makes the tidy drawings meanwhile (Writer.drawings), at this share of the search's cost per part
# per tidy part: 0.11 s for 15,600 tidy parts, against 0.33 s for the search of 6,900 parts here (the
# 190 s bench book, 2026-11-27, fifth session: docs/BENCHMARKS.md, "gaps"). To be measured again when
# either changes (with the search's points read in the drawing processes the share grows).
TIDY_PART_COST = 0.14
# The share of the distinct states this process draws when a helper draws the rest (_drawings): the
# helper's part must also be pickled, sent and unpickled (~0.1 s for the 2,400 of the 190 s bench
# book through the pool's pipe, ~0.05 s through a memory file: docs/BENCHMARKS.md, "xfer") while this
# process only collects its own (Writer.prepare). Measured through the pipe, halves left this process waiting
# 0.10 s for the helper's (median of 6 runs), 0.53 0.04 s, 0.56 none (the helper waiting then):
# docs/BENCHMARKS.md, "The SVG stage's middle, halved". The helper also reads its parts for the reuse
# search (_draw_sent): through the memory file, 0.53 left this process waiting 0.08 s (median of 4),
# 0.56 and 0.59 0.03 s, the hand-over itself (docs/BENCHMARKS.md, "pts").
FIRST_SHARE = 0.56
# Share of animation_svg's time done when drawing the frames ends, when tidying the drawings
# (compact.Writer.finish) ends, when the reused drawings and parts are found (render/reuse.py),
# when the shared parts are found and when the tracks are written; the rest makes the document's
# bytes (measured 2026-11-27, fourth session, processor time of this process in generate, on the
# sample story and bench/generate.py's 190 s input: docs/BENCHMARKS.md, "Issue 16, where it stands
# (end of the fourth session"; DRAWN_SHARE again in the fifth, once told as this process's part is
# drawn: "gaps"). REUSE_STEPS: shares of the reuse step done when the
# points are read and when the tracks' drawings are searched (the parts' search is the rest).
DRAWN_SHARE = 0.42
TIDIED_SHARE = 0.65
REUSED_SHARE = 0.91
SHARED_SHARE = 0.96
REUSE_STEPS = (0.3, 0.6)
TRACKED_SHARE = 0.98
# The body's motion (animate/body.py) is written in steps of MOTION_STEP px (the torso's and
# the neck's shift) and of 0.1 degree (the torso's lean, TORSO_DECIMALS): each change makes the
# browser repaint the torso, so no finer than a viewer sees (a full breath, ~4 px, in ~9 steps).
MOTION_STEP = 0.5
TORSO_DECIMALS = 1
# ... and changes at most BODY_RATE times a second (each value held over fps / BODY_RATE
# frames): the body moves slowly, and a torso repainted in every frame of a breath cost the
# browser's playback frames (docs/BENCHMARKS.md, "Body"); animators draw such motion on threes.
BODY_RATE = 10


def frame_ms(index: int, fps: int) -> int:
    """Start of frame `index` at `fps` frames per second, in whole milliseconds."""
    return round(index * 1000 / fps)


def clock(ms: int) -> str:
    """A SMIL clock value (seconds, no unit) for `ms` milliseconds: 1234 -> '1.234', 500 -> '0.5', 0 -> '0'."""
    return decimal_text(ms / 1000, 3)  # exact: ms / 1000 is the double nearest a 3-decimal number


def track_of(name: str) -> str:
    """The track a part of render/svg.py's face_parts belongs to (TRACK_OF by its name)."""
    return TRACK_OF.get(name, name)


@dataclass
class _Track:
    """One track: its distinct drawings (tidy part numbers), the drawing number of every frame,
    and the dominant mouth symbol of each drawing (mouth track only)."""

    drawings: list[list[int]]
    keys: list[int]
    shapes: list[str]


def _tracks(raw: Sequence[tuple[int, ...]], states: Sequence[FaceState], shown: Sequence[int],
            raw_tracks: Sequence[str], mapping: Sequence[int]) -> dict[str, _Track]:
    """Group the raw parts of each distinct drawing `raw` (of `states`; track names `raw_tracks`,
    tidy numbers `mapping`) into tracks, in drawing order, for the frames (frame i shows drawing
    `shown[i]`; the drawings numbered as frames first show them); equal drawings of a track get
    one number, in the order frames first show them. Every drawing has its parts in the same
    tracks in the same order (render/svg.py's face_parts): numpy over all drawings at once."""
    if not len(raw):
        return {}
    parts = np.asarray(raw)  # (drawings, parts)
    names = [raw_tracks[number] for number in raw[0]]
    assert (np.asarray(raw_tracks)[parts] == np.asarray(names)).all(), "drawings with their parts in other tracks"
    tidy = np.asarray(mapping)[parts]
    places: dict[str, list[int]] = {}
    for place, name in enumerate(names):
        places.setdefault(name, []).append(place)
    tracks = {}
    frames = np.asarray(shown, dtype=np.intp)
    for name, at in places.items():
        distinct, numbers = distinct_rows(tidy[:, at])
        shapes = ([max(states[index].mouth, key=operator.itemgetter(1))[0]
                   for index in np.unique(numbers, return_index=True)[1].tolist()]  # each drawing's first
                  if name == MOUTH_TRACK else [])
        tracks[name] = _Track(distinct.tolist(), np.asarray(numbers)[frames].tolist(), shapes)
    return tracks


def _discrete(keys: Sequence[int], fps: int, value: Callable[[int], str]) -> dict[str, str]:
    """The attributes of a discrete SMIL animation holding `value(key)` over each run of equal
    `keys` (one per frame) from just before the run's first frame boundary, frozen at the end:
    calcMode, values, keyTimes (fractions of the whole), dur and fill."""
    array = np.asarray(keys)
    firsts = np.flatnonzero(np.concatenate(([True], array[1:] != array[:-1])))  # each run's first frame
    times, dur = _key_times(len(keys), fps)
    shown = array[firsts].tolist()
    texts = {key: value(key) for key in dict.fromkeys(shown)}  # value once per distinct key
    return {"calcMode": "discrete", "values": ";".join([texts[key] for key in shown]),
            "keyTimes": ";".join(times[firsts].tolist()), "dur": dur, "fill": "freeze"}


@functools.lru_cache(maxsize=1)
def _key_times(frames: int, fps: int) -> tuple[np.ndarray, str]:
    """The key time (text) of a run of `frames` frames beginning at each frame, just before its
    boundary, as an object array; and the `dur` of the animation. Made once for the document's
    animations alike (the tracks', the roll's, the body's: ~10,000 runs on a 3-minute book)."""
    total = 10 ** len(str(frame_ms(frames, fps)))  # ms: 633 -> 1000, 190325 -> 1000000
    units = 10 ** KEY_TIME_DECIMALS
    lead = max(KEY_TIME_LEAD, math.ceil(KEY_TIME_MIN_LEAD * units / total))
    starts = np.rint(np.arange(frames) * 1000 / fps).astype(np.int64)  # frame_ms of each (both round half to even)
    texts = fraction_texts(np.maximum(0, starts * units // total - lead).tolist(), KEY_TIME_DECIMALS)
    return np.array(texts, dtype=object), clock(total)


def _reuse(tracks: dict[str, _Track], writer: Writer, mapping: Sequence[int], tolerance: float,
           progress: Callable[[float], None], parts_read: Read, workers: int = 1,
           meanwhile: Callable[[], object] = lambda: None) -> Callable[[], tuple[dict[str, dict[int, Reuse]], dict[int, Reuse]]]:
    """A getter of the drawings of each of `tracks` shown as a transform of an earlier drawing of
    their track within `tolerance` px (render/reuse.py's find; none for 0), by track and drawing
    number; and of the ALONE parts (tidy part numbers: mouths, eyes, face outlines) of the drawings
    still written shown as a transform of an earlier written part (reuse.find_alike), of the UNMOVED
    parts only those shown as such a part unmoved (reuse.IDENTITY): the mouth mix
    changes in nearly every face drawing, so most are written, but their parts repeat under other
    poses. A drawing's parts are tidy part numbers; `mapping` gives the tidy number of each of
    `writer`'s raw parts, the first of which is the part's geometry as drawn (the others differ by
    less than the whole-pixel rounding). A part belongs to one track, so the tracks are searched
    apart: with `workers` 2 and POOL_STATES drawings or more, about half of them (by distinct parts, TIDY_PART_COST) by a child forked now
    (workers.forked; the same result), the rest when the getter is called, which then waits for
    the child. `progress(fraction)` is told the share done (REUSE_STEPS) as this process has read
    the points, searched each of its tracks and its parts. `parts_read` (_drawings'): the parts as the
    drawing processes read them, whose points the search takes (emptied by the search here, _search).
    The getter calls `meanwhile()` once, after this process's search and before it waits for the child's."""
    if tolerance <= 0:
        def none_reused() -> tuple[dict[str, dict[int, Reuse]], dict[int, Reuse]]:
            meanwhile()
            return {name: {} for name in tracks}, {}

        return none_reused
    first: dict[int, int] = {}
    for raw, tidy in enumerate(mapping):
        first.setdefault(tidy, raw)
    names = list(tracks)
    # split by the parts to read and fit; the child takes the side with the largest track (the face's, its
    # mouths the most), as this process makes the tidy drawings meanwhile
    there, here = (shares([len({number for drawing in track.drawings for number in drawing}) for track in tracks.values()],
                          TIDY_PART_COST * (max(mapping, default=-1) + 1))  # this process makes the tidy drawings too
                   if workers >= 2 and sum(len(track.drawings) for track in tracks.values()) >= POOL_STATES
                   else ([], range(len(names))))
    theirs = forked(workers if there else 1, _search, {names[index]: tracks[names[index]] for index in there}, writer, first,
                    tolerance, parts_read)

    def result() -> tuple[dict[str, dict[int, Reuse]], dict[int, Reuse]]:
        drawings, moved = _search({names[index]: tracks[names[index]] for index in here}, writer, first, tolerance, parts_read,
                                  progress)
        try:
            meanwhile()
        finally:  # the child's result taken even when `meanwhile` fails: the child does not wait on its pipe
            other_drawings, other_moved = theirs()
        both = {**drawings, **other_drawings}
        return {name: both[name] for name in names}, {**moved, **other_moved}

    return result


def _search(tracks: dict[str, _Track], writer: Writer, first: dict[int, int], tolerance: float, parts_read: Read,
            progress: Callable[[float], None] | None = None) -> tuple[dict[str, dict[int, Reuse]], dict[int, Reuse]]:
    """_reuse's search for `tracks` alone (`first`: the first raw part of each tidy part number),
    the parts' points taken from `parts_read` (_drawings') or read from their texts (_shapes). Its
    readings are let go once the points are made (a search computed after it in this process,
    forked's when the child is lost, reads the parts' texts: the same values)."""
    report = progress or (lambda fraction: None)
    raws = {number: writer.raw[first[number]]
            for number in dict.fromkeys(number for track in tracks.values() for drawing in track.drawings for number in drawing)}
    parts = dict(zip(raws, _shapes(writer.raw, [first[number] for number in raws], parts_read), strict=True))
    parts_read.readings.clear()  # let go before the fits (a few MB less at the peak, docs/BENCHMARKS.md "xfer")
    read, searched = REUSE_STEPS
    report(read)
    drawings = {}
    for done, (name, track) in enumerate(tracks.items(), 1):
        drawings[name] = find(joined([[parts[number] for number in drawing] for drawing in track.drawings]), tolerance)
        report(read + (searched - read) * done / len(tracks))
    written = [drawing for name, track in tracks.items() for number, drawing in enumerate(track.drawings)
               if number not in drawings[name]]
    beginnings = ALONE + UNMOVED
    alone = [number for number in dict.fromkeys(number for drawing in written for number in drawing)
             if raws[number].element.startswith(beginnings)]
    found = find_alike([parts[number] for number in alone], tolerance)
    return drawings, {alone[number]: Reuse(alone[reuse.source], reuse.matrix, reuse.error)
                      for number, reuse in found.items()
                      if reuse.matrix == IDENTITY or raws[alone[number]].element.startswith(ALONE)}


def _shapes(raw: Sequence[RawPart], numbers: Sequence[int], read: Read) -> list[Shape | None]:
    """The Shape (render/reuse.py) of each of the raw parts `numbers` (of `raw`, a Writer's): from
    the drawing process that drew it (`read`: its readings, reuse.shapes_from, or its parts as drawn
    read now, reuse.read_parts), or read from their texts (reuse.shapes_of) once they are let go."""
    if not read.readings:
        return shapes_of([(raw[number].element, *raw[number].definitions) for number in numbers])
    which, number = read.which[numbers], read.number[numbers]
    layouts: Layouts = {}  # of the skeletons the helper met: not made again
    for readings in read.readings:
        if isinstance(readings, Readings):
            layouts.update(zip(readings.skeletons, readings.layouts, strict=True))
    shapes: list[Shape | None] = [None] * len(numbers)
    for process, readings in enumerate(read.readings):
        places = np.flatnonzero(which == process)
        chosen = number[places].tolist()
        if isinstance(readings, Unread):  # read here, the parts taken alone
            readings, chosen = read_parts([readings.texts[part] for part in chosen], layouts, readings.tenths,
                                          [readings.formed[part] for part in chosen]), range(len(chosen))
        for place, shape in zip(places.tolist(), shapes_from(readings, chosen), strict=True):
            shapes[place] = shape
    return shapes


def _aliased(tracks: dict[str, _Track], reused: dict[str, dict[int, Reuse]],
             moved: dict[int, Reuse]) -> tuple[dict[str, _Track], dict[str, dict[int, Reuse]], dict[int, Reuse]]:
    """`tracks`, the drawings `reused` and the parts `moved` (_reuse's) without the transforms that
    are the IDENTITY (render/reuse.py writes a matrix as short as the tolerance allows, and many
    are): a part shown as its source unmoved is that part in its drawing; a drawing shown as its
    source unmoved, or made equal to an earlier written drawing by that, is no longer shown: its
    frames show that drawing (in the mouth track only where both show one mouth shape), as do the
    drawings reused from it. The drawings no frame shows stay in their place in `drawings`."""
    parts = {number: reuse.source for number, reuse in moved.items() if reuse.matrix == IDENTITY}
    new_tracks, new_reused = {}, {}
    for name, track in tracks.items():
        own = reused[name]
        drawings = [drawing if number in own else list(map(parts.get, drawing, drawing))  # C loops: parts.get(part, part)
                    for number, drawing in enumerate(track.drawings)]
        alias: dict[int, int] = {}
        firsts: dict[tuple[object, ...], int] = {}
        for number, drawing in enumerate(drawings):
            if number not in own:
                key = (*drawing, track.shapes[number] if track.shapes else "")
                alias[number] = firsts.setdefault(key, number)
        for number, reuse in own.items():
            source = alias[reuse.source]
            alias[number] = (source if reuse.matrix == IDENTITY and (not track.shapes or track.shapes[number] == track.shapes[source])
                             else number)
        new_tracks[name] = _Track(drawings, list(map(alias.__getitem__, track.keys)), track.shapes)
        new_reused[name] = {number: Reuse(alias[reuse.source], reuse.matrix, reuse.error)
                            for number, reuse in own.items() if alias[number] == number}
    return new_tracks, new_reused, {number: reuse for number, reuse in moved.items() if number not in parts}


def _track_group(track: str, drawings: list[list[str]], keys: Sequence[int], fps: int, shapes: Sequence[str],
                 names: Iterator[str], reused: dict[int, Reuse]) -> str:
    """The text of one track as a `<g data-part>` (`drawings`: each drawing's element texts): its drawing
    as is if it never changes, else each distinct drawing once as a `<g id>` (ids from `names`) in the
    track's own `<defs>` and one `<use>` whose `href` a discrete `<animate>` (_discrete) points at the
    drawing of every run of frames. A drawing of one element (compact.bare) is that element with the
    id, no `<g>` around it (one element fewer for the browser to build). The mouth track's drawings
    are `<g>`s carrying `data-shape`. Written as lxml writes the elements (render/moved.py reads them)."""
    if len(set(keys)) == 1:
        return markup("g", {"data-part": track}, "".join(drawings[keys[0]]))
    store = []
    ids = {number: next(names) for number in sorted(set(keys))}  # drawings no frame shows (_aliased) left out
    # the attributes written as markup writes them, the data-shape once per shape (ids and matrices
    # need no escaping): a markup call per drawing took a third of the time
    mouth = track == MOUTH_TRACK
    shaped = {shape: attributes_text({"data-shape": shape}) for shape in set(shapes)} if mouth else {}
    for number, name in ids.items():
        drawing = drawings[number]
        shape = shaped[shapes[number]] if mouth else ""
        if number in reused:
            matrix = reused[number].matrix
            moving = f' transform="matrix({matrix})"' if matrix != IDENTITY else ""
            store.append(f'<use id="{name}" href="#{ids[reused[number].source]}"{moving}{shape}/>')
        elif not mouth and bare(drawing):
            store.append(with_id(drawing[0], name))
        else:
            store.append(f'<g id="{name}"{shape}>{"".join(drawing)}</g>')  # never empty: a drawing has parts
    animate = markup("animate", {"attributeName": "href", **_discrete(keys, fps, lambda key: f"#{ids[key]}")})
    return markup("g", {"data-part": track}, markup("defs", {}, "".join(store)) + markup("use", {"href": f"#{ids[keys[0]]}"}, animate))


def _steps(keys: Sequence[int], fps: int, kind: str, value: Callable[[int], str]) -> etree._Element:
    """A discrete `<animateTransform>` of `kind` ("rotate", "skewX") holding `value(key)` over each
    run of equal `keys` (one per frame): its key times are the runs' frame boundaries (_discrete)."""
    return element(None, "animateTransform", {"attributeName": "transform", "type": kind,
                                              **_discrete(keys, fps, value)})


def _roll(layers: Sequence[etree._Element], rolls: Sequence[int], fps: int, centre: str) -> None:
    """Turn each of `layers` by the head's roll: `rolls` (one per frame, hundredths of a degree,
    positive counter-clockwise) as one discrete `<animateTransform>` (_steps); `centre` "x y" is
    the rotation origin. Nothing is added when the head never rolls."""
    if not any(rolls):
        return
    for layer in layers:
        layer.insert(0, _steps(rolls, fps, "rotate", lambda roll: f"{-roll / 10 ** ROLL_DECIMALS:g} {centre}"))


def _lean(neck: etree._Element, leans: Sequence[int], fps: int, pivot: float) -> None:
    """Lean the clothes layer's `neck` path with the head: `leans` (one per frame, tenths of a degree of
    skewX about the height `pivot`, render/scenery.py's lean) as a discrete `<animateTransform>`
    (_steps) of a group around it, moved to the pivot. Nothing changes when the neck never leans."""
    if not any(leans):
        return
    at = decimal_text(pivot, DECIMALS)
    holder = element(None, "g", transform=f"translate(0 {at})")
    neck.addprevious(holder)
    leaning = element(holder, "g")
    leaning.append(_steps(leans, fps, "skewX", lambda step: decimal_text(step / 10 ** LEAN_DECIMALS, LEAN_DECIMALS)))
    leaning.append(neck)
    neck.set("transform", f"translate(0 -{at})")


def _shifts(dx: Sequence[float] | np.ndarray, dy: Sequence[float] | np.ndarray) -> tuple[list[int], Callable[[int], str], bool]:
    """Per-frame shifts (`dx`, `dy` pixels) in MOTION_STEP steps as numbers of distinct shifts
    (keys for _steps), the translate value of each number, and whether any frame is shifted."""
    steps_x, steps_y = (np.round(np.asarray(v, dtype=float) / MOTION_STEP).astype(int).tolist() for v in (dx, dy))
    pairs = list(zip(steps_x, steps_y, strict=True))
    distinct = list(dict.fromkeys(pairs))
    number = {pair: index for index, pair in enumerate(distinct)}

    def text(key: int) -> str:
        x, y = distinct[key]
        return f"{decimal_text(x * MOTION_STEP, DECIMALS)} {decimal_text(y * MOTION_STEP, DECIMALS)}"

    return [number[pair] for pair in pairs], text, distinct != [(0, 0)]


def _move(parts: Sequence[etree._Element], keys: Sequence[int], fps: int, kind: str,
          value: Callable[[int], str]) -> etree._Element:
    """Wrap `parts` (consecutive children of one parent) in a `<g>` moved by a discrete
    `<animateTransform>` of `kind` (_steps of `keys` and `value`); return the group."""
    holder = element(None, "g")
    parts[0].addprevious(holder)
    holder.append(_steps(keys, fps, kind, value))
    holder.extend(parts)
    return holder


def _body(dressed: etree._Element, body: BodyMotion, figure: Figure, fps: int) -> None:
    """Move the clothes layer `dressed` with the `body` (one value per frame): its first child
    (the neck, leaned by _lean) rises with the breath; the rest, the torso, goes into a
    `<g class="torso">` shifted (breath, turn) by one translation, inside it a group leaned
    about scenery's torso_pivot by one rotation, each a discrete `<animateTransform>` (_steps)
    in MOTION_STEP / 0.1 degree steps, changing at most BODY_RATE times a second. A motion that
    never moves adds nothing."""
    hold = max(1, round(fps / BODY_RATE))
    held = np.arange(len(body.breath)) // hold * hold  # the frame whose value each frame shows
    dx, dy, neck_dy = (values[held] for values in torso_shift(figure, body.turn, body.breath))
    torso = list(dressed)[1:]
    angles = np.round(np.asarray(body.roll)[held] * 10 ** TORSO_DECIMALS).astype(int).tolist()
    keys, text, moving = _shifts(dx, dy)
    outer = None
    if torso and any(angles):
        x, y = torso_pivot(figure)
        centre = f"{decimal_text(x, DECIMALS)} {decimal_text(y, DECIMALS)}"
        outer = _move(torso, angles, fps, "rotate",
                      lambda angle: f"{decimal_text(-angle / 10 ** TORSO_DECIMALS, TORSO_DECIMALS)} {centre}")
    if torso and moving:
        outer = _move([outer] if outer is not None else torso, keys, fps, "translate", text)
    if outer is not None:
        outer.set("class", "torso")
    keys, text, moving = _shifts([0.0] * len(neck_dy), neck_dy)
    if moving:
        _move([dressed[0]], keys, fps, "translate", text)


def _stage(root: etree._Element, defs: etree._Element, figure: Figure, clothes: str, background: str,
           leans: Sequence[int], body: BodyMotion | None, fps: int) -> tuple[etree._Element, etree._Element]:
    """Append to `root` the layers in front of the background: the (empty) hair layer, the clothes
    layer (render/scenery.py; its neck leaned by `leans`, _lean, and moved with `body`, _body), the
    desk layer of `background` if it has one, and the (empty) face layer; their paint servers go
    into `defs`. Returns the hair and face layers, for the tracks."""
    hair = element(root, "g", id="hair")
    dressed = clothes_layer(clothes, figure, defs)
    _lean(dressed[0], leans, fps, neck_pivot(figure))
    if body is not None:
        _body(dressed, body, figure, fps)
    root.append(dressed)
    desk = desk_layer(background, figure, defs)
    if desk is not None:
        root.append(desk)
    return hair, element(root, "g", id="face")


DrawingKey = tuple[object, ...]  # _draw's key of a drawing: the fields of the state but its roll, the pupils


# the fields of a state but its pose and of a pose but its roll, each read as a tuple by one
# attrgetter (several names: a tuple)
_STATE_FIELDS = operator.attrgetter(*(f.name for f in dataclasses.fields(FaceState) if f.name != "pose"))
_POSE_FIELDS = operator.attrgetter(*(f.name for f in dataclasses.fields(Pose) if f.name != "roll"))


def _unrolled_fields(state: FaceState) -> tuple[object, ...]:
    """The fields of face/pose.py's unrolled(state) (the state without roll), as a tuple: equal
    for equal unrolled states, without making (and checking) a FaceState per frame."""
    fields: tuple[object, ...] = _POSE_FIELDS(state.pose) + _STATE_FIELDS(state)
    return fields


def _draw(face: FaceModel, states: Sequence[FaceState], progress: Callable[[float], None] | None = None,
          tenths: dict[str, np.ndarray] | None = None,
          forms: dict[Part, Formed] | None = None) -> list[tuple[DrawingKey, tuple[Part, ...]]]:
    """Draw each of `states` (render/svg.py's all_face_parts, uid UID, up to BATCH states at a time):
    its key and its parts. The head's roll is not drawn (the layers turn): the face is posed with
    it and turned back by the roll as written (ROLL_DECIMALS; the two turns cancel exactly). The
    drawing depends on the state without roll and on the pupils (written to 0.1 px), the key:
    states that share it differ by a turn of under 0.005 degrees (the roll's rounding), which
    moves no point by more than 0.02 px. `progress(fraction)` is told the share drawn after every batch;
    `tenths` gets the numbers of the path data all_face_parts wrote from whole tenths (pathdata.Tenths),
    `forms` the Form and slots of its parts (compact.Formed)."""
    lifted = lift(face)
    origin = rig(lifted).origin
    drawings = []
    size = min(BATCH, max(MIN_BATCH, len(states) // BATCHES))
    for start in range(0, len(states), size):
        if progress is not None:
            progress(start / len(states))
        batch = states[start:start + size]
        rolls = [round(state.pose.roll * 10 ** ROLL_DECIMALS) / 10 ** ROLL_DECIMALS for state in batch]
        posed = unroll_faces(pose_faces(lifted, batch), rolls, origin)
        pupils = np.round(posed.pupils, 1).reshape(len(batch), 4).tolist()
        for state, eyes, parts in zip(batch, pupils, all_face_parts(face, posed, UID, tenths=tenths, forms=forms), strict=True):
            drawings.append(((*_unrolled_fields(state), *eyes), parts))
    return drawings


Numbered = list[tuple[DrawingKey, tuple[int, ...]]]  # _draw's drawings, parts as numbers of a Drawn's parts


def _draw_compacted(face: FaceModel, states: Sequence[FaceState], progress: Callable[[float], None] | None = None,
                    sent: bool = False) -> tuple[Numbered, Drawn, Unread]:
    """_draw of `states`, each drawing's parts numbered by the distinct parts, which are made ready
    for the Writer (compact.drawn_parts: their path data compacted, their skeletons; `sent`: for
    another process): what a drawing process does of compact.Writer.finish's work; and the
    distinct parts as drawn, for the reuse search to read (Unread, by their number)."""
    tenths: dict[str, np.ndarray] = {}  # compacting and reading take the path data's numbers as drawn, not read again
    forms: dict[Part, Formed] = {}  # and the parts' values as drawn, not cut out of their text
    drawings = _draw(face, states, progress, tenths, forms)
    numbers: dict[Part, int] = {}
    numbered = [(key, tuple(numbers.setdefault(part, len(numbers)) for part in parts)) for key, parts in drawings]
    return (numbered, drawn_parts(list(numbers), tenths, sent, forms),
            Unread([(part.text, *part.clips) for part in numbers], list(map(forms.get, numbers)), tenths))


def _draw_sent(face: FaceModel, states: Sequence[FaceState]) -> tuple[Numbered, Drawn, Readings]:
    """_draw_compacted of `states` in a drawing helper, for this process, its parts read there
    (reuse.read_parts: while this process collects its own, the helper has time to spare)."""
    numbered, drawn, unread = _draw_compacted(face, states, None, sent=True)
    return numbered, drawn, read_parts(unread.texts, {}, unread.tenths, unread.formed)


class Unread(NamedTuple):
    """A drawing process's distinct parts as drawn, for reuse.read_parts: their texts (the
    element's and its definitions'), Form and slots (compact.Formed, or None), and the numbers of
    their path data as drawn (pathdata.Tenths)."""

    texts: list[tuple[str, ...]]
    formed: list[Formed | None]
    tenths: dict[str, np.ndarray]


class Read(NamedTuple):
    """The distinct parts of the drawing processes for the reuse search, each process's read
    (the helper's, _draw_sent) or not yet (this one's, _draw_compacted's Unread: read by the
    search, only the parts it takes) in a list emptied once the search has taken them (_search);
    and for each of a Writer's raw parts which of them holds it (`which`) and its number there
    (`number`), (R,) each."""

    readings: list[Readings | Unread]
    which: np.ndarray
    number: np.ndarray


def _drawings(face: FaceModel, states: Sequence[FaceState], workers: int, progress: Callable[[float], None],
              writer: Writer, helper: Helper | None = None) -> tuple[list[tuple[int, ...]], Compacted, Read]:
    """_draw_compacted of `states` collected by `writer` in order (_collected): the raw part
    numbers of each drawing, the path data compacted (pathdata.merged of the processes'), and the
    parts as the processes read them (Read). In one go, or with `workers` 2 and at least
    POOL_STATES states in two parts (FIRST_SHARE of them first), the second drawn by a helper
    (_draw_sent) meanwhile: `helper`'s, or one forked now (workers.helper_process), which ends on its
    own once its part is back; the first is collected and its templates and tidy texts made
    (Writer.prepare) while the second comes. The helper's part comes back through its memory file
    (workers.memory_file: no pipe). When the helper cannot be started, has not begun or fails, its
    part is drawn here (workers.offloaded)."""
    where: dict[DrawingKey, int] = {}
    numbers: list[np.ndarray] = []  # per process, each of its raw parts' number among its distinct parts
    if workers < 2 or len(states) < POOL_STATES:
        numbered, drawn, unread = _draw_compacted(face, states, progress)
        raw = _collected(writer, numbered, drawn, where, [], numbers)
        return raw, drawn.done, Read([unread], *_sources(numbers))
    half = round(len(states) * FIRST_SHARE)
    # every result taken before leaving: a helper forked here ends on its own
    with nullcontext(helper) if helper is not None else helper_process(workers, wait=False) as (pool, through):
        other = offloaded(pool, _draw_sent, face, states[half:], through=through)
        # the helper draws its part meanwhile: this one's share done is about the whole's, and once it
        # is drawn the helper's core is about to be free (generate's ffmpeg begins then, on it); with
        # no helper, its part is drawn here after
        own = 1.0 if pool is not None else FIRST_SHARE
        numbered, drawn, unread = _draw_compacted(face, states[:half], lambda done: progress(done * own))
        progress(own)
        raw = _collected(writer, numbered, drawn, where, [], numbers)
        writer.prepare()
        done = drawn.done
        numbered, drawn, sent = other()
        if pool is not None:  # its last job: it ends on its own, its memory let go before the search's child
            pool.shutdown(wait=False)
    raw = _collected(writer, numbered, drawn, where, raw, numbers)
    return raw, merged(done, drawn.done), Read([unread, sent], *_sources(numbers))


def _sources(numbers: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Read's `which` and `number` of raw parts collected in turn from drawing processes whose parts'
    `numbers` (_collected's, one array per process) are given in that order."""
    return (np.repeat(np.arange(len(numbers), dtype=np.int8), [len(own) for own in numbers]),
            np.concatenate(numbers))


def _collected(writer: Writer, drawings: Numbered, drawn: Drawn, where: dict[DrawingKey, int],
               raw: list[tuple[int, ...]], numbers: list[np.ndarray]) -> list[tuple[int, ...]]:
    """`raw` (the raw part numbers of the drawings collected before) and those of the `drawings` of
    one drawing process (_draw_compacted's, with `drawn`) collected by `writer` (Writer.collected).
    A drawing whose key an earlier one has (`where`: the first drawing of each key, filled) is
    that one's. `numbers` gets the number in `drawn` of each raw part collected here (they follow
    the writer's raw parts before)."""
    firsts = [where.setdefault(key, index) for index, (key, _) in enumerate(drawings, len(raw))]
    own = [index for index, first in enumerate(firsts, len(raw)) if first == index]
    parts = [drawings[index - len(raw)][1] for index in own]
    collected = writer.collected(drawn, parts)
    numbers.append(np.fromiter(dict.fromkeys(chain.from_iterable(parts)), dtype=np.int32))  # as collected: first shown first
    mine = dict(zip(own, collected))
    return raw + [mine[first] if first in mine else raw[first] for first in firsts]


@collector_paused()  # its containers hold no cycles (workers.collector_paused; also for callers but generate)
def animation_svg(face: FaceModel, states: Sequence[FaceState], fps: int, *, background: str = "plain",
                  clothes: str = "none", wide: bool = False, title: str = "",
                  body: BodyMotion | None = None, progress: Callable[[float], None] | None = None,
                  workers: int = 1, tolerance: float = TOLERANCE, helper: Helper | None = None,
                  meanwhile: Callable[[], object] = lambda: None) -> bytes:
    """The animation of `states` (frame i shows time i / fps s) as a standalone SVG document (UTF-8 bytes).

    `background` and `clothes` name the scenery layers (render/scenery.py);
    `wide` makes the picture a 16:9 stage around the face, deep enough for the shoulders
    (the announcer's);
    `title` becomes the document's <title> (escaped like every text by lxml);
    `body` (animate/body.py, one value per state) moves the clothes layer: the shoulders
    follow the head and breathe (None: a still body).
    The root is `<svg id="cf-face">`; each track is a `<g data-part="...">`;
    the mouth track's drawings carry `data-shape`, the dominant basic mouth shape they show.
    `progress(fraction)`, when given, is told the share 0..1 of the work done as the frames are
    drawn (every BATCH distinct states) and tidied, and 1.0 at the end.
    `workers`: processes to draw with (workers.processes(); 1: this one alone), same bytes.
    `helper` (workers.helper_process's, with `workers` 2): the process that draws the second part
    (_drawings), forked before (generate's analysis helper) rather than now: a fork of this
    process, large by then, makes every page it writes after the fork a fault (a copy while the
    child lives), ~8,500 on the 3-minute bench book (docs/BENCHMARKS.md, "mainmem"). Its pool
    is shut down once that part is back (the process ends on its own).
    `tolerance` (px): a drawing within it of a transform of an earlier drawing of its track is
    shown as that (render/reuse.py); 0: every distinct drawing written in full.
    `meanwhile()` is called once, when this process has searched its share of the reused drawings and
    would wait for the child searching the rest (the child's share usually takes ~5-20 ms longer:
    docs/BENCHMARKS.md, "tail2"): work of the caller's that does not need the document (generate's
    page texts) then costs no time.
    """
    report = progress or (lambda fraction: None)
    width, height = float(face.width), float(face.height)
    box_height = height * STAGE_DEPTH if wide else height
    box_width = max(width, box_height * WIDE) if wide else width
    box = ((width - box_width) / 2, 0.0, box_width, box_height)
    root = svg_root({"id": "cf-face", "width": f"{box_width:g}", "height": f"{box_height:g}",
                     "viewBox": " ".join(f"{v:g}" for v in box), "data-fps": str(fps)})
    if title:
        element(root, "title").text = title
    style = element(root, "style")
    defs = element(root, "defs")
    defs.extend(face_defs(face))
    figure = figure_of(face, box)
    root.append(background_layer(background, figure, defs))
    writer = Writer(track_of)
    origin = rig(lift(face)).origin
    rolls = [round(state.pose.roll * 10 ** ROLL_DECIMALS) for state in states]
    # the neck's lean in each frame, in steps of LEAN_DECIMALS: it follows the roll as written
    leans = [round(lean(figure, origin, roll / 10 ** ROLL_DECIMALS) * 10 ** LEAN_DECIMALS) for roll in rolls]
    numbers: dict[FaceState, int] = {}
    shown = [numbers.setdefault(state, len(numbers)) for state in states]  # each state hashed once
    distinct = list(numbers)
    raw, done, read = _drawings(face, distinct, workers, lambda done: report(DRAWN_SHARE * done), writer, helper)
    mapping = writer.finish(lambda tidied: report(DRAWN_SHARE + (TIDIED_SHARE - DRAWN_SHARE) * tidied), done)
    tracks = _tracks(raw, distinct, shown, [part.label for part in writer.raw], mapping)
    # the reuse search begun (half the tracks in a child) before the tidy drawings are made here
    reuse = _reuse(tracks, writer, mapping, tolerance,
                   lambda done: report(TIDIED_SHARE + (REUSED_SHARE - TIDIED_SHARE) * done), read, workers, meanwhile)
    tidy = writer.drawings()
    defs.extend(writer.definitions)  # clip paths several drawings share (an eye's, under any gaze)
    report(TIDIED_SHARE)
    # what does not wait for the search, done before this process's share of it: the child's share
    # usually takes longer (docs/BENCHMARKS.md, "tail"), so this costs no time
    style.text = writer.style_sheet()
    hair, layer = _stage(root, defs, figure, clothes, background, leans, body, fps)
    _roll((hair, layer), rolls, fps, f"{origin[0]:.6g} {origin[1]:.6g}")
    del raw, done  # freed while the child searches (~5 ms), not at the return
    reused, moved = reuse()
    tracks, reused, moved = _aliased(tracks, reused, moved)
    report(REUSED_SHARE)
    # the parts several drawings show get a <defs> of their own after the document's, which a page
    # can leave undisplayed as it does the tracks' (render/pages.inline_svg)
    visible = {name: set(track.keys) for name, track in tracks.items()}
    elements, shared = share({name: [[] if number in reused[name] or number not in visible[name] else drawing
                                     for number, drawing in enumerate(track.drawings)]
                              for name, track in tracks.items()}, tidy,
                             {number: (reuse.source, reuse.matrix) for number, reuse in moved.items()})
    # the texts made without lxml (the tidy drawings' and what holds them) go in at the end in place of
    # these comments: the drawings are neither parsed nor serialized again
    texts = []
    if shared:
        texts.append(markup("defs", {"id": PARTS_ID}, shared))
        defs.addnext(etree.Comment(f"{SPLICE}0"))
    classes = writer.classes()
    elements = {name: merge_all_alike(drawings, classes, writer.extents) for name, drawings in elements.items()}
    report(SHARED_SHARE)
    names = short_ids(FRAME_LETTER)
    for number, (name, track) in enumerate(tracks.items(), 1):
        (hair if name in HAIR_TRACKS else layer).append(etree.Comment(f"{SPLICE}{len(texts)}"))
        texts.append(_track_group(name, elements[name], track.keys, fps, track.shapes, names, reused[name]))
        report(SHARED_SHARE + (TRACKED_SHARE - SHARED_SHARE) * number / len(tracks))
    report(TRACKED_SHARE)
    document = re.sub(rf"<!--{SPLICE}(\d+)-->".encode(), lambda match: texts[int(match.group(1))].encode(),
                      etree.tostring(root, xml_declaration=True, encoding="utf-8"))
    report(1.0)
    return document
