"""The text of a log file: which encoding wrote it.

Tried in this order:

* the Unicode form a byte-order mark names (UTF-8, UTF-16, UTF-32);
* UTF-8;
* Korean (CP949, the EUC-KR that Excel and loggers write on a Korean
  Windows: ``시간(초),온도1(℃)``), when the bytes outside ASCII read as
  Hangul words and no Chinese character (:func:`korean`);
* Windows-1251, when the bytes outside ASCII form words of Cyrillic letters
  (:func:`cyrillic`), as a Russian or Ukrainian Windows writes them
  (``Время,Температура``);
* a Chinese or Japanese code page, when the bytes outside ASCII read as one
  (:func:`east_asian`): GBK/GB 18030, which Excel and most data-acquisition
  programs on a Chinese Windows write (``时间,温度1(℃)``), Shift-JIS (CP932),
  which Japanese loggers write (``日時,温度(℃)``), or Big5 (CP950), as in
  Taiwan (``時間(s),溫度1(°C)``);
* Windows-1252, then Latin-1, which reads any byte.

A Western file does not pass for an East Asian one by chance: the text
must read without a fault in the code page, and hold a word of two Chinese or
Japanese characters or more (``时间``, ``温度``: four bytes outside ASCII in a
row) or a full-width unit sign (``℃``, ``μ``, ``（）``). The accented letters of
a Western file stand alone (``Température``) or in pairs (``Größe``).

Chinese bytes read as Korean give Hangul too (``传感器`` reads ``눈먁포``): every
pair of bytes from 0xB0 to 0xC8 is a Hangul syllable in EUC-KR and a Chinese
character in GB 2312. They are told apart by what the syllables are: those of
a Korean text are mostly among the few hundred syllables that make up most
Korean words (:data:`COMMON_HANGUL`), while bytes of Chinese land on any of
EUC-KR's 2350, one in seven of them common.

A Cyrillic word in Windows-1251 is a run of letters from 0xC0 to 0xFF
(``Время``: five in a row), and the text holds few bytes from 0x80 to 0xBF
(``Ё``, ``°``, ``№``): :data:`CYRILLIC_RUN`, :data:`CYRILLIC_SHARE`. A
Western file's accented letters stand alone or in pairs. A Chinese, Japanese
or Korean text comes in pairs of bytes, so its runs of bytes outside ASCII
are of even length: a text with a word of odd length is read as Cyrillic
before the East Asian code pages are tried, one whose words are all of even
length only after none of them reads it.
"""

from __future__ import annotations

import codecs
import re

