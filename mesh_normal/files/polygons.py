"""Fan triangulation of polygons given as corner counts, vectorised."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def fan(counts: NDArray[np.integer]) -> tuple[NDArray[np.intp], NDArray[np.intp], list[str]]:
    """Triangulate polygons of ``counts[i]`` corners as fans from each one's first corner.

    Parameters
    ----------
    counts : (p,) int
        Corners of each polygon; their corners are consecutive in one flat array.

    Returns
    -------
    corners : (t, 3) intp
        Positions in the flat corner array: polygon ``[a, b, c, d]`` gives ``[a, b, c]`` and
        ``[a, c, d]``, in polygon order. Polygons with fewer than three corners give none.
    source : (t,) intp
        The polygon each triangle came from.
    notes : list of str
        What was triangulated or skipped, as sentences (empty for all triangles).
    """
    counts = np.asarray(counts, dtype=np.intp)
    starts = np.cumsum(counts) - counts
    if np.all(counts == 3):
        return starts[:, None] + np.arange(3), np.arange(len(counts)), []
    pieces = np.maximum(counts - 2, 0)
    source = np.repeat(np.arange(len(counts)), pieces)
    first = starts[source]
    step = np.arange(len(source)) - np.repeat(np.cumsum(pieces) - pieces, pieces) + 1
    corners = np.stack([first, first + step, first + step + 1], axis=1)
    return corners, source, _notes(counts)


def _notes(counts: NDArray[np.integer]) -> list[str]:
    quads, larger = int(np.sum(counts == 4)), int(np.sum(counts > 4))
    short = int(np.sum(counts < 3))
    notes = []
    if quads or larger:
        parts = [_plural(quads, "quad"), _plural(larger, "larger polygon")]
        made = " and ".join(part for part in parts if part)
        notes.append(f"Triangulated {made} as fans from each one's first corner.")
    if short:
        notes.append(f"Skipped {_plural(short, 'face')} with fewer than three corners.")
    return notes


def _plural(count: int, noun: str) -> str:
    return "" if not count else f"{count:,} {noun}" + ("" if count == 1 else "s")
