"""Hair from a photo: does the hair polygon stay off the face, is its colour the hair's
(docs/BENCHMARKS.md, "Hair from a photo"; docs/photo.md).

Data and crops: those of bench/photo.py (43 faces of dlib's example photos, each cut out
twice its box and scaled to a 160 px box). For every crop the face model is made
(`face_from_photo`) and compared with the face mesh and a reference hair region read
here on its own:

- overlap: the share of the hair polygon's area (photo pixels, as `PhotoFace.hair`)
  that lies on the face oval below the brows (below the line through the brow arch
  tops, mesh points 105 and 334); the goal is about 0;
- colour: the CIE76 distance (CIELAB, D65) between the model's hair colour and the
  median Lab colour of the reference hair region: the selfie segmentation's person
  (confidence over REF_PERSON) outside the face oval, above the eyes, not skin-coloured
  (over REF_SKIN from the model's skin colour), within REF_SIDE face widths of the face;
- failures: crops whose face is not found or not made into a model; fallbacks: models
  whose hair colour is the eyebrow colour (warned);
- seconds per crop for `face_from_photo` (the models loaded).
"""

from __future__ import annotations

import statistics
import time

import numpy as np
from PIL import Image

from bench.photo import annotated_faces, crop

# The reference hair region: person confidence over this, Lab distance (CIE76) to the
# skin colour over this, at most this many face widths beside the face box.
REF_PERSON = 0.5
REF_SKIN = 20.0
REF_SIDE = 0.5
# Fewer reference pixels than this: no colour figure for that crop.
REF_MIN_PIXELS = 30
# Mesh points: the brow arch tops (the line below which the face must stay bare).
BROW_TOPS = (105, 334)


def _lab(rgb: np.ndarray) -> np.ndarray:
    """(..., 3) CIELAB of (..., 3) RGB 0..255."""
    from skimage.color import rgb2lab

    return rgb2lab(np.asarray(rgb, float).reshape(-1, 1, 3) / 255.0).reshape(np.shape(rgb))


def _hex_rgb(colour: str) -> np.ndarray:
    return np.array([int(colour[i:i + 2], 16) for i in (1, 3, 5)], float)


