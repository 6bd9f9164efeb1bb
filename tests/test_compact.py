"""The compactor's shared definitions (render/compact.py): a clip path that several drawings hold
alike (an eye's outline under different gazes) is written once, and the frames using it look the
same as when each frame carries its own copy."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from lxml import etree
from PIL import Image

from cartoonface.face.model import load_face
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.animation import animation_svg
from cartoonface.render.compact import merge_alike, merge_all_alike, short_id
from cartoonface.render.elements import Part
from cartoonface.render.png import svg_to_png
from tests.stills import frozen

ROOT = Path(__file__).resolve().parent.parent
NS = {"s": "http://www.w3.org/2000/svg"}
S = "{http://www.w3.org/2000/svg}"
FPS = 30
# A still head looking about (gaze_h, gaze_v in degrees), then turning, so that some eye
# outlines repeat under different gazes and others do not.
GAZES = ((0.0, 0.0), (6.0, 0.0), (-6.0, 2.0), (0.0, 5.0), (9.0, -3.0), (0.0, 0.0))


@pytest.fixture(scope="module")
def face():
    return load_face(ROOT / "samples" / "faces" / "female.json")


def looking_about() -> list[FaceState]:
    """Frames of a still head glancing about, then of a turning head; mouths vary."""
    still = [FaceState(gaze_h=h, gaze_v=v, mouth=((symbol, 1.0),))
             for (h, v), symbol in zip(GAZES, "aoeium", strict=True) for _ in range(2)]
    turning = [FaceState(pose=Pose(turn=float(i), tilt=i / 2), gaze_h=3.0 * (i % 2)) for i in range(4)]
    return still + turning


def pixels(data: bytes) -> np.ndarray:
    with Image.open(io.BytesIO(svg_to_png(data))) as image:
        return np.asarray(image.convert("RGBA"), dtype=np.int16)


def test_clip_paths_shared_by_several_drawings_are_written_once(face):
    svg = etree.fromstring(animation_svg(face, looking_about(), FPS))
    defs = svg.find("s:defs", NS)
    shared = [clip for clip in defs.iterfind("s:clipPath", NS)]
    assert shared, "the still head's eye outlines are shared by the drawings of its gazes"
    outlines = [etree.tostring(clip[0]).replace(f' id="{clip[0].get("id")}"'.encode(), b"") for clip in shared]
    assert len(outlines) == len(set(outlines)), "each shared clip path once"
    used = {node.get("clip-path")[5:-1] for node in svg.iter() if node.get("clip-path")}
    for clip in shared:
        assert clip.get("id") in used
        users = [node for node in svg.iter() if node.get("clip-path") == f"url(#{clip.get('id')})"]
        assert len(users) >= 2, "only clip paths of two or more drawings are shared"
    inside = [clip for clip in svg.find("s:g[@id='face']", NS).iter(f"{S}clipPath")]
    assert inside, "the turning head's clip paths, each of one drawing, stay in their frames"


def in_frame_copies(data: bytes) -> bytes:
    """The still SVG `data` with each reference to a shared clip path (a `clip-path` or a `<use>`
    of its outline) given a copy of it of its own, placed just before the referring element and
    the shared ones removed: the form the compactor wrote before it shared them."""
    svg = etree.fromstring(data)
    shared = {clip.get("id"): clip for clip in svg.find("s:defs", NS).iterfind("s:clipPath", NS)}
    referring = [node for node in svg.iter() if node.get("clip-path", "")[5:-1] in shared
                 or node.get("href", "")[1:-1] in shared]
    for number, node in enumerate(referring):
        name = node.get("clip-path", "")[5:-1] or node.get("href")[1:-1]
        copy = etree.fromstring(etree.tostring(shared[name]))
        copy.set("id", f"copy{number}")
        copy[0].set("id", f"copy{number}_")
        node.addprevious(copy)
        if node.get("clip-path"):
            node.set("clip-path", f"url(#copy{number})")
        else:
            node.set("href", f"#copy{number}_")
    for clip in shared.values():
        clip.getparent().remove(clip)
    return etree.tostring(svg)


@pytest.mark.parametrize("frame", [0, 3, 7, 9, 12, 15])
def test_a_frame_with_shared_clip_paths_looks_as_with_its_own(face, frame):
    # the frame at the same time, drawn with the shared clip paths and with copies of its own
    still = frozen(animation_svg(face, looking_about(), FPS), frame, FPS)
    before = in_frame_copies(still)
    assert before != still, "the frame uses shared clip paths"
    after, own = pixels(still), pixels(before)
    assert after.shape == own.shape
    differ = np.abs(after - own).max(axis=2) > 2
    assert differ.mean() < 1e-4, f"{differ.sum()} pixels differ"


def talking_about(count: int) -> list[FaceState]:
    """`count` frames of a head turning, tilting, rolling and glancing while it talks: many
    distinct states, each part shape seen under many positions."""
    mouths = "amfoeiunhrz"
    return [FaceState(pose=Pose(turn=12 * np.sin(i / 23), tilt=6 * np.sin(i / 17), roll=4 * np.sin(i / 29)),
                      gaze_h=5 * np.sin(i / 7), blink=float(i % 41 == 0), smile=0.5 * (i % 3 == 0),
                      mouth=((mouths[i % len(mouths)], 0.7), (mouths[i // 3 % len(mouths)], 0.3)),
                      emotion=(("happy", 0.6),) if i % 5 == 0 else ())
            for i in range(count)]


def test_parts_tidied_by_skeleton_equal_parts_tidied_one_by_one(face):
    """Writer.finish tidies one part of each skeleton and fills in the others' values: every
    tidy drawing it gives is the one _tidy_part makes of that raw part by itself."""
    from cartoonface.face.lift import lift
    from cartoonface.face.pose import pose_face
    from cartoonface.render.animation import track_of
    from cartoonface.render.compact import _PATH_DATA, Writer
    from cartoonface.render.pathdata import compacted
    from cartoonface.render.svg import face_parts

    writer = Writer(track_of)
    lifted = lift(face)
    for state in talking_about(60):
        writer.collect(face_parts(face, pose_face(lifted, state), "u"))
    raw = list(writer.raw)
    compact = compacted(d for part in raw for text in (part.element, *part.definitions)
                        for d in _PATH_DATA.findall(text)).compact
    alone = Writer(track_of)
    expected = [b"".join(etree.tostring(node) for node in alone._tidy_part((part.element, *part.definitions), compact))
                for part in raw]
    mapping = writer.finish()
    tidy = writer.drawings()
    assert len(set(expected)) == len(tidy) > 20
    # the same drawings, numbered alike, before finish renames their ids and classes
    renamed = ["".join(tidy[number]) for number in mapping]
    firsts = {}
    for number, text in zip(mapping, expected, strict=True):
        assert firsts.setdefault(number, text) == text, "one tidy drawing per distinct expected drawing"
    assert len(set(renamed)) == len(tidy)
    assert list(alone.styles) == list(writer.styles), "style classes made in the same order"


def test_parts_collected_from_drawing_processes_tidy_as_collected_in_one(face):
    """Writer.collected takes the skeletons each drawing process made of its own parts
    (compact.drawn_parts): halves cut anywhere, their path data compacted apart (another first
    path data chooses the points kept), drawings left out (a state whose key an earlier drawing
    has) among them the one holding a first path data, templates and tidy texts made ahead
    (Writer.prepare), give the tidy drawings, each drawing's tidy part numbers and the style
    classes of one process collecting the same drawings."""
    from functools import reduce

    from cartoonface.render.animation import _draw_compacted, track_of
    from cartoonface.render.compact import Writer, part_paths
    from cartoonface.render.pathdata import compacted, merged

    states = talking_about(90)
    whole, drawn, _ = _draw_compacted(face, states)
    everything = compacted(part_paths((text, *clips) for _, text, clips in drawn.parts))
    holding = {index for index, (_, numbers) in enumerate(whole)
               if any(f' d="{d}"' in drawn.parts[number][1] for number in numbers for d in everything.firsts.values())}
    assert everything.firsts and holding
    for left_out in (set(), {min(holding)} | set(range(5, 90, 11))):
        reference = Writer(track_of)
        reference_raw = [reference.collect([Part(*drawn.parts[number]) for number in numbers])
                         for index, (_, numbers) in enumerate(whole) if index not in left_out]
        mapping = reference.finish()
        expected = [[mapping[number] for number in numbers] for numbers in reference_raw]
        drawings = reference.drawings()
        for cut in (7, 45, 80):
            # the second half as a helper sends it (its compact forms only of the parts that may change)
            halves = [_draw_compacted(face, states[:cut])[:2], _draw_compacted(face, states[cut:], sent=True)[:2]]
            done = reduce(merged, (half.done for _, half in halves))
            writer = Writer(track_of)
            raw = []
            for offset, (numbered, half) in zip((0, cut), halves, strict=True):
                raw += writer.collected(half, [numbers for index, (_, numbers) in enumerate(numbered, offset)
                                               if index not in left_out])
                writer.prepare()  # templates and tidy texts made ahead (some parts' made again by finish)
            mapping = writer.finish(None, done)
            assert [[mapping[number] for number in numbers] for numbers in raw] == expected
            assert writer.drawings() == drawings
            assert writer.style_sheet() == reference.style_sheet()


def test_two_processes_draw_the_same_bytes(face):
    """Drawing the states in two processes gives the document one process gives; the caller's
    `meanwhile` is called once, in this process, either way (and with no reuse search: tolerance 0)."""
    import os

    from cartoonface.render.animation import POOL_STATES

    states = talking_about(POOL_STATES + 50)
    assert len(set(states)) >= POOL_STATES
    called: list[int] = []

    def meanwhile() -> None:
        called.append(os.getpid())

    assert (animation_svg(face, states, FPS, workers=2, meanwhile=meanwhile)
            == animation_svg(face, states, FPS, meanwhile=meanwhile))
    animation_svg(face, states[:5], FPS, tolerance=0, meanwhile=meanwhile)
    assert called == [os.getpid()] * 3


def test_a_failing_meanwhile_fails_the_document_and_leaves_no_child(face, capfd):
    """An exception of `meanwhile` reaches animation_svg's caller; the child searching the rest ends,
    reporting no error (its result is taken before the exception goes on)."""
    import multiprocessing
    import time

    from cartoonface.render.animation import POOL_STATES

    def failing() -> None:
        raise RuntimeError("meanwhile failed")

    with pytest.raises(RuntimeError, match="meanwhile failed"):
        animation_svg(face, talking_about(POOL_STATES + 50), FPS, workers=2, meanwhile=failing)
    waited = 0.0
    while multiprocessing.active_children() and waited < 10:
        time.sleep(0.05)
        waited += 0.05
    assert not multiprocessing.active_children()
    assert "Error" not in capfd.readouterr().err


def test_a_helper_begun_before_draws_the_same_bytes(face, monkeypatch):
    """A helper process forked before (generate's analysis helper, workers.helper_process) draws the
    second part, handed back through its memory file, which is emptied then: the document one
    process gives; its pool is shut down after (no new work), its process ends on its own."""
    import os

    import cartoonface.workers as workers
    from cartoonface.render.animation import POOL_STATES
    from cartoonface.workers import helper_process

    read = []
    original = workers._read
    monkeypatch.setattr(workers, "_read", lambda through, size: read.append(size) or original(through, size))
    states = talking_about(POOL_STATES + 50)
    expected = animation_svg(face, states, FPS)
    with helper_process(2) as helper:
        assert helper.pool is not None and helper.through is not None  # Linux, as the tests run
        helper_pid = helper.pool.submit(os.getpid).result()
        assert helper_pid != os.getpid()
        assert animation_svg(face, states, FPS, workers=2, helper=helper) == expected
        assert len(read) == 1 and read[0] > 0  # its part came through the memory file,
        assert os.fstat(helper.through).st_size == 0  # which holds nothing after
        with pytest.raises(RuntimeError):
            helper.pool.submit(os.getpid)


def test_no_second_process_under_a_cpu_limit():
    """A process with a CPU-time limit (a web job) draws alone: the limit counts per process."""
    import resource

    from cartoonface.workers import processes

    soft, hard = resource.getrlimit(resource.RLIMIT_CPU)
    if soft != resource.RLIM_INFINITY:
        pytest.skip("this test process already has a CPU limit")
    resource.setrlimit(resource.RLIMIT_CPU, (10 ** 6, hard))
    try:
        assert processes() == 1
    finally:
        resource.setrlimit(resource.RLIMIT_CPU, (soft, hard))
    assert processes() in (1, 2)


def test_a_pool_that_cannot_start_falls_back_to_one_process(face, monkeypatch):
    """When the second process cannot be started (no memory, no thread) the states are drawn here."""
    import cartoonface.render.animation as animation
    import cartoonface.workers as workers

    class NoFork:
        def __init__(self, *args, **named):
            raise OSError(12, "Cannot allocate memory")

    states = talking_about(animation.POOL_STATES + 10)
    expected = animation_svg(face, states, FPS)
    monkeypatch.setattr(workers, "ProcessPoolExecutor", NoFork)
    assert animation_svg(face, states, FPS, workers=2) == expected


def wrapped(data: bytes) -> bytes:
    """The still SVG `data` in the form the compactor wrote before it left out wrappers: every
    drawn element with an id in a `<defs>` (a track's drawing or a shared part of one element)
    inside a `<g>` that takes its id, and every shape with a clip path inside a `<g>` that clips."""
    svg = etree.fromstring(data)
    for defs in list(svg.iter(f"{S}defs")):
        for node in list(defs):
            if node.get("id") and node.tag in (f"{S}path", f"{S}ellipse", f"{S}circle", f"{S}use"):
                holder = etree.Element(f"{S}g", id=node.attrib.pop("id"))
                node.addprevious(holder)
                holder.append(node)
    for node in list(svg.iter(f"{S}path", f"{S}ellipse", f"{S}circle")):
        if node.get("clip-path"):
            holder = etree.Element(f"{S}g", {"clip-path": node.attrib.pop("clip-path")})
            node.addprevious(holder)
            holder.append(node)
    return etree.tostring(svg)


def test_no_group_wraps_one_element_for_nothing(face):
    svg = etree.fromstring(animation_svg(face, talking_about(60), FPS))
    drawings = [node for defs in svg.iter(f"{S}defs") for node in defs
                if node.tag in (f"{S}g", f"{S}path", f"{S}ellipse", f"{S}circle", f"{S}use")]
    assert len(drawings) > 60
    for node in drawings:
        if node.tag == f"{S}g" and node.get("data-shape") is None:
            assert len(node) != 1 or node[0].get("id") is not None, "a drawing of one element is that element"
    for group in svg.iter(f"{S}g"):
        if set(group.attrib) == {"clip-path"} and len(group) == 1:
            assert group[0].tag not in (f"{S}path", f"{S}ellipse", f"{S}circle"), "one shape carries its clip"
    assert any(node.tag != f"{S}g" for node in drawings), "some drawings are one element"
    assert any(node.get("clip-path") for node in svg.iter(f"{S}ellipse", f"{S}circle", f"{S}path"))


@pytest.mark.parametrize("frame", [0, 11, 23, 37, 52])
def test_a_frame_without_wrappers_looks_as_with_them(face, frame):
    still = frozen(animation_svg(face, talking_about(60), FPS), frame, FPS)
    before = wrapped(still)
    assert before != still
    differ = np.abs(pixels(still) - pixels(before)).max(axis=2) > 2
    assert differ.mean() < 1e-4, f"{differ.sum()} pixels differ"


BROW_STYLE = {"fill": "#4a2a20", "stroke": "#4a2a20", "stroke-width": ".6"}


@pytest.mark.parametrize("second", ["m60,20c5-6,15-6,20,0l-20,4z", "m60,20 20,0 0,8-20,0z", "M60,20H80V28H60Z",
                                    "m60,20l10-8,10,8q-10,6-20,0", "m60,20s10-10,20,0 -20,8-20,0"])
def test_paths_alike_lying_apart_are_one_path_with_the_same_pixels(second):
    def path(d: str) -> str:
        return f'<path d="{d}" class="n"/>'

    first = "m10,20c5-6,15-6,20,0l-20,4z"
    drawing = [path(first), path(second)]
    separate = "".join(drawing).encode()
    merged = merge_alike(drawing, {"n": BROW_STYLE})
    assert len(merged) == 1
    (kept,) = etree.fromstring(f'<g xmlns="{S[1:-1]}">{merged[0]}</g>')
    assert kept.tag == f"{S}path" and set(kept.attrib) == {"d", "class"} and kept.get("d").startswith(first)

    def picture(body: bytes) -> np.ndarray:
        style = f".n{{{';'.join(f'{k}:{v}' for k, v in BROW_STYLE.items())}}}"
        return pixels(f'<svg xmlns="{S[1:-1]}" width="100" height="40"><style>{style}</style>'.encode()
                      + body + b"</svg>")

    assert np.array_equal(picture(separate), picture(merged[0].encode()))


@pytest.mark.parametrize("second, style", [("m25,20c5-6,15-6,20,0l-20,4z", BROW_STYLE),  # overlapping
                                           ("m60,20c5-6,15-6,20,0l-20,4z", {"fill": "url(#g)"}),
                                           ("m60,20c5-6,15-6,20,0l-20,4z", {"fill": "#000", "opacity": ".5"}),
                                           ("m60,20a5,5,0,0,0,10,0z", BROW_STYLE)])  # an arc: not read
def test_paths_that_could_draw_otherwise_stay_apart(second, style):
    drawing = [f'<path d="{d}" class="n"/>' for d in ("m10,20c5-6,15-6,20,0l-20,4z", second)]
    assert merge_alike(drawing, {"n": style}) == drawing


def test_short_ids_count_in_base_36():
    """short_ids gives the ids short_id makes, in order, past every change of width: each the
    letter and its number in base 36 (read back by int(..., 36))."""
    from itertools import islice

    from cartoonface.render.compact import short_id, short_ids

    ids = list(islice(short_ids("k"), 36 ** 3 + 40))
    assert [int(name[1:], 36) for name in ids] == list(range(len(ids)))
    assert all(name == short_id("k", number) and name[0] == "k" for number, name in enumerate(ids))


def test_parts_differing_in_sizes_share_a_skeleton_and_tidy_as_one_by_one():
    """A part's sizes (compact.SIZES) as plain numbers leave its skeleton, as its positions do, so
    parts differing only in them share one skeleton (one template); a size that is no plain number
    stays in it. Tidied by that skeleton, each part is what tidying it alone gives."""
    from cartoonface.render.compact import Writer, _skeleton
    from cartoonface.render.pathdata import compacted

    def part(rx: str, width: str) -> str:
        return (f'<g class="gloss"><ellipse cx="10.4" cy="20.6" rx="{rx}" ry="2" fill="#fff" opacity="0.2"/>'
                f'<rect x="1" y="2" width="{width}" height="4.5" fill="#000"/><path d="M1 2L30.4 40.6" stroke="#111"/></g>')

    texts = [part("6", "3"), part("7.5", "3"), part("6", "50%"), part("7.5", "50%")]
    compact = compacted(["M1 2L30.4 40.6"]).compact
    skeletons = [_skeleton((text,), compact)[0] for text in texts]
    assert skeletons[0] == skeletons[1] != skeletons[2] == skeletons[3]
    assert 'width="50%"' in skeletons[2] and 'rx="6"' not in skeletons[0]
    together = Writer(lambda name: name)
    numbers = [together.collect([Part("gloss", text)]) for text in texts]
    mapping = together.finish()
    tidy = together.drawings()
    alone = Writer(lambda name: name)
    for text, (raw,) in zip(texts, numbers, strict=True):
        written = etree.fromstring(f'<g xmlns="http://www.w3.org/2000/svg">{"".join(tidy[mapping[raw]])}</g>')
        assert _unclassed(list(written)) == _unclassed(alone._tidy_part((text,), compact))


def _unclassed(elements: list[etree._Element]) -> list[tuple[str, dict[str, str]]]:
    """Every node of `elements`: its tag and attributes but its class (the Writers name their style
    classes apart)."""
    return [(node.tag, {name: value for name, value in node.attrib.items() if name != "class"})
            for element in elements for node in element.iter()]


def test_merging_many_drawings_at_once_is_merging_each_alone():
    def path(d: str, label: str = "n") -> str:
        return f'<path d="{d}" class="{label}"/>'

    apart = [path("m10,20c5-6,15-6,20,0l-20,4z"), path("m60,20 20,0 0,8-20,0z"), path("M90,20H110V28H90Z")]
    overlapping = path("m25,20c5-6,15-6,20,0l-20,4z")
    other = path("m200,20 5,0 0,5z", "o")
    painted = [path("m10,20 5,0 0,5z", "p"), path("m60,20 5,0 0,5z", "p")]  # a paint server: never joined
    use = '<use href="#g1"/>'
    drawings = [apart[:2], [apart[0], use, apart[1]], [], [use, use], [apart[0], overlapping], [other, *apart],
                [*apart, other, apart[0], apart[2]], [apart[1]], [apart[2], apart[0]], [other], [other, other], apart[:2],
                painted, [*painted, *apart[:2]], [apart[0], *painted, apart[1]]]
    styles = {"n": BROW_STYLE, "o": BROW_STYLE, "p": {"fill": "url(#g)"}}
    each = [merge_alike(drawing, styles) for drawing in drawings]
    assert merge_all_alike(drawings, styles) == each
    assert sum(len(merged) < len(drawing) for merged, drawing in zip(each, drawings, strict=True)) >= 5  # some join,
    assert all(merged[:2] == painted for merged in each[-3:-1]) and each[-1] == drawings[-1]  # never the painted


def test_short_ids_are_the_numbers_in_base_36_after_the_letter():
    numbers = [*range(0, 3000), 36 ** 2 - 1, 36 ** 2, 36 ** 3 - 1, 36 ** 3, 36 ** 4 + 5, 10 ** 9]
    ids = [short_id("f", number) for number in numbers]
    assert all(text[0] == "f" and text[1:] == text[1:].lower() and int(text[1:], 36) == number
               and (text[1] != "0" or number == 0) for text, number in zip(ids, numbers, strict=True))
