"""Still pictures of an animation's frames (render/animation.py's documents), for the tests that
compare frames drawn still with the animation."""

from __future__ import annotations

from lxml import etree

S = "{http://www.w3.org/2000/svg}"


def frozen(data: bytes, frame: int, fps: int) -> bytes:
    """The animation `data` as a still SVG of frame `frame` (frame / fps s): each discrete animation
    replaced by the value it holds in the middle of that frame (a track's `<use>` pointed at the
    frame's drawing, a layer's transform set to the frame's turn or shift)."""
    ms = (frame + 0.5) * 1000 / fps
    svg = etree.fromstring(data)
    for animate in list(svg.iter(f"{S}animate", f"{S}animateTransform")):
        holder = animate.getparent()
        total = float(animate.get("dur")) * 1000
        times = [float(value) * total for value in animate.get("keyTimes").split(";")]
        value = animate.get("values").split(";")[max(index for index, at in enumerate(times) if at <= ms)]
        if animate.tag == f"{S}animate":
            holder.set(animate.get("attributeName"), value)
        else:
            holder.set("transform", f"{animate.get('type')}({value})")
        holder.remove(animate)
    return etree.tostring(svg)
