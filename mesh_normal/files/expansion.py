"""One budget for everything an input expands into, checked as the expansion happens.

A few kilobytes can stand for gigabytes: a zip member that unpacks a thousand times, a 3MF
or glTF that places one object thousands of times, compressed point data. Each reader charges
what it is about to make against one budget per input (:func:`expanding`): the memory the
expansion will take, in bytes, by the readers' own measured factors. Nested inputs (a 3MF
inside a ``.zip``, a member of a member) charge the same budget, never a fresh one. Beyond it,
:class:`ExpansionTooLarge`: a 413 whose sentence names what expanded and by how much.

The budget is :func:`expansion_limit` of the input's size: :data:`EXPANSION_RATIO` times
it, at least :data:`MIN_EXPANSION` (small files may hold a mesh that compresses well), at
most ``most`` (the server's operator sets it; the library's default is :data:`MAX_EXPANSION`).
The readers' entry points (``read_mesh``, ``read_mesh_files``, ``read_points``) open one for
their input when their caller has not, so the library alone is guarded too.
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Iterator
from dataclasses import dataclass

from mesh_normal.files.errors import MeshFileError

#: Memory an input may expand into, per byte of the input.
EXPANSION_RATIO = 100
#: What any input may expand into, whatever its size.
MIN_EXPANSION = 256 * 2**20
#: The library's most for one input, when the caller sets none.
MAX_EXPANSION = 8 * 2**30


class ExpansionTooLarge(MeshFileError):
    """An input that would expand past its budget (a 413: the input itself is the cause)."""

    def __init__(self, message: str) -> None:
        super().__init__(message, 413)


#: The most for one input when a budget is opened without one: MAX_EXPANSION, or what the
#: caller set for its context (:func:`set_most`: the server's operator's limit).
_most: contextvars.ContextVar[int] = contextvars.ContextVar(
    "mesh_normal_expansion_most", default=MAX_EXPANSION
)


def set_most(most: int) -> None:
    """Set the most for one input in the current context: a worker process's whole life (it
    runs its jobs in its main thread), or a request's task and the threads it starts."""
    _most.set(most)


def expansion_limit(size: int, most: int | None = None) -> int:
    """The most memory an input of ``size`` bytes may expand into."""
    most = _most.get() if most is None else most
    return min(most, max(MIN_EXPANSION, EXPANSION_RATIO * size))


def megabytes(count: float) -> str:
    """A size in words: ``22 KB``, ``1.3 MB``, ``1,260 MB``."""
    if count < 2**20:
        return f"{max(count, 0) / 2**10:,.0f} KB"
    if count < 10 * 2**20:
        return f"{count / 2**20:,.1f} MB"
    return f"{count / 2**20:,.0f} MB"


@dataclass(slots=True)
class Expansion:
    """The budget of one input of ``size`` bytes: ``limit`` bytes, ``used`` so far."""

    size: int
    limit: int
    used: int = 0

    def charge(self, cost: int, what: str) -> None:
        """Take ``cost`` bytes for ``what`` (a sentence's subject: "unpacking the .zip file's
        members", "the 3MF file's build, 5,100,000 triangles"), or raise ExpansionTooLarge."""
        if self.used + cost > self.limit:
            need, limit = megabytes(self.used + cost), megabytes(self.limit)
            rule = (
                "the most for one upload on this server"
                if self.limit < max(MIN_EXPANSION, EXPANSION_RATIO * self.size)
                else f"{EXPANSION_RATIO} times its size, at least {megabytes(MIN_EXPANSION)}"
            )
            raise ExpansionTooLarge(
                f"The upload of {megabytes(self.size)} expands too far: {what} would take "
                f"{'just over' if need == limit else 'about'} {need} of memory, more than "
                f"the {limit} an upload of its size may expand into here ({rule})."
            )
        self.used += cost


_current: contextvars.ContextVar[Expansion | None] = contextvars.ContextVar(
    "mesh_normal_expansion", default=None
)


@contextlib.contextmanager
def expanding(size: int, most: int | None = None) -> Iterator[Expansion]:
    """One budget for an input of ``size`` bytes for the ``with`` block (and the threads it
    starts with the context copied). Inside another block, that outer budget stays."""
    outer = _current.get()
    if outer is not None:
        yield outer
        return
    budget = Expansion(size, expansion_limit(size, most))
    token = _current.set(budget)
    try:
        yield budget
    finally:
        _current.reset(token)


def charge(cost: int, what: str) -> None:
    """Charge the open budget (see :meth:`Expansion.charge`); outside any, nothing."""
    budget = _current.get()
    if budget is not None:
        budget.charge(cost, what)
