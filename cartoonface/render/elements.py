"""SVG elements built with lxml: the namespace, one element helper, documents as bytes.

Every render module builds its SVG with `element` (and `svg_root` for a document), so
attribute names and number formats follow one rule: keyword names are written with
hyphens ("stroke_width" -> "stroke-width"), numbers to 0.1 with
`cartoonface.render.numbers.decimal_text`; a mapping of attributes is written as given.

The one exception is the hot path of an animation, a face drawn in thousands of states
(render/svg.py's face_parts): its parts are written as text (`Part`, `attributes_text`) and
parsed with `parse_elements` only where a tree is needed.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from typing import NamedTuple

from lxml import etree

from cartoonface.render.numbers import decimal_text

SVG = "http://www.w3.org/2000/svg"
NSMAP = {None: SVG}
# Decimals of a number given to `element` as a keyword attribute (pixels: a tenth is the
# finest step a screen shows); render/scenery.py writes its path data alike.
DECIMALS = 1


def element(parent: etree._Element | None, tag: str, attrs: Mapping[str, str] | None = None,
            /, **named: str | float) -> etree._Element:
    """The SVG element `tag` (no namespace: "path") appended to `parent`, or a free element
    when `parent` is None. Its attributes are `attrs` in their order, then `named` with
    underscores as hyphens, numbers written with DECIMALS decimals. Returns it."""
    node = (etree.Element(f"{{{SVG}}}{tag}", attrs) if parent is None
            else etree.SubElement(parent, f"{{{SVG}}}{tag}", attrs))
    for name, value in named.items():
        node.set(name.replace("_", "-"), value if isinstance(value, str) else decimal_text(value, DECIMALS))
    return node


def svg_root(attrs: Mapping[str, str]) -> etree._Element:
    """An `<svg>` document root with attributes `attrs`, SVG the default namespace (no prefix)."""
    return etree.Element(f"{{{SVG}}}svg", attrs, nsmap=NSMAP)


def svg_bytes(root: etree._Element) -> bytes:
    """The document `root` as UTF-8 SVG bytes with an XML declaration."""
    return etree.tostring(root, xml_declaration=True, encoding="utf-8")


class Part(NamedTuple):
    """One top-level part of a drawing as SVG text, without a namespace declaration (parse it
    with parse_elements): `name` its class ("hair", "eye-l", ...), `text` the element, `clips`
    the texts of the definitions (clip paths) it refers to, in document order. (A named tuple:
    the drawing processes number ~75,000 parts by equality, hashed at half the cost of a frozen
    dataclass's.)"""

    name: str
    text: str
    clips: tuple[str, ...] = ()


def attributes_text(attrs: Mapping[str, str]) -> str:
    """`attrs` as the text of attributes inside a start tag, each after a space, values escaped as
    lxml escapes them: {"fill": "#fff", "opacity": "0.5"} -> ' fill="#fff" opacity="0.5"'."""
    return "".join(f' {name}="{_attribute_value(value)}"' for name, value in attrs.items())


def markup(tag: str, attrs: Mapping[str, str], inner: str = "") -> str:
    """The text of the SVG element `tag` with `attrs` (in order) holding the text `inner`, as lxml
    writes it inside a document: `<g id="a"/>` when empty."""
    attributes = attributes_text(attrs)
    return f"<{tag}{attributes}>{inner}</{tag}>" if inner else f"<{tag}{attributes}/>"


def _attribute_value(value: str) -> str:
    """`value` escaped as lxml writes an attribute value (not html.escape's: "'" stays)."""
    if not _SPECIAL.search(value):  # most values (ids, references, numbers): one look
        return value
    for plain, escaped in _LXML_ESCAPES:
        value = value.replace(plain, escaped)
    return value


_SPECIAL = re.compile('[&<>"\n\r\t]')
_LXML_ESCAPES = (("&", "&amp;"), ("<", "&lt;"), (">", "&gt;"), ('"', "&quot;"), ("\n", "&#10;"), ("\r", "&#13;"),
                 ("\t", "&#9;"))


def parse_elements(texts: Iterable[str]) -> list[etree._Element]:
    """Parse SVG element texts written without a namespace declaration (Part texts, in the SVG
    namespace); returns them as free elements, in order."""
    holder = etree.fromstring(f'<g xmlns="{SVG}">{"".join(texts)}</g>')
    nodes = list(holder)
    for node in nodes:
        holder.remove(node)
    return nodes
