"""Transcript -> sentences -> syllables: readings, overrides, erhua, tone changes, numbers."""

from __future__ import annotations

import pytest
from pypinyin import Style, lazy_pinyin

from cartoonface.errors import InputError, TranscriptError
from cartoonface.speech.mouth_shapes import MOUTH_SYMBOLS, shapes_for
from cartoonface.speech.pinyin import syllable_parts
from cartoonface.speech.transcript import SentenceText, parse_transcript


@pytest.fixture(scope="module")
def parse():
    """parse_transcript, warmed once (pypinyin and OpenCC load their dictionaries)."""
    parse_transcript("你好。")
    return parse_transcript


def pinyins(sentences: tuple[SentenceText, ...]) -> list[str]:
    return [s.pinyin for sentence in sentences for s in sentence.syllables]


def reading_of(sentences: tuple[SentenceText, ...], text: str) -> list[str]:
    return [s.pinyin for sentence in sentences for s in sentence.syllables if s.text == text]


def tones(sentences: tuple[SentenceText, ...]) -> list[int]:
    return [syllable_parts(p).tone for p in pinyins(sentences)]


# --- sentences -------------------------------------------------------------------------

def test_sentences_split_on_chinese_and_latin_ends(parse):
    result = parse("你好。你好吗？好！走吧；再见…\n来了!去?是;")
    assert [s.text for s in result] == ["你好。", "你好吗？", "好！", "走吧；", "再见…", "来了!",
                                        "去?", "是;"]


def test_line_breaks_end_sentences_and_blank_lines_vanish(parse):
    result = parse("第一行\n\n\n第二行\r\n第三行")
    assert [s.text for s in result] == ["第一行", "第二行", "第三行"]


def test_quotes_stay_with_their_sentence(parse):
    result = parse("他说：“你好。”然后走了。「再見！」")
    assert [s.text for s in result] == ["他说：“你好。”", "然后走了。", "「再見！」"]


def test_commas_are_clause_ends_not_sentence_ends(parse):
    (sentence,) = parse("今天，我们去银行、邮局：还有商店。")
    texts = [s.text for s in sentence.syllables]
    assert [texts[k] for k in sentence.clause_ends] == ["天", "行", "局"]


def test_decimal_point_does_not_end_a_sentence(parse):
    assert len(parse("圆周率是3.14。对")) == 2


def test_every_syllable_has_valid_reading_zhuyin_and_shapes(parse):
    for sentence in parse("我們一起去看看吧，好不好？小孩儿在哪儿。"):
        for syllable in sentence.syllables:
            assert syllable.shapes == shapes_for(syllable.pinyin)
            assert 1 <= len(syllable.shapes) <= 4 and set(syllable.shapes) <= set(MOUTH_SYMBOLS)
            assert syllable.zhuyin and all("\u3100" <= c <= "\u312f" or c in "ˊˇˋ˙"
                                           for c in syllable.zhuyin)


# --- readings --------------------------------------------------------------------------

def test_polyphones_in_context(parse):
    assert reading_of(parse("我去银行。"), "行") == ["hang2"]
    assert reading_of(parse("我们慢慢行走。"), "行") == ["xing2"]
    assert reading_of(parse("还钱。"), "还") == ["huan2"]


def test_traditional_text_reads_like_simplified_and_is_shown_unchanged(parse):
    result = parse("銀行的長度，還錢。")
    assert reading_of(result, "行") == ["hang2"]
    assert reading_of(result, "長") == ["chang2"]
    assert reading_of(result, "還") == ["huan2"]
    assert result[0].text == "銀行的長度，還錢。"
    assert [s.text for s in result[0].syllables] == list("銀行的長度還錢")


def test_neutral_tone_is_five_and_u_umlaut_is_spelt(parse):
    result = parse("好了，绿色。")
    assert reading_of(result, "了") == ["le5"]
    assert reading_of(result, "绿") == ["lü4"]


# --- erhua -----------------------------------------------------------------------------

