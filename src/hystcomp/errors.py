"""The exceptions that hystcomp raises.

Every error a user can cause is an instance of :class:`HystcompError` and also of a
builtin (``ValueError`` or ``TypeError``), so ``except ValueError`` keeps working. Messages
name the argument, what was expected, what was found, and the fix.
"""

from __future__ import annotations


class HystcompError(Exception):
    """Base class of every error raised on purpose by hystcomp."""


class InvalidParameterError(HystcompError, ValueError):
    """A parameter (a hyperparameter, option or model parameter) has a wrong value."""


class InvalidTypeError(HystcompError, TypeError):
    """An argument has a wrong type (for example a string where a number is expected)."""


class InvalidSignalError(HystcompError, ValueError):
    """A signal is not a finite, 1-D, long-enough array of samples."""


class NotInvertibleError(HystcompError, ValueError):
    """A model has no inverse: a partial sum of its weights is not positive (PI, MPI), or
    a branch of a Preisach model falls.

    Attributes
    ----------
    index : int or None
        The first index ``i`` at which ``w_0 + ... + w_i <= 0``; None for a Preisach model
        (the message names the table's entries or the voltages).
    """

    def __init__(self, message: str, index: int | None = None):
        super().__init__(message)
        self.index = index


class NotFittedError(HystcompError, ValueError):
    """A model is used before it was fitted or given parameters."""


class IdentificationError(HystcompError, ValueError):
    """The data do not allow the requested identification."""


class DataFileError(HystcompError, ValueError):
    """A data file is missing, unreadable, or lacks the expected columns."""


class ModelFileError(HystcompError, ValueError):
    """A model file is missing, corrupt, foreign, or of an unsupported version."""


class OutputPathError(HystcompError, ValueError):
    """An output cannot be written where asked.

    The folder does not exist, the path is a folder, the path is one of the command's own
    input files, or the write itself failed (permissions, a full disk). Nothing is left
    half-written: the existing file, if any, is unchanged.
    """


class HystcompWarning(UserWarning):
    """Something the user should know before relying on a result (the command line prints
    it as a ``hystcomp: warning:`` line)."""
