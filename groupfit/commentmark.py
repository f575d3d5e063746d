"""A comment mark before a text table's header and before the rows of units right under it, dropped.

NumPy's ``savetxt`` writes its header after ``# `` (``# time_s T1 T2``), and a header of two lines (names, then
units) as two such lines (``# s degC degC``); MATLAB scripts write ``%``. The mark is no column: it is dropped
from the header and from a row of units right under it, so that the names and units stand over their columns.
A column named ``#`` alone (a HOBO logger's row number: ``"#","Date Time"``) is a name, not a mark.
"""

from __future__ import annotations

import re

from groupfit.tablehead import units_of_row

COMMENT_MARK = re.compile(r"^\s*(?:#|%|//)\s*(?=\S)")
"""A comment mark before a header's first name (NumPy's ``savetxt``: ``# time_s,T1``; MATLAB: ``% time T1``)."""
MARKS = ("#", "%", "//")
"""The comment marks, alone in a field of a table split at spaces."""


def without_comment_marks(body: str, sep: str | None) -> str:
    """The body (its header line first) without the comment mark before its header's first name and before the
    rows of units right under it.

    Parameters
    ----------
    body
        The table's text from its header line on.
    sep
        Its field separator; None for a table split at runs of spaces.
    """
    lines = body.split("\n")
    units_rows = 0
    while 1 + units_rows < len(lines) and _marked_units(lines[1 + units_rows], sep):
        units_rows += 1
    marked = range(1 + units_rows)
    if sep is None:
        fields = lines[0].split()
        values = lines[1 + units_rows].split() if 1 + units_rows < len(lines) else []
        if not (fields and fields[0] in MARKS and len(fields) == len(values) + 1):
            return body
        for k in marked:  # blanked, not cut: the names and units stay over their columns
            mark = lines[k].split()[0]
            at = lines[k].index(mark)
            lines[k] = lines[k][:at] + " " * len(mark) + lines[k][at + len(mark) :]
        return "\n".join(lines)
    first = lines[0].split(sep, 1)[0]
    if not COMMENT_MARK.match(first) or first.strip().strip('"') in MARKS:
        return body
    for k in marked:
        lines[k] = COMMENT_MARK.sub("", lines[k], count=1)
    return "\n".join(lines)


def _marked_units(line: str, sep: str | None) -> bool:
    """Whether a line is a row of units after a comment mark (``# s degC degC um``)."""
    if not COMMENT_MARK.match(line):
        return False
    fields = COMMENT_MARK.sub("", line, count=1).split(sep)
    return units_of_row([field.strip().strip('"') for field in fields]) is not None


__all__ = ["COMMENT_MARK", "without_comment_marks"]
