"""Mouth-shape symbols of Mandarin syllables (thesis 002 5.2.2) and their onsets (5.3)."""

from __future__ import annotations

import pytest

from cartoonface.errors import TranscriptError
from cartoonface.speech import mouth_shapes as ms
from cartoonface.speech.mouth_shapes import (
    MOUTH_SYMBOLS, shape_onsets, shapes_for,
)
from cartoonface.speech.pinyin import syllable_parts

INITIALS = ("b", "p", "m", "f", "d", "t", "n", "l", "g", "k", "h", "j", "q", "x",
            "zh", "ch", "sh", "r", "z", "c", "s")

# Every final in its spellings: zero-initial (y/w), after initials, u-umlaut spelt u after
# j/q/x and y, apical -i, er, syllabic nasals and erhua.
FINAL_SPELLINGS = (
    "a1", "o1", "e4", "ê2", "ai4", "ei4", "ao4", "ou1", "an1", "en1", "ang2", "eng1", "er2",
    "yi1", "ya1", "yo1", "ye3", "yai2", "yao4", "you3", "yan4", "yin1", "yang2", "ying2", "yong3",
    "wu3", "wa1", "wo3", "wai4", "wei4", "wan2", "wen2", "wang2", "weng1",
    "yu2", "yue4", "yuan2", "yun2",
    "ju1", "qu4", "xu3", "jue2", "que4", "xue2", "juan3", "quan2", "xuan1", "jun1", "qun2", "xun4",
    "lü4", "lv4", "nü3", "lüe4", "nüe4", "lue4", "jiong3", "qiong2", "xiong1",
    "dong1", "gong1", "liu2", "dui4", "lun2", "bian4", "tiao4", "niang2", "ling2", "kuai4",
    "zi3", "ci2", "si4", "zhi1", "chi1", "shi4", "ri4",
    "n2", "ng2", "m2", "hm5", "hng5",
    "huar1", "dianr3", "wanr2", "zher4", "nar3", "shir4", "yuanr4", "biaor4", "menr2", "gair4",
)


def final_symbols(pinyin: str) -> list[str]:
    """The symbols of the syllable's final alone (medial + rhyme), from the module's tables."""
    parts = syllable_parts(pinyin)
    medial = [ms.MEDIAL_SHAPE[parts.medial]] if parts.medial else []
    return medial + list(ms.RHYME_SHAPES[parts.final])


def all_readings() -> list[str]:
    """Every distinct tone-numbered reading of pypinyin's character dictionary."""
    from pypinyin.contrib.tone_convert import to_tone3
    from pypinyin.pinyin_dict import pinyin_dict

    marked = {p for value in pinyin_dict.values() for p in value.split(",")}
    return sorted({to_tone3(p, v_to_u=True, neutral_tone_with_five=True) for p in marked})


@pytest.fixture(scope="module")
def readings() -> list[str]:
    return all_readings()


def test_twelve_distinct_symbols_in_the_contract_order():
    assert MOUTH_SYMBOLS == ("m", "f", "h'", "h", "r", "z", "a", "i", "u", "e", "o", "n")


def test_every_initial_has_one_of_the_six_initial_shapes():
    assert set(ms.INITIAL_SHAPE) == set(INITIALS)
    assert set(ms.INITIAL_SHAPE.values()) == {"m", "f", "h'", "h", "r", "z"}
    # Table 5.3/5.5: the bilabials share the closed-lips shape m, f is alone.
    assert {ms.INITIAL_SHAPE[i] for i in ("b", "p", "m")} == {"m"}
    assert [i for i in INITIALS if ms.INITIAL_SHAPE[i] == "f"] == ["f"]


@pytest.mark.parametrize("initial", INITIALS)
def test_every_initial_before_a(initial):
    """Before a the initial's shape is kept (5.2.2); j/q/x only come before i/ü."""
    syllable = {"j": "jia1", "q": "qia4", "x": "xia4", "r": "rang4"}.get(initial, initial + "a1")
    shapes = shapes_for(syllable)
    assert 1 <= len(shapes) <= 4 and set(shapes) <= set(MOUTH_SYMBOLS)
    if final_symbols(syllable)[0] == "a":
        assert shapes[0] == ms.INITIAL_SHAPE[initial]
        assert "a" in shapes


@pytest.mark.parametrize("pinyin", FINAL_SPELLINGS)
def test_every_final_gets_one_to_four_symbols(pinyin):
    shapes = shapes_for(pinyin)
    assert 1 <= len(shapes) <= 4
    assert set(shapes) <= set(MOUTH_SYMBOLS)
    assert all(a != b for a, b in zip(shapes, shapes[1:]))


def test_every_reading_pypinyin_knows_is_a_syllable(readings):
    for pinyin in readings:
        shapes = shapes_for(pinyin)
        assert 1 <= len(shapes) <= 4 and set(shapes) <= set(MOUTH_SYMBOLS), pinyin


