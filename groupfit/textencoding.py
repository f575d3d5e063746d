"""The text of a log file: which encoding wrote it.

Tried in this order:

* the Unicode form a byte-order mark names (UTF-8, UTF-16, UTF-32);
* UTF-8;
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
EAST_ASIAN = ("gb2312", "cp932", "cp950", "gb18030")
"""GB 2312 (both bytes of every character from 0xA1: simplified Chinese proper) before Shift-JIS, whose
common kanji begin below 0xA1, and Big5, whose second bytes are often below 0xA1; GB 18030 (GBK's
characters beyond GB 2312), which reads almost any bytes, last."""
HIGH_BYTE = re.compile(rb"[\x80-\xff]")
CJK_WORD = re.compile(r"[\u3040-\u30ff\u3400-\u4dbf\u4e00-\u9fff]{2,}")
"""Two Chinese characters, kanji or kana in a row: a word of a Chinese or Japanese header."""
UNIT_SIGNS = re.compile(r"[℃℉μ（）［］：～]")
"""Full-width signs a header marks a unit with (``T1(℃)``, ``位移（μm）``): no Western byte pair reads as one."""
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


def decode(content: bytes) -> str:
    """The text of a file in the encoding that wrote it (module docstring)."""
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
    text = east_asian(content)
    if text is not None:
        return text
    for encoding in WESTERN:
        try:
            return content.decode(encoding)
        except UnicodeDecodeError:
            continue
    raise AssertionError("latin-1 decodes every byte")


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


__all__ = ["BYTE_ORDER_MARKS", "decode", "east_asian", "looks_binary"]