BYTE_ORDER_MARKS = (
    (codecs.BOM_UTF32_LE, "utf-32-le"),
    (codecs.BOM_UTF32_BE, "utf-32-be"),
    (codecs.BOM_UTF16_LE, "utf-16-le"),
    (codecs.BOM_UTF16_BE, "utf-16-be"),
    (codecs.BOM_UTF8, "utf-8"),
)
"""UTF-32 before UTF-16: the UTF-32 little-endian mark begins with UTF-16's."""
WESTERN = ("cp1252", "latin-1")
"""Tried after UTF-8 and the East Asian code pages, in this order; Latin-1 reads any byte."""
KOREAN = "cp949"
"""Korean Windows' code page: EUC-KR and the syllables beyond it."""
EAST_ASIAN = ("gb2312", "cp932", "cp950", "gb18030")
"""GB 2312 (both bytes of every character from 0xA1: simplified Chinese proper) before Shift-JIS, whose
common kanji begin below 0xA1, and Big5, whose second bytes are often below 0xA1; GB 18030 (GBK's
characters beyond GB 2312), which reads almost any bytes, last."""
HIGH_BYTE = re.compile(rb"[\x80-\xff]")
CJK_WORD = re.compile(r"[\u3040-\u30ff\u3400-\u4dbf\u4e00-\u9fff]{2,}")
"""Two Chinese characters, kanji or kana in a row: a word of a Chinese or Japanese header."""
UNIT_SIGNS = re.compile(r"[℃℉μ（）［］：～]")
"""Full-width signs a header marks a unit with (``T1(℃)``, ``位移（μm）``): no Western byte pair reads as one."""
HANGUL = re.compile(r"[\uac00-\ud7a3]")
HANGUL_WORD = re.compile(r"[\uac00-\ud7a3]{2,}")
NOT_KOREAN = re.compile(r"[\u3040-\u30ff\u3400-\u4dbf\u4e00-\u9fff\uf900-\ufaff\uff61-\uff9f\ue000-\uf8ff]")
"""Kana, Chinese characters (a Korean log writes none), half-width katakana and private use: a misread."""
COMMON_HANGUL = frozenset(
    "가각간갈감값강개거건검게겨격결경계고곡골공과관광교구국군굴궤귀규균그극근글금급기긴길김깊"
    "나난날남내냉너널네녀년노높누는늘능니님"
    "다단달담답당대더던데도독돌동되된두둘드득들등디따때또뜨"
    "라락란람랑래량러럼레력련렬령로록론료루류률르른를름리린립"
    "마막만많말맞매머먼메며면명모목무문물미민밀"
    "바박반받발방배백버번벌범법베벨변별병보복본볼부북분불브블비빈빌빛"
    "사산살상새색생서석선설섬성세센셀소속손송쇄수숙순술스습승시식신실심"
    "아안알압앙앞애액야약양어억언얼업없에엔여역연열염영예오온올완왕외요용우운울움원월웨위유율으은을음응의이익인일임입있"
    "자작잔장재저적전절점접정제조족존종좌주준줄중즈즉증지직진질집짜째"
    "차착찰참창채책처척천철첨청체초총최추축출충취측층치칙침칩"
    "카칼커컨케켈코콘콜쿨크큰클키"
    "타탄탈태터털테텔토톤통투튜트특틀티팅"
    "파판팔패퍼펌페펜편평포폭표푸품프플피핀필"
    "하학한할함합항해핵행향허헤현형호혹혼화확환활회획효후휴흐흡흰히"
)
"""Hangul syllables that make up most Korean words, and every word of a log's header (``시간``, ``온도``,
``변위``, ``주축``, ``냉각수``, ``센서``): about 400 of EUC-KR's 2350."""
COMMON_SHARE = 0.8
"""The least share of a text's Hangul syllables that are common for it to read as Korean."""
CYRILLIC = "cp1251"
CYRILLIC_RUN = re.compile(rb"[\xc0-\xff]{3,}")
"""Three letters or more in a row from Windows-1251's Cyrillic block: a Cyrillic word, not accented Latin ones."""
CYRILLIC_SHARE = 0.6
"""The least share of the bytes outside ASCII that stand in such runs for the text to read as Cyrillic; at most
:data:`CYRILLIC_OTHER` of them may fall from 0x80 to 0xBF."""
CYRILLIC_OTHER = 0.2
LOW_HIGH_BYTE = re.compile(rb"[\x80-\xbf]")
HIGH_RUN = re.compile(rb"[\x80-\xff]+")
RARE_GB_LEAD = 0xD8
"""GB 2312's second level (first byte from 0xD8): rare characters, seldom in a Chinese header."""
RARE_GB_SHARE = 0.4
MISREAD = re.compile(r"[\uff61-\uff9f\ue000-\uf8ff]")
"""Half-width katakana, what a Chinese text read as Shift-JIS turns into, and characters of private use, what
Big5 read as GB 18030 turns into: never what a header is written in."""


CONTROL_BYTES = re.compile(rb"[\x01-\x08\x0e-\x1f\x7f]")
"""Bytes no text holds (a NUL is left out: a logger's power loss writes lines of them into a text log)."""
BINARY_SHARE = 0.05
"""Share of :data:`CONTROL_BYTES` in a file's first 4 KiB beyond which it is binary data, not text."""


def looks_binary(content: bytes) -> bool:
    """Whether a file is binary data (a program's own format) rather than text in any encoding read here."""
    if any(content.startswith(mark) for mark, _ in BYTE_ORDER_MARKS):
        return False
    sample = content[:4096]
    return bool(sample) and len(CONTROL_BYTES.findall(sample)) > BINARY_SHARE * len(sample)