def lower_face(mesh: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """(H, W) bool: the face oval of the (478, 3) mesh below the line through the brow
    arch tops, on an image of `shape`."""
    from cartoonface.photo.landmarks_map import OVAL
    from cartoonface.photo.palette import polygon_mask

    (xa, ya), (xb, yb) = mesh[BROW_TOPS[0], :2], mesh[BROW_TOPS[1], :2]
    rows, cols = np.mgrid[0:shape[0], 0:shape[1]]
    line = ya + (cols - xa) * (yb - ya) / (xb - xa)
    return polygon_mask(shape, mesh[list(OVAL), :2]) & (rows > line)


def overlap(polygon: np.ndarray, mesh: np.ndarray, shape: tuple[int, int]) -> float:
    """Share of the (N, 2) polygon's area on the face oval below the brows (0..1)."""
    from cartoonface.photo.palette import polygon_mask

    area = polygon_mask(shape, polygon)
    return float((area & lower_face(mesh, shape)).sum() / max(1, area.sum()))


def reference_hair(rgb: np.ndarray, mesh: np.ndarray, person: np.ndarray, skin: np.ndarray) -> np.ndarray | None:
    """(3,) median Lab of the reference hair region, None when it has too few pixels."""
    from cartoonface.photo.landmarks_map import OVAL, eyes
    from cartoonface.photo.palette import polygon_mask

    shape = rgb.shape[:2]
    (x0, _), (x1, _) = mesh[:, :2].min(axis=0), mesh[:, :2].max(axis=0)
    side = REF_SIDE * (x1 - x0)
    rows, cols = np.mgrid[0:shape[0], 0:shape[1]]
    lab = _lab(rgb)
    near = (cols > x0 - side) & (cols < x1 + side) & (rows < eyes(mesh)[0][1])
    region = (person > REF_PERSON) & near & ~polygon_mask(shape, mesh[list(OVAL), :2])
    region &= np.linalg.norm(lab - _lab(skin), axis=-1) > REF_SKIN
    return np.median(lab[region], axis=0) if region.sum() >= REF_MIN_PIXELS else None


def crop_figures() -> list[dict[str, float | bool | None]]:
    """Per crop, in annotation order: "overlap" (share, None when no model), "colour"
    (CIE76, None without a reference region), "fallback" (eyebrow colour), "seconds"
    (face_from_photo), "turn" (degrees), "fringe" (the outline dips over the forehead)."""
    from cartoonface.errors import InputError
    from cartoonface.photo.landmarks import landmarker
    from cartoonface.photo.model_from_photo import face_from_photo, photo_from_image

    marker = landmarker()
    rows: list[dict[str, float | bool | None]] = []
    for path, box, _ in annotated_faces():
        with Image.open(path) as image:
            picture, _, _ = crop(image.convert("RGB"), box)
        photo = photo_from_image(picture, path.name)
        started = time.perf_counter()
        try:
            result = face_from_photo(photo)
        except InputError:
            rows.append({"overlap": None, "colour": None, "fallback": False, "seconds": None, "turn": None,
                         "fringe": False})
            continue
        seconds = time.perf_counter() - started
        found = marker.find(photo.rgb)
        if found is None:
            rows.append({"overlap": None, "colour": None, "fallback": False, "seconds": seconds, "turn": None,
                         "fringe": False})
            continue
        mesh = found.points
        ref = reference_hair(photo.rgb, mesh, marker.person(photo.rgb), _hex_rgb(result.face.palette.skin))
        rows.append({
            "overlap": overlap(result.hair, mesh, photo.rgb.shape[:2]),
            "colour": None if ref is None else float(np.linalg.norm(_lab(_hex_rgb(result.face.palette.hair)) - ref)),
            "fallback": any("eyebrow colour" in note for note in result.warnings),
            "seconds": seconds,
            "turn": result.turn,
            "fringe": bool(getattr(result, "fringe", False)),  # the GrabCut version had none
        })
    return rows


def main() -> None:
    """Print the figures."""
    rows = crop_figures()
    overlaps = [float(r["overlap"]) for r in rows if r["overlap"] is not None]
    colour = [float(r["colour"]) for r in rows if r["colour"] is not None]
    seconds = [float(r["seconds"]) for r in rows if r["seconds"] is not None]
    failures = sum(r["overlap"] is None for r in rows)
    fallbacks = sum(bool(r["fallback"]) for r in rows)
    print(f"crops: {len(rows)}; failures (no face / no model): {failures}; hair colour from the eyebrows: {fallbacks}; "
          f"outlines with a fringe: {sum(bool(r['fringe']) for r in rows)}")
    print(f"hair polygon on the face oval below the brows: median {statistics.median(overlaps):.1%}, "
          f"mean {statistics.mean(overlaps):.1%}, worst {max(overlaps):.1%}; "
          f"crops over 5 %: {sum(o > 0.05 for o in overlaps)}/{len(overlaps)}")
    print(f"hair colour vs the reference hair region (CIE76, {len(colour)} crops with a region): "
          f"median {statistics.median(colour):.1f}, mean {statistics.mean(colour):.1f}, worst {max(colour):.1f}; "
          f"over 10: {sum(c > 10 for c in colour)}")
    print(f"face_from_photo per crop (models loaded): median {statistics.median(seconds) * 1000:.0f} ms, "
          f"max {max(seconds) * 1000:.0f} ms")


def figure_sheet(before: list[dict[str, float | bool | None]], after: list[dict[str, float | bool | None]],
                 path: str) -> None:
    """Write a PNG (256 colours) of the per-crop figures `before` and `after` (lists of
    crop_figures() rows): the overlap with the face and the colour distance per crop.
    Needs matplotlib (installed with mediapipe, the photo extra)."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def values(rows: list[dict[str, float | bool | None]], key: str, scale: float = 1.0) -> np.ndarray:
        return np.array([np.nan if r[key] is None else float(r[key]) * scale for r in rows])  # type: ignore[arg-type]

    index = np.arange(len(after))
    figure, (top, bottom) = plt.subplots(2, 1, figsize=(9, 5.2), dpi=90, sharex=True)
    width = 0.4
    top.bar(index - width / 2, values(before, "overlap", 100), width, label="before (GrabCut)", color="#b0b0b0")
    top.bar(index + width / 2, values(after, "overlap", 100), width, label="after (selfie segmentation)", color="#1565c0")
    top.set_ylabel("% of the outline on\nthe face below the brows")
    top.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=2, fontsize=8)
    bottom.bar(index - width / 2, values(before, "colour"), width, color="#b0b0b0")
    bottom.bar(index + width / 2, values(after, "colour"), width, color="#1565c0")
    for rows, shift in ((before, -width / 2), (after, width / 2)):
        fell = [i for i, r in enumerate(rows) if r["fallback"]]
        bottom.plot(index[fell] + shift, values(rows, "colour")[fell] + 2, "v", color="#c62828", markersize=5,
                    label="eyebrow colour (fallback)" if fell else None)
    bottom.set_ylabel("hair colour vs the\nhair region (CIE76)")
    bottom.set_xlabel("crop (dlib examples, annotation order)")
    bottom.legend(loc="upper left", fontsize=8)
    figure.tight_layout()
    out = io.BytesIO()
    figure.savefig(out, format="png")
    plt.close(figure)
    out.seek(0)
    Image.open(out).convert("RGB").quantize(256).save(path, optimize=True)
