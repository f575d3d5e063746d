"""Which way a line of names (or units) stands over the columns of a table aligned by spaces: flush left or right.

A word one space from the names of two columns (``Spindel`` of ``Temp Spindel Temp Bett``, names written one
space apart) or a column of cells one space from two named columns (the time of ``02.03.2026 08:00:00`` under
``Datum Zeit``) belongs to one of them, and the line's other names tell which. When they begin where their
columns begin and do not all end there (flush left), every column begins where its name does, so the word or
the cells, beginning no name, belong to the column on their left; when they end where their columns end
(flush right), to the column on their right. When the names tell neither, the part is not placed and the table
is refused.
"""

from __future__ import annotations

from typing import Sequence

Span = tuple[int, int]
"""Character positions in a line: ``(first, end)``, the end excluded."""
LEFT = -1
"""Names flush left: a part between two columns belongs to the one on its left."""
RIGHT = 1
"""Names flush right: a part between two columns belongs to the one on its right."""


def flush_side(names: Sequence[Span | None], columns: Sequence[Span]) -> int | None:
    """:data:`LEFT` when some name begins where its column begins but ends elsewhere and none does the
    opposite, :data:`RIGHT` the other way round, None otherwise.

    Parameters
    ----------
    names
        Where each column's name stands in its line (None: the column has none).
    columns
        Where each column's cells stand.
    """
    flush_left = flush_right = 0
    for name, (first, end) in zip(names, columns):
        if name is None:
            continue
        begins, ends = name[0] == first, name[1] == end
        flush_left += begins and not ends
        flush_right += ends and not begins
    if flush_left and not flush_right:
        return LEFT
    if flush_right and not flush_left:
        return RIGHT
    return None


__all__ = ["LEFT", "RIGHT", "flush_side"]
