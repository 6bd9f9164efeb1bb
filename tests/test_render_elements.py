"""render/elements.py (the one SVG element helper) and render/numbers.py's decimal_text and fraction_texts."""

from __future__ import annotations

import numpy as np
import pytest
from lxml import etree

from cartoonface.render.elements import DECIMALS, SVG, element, markup, svg_bytes, svg_root
from cartoonface.render.numbers import decimal_text, fraction_texts


@pytest.mark.parametrize("decimals", [1, 3, 9])
def test_decimal_text_is_the_value_to_its_decimals_without_trailing_zeros(decimals: int) -> None:
    rng = np.random.default_rng(decimals)
    values = [*rng.uniform(-2000, 2000, 200), *rng.integers(-50, 50, 20).astype(float), 0.0, 0.5, -0.04]
    for value in values:
        text = decimal_text(float(value), decimals)
        assert abs(float(text) - value) <= 0.5 * 10.0 ** -decimals + 1e-9
        whole, _, fraction = text.partition(".")
        assert len(fraction) <= decimals and not fraction.endswith("0") and not text.endswith(".")
        assert whole.lstrip("-") != ""  # a leading zero is kept: "0.5", never ".5"


@pytest.mark.parametrize("decimals", [1, 3, 7, 15])
def test_fraction_texts_are_decimal_texts_of_the_fractions(decimals: int) -> None:
    rng = np.random.default_rng(decimals)
    top = 10 ** decimals
    numerators = [0, 1, top - 1, top // 10, *(int(n) for n in rng.integers(0, top, 2000, dtype=np.int64)),
                  *(int(n) // 1000 * 1000 for n in rng.integers(0, top, 50, dtype=np.int64))]  # trailing zeros
    assert fraction_texts(numerators, decimals) == [decimal_text(n / top, decimals) for n in numerators]


def test_element_writes_attributes_in_order_with_hyphens_and_numbers_to_its_decimals() -> None:
    parent = element(None, "g")
    node = element(parent, "rect", {"class": "a", "data-x": "1"}, stroke_width=0.25, x=3.0, fill="#fff")
    assert node.getparent() is parent and node.tag == f"{{{SVG}}}rect"
    assert list(node.attrib.items()) == [("class", "a"), ("data-x", "1"), ("stroke-width", decimal_text(0.25, DECIMALS)),
                                         ("x", "3"), ("fill", "#fff")]


def test_a_document_has_svg_as_its_default_namespace() -> None:
    root = svg_root({"width": "10", "height": "20"})
    element(root, "path", d="M0 0")
    data = svg_bytes(root)
    assert data.startswith(b"<?xml") and b'<svg xmlns="http://www.w3.org/2000/svg" width="10" height="20">' in data
    parsed = etree.fromstring(data)
    assert parsed[0].tag == f"{{{SVG}}}path" and parsed[0].get("d") == "M0 0"


@pytest.mark.parametrize("inner", ["", '<path d="m1,2 3,4z"/>'])
def test_markup_writes_what_lxml_writes_inside_a_document(inner):
    """elements.markup (the tracks' holders written as text, render/animation.py) gives the bytes lxml
    writes for the same element in an SVG document, escaping included."""
    attrs = {"id": "f1", "data-shape": "h'", "title": 'a "b" <c> & d\n\te\r'}
    expected = etree.Element(f"{{{SVG}}}svg", nsmap={None: SVG})
    built = etree.SubElement(expected, f"{{{SVG}}}g", attrs)
    built.extend(etree.fromstring(f'<g xmlns="{SVG}">{inner}</g>'))
    assert etree.tostring(expected).decode() == f'<svg xmlns="{SVG}">{markup("g", attrs, inner)}</svg>'
