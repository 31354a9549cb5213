"""The one error a mesh file can raise: a plain sentence and the HTTP status it deserves."""

from __future__ import annotations

import re


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


#: An object's repr in a message: ``<ZipInfo filename='a.obj' file_size=9>``.
_REPR = re.compile(r"<[A-Za-z_][\w.]*(?: [^<>]*)?>")


def failure_reason(error: Exception) -> str:
    """What a reader's own exception says about the file, in our words where Python's are
    about the reader ("'NoneType' object is not subscriptable", "Python int too large to
    convert to C long", a bare ``AssertionError``, an object's repr, the hint to call
    ``sys.set_int_max_str_digits``); other exceptions (a zip, JSON or XML parser's) keep
    their words."""
    if isinstance(error, OverflowError):
        return "a number in it is too large"
    if isinstance(error, ValueError) and "integer string conversion" in str(error):
        return "a number in it has too many digits"  # int() of over 4,300 digits refused
    if isinstance(error, LookupError):  # KeyError, IndexError: an entry that is not there
        return "it refers to an entry that it does not hold"
    if isinstance(error, TypeError | AttributeError):
        return "an entry holds the wrong kind of value (such as null, or a list for an object)"
    message = _REPR.sub("an entry", str(error)).strip().rstrip(".")
    if isinstance(error, AssertionError) or not message or message == type(error).__name__:
        return "its structure is not what the format requires"  # a reader's own assertion
    return message[:200]
