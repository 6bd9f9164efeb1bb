"""What the gzipped bytes of animation.svg are made of (issue 16: 150 KB per minute gzipped).

Each kind of element (where it is: the shared parts' `<defs>`, a part track or the rest of the
document; its tag, a `<use>` with a transform told apart; its style class) costs what gzip -6 of the
document saves when every element of that kind is taken out (a `<g>`: its children kept), and the
key times and values of each track's `<animate>` what emptying them saves. The costs overlap (what
one kind repeats of another is paid once), so they do not add up to the whole; they tell what a
cut of a kind could buy at most.

`python -m bench.weight [ANIMATION.svg MINUTES]`: the kinds of that document, else of the audio book
made by `generate` from bench/generate.py's 3-minute input.
"""

from __future__ import annotations

import gzip
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

from lxml import etree

from cartoonface.data import SAMPLE_FACES
from cartoonface.pipeline import generate
from cartoonface.render.animation import PARTS_ID

SVG = "{http://www.w3.org/2000/svg}"
SMALLEST = 0.004  # kinds under this share of the document's raw bytes are left out
ROWS = 30  # kinds printed, the costliest first
Kind = tuple[str, str, str]  # where, tag, class


def kind(node: etree._Element) -> Kind:
    """Where `node` is (the shared parts, a track by its data-part, the document), its tag ("use+matrix": a
    `<use>` with a transform; "clip-path": a path in a clip path), its class."""
    place = next((ancestor.get("data-part") or "shared" for ancestor in node.iterancestors()
                  if ancestor.get("data-part") or ancestor.get("id") == PARTS_ID), "document")
    tag = etree.QName(node).localname
    if tag == "use" and node.get("transform"):
        tag = "use+matrix"
    parent = node.getparent()
    if tag == "path" and parent is not None and parent.tag == f"{SVG}clipPath":
        tag = "clip-path"
    return place, tag, node.get("class", "")


def cost(data: bytes, packed: int, take: list[etree._Element], root: etree._Element) -> int:
    """The gzipped bytes `data` (`packed` of them gzipped, parsed as `root`) saves without `take`
    (elements of `root`; a `<g>` replaced by its children)."""
    copy = etree.fromstring(data)
    paths = root.getroottree()
    for node in [copy.getroottree().xpath(paths.getpath(node))[0] for node in take]:
        parent = node.getparent()
        if node.tag == f"{SVG}g":
            parent[parent.index(node):parent.index(node) + 1] = list(node)
        else:
            parent.remove(node)
    return packed - len(gzip.compress(etree.tostring(copy, xml_declaration=True, encoding="utf-8"), 6))


def weights(data: bytes) -> list[tuple[int, int, int, str]]:
    """(gzipped bytes saved, raw bytes, elements, what) of each kind of the SVG document `data` and of
    each track's key times and values, the costliest first."""
    packed = len(gzip.compress(data, 6))
    root = etree.fromstring(data)
    kinds: dict[Kind, list[etree._Element]] = defaultdict(list)
    for node in root.iter():
        if (isinstance(node.tag, str) and etree.QName(node).localname not in ("svg", "style", "title", "defs")
                and not node.get("data-part") and node.get("id") not in ("hair", "face")):
            kinds[kind(node)].append(node)
    rows = []
    for what, nodes in kinds.items():
        raw = sum(len(etree.tostring(node, with_tail=False)) for node in nodes)
        if raw >= SMALLEST * len(data):
            place, tag, style = what
            rows.append((cost(data, packed, nodes, root), raw, len(nodes), f"{place} {tag}{'.' + style if style else ''}"))
    for number, animate in enumerate(root.iter(f"{SVG}animate")):
        holder = animate.getparent()
        track = holder.getparent().get("data-part") if holder is not None and holder.getparent() is not None else ""
        for name in ("keyTimes", "values"):
            copy = etree.fromstring(data)
            emptied = list(copy.iter(f"{SVG}animate"))[number]
            emptied.set(name, "")
            saved = packed - len(gzip.compress(etree.tostring(copy, xml_declaration=True, encoding="utf-8"), 6))
            rows.append((saved, len(animate.get(name, "")), 1, f"{track} <animate> {name}"))
    return sorted(rows, reverse=True)


def report(data: bytes, minutes: float) -> None:
    """Print the ROWS costliest kinds of `data` (`minutes` of animation) per minute."""
    print(f"whole: {len(data) / minutes / 1e3:.0f} KB raw, {len(gzip.compress(data, 6)) / minutes / 1e3:.1f} KB "
          "gzipped per minute; per kind (KB per minute gzipped saved without it, raw, elements):")
    for saved, raw, count, what in weights(data)[:ROWS]:
        print(f"| {what} | {saved / minutes / 1e3:.1f} | {raw / minutes / 1e3:.0f} | {count:,} |")


def main(document: Path | None = None, minutes: float = 0.0) -> None:
    """report of `document` (`minutes` long), else of the audio book of bench/generate.py's input."""
    if document is not None:
        report(document.read_bytes(), minutes)
        return
    from bench.generate import build_input

    face = sorted(SAMPLE_FACES.glob("*.json"))[0]
    with tempfile.TemporaryDirectory(prefix="cartoonface-bench-") as tmp:
        audio, transcript, seconds = build_input(Path(tmp))
        result = generate(face, audio, transcript, Path(tmp) / "out")
        report((result.out_dir / "animation.svg").read_bytes(), result.duration / 60)


if __name__ == "__main__":
    main(Path(sys.argv[1]), float(sys.argv[2])) if sys.argv[1:] else main()