def decode(content: bytes, encoding: str | None = None) -> str:
    """The text of a file in the encoding that wrote it (module docstring), or in ``encoding`` when it is given
    (``--encoding``: a byte-order mark is read past; bytes that are no text in it raise ``UnicodeDecodeError``)."""
    if encoding is not None:
        text = content.decode(encoding)
        return text[1:] if text.startswith("\ufeff") else text
    for mark, encoding in BYTE_ORDER_MARKS:
        if content.startswith(mark):
            try:
                return content[len(mark) :].decode(encoding)
            except UnicodeDecodeError:
                break
    try:
        return content.decode("utf-8")
    except UnicodeDecodeError:
        pass
    for guess in (korean, cyrillic_odd, east_asian, cyrillic):
        text = guess(content)
        if text is not None:
            return text
    for encoding in WESTERN:
        try:
            return content.decode(encoding)
        except UnicodeDecodeError:
            continue
    raise AssertionError("latin-1 decodes every byte")


READ_AS = ("cp1252", "latin-1", KOREAN, CYRILLIC, "gb18030", "cp932", "cp950")
"""The encodings :func:`decode` may have read a file in."""
WRITTEN_IN = (
    "utf-8", "cp1250", "cp1251", "cp1252", "cp1253", "cp1254", "cp1257", "iso-8859-2", "koi8-r",
    "gbk", "cp949", "cp932", "cp950",
)  # fmt: skip
"""The encodings a file misread in one of :data:`READ_AS` may have been written in."""


def misread(name: str, names) -> tuple[str, str] | None:
    """``(read, encoding)``: the name among ``names`` that is ``name`` misread, and the encoding the file was
    written in (``Èas (s)`` is ``Čas (s)`` written in cp1250); None when none is."""
    if name.isascii():
        return None
    for read in (str(n) for n in names if str(n) != name):
        for read_as in READ_AS:
            try:
                raw = read.encode(read_as)
            except UnicodeEncodeError:
                continue
            for written_in in WRITTEN_IN:
                if written_in != read_as and _decoded(raw, written_in) == name:
                    return read, written_in
    return None


def _decoded(raw: bytes, encoding: str) -> str | None:
    try:
        return raw.decode(encoding)
    except UnicodeDecodeError:
        return None


def korean(content: bytes) -> str | None:
    """The text read as Korean (:data:`KOREAN`), None when it does not read as Korean (module docstring)."""
    if not HIGH_BYTE.search(content):
        return None
    try:
        text = content.decode(KOREAN)
    except UnicodeDecodeError:
        return None
    syllables = HANGUL.findall(text)
    if NOT_KOREAN.search(text) or not HANGUL_WORD.search(text):
        return None
    common = sum(syllable in COMMON_HANGUL for syllable in syllables)
    return text if common >= COMMON_SHARE * len(syllables) else None


def cyrillic(content: bytes) -> str | None:
    """The text read as Windows-1251, None when its bytes outside ASCII do not form Cyrillic words (module
    docstring)."""
    high = len(HIGH_BYTE.findall(content))
    if not high or len(LOW_HIGH_BYTE.findall(content)) > CYRILLIC_OTHER * high:
        return None
    if sum(len(run) for run in CYRILLIC_RUN.findall(content)) < CYRILLIC_SHARE * high:
        return None
    try:
        return content.decode(CYRILLIC)
    except UnicodeDecodeError:
        return None


def cyrillic_odd(content: bytes) -> str | None:
    """:func:`cyrillic` for a text no East Asian code page wrote: a run of bytes outside ASCII of odd length, or
    pairs of bytes most of which would be GB 2312's rare characters (first byte from 0xD8: Cyrillic small
    letters); None for any other."""
    runs = HIGH_RUN.findall(content)
    if not any(len(run) % 2 for run in runs):
        leads = [byte for run in runs for byte in run[::2]]
        if not leads or sum(byte >= RARE_GB_LEAD for byte in leads) < RARE_GB_SHARE * len(leads):
            return None
    return cyrillic(content)


def east_asian(content: bytes) -> str | None:
    """The text read in a Chinese or Japanese code page (:data:`EAST_ASIAN`), None when it does not read as
    one (module docstring)."""
    if not HIGH_BYTE.search(content):
        return None
    for encoding in EAST_ASIAN:
        try:
            text = content.decode(encoding)
        except UnicodeDecodeError:
            continue
        if MISREAD.search(text):
            continue
        if CJK_WORD.search(text) or UNIT_SIGNS.search(text):
            return text
    return None


__all__ = ["BYTE_ORDER_MARKS", "cyrillic", "decode", "east_asian", "korean", "looks_binary", "misread"]
