"""The normals a file stores, compared like with like with the ones we compute.

- per-face normals (STL facets, PLY face ``nx ny nz``) with our face normals;
- per-vertex normals (PLY vertex ``nx ny nz``, OBJ ``vn`` that follow ``v``) with our vertex
  normals, trying each weighting (angle, area, uniform, max);
- per-corner normals (OBJ ``f v//vn``) with our corner normals, trying a few crease angles
  (30, 60 and 180 degrees, the last being the smooth vertex normals) and then the weightings.

The best match is the candidate with which most stored normals agree (within
``AGREEMENT_DEGREES``); ties go to the smaller median angle, then to the earlier candidate.
Both are taken up to the sign (see :meth:`Angles.rank`): normals stored inside out still name
the weighting they were made with, and count as opposite.

Angles are taken as ``2 atan2(|a - b|, |a + b|)`` for unit a and b (Kahan): accurate over the
whole range, where the arccosine of a dot product rounds every angle below about 1e-8 rad to
0. The median and the maximum come from the same array of angles, so the median never
exceeds the maximum.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

import mesh_normal._core as _core
from mesh_normal.files import LoadedMesh
from mesh_normal.mesh.corners import corner_normals
from mesh_normal.mesh.faces import FaceGeometry
from mesh_normal.mesh.medians import median
from mesh_normal.mesh.report.models import (
    AGREEMENT_DEGREES,
    COMPARISON_CREASE,
    FileNormals,
    StoredKind,
)
from mesh_normal.mesh.vertices import Weighting, vertex_normals
from mesh_normal.types import BoolArray, FloatArray

#: The weightings tried, in the order that breaks ties (angle first: ours by default).
TRIED_WEIGHTINGS: tuple[Weighting, ...] = ("angle", "area", "uniform", "max")
#: The crease angles tried for per-corner normals, in the order that breaks ties.
TRIED_CREASES: tuple[float, ...] = (COMPARISON_CREASE, 60.0, 180.0)
#: A candidate whose every angle is below this is taken without trying the others: a file
#: writing 6 decimals is within about 6e-5 degrees of the normals it was written from.
EXACT_DEGREES = 1e-3

_WORDS: dict[Weighting, str] = {
    "angle": "angle-weighted",
    "area": "area-weighted",
    "uniform": "unweighted (uniform)",
    "max": "Max-weighted",
}


@dataclass(frozen=True, slots=True)
class Candidate:
    """Our normals of one kind, made one way, row for row beside the file's.

    Attributes
    ----------
    normals : (k, 3) float64
        Unit normals; any row where ``missing``.
    missing : (k,) bool
        We have no normal there (a degenerate face, a cancelled sum).
    weighting : {"uniform", "area", "angle", "max"} or None
        None for face normals.
    crease : float or None
        The crease angle in degrees, for corner normals.
    """

    normals: FloatArray
    missing: BoolArray
    weighting: Weighting | None = None
    crease: float | None = None


@dataclass(frozen=True, slots=True)
class Angles:
    """The angles between the file's normals and one candidate, at the rows both have.

    Attributes
    ----------
    candidate : Candidate
    radians : (c,) float64
        The angle at each compared row (the stored normal is usable and the candidate has
        one), in order.
    """

    candidate: Candidate
    radians: FloatArray

    def agreeing(self) -> int:
        """How many angles are within ``AGREEMENT_DEGREES``."""
        return int(np.count_nonzero(self.radians <= math.radians(AGREEMENT_DEGREES)))

    def rank(self) -> tuple[int, float]:
        """Smaller is better: most agreeing, then the smallest median, by the angle between
        the lines (the smaller of the angle and 180 degrees minus it), so that normals stored
        inside out still find the weighting they were made with.
        """
        lines = np.minimum(self.radians, math.pi - self.radians)
        agreeing = int(np.count_nonzero(lines <= math.radians(AGREEMENT_DEGREES)))
        return -agreeing, median(lines) if len(lines) else math.inf

    def exact(self) -> bool:
        """Every compared angle is below ``EXACT_DEGREES`` (and at least one was compared).

        Only normals that agree stop the search early; inside-out ones try every candidate.
        """
        return bool(len(self.radians)) and float(self.radians.max()) < math.radians(EXACT_DEGREES)


def unit_rows(stored: FloatArray) -> tuple[FloatArray, BoolArray]:
    """The stored normals scaled to unit length, and which are usable (finite, not zero).

    Parameters
    ----------
    stored : (k, 3) float64

    Returns
    -------
    unit : (k, 3) float64
        Unit rows; rows that are not usable are left as they were divided (ignore them).
    usable : (k,) bool
    """
    stored = np.ascontiguousarray(stored, dtype=np.float64)
    unit, usable = np.empty(np.shape(stored)), np.empty(len(stored), dtype=bool)
    # Each row over its largest |component| first (so that the length can neither overflow
    # nor underflow), then over its length; a row that is not finite or is zero is divided
    # by 1.0 twice. One compiled pass on every core.
    _core.unit_rows(stored, unit, usable)
    return unit, usable


def angles_between(unit: FloatArray, usable: BoolArray, candidate: Candidate) -> Angles:
    """The angles between unit stored normals and a candidate's, where both are defined.

    Parameters
    ----------
    unit : (k, 3) float64
        Unit rows where ``usable``.
    usable : (k,) bool
    """
    compared = usable & ~candidate.missing
    every = bool(compared.all())
    rows = _EVERY_ROW if every else np.flatnonzero(compared)
    count = len(compared) if every else len(rows)
    # tan(angle / 2) = |a - b| / |a + b| for unit a and b: no rounding to 0 near 0 (as an
    # arccosine of a dot product has) nor loss of precision near 180 degrees.
    differences, totals = np.empty(count), np.empty(count)
    ours = np.ascontiguousarray(candidate.normals, dtype=np.float64)
    _core.half_angle_sides(unit, ours, every, rows, differences, totals)  # every core, no copies
    radians = np.arctan2(differences, totals, out=differences)
    radians *= 2.0
    return Angles(candidate, radians)


#: What :func:`mesh_normal._core.half_angle_sides` is given for ``rows`` when every row is
#: compared.
_EVERY_ROW = np.empty(0, dtype=np.intp)


def best_match(
    unit: FloatArray, usable: BoolArray, candidates: Iterator[Candidate]
) -> Angles | None:
    """The candidate that matches best (see the module's rule), computing no more than needed."""
    best: Angles | None = None
    best_rank: tuple[int, float] | None = None  # taken once a second candidate comes
    for candidate in candidates:
        angles = angles_between(unit, usable, candidate)
        if best is None:
            best = angles
        else:
            if best_rank is None:
                best_rank = best.rank()
            rank = angles.rank()  # a median each: not taken for a lone candidate (face normals)
            if rank < best_rank:
                best, best_rank = angles, rank
        if best.exact():
            break
    return best


def vertex_candidates(geometry: FaceGeometry) -> Iterator[Candidate]:
    """Our vertex normals, each weighting in turn."""
    for weighting in TRIED_WEIGHTINGS:
        smooth = vertex_normals(geometry, weighting=weighting)
        yield Candidate(smooth.normals, smooth.missing, weighting)


def _corners(geometry: FaceGeometry, crease: float, weighting: Weighting) -> Candidate:
    corners = corner_normals(geometry, crease_angle=crease, weighting=weighting)
    return Candidate(corners.normals.reshape(-1, 3), corners.missing.ravel(), weighting, crease)


def corner_match(geometry: FaceGeometry, unit: FloatArray, usable: BoolArray) -> Angles | None:
    """The best corner normals: first the crease angle (angle-weighted), then the weighting.

    Two rounds, not every pair, since corner normals cost far more than vertex normals.
    """
    first: Weighting = TRIED_WEIGHTINGS[0]
    crease = best_match(unit, usable, (_corners(geometry, angle, first) for angle in TRIED_CREASES))
    if crease is None or crease.exact():
        return crease
    chosen = crease.candidate.crease
    assert chosen is not None  # corner candidates always have one
    others = (_corners(geometry, chosen, weighting) for weighting in TRIED_WEIGHTINGS[1:])
    weighted = best_match(unit, usable, others)
    return crease if weighted is None or crease.rank() <= weighted.rank() else weighted


def describe(kind: StoredKind, candidate: Candidate) -> str:
    """Which of our normals the file's were compared with, in words."""
    if kind == "face" or candidate.weighting is None:
        return "our face normals"
    weighting = _WORDS[candidate.weighting]
    tried = f"the best of {len(TRIED_WEIGHTINGS)} weightings"
    if kind == "vertex":
        return f"our {weighting} vertex normals ({tried})"
    creases = ", ".join(f"{angle:g}" for angle in TRIED_CREASES)
    return (
        f"our {weighting} corner normals with a crease angle of {candidate.crease:g}° "
        f"(the best of crease angles {creases}° and {len(TRIED_WEIGHTINGS)} weightings)"
    )


def _match(
    mesh: LoadedMesh, geometry: FaceGeometry
) -> tuple[StoredKind, FloatArray, Callable[[FloatArray, BoolArray], Angles | None]] | None:
    """The kind of the file's normals, the normals, and how to find our best match."""
    if mesh.file_face_normals is not None:
        flat = Candidate(geometry.normals, geometry.degenerate)
        return "face", mesh.file_face_normals, lambda u, ok: best_match(u, ok, iter([flat]))
    # Per-vertex first: an OBJ whose vn follow its v gives both kinds, and normals that are
    # the same at every corner of a vertex are vertex normals (compared as corners, they
    # would disagree at every crease).
    if mesh.file_vertex_normals is not None:
        stored = mesh.file_vertex_normals
        return "vertex", stored, lambda u, ok: best_match(u, ok, vertex_candidates(geometry))
    if mesh.file_corner_normals is not None:
        stored = mesh.file_corner_normals.reshape(-1, 3)
        return "corner", stored, lambda u, ok: corner_match(geometry, u, ok)
    return None


def stored_normal_agreement(mesh: LoadedMesh, geometry: FaceGeometry) -> FileNormals | None:
    """How well the normals stored in ``mesh``'s file agree with ours, or ``None`` without any.

    ``geometry`` is the mesh's, as :func:`~mesh_normal.mesh.report.analysis.analyse_mesh` made it.
    """
    found = _match(mesh, geometry)
    if found is None:
        return None
    kind, stored, match = found
    unit, usable = unit_rows(stored)
    angles = match(unit, usable)
    assert angles is not None  # every kind has at least one candidate
    degrees = np.degrees(angles.radians)
    compared = len(degrees)
    return FileNormals(
        kind=kind,
        compared_with=describe(kind, angles.candidate),
        weighting=angles.candidate.weighting,
        crease_angle_degrees=angles.candidate.crease,
        stored=len(stored),
        compared=compared,
        unusable=int(np.count_nonzero(~usable)),
        agreeing=angles.agreeing(),
        opposite=int(np.count_nonzero(angles.radians > math.pi / 2)),
        agreement_degrees=AGREEMENT_DEGREES,
        median_angle_degrees=median(degrees) if compared else None,
        max_angle_degrees=float(degrees.max()) if compared else None,
    )
