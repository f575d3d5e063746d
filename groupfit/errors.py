"""Exceptions that carry a user-facing message.

Every error a user can cause by what they feed groupfit (a file, a column, a
value, a configuration key) is raised as :class:`InputError`. The command line
prints its message as one line on stderr and exits with status 2.
"""


class InputError(ValueError):
    """Bad user input: the message names the file, column, row or value at fault."""


def first_line(exc: BaseException) -> str:
    """The first line of an exception's message, or its type's name when it has none: a library's reason
    quoted inside one line of groupfit's own."""
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__
