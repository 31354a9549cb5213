"""The report's objects: the file's groups (OBJ ``o`` and ``g``, ASCII STL solids, glTF nodes,
3MF build items), each with its counts and verdicts.

:func:`object_reports` sums the per-face arrays of the analysis up by group; the mesh totals of
the report are not changed by it. Topology and orientation are those of the whole mesh: an
object's faces keep the components (and so the fix) they have in it.
"""

from __future__ import annotations

import numpy as np

from mesh_normal.mesh.orientation import METHODS, VERDICTS, Orientation, Verdict
from mesh_normal.mesh.report.models import ObjectReport
from mesh_normal.record import INDEX_LIST_LIMIT
from mesh_normal.types import BoolArray, FloatArray, IndexArray

_NONE = METHODS.index("none")
_UNDETERMINED = VERDICTS.index("undetermined")


def object_reports(
    groups: IndexArray,
    names: tuple[str, ...],
    areas: FloatArray,
    degenerate: BoolArray,
    orientation: Orientation,
    points: IndexArray,
) -> list[ObjectReport]:
    """One :class:`ObjectReport` for each of the first INDEX_LIST_LIMIT groups.

    Parameters
    ----------
    groups : (m,) intp
        The group of each face, an index into ``names``.
    names : tuple of str
        The groups' names.
    areas : (m,) float64
        The faces' areas.
    degenerate : (m,) bool
        The faces without a usable normal.
    orientation : Orientation
        What :func:`~mesh_normal.mesh.orientation.orient` found and did, per face and component.
    points : (m, 3) intp
        The faces by position, as the topology saw them
        (:func:`~mesh_normal.mesh.topology.by_position`).
    """
    count = len(names)
    table = orientation.components
    component = orientation.topology.face_component
    flipped = orientation.flipped

    def per_object(weights: BoolArray | None = None) -> IndexArray:
        if count == 1:  # one object (its groups a view of one zero): no array a face
            total = len(groups) if weights is None else np.count_nonzero(weights)
            return np.array([total], dtype=np.intp)
        return np.bincount(groups, weights, count).astype(np.intp)

    # Faces with a repeated point are in no component (-1): they have no edges, no verdict.
    total, flips = per_object(), per_object(flipped)
    if count == 1:  # the components' own counts: nothing a face
        decidable_parts = table.method != _NONE
        decided = np.array([np.sum(table.faces[decidable_parts])], dtype=np.intp)
        decided_flips = np.array([np.sum(table.flipped[decidable_parts])], dtype=np.intp)
        with_verdict_faces = np.sum(table.faces[table.orientation != _UNDETERMINED])
        has_verdict = np.array([with_verdict_faces > 0])
        in_part = None
    else:
        # Each component's answer looked up a face at a time, -1 reading the appended False:
        # one byte a face each, no index array of 8.
        in_part = component >= 0
        decidable = np.append(table.method != _NONE, False)[component]
        with_verdict = np.append(table.orientation != _UNDETERMINED, False)[component]
        decided, decided_flips = per_object(decidable), per_object(decidable & flipped)
        has_verdict = per_object(with_verdict) > 0
        del decidable, with_verdict
    area = np.array([np.sum(areas)]) if count == 1 else np.bincount(groups, areas, count)
    degenerates = per_object(degenerate)
    if count == 1:  # the one object is the mesh: its topology has counted what it holds
        topology = orientation.topology
        parts = np.array([topology.components], dtype=np.intp)
        edges_ok = topology.boundary_edges == 0 and topology.nonmanifold_edges == 0
        closed = np.array([bool(np.any(component >= 0)) and edges_ok])
    else:
        assert in_part is not None
        parts = _parts(groups[in_part], component[in_part], count)
        closed = _closed(groups[in_part], points[in_part], count)
    verdicts = _verdicts(has_verdict, flips, decided, decided_flips)
    return [
        ObjectReport(
            name=names[index],
            faces=int(total[index]),
            area=float(area[index]),
            degenerate_faces=int(degenerates[index]),
            components=int(parts[index]),
            closed=bool(closed[index]),
            orientation=verdicts[index],
            faces_flipped=int(flips[index]),
        )
        for index in range(min(count, INDEX_LIST_LIMIT))
    ]


def _parts(groups: IndexArray, components: IndexArray, count: int) -> IndexArray:
    """How many distinct components the faces of each group belong to."""
    width = np.int64(components.max() + 1) if len(components) else np.int64(1)
    pairs = np.unique(groups.astype(np.int64) * width + components)  # below count * m
    return np.bincount(pairs // width, minlength=count).astype(np.intp)


def _closed(groups: IndexArray, points: IndexArray, count: int) -> BoolArray:
    """Whether every edge of a group's faces is used by exactly two of its own faces.

    Judged on the group alone, by position like the mesh's topology: two closed objects that
    touch (a tetrahedron on a cube's corner) are each closed though the mesh is not.
    """
    width = np.int64(points.max() + 1) if points.size else np.int64(1)
    if count * int(width) ** 2 < 2**62:
        # One int64 key (group, low, high) an edge, made a corner column at a time and sorted
        # in place: 8 bytes a half-edge, where numbering the edges first takes several times that.
        keys = np.empty((3, len(points)), dtype=np.int64)
        for corner in range(3):
            one, two = points[:, corner], points[:, (corner + 1) % 3]
            np.multiply(groups, width * width, out=keys[corner])
            keys[corner] += np.minimum(one, two) * width
            keys[corner] += np.maximum(one, two)
        flat = keys.ravel()
        flat.sort()
        starts = np.flatnonzero(np.r_[True, flat[1:] != flat[:-1]])
        uses = np.diff(np.r_[starts, len(flat)])
        owner = flat[starts] // (width * width)
    else:
        return _closed_numbered(groups, points, count)
    return _uses_closed(owner, uses, count)


def _closed_numbered(groups: IndexArray, points: IndexArray, count: int) -> BoolArray:
    """:func:`_closed` for vertex counts too large for one key: the edges numbered first."""
    after = np.roll(points, -1, axis=1)
    low, high = np.minimum(points, after).ravel(), np.maximum(points, after).ravel()
    # Edges numbered 0 .. e - 1 (e <= 3m) first, so that (group, edge) fits one int64 key.
    _, edge = np.unique(low.astype(np.int64) * (high.max() + 1) + high, return_inverse=True)
    span = np.int64(edge.max() + 1) if len(edge) else np.int64(1)
    used, uses = np.unique(
        np.repeat(groups, 3).astype(np.int64) * span + edge.ravel(), return_counts=True
    )
    return _uses_closed(used // span, uses, count)


def _uses_closed(owner: IndexArray, uses: IndexArray, count: int) -> BoolArray:
    """Closed: a group with edges, each used twice (``owner`` and ``uses`` an edge each)."""
    closed: BoolArray = (np.bincount(owner, minlength=count) > 0) & (
        np.bincount(owner, uses != 2, count) == 0
    )
    return closed


def _verdicts(
    any_verdict: BoolArray, flips: IndexArray, decided: IndexArray, decided_flips: IndexArray
) -> list[Verdict]:
    """outward: nothing flipped; inward: every decidable face and only those; else mixed."""
    inward = (decided > 0) & (decided_flips == decided) & (flips == decided_flips)
    return [
        "undetermined" if not seen else "outward" if not flip else "inward" if turned else "mixed"
        for seen, flip, turned in zip(
            any_verdict.tolist(), flips.tolist(), inward.tolist(), strict=True
        )
    ]
