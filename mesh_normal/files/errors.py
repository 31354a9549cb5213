"""The one error a mesh file can raise: a plain sentence and the HTTP status it deserves."""

from __future__ import annotations


class MeshFileError(ValueError):
    """A file that cannot be read as a mesh, with one plain sentence naming the problem.

    ``status_code`` is 400 for a broken file or bad content (truncated, out-of-range index,
    NaN coordinate, no faces) and 415 for a format that is unknown or not supported.
    """

    status_code: int

    def __init__(self, message: str, status_code: int = 400) -> None:
        super().__init__(message)
        self.status_code = status_code


def unsupported(message: str) -> MeshFileError:
    """A 415 error: the format is unknown or not supported."""
    return MeshFileError(message, 415)


def failure_reason(error: Exception) -> str:
    """What a reader's own exception says about the file, in our words where Python's are
    about the reader ("'NoneType' object is not subscriptable", "Python int too large to
    convert to C long"); other exceptions (a zip, JSON or XML parser's) keep their words."""
    if isinstance(error, OverflowError):
        return "a number in it is too large"
    if isinstance(error, LookupError):  # KeyError, IndexError: an entry that is not there
        return "it refers to an entry that it does not hold"
    if isinstance(error, TypeError | AttributeError):
        return "an entry holds the wrong kind of value (such as null, or a list for an object)"
    return (str(error).strip().rstrip(".") or type(error).__name__)[:200]
