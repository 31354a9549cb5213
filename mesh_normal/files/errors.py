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
