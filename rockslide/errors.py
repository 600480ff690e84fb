"""The one exception family of rockslide.

Exceptions are for bad input and broken files only. Physical outcomes (overturning, flight, the
Painleve case) are data in the result, never exceptions. The CLI turns every ``RockslideError``
into one line on stderr and exit code 2.
"""

from __future__ import annotations

import contextlib


class RockslideError(Exception):
    """A user error: a bad case file, record, option or output location.

    Parameters
    ----------
    message : str
        What is wrong and what was expected.
    source : str, optional
        The file (or option) the error is about.
    field : str, optional
        The key path (``contact.mu_static``), line (``line 12``) or column the error is about.
    """

    def __init__(self, message: str, *, source: str | None = None, field: str | None = None):
        self.message = message
        self.source = source
        self.field = field
        super().__init__(self.__str__())

    def __str__(self) -> str:
        parts = [p for p in (self.source, self.field) if p]
        return ": ".join(parts + [self.message])


class CaseError(RockslideError):
    """A case file (YAML) or a command-line option is invalid."""


class RecordError(RockslideError):
    """An accelerogram file cannot be found, read or used."""


class OutputError(RockslideError):
    """A result cannot be written (exists already, unwritable folder) or read back."""


def exception_text(exc: BaseException) -> str:
    """An exception's message on one line (its whitespace collapsed), or its type's name when it
    has none: how rockslide quotes a library's error inside its own."""
    return " ".join(str(exc).split()) or type(exc).__name__


@contextlib.contextmanager
def numbers_from(source: str, *, field: str | None = None, error: type[RockslideError] = CaseError,
                 what: str = "its numbers"):
    """The one place where numpy's floating-point warnings (overflow, division by zero, invalid
    operation) become an error naming the input they came from: inside, they raise, and leave as
    one ``error`` naming ``source`` and ``field``, never as a warning line per operation or an
    infinity further on. Underflow (a denormal) stays quiet: its value is checked where it matters.
    Code inside that expects such a case says so with its own ``np.errstate``.

    Parameters
    ----------
    source : str
        The file or option whose numbers are computed on (``hazard.csv``, ``--median``).
    field : str, optional
        The key or line.
    error : type
        The exception raised (`CaseError` unless the input is a record or a result).
    what : str
        What went out of range, for the message.
    """
    import numpy as np

    with np.errstate(over="raise", divide="raise", invalid="raise", under="ignore"):
        try:
            yield
        except (FloatingPointError, OverflowError, ZeroDivisionError) as exc:
            raise error(f"{what} go beyond what floating-point numbers hold ({exception_text(exc)}); expected "
                        "values of a physical size", source=source, field=field) from None
