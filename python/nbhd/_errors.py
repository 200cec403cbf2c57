"""The exceptions nbhd raises. Every one carries the Rust library's message (which argument,
which point index, what the sizes were) and derives from :class:`NbhdError`; most also derive
from the built-in exception a Python caller would catch for that kind of failure."""


class NbhdError(Exception):
    """Base class of every error nbhd raises."""


class NbhdValueError(NbhdError, ValueError):
    """Bad input or option: empty or non-finite points, k = 0, a negative or NaN radius, a
    query of the wrong dimension, an unknown option name, an index out of range."""


class DegenerateError(NbhdValueError):
    """Every neighbourhood is degenerate (none reaches 3 points): usually an epsilon in the
    wrong units (relative to the mean spacing h by default)."""


class NbhdMemoryError(NbhdError, MemoryError):
    """The output does not fit in memory; the message gives the bytes needed."""


class NbhdIOError(NbhdError, OSError):
    """A point-cloud file could not be read or written; the message names the file and the
    line or byte where it went wrong."""


class CancelledError(NbhdError):
    """The computation was stopped."""


__all__ = [
    "NbhdError",
    "NbhdValueError",
    "DegenerateError",
    "NbhdMemoryError",
    "NbhdIOError",
    "CancelledError",
]