def test_erhua_is_one_syllable(parse):
    for text, shown in (("一点儿", "点儿"), ("院儿里", "院儿"), ("这儿", "这儿"), ("玩兒", "玩兒")):
        syllables = parse(text)[0].syllables
        assert len(syllables) == len(text) - 1, text
        (merged,) = [s for s in syllables if s.text == shown]
        assert syllable_parts(merged.pinyin).erhua
    assert reading_of(parse("一点儿"), "点儿")[0].startswith("dianr")


def test_er_as_a_word_is_its_own_syllable(parse):
    for text in ("女儿", "儿子", "儿童节", "婴儿", "儿"):
        syllables = parse(text)[0].syllables
        assert len(syllables) == len(text), text
        assert [s.pinyin for s in syllables if s.text == "儿"] == ["er2"], text


def test_override_keeps_er_apart(parse):
    assert len(parse("花儿{er2}")[0].syllables) == 2


# --- tone changes ----------------------------------------------------------------------

def test_third_tone_pairs_rise(parse):
    assert pinyins(parse("你好")) == ["ni2", "hao3"]
    assert pinyins(parse("水果")) == ["shui2", "guo3"]


@pytest.mark.parametrize("text", ["我很好", "展览馆", "我也很好", "小老板", "我想买五把好雨伞"])
def test_runs_of_third_tones_leave_no_two_in_a_row(parse, text):
    """Every third tone before a third tone changes; the last of a run stays third."""
    sandhi_free = [syllable_parts(p).tone for p in
                   lazy_pinyin(text, style=Style.TONE3, neutral_tone_with_five=True)]
    surface = tones(parse(text))
    assert not any(a == b == 3 for a, b in zip(surface, surface[1:]))
    assert surface[-1] == sandhi_free[-1] == 3
    assert all(s == b or (b, s) == (3, 2) for s, b in zip(surface, sandhi_free))


def test_third_tones_group_from_the_right(parse):
    assert pinyins(parse("小老板")) == ["xiao3", "lao2", "ban3"]
    assert tones(parse("我很好")) == [3, 2, 3]


def test_doubled_third_tone_takes_the_neutral_tone(parse):
    assert pinyins(parse("姐姐")) == ["jie3", "jie5"]
    assert tones(parse("奶奶好")) == [3, 5, 3]


def test_third_tone_sandhi_stops_at_a_pause(parse):
    assert tones(parse("你，好")) == [3, 3]


def test_tone_changes_of_yi(parse):
    assert reading_of(parse("一定"), "一") == ["yi2"]
    assert reading_of(parse("一天"), "一") == ["yi4"]
    assert reading_of(parse("一年"), "一") == ["yi4"]
    assert reading_of(parse("一起"), "一") == ["yi4"]
    assert reading_of(parse("第一"), "一") == ["yi1"]
    assert reading_of(parse("统一思想"), "一") == ["yi1"]
    assert reading_of(parse("看一看"), "一") == ["yi5"]
    assert reading_of(parse("说一"), "一") == ["yi1"]


def test_tone_changes_of_bu(parse):
    assert reading_of(parse("不是"), "不") == ["bu2"]
    assert reading_of(parse("不对"), "不") == ["bu2"]
    assert reading_of(parse("不好"), "不") == ["bu4"]
    assert reading_of(parse("不来"), "不") == ["bu4"]
    assert reading_of(parse("是不是"), "不") == ["bu2"]
    assert reading_of(parse("好不好"), "不") == ["bu4"]


# --- numbers ---------------------------------------------------------------------------

def spoken(parse, text: str) -> str:
    return "".join(s.text for sentence in parse(text) for s in sentence.syllables)


def test_numbers_are_read_in_chinese(parse):
    assert spoken(parse, "共100个") == "共一百个"
    assert spoken(parse, "1,000元") == "一千元"
    assert spoken(parse, "增长50%") == "增长百分之五十"
    assert spoken(parse, "3.14") == "三点一四"
    assert spoken(parse, "-5度") == "负五度"
    assert spoken(parse, "2个人") == "两个人"
    assert spoken(parse, "12:30") == "十二点三十"
    assert spoken(parse, "25℃") == "二十五摄氏度"
    assert spoken(parse, "２０２４年") == "二零二四年"
    assert spoken(parse, "增长５０％，－３．５") == "增长百分之五十负三点五"