def test_h_initials_dropped_before_i_u_e_o_kept_before_a(readings):
    """Thesis 002 5.2.2: h' and h are eliminated before i, u, e, o, not before a."""
    seen = {"dropped": 0, "kept": 0}
    for pinyin in readings:
        parts = syllable_parts(pinyin)
        if not parts.initial or ms.INITIAL_SHAPE[parts.initial] not in ("h'", "h"):
            continue
        if parts.final in ("n", "ng", "m"):
            continue
        behind = final_symbols(pinyin)[0]
        shapes = shapes_for(pinyin)
        if behind in ("i", "u", "e", "o"):
            assert shapes[0] == behind, pinyin
            seen["dropped"] += 1
        else:   # a, and n/h which the rule does not name
            assert shapes[0] == ms.INITIAL_SHAPE[parts.initial], pinyin
            seen["kept"] += 1
    assert seen["dropped"] > 50 and seen["kept"] > 20


def test_an_becomes_en_after_medial_i_or_u_umlaut(readings):
    """Thesis 002 5.2.2: the an rhyme after the finals i, ü is shaped en; not after u."""
    checked = 0
    for pinyin in readings:
        parts = syllable_parts(pinyin)
        if parts.final != "an" or parts.erhua:
            continue
        shapes = shapes_for(pinyin)
        if parts.medial in ("i", "ü"):
            assert shapes[-2:] == ("e", "n") and "a" not in shapes, pinyin
        else:
            assert shapes[-2:] == ("a", "n"), pinyin
        checked += 1
    assert checked > 40


def test_o_becomes_uo_after_m_only():
    """Thesis 002 5.2.2: o after the symbol m is shaped uo."""
    for pinyin in ("bo1", "po2", "mo4"):
        assert shapes_for(pinyin) == ("m", "u", "o")
    assert shapes_for("fo2") == ("f", "o")
    assert shapes_for("lo5")[-1] == "o" and "u" not in shapes_for("lo5")
    assert shapes_for("o1") == ("o",)


def test_thesis_examples():
    # 5.2.1: "hei" loses its pre-posture before the i/e of ei.
    assert shapes_for("hei1")[0] not in ("h'", "h")
    # 5.2.2: "he" is h' then h in Chen and Tsai; with h now the velar class, one held h.
    assert set(shapes_for("he2")) == {"h"}
    # 5.2.1: u-umlaut is shaped u.
    assert shapes_for("yu2") == shapes_for("wu2") == ("u",)
    # 5.3: "zhi" is given as a syllable of two basic shapes.
    assert len(shapes_for("zhi1")) == 2


def test_apical_vowel_and_u_umlaut_spellings():
    for pinyin in ("zi3", "ci2", "si4", "zhi1", "chi1", "shi4", "ri4"):
        assert syllable_parts(pinyin).final == "-i"
    for pinyin in ("ju1", "qu4", "xu3", "yu2", "lü4", "lv4", "nü3"):
        parts = syllable_parts(pinyin)
        assert (parts.medial, parts.final) == ("", "ü"), pinyin
    assert syllable_parts("xuan2").medial == "ü"
    assert syllable_parts("lv4") == syllable_parts("lü4")
    assert shapes_for("ji1") == shapes_for("yi1")


def test_syllable_parts_for_the_aligner():
    parts = syllable_parts("zhuang4")
    assert (parts.initial, parts.medial, parts.final, parts.tone, parts.erhua) == \
        ("zh", "u", "ang", 4, False)
    assert syllable_parts("dianr3").erhua and syllable_parts("dianr3").final == "an"
    assert syllable_parts("er2").final == "er" and not syllable_parts("er2").erhua
    assert syllable_parts("de5").tone == 5
    assert syllable_parts("wei4").initial == "" and syllable_parts("wei4").final == "ei"


def test_erhua_ends_in_the_er_shape_and_loses_n_and_i_codas():
    er = shapes_for("er2")[-1]
    for pinyin in ("huar1", "dianr3", "wanr2", "zher4", "shir4", "menr2", "gair4", "biaor4"):
        shapes = shapes_for(pinyin)
        assert shapes[-1] == er and 1 <= len(shapes) <= 4, pinyin
    assert "n" not in shapes_for("wanr2") and "n" not in shapes_for("menr2")
    assert shapes_for("gair4")[-2:] != ("i", er)


@pytest.mark.parametrize("bad", ["hagn2", "hang", "gi1", "bü4", "ja1", "xyz3", "ia1", "", "ma6"])
def test_bad_pinyin_names_the_value(bad):
    with pytest.raises(TranscriptError, match=repr(bad).replace("[", r"\[")):
        shapes_for(bad)


def test_onsets_start_at_zero_and_increase_inside_the_syllable():
    for n in range(1, 5):
        onsets = shape_onsets(n)
        assert len(onsets) == n and onsets[0] == 0.0
        assert all(a < b for a, b in zip(onsets, onsets[1:]))
        assert onsets[-1] < 1.0


def test_onsets_step_by_the_thesis_proportions():
    """5.3's numbers are the intervals between consecutive shape starts."""
    thesis = {2: (80.95,), 3: (43.37, 39.75), 4: (24.5, 21.15, 25.88)}
    for n, percents in thesis.items():
        onsets = shape_onsets(n)
        steps = [b - a for a, b in zip(onsets, onsets[1:])]
        assert steps == pytest.approx([p / 100 for p in percents], abs=1e-6)


@pytest.mark.parametrize("n", [0, 5, -1])
def test_onsets_reject_impossible_counts(n):
    with pytest.raises(ValueError):
        shape_onsets(n)