def test_years_and_long_numbers_are_read_digit_by_digit(parse):
    result = parse("2024年，13812345678")
    assert spoken(parse, "2024年") == "二零二四年"
    assert pinyins(result)[:4] == ["er4", "ling2", "er4", "si4"]
    assert len(result[0].syllables) == 5 + 11
    # a digit read alone keeps yi1: no tone change, no phrase reading
    assert reading_of(parse("1月1日"), "一") == ["yi1", "yi1"]
    assert reading_of(parse("2011年"), "一") == ["yi1", "yi1"]


def test_yi_in_cardinals_changes_tone(parse):
    assert reading_of(parse("100"), "一") == ["yi4"]
    assert reading_of(parse("10000"), "一") == ["yi2"]


# --- overrides -------------------------------------------------------------------------

def test_override_sets_the_reading_and_is_not_shown(parse):
    result = parse("我们{men5}行{hang2}走。")
    assert reading_of(result, "行") == ["hang2"]
    assert result[0].text == "我们行走。"


def test_tone_marked_override(parse):
    assert reading_of(parse("行{háng}"), "行") == ["hang2"]


def test_override_is_not_changed_by_sandhi(parse):
    assert pinyins(parse("你{ni3}好")) == ["ni3", "hao3"]


def test_override_after_a_latin_word_gives_its_syllables(parse):
    syllables = parse("我爱hello{ha1 lou2}。")[0].syllables
    assert [s.pinyin for s in syllables] == ["wo3", "ai4", "ha1", "lou2"]
    assert syllables[2].text == "hello"


@pytest.mark.parametrize("text, fragment", [
    ("你好\n行{hagn2}走", "line 2, column 2"),
    ("行{hagn2}", "'hagn2'"),
    ("行{hang}", "no tone"),
    ("行{hang2", "without a closing"),
    ("行hang2}", "without an opening"),
    ("。{hang2}", "must follow a Chinese character"),
    ("行{hang2 xing2}", "exactly one reading"),
    ("行{}", "exactly one reading"),
    ("hello{ha1 lou9}", "'lou9'"),
])
def test_bad_overrides_name_position_and_reading(parse, text, fragment):
    with pytest.raises(TranscriptError, match=fragment) as error:
        parse(text, source="story.txt")
    assert str(error.value).startswith("story.txt: ")


# --- Latin, emoji, symbols, empty ------------------------------------------------------

def test_acronyms_are_spelled_and_english_words_read(parse):
    (sentence,) = parse("我用iPhone看CCTV，OK？")
    shown = [s.text for s in sentence.syllables]
    assert [t for t in shown if t.isascii() and t] == ["iPhone", "C", "C", "T", "V", "O", "K"]
    assert not sentence.notes  # iPhone is in the dictionary: nothing guessed


def test_emoji_and_symbols_are_dropped_with_a_note(parse):
    result = parse("你好😀！再见$。👍🏽")
    assert [s.text for s in result] == ["你好😀！", "再见$。"]
    assert pinyins(result) == ["ni2", "hao3", "zai4", "jian4"]
    notes = [n for s in result for n in s.notes]
    assert any("😀" in n for n in notes) and any("$" in n for n in notes)
    assert any("👍" in n for n in notes)   # from the sentence with nothing spoken


@pytest.mark.parametrize("text", ["", "   \n\t", "Hello world.", "😀😀", "。，！"])
def test_nothing_to_say_is_a_transcript_error(parse, text):
    with pytest.raises(TranscriptError):
        parse(text)


def test_transcript_error_is_an_input_error():
    assert issubclass(TranscriptError, InputError)


def test_any_character_pypinyin_knows_does_not_crash(parse):
    from pypinyin.pinyin_dict import pinyin_dict

    chars = "".join(chr(code) for code in sorted(pinyin_dict)[::9])
    text = "。".join(chars[k:k + 30] for k in range(0, len(chars), 30))
    result = parse(text)
    assert sum(len(s.syllables) for s in result) > 0.9 * len(chars) * 0.9
