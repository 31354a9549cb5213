"""One point cloud analysed once, as :mod:`mesh_normal.mesh.report.analysis` analyses a mesh.

:func:`analyse_points` estimates the normals (:func:`~mesh_normal.points.point_normals`) and
sums them up in a :class:`~mesh_normal.points.report.PointReport`: the file, the bounds, how far
apart the points are, the neighbourhood used, how many points got each
:class:`~mesh_normal.points.PointStatus`, how each part was oriented, how the normals the file
stores agree with ours, and a diagnosis in plain sentences. ``report.to_json()`` is the JSON of
``POST /api/points``; like the mesh report's, it never holds ``NaN`` or ``Infinity``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from mesh_normal.mesh.checks import HeldCloud, held_points, read_only
from mesh_normal.points.estimate import (
    PointNormals,
    PointStatus,
    coincident_groups,
    point_normals,
)
from mesh_normal.points.estimate import _checked_points as checked_points
from mesh_normal.points.io.read import PointCloud
from mesh_normal.points.orient import OrientMode
from mesh_normal.points.report import (
    ALL_CLEAR,
    FLIPPED_FRACTION,
    POINT_AGREEMENT_DEGREES,
    Neighbourhood,
    Orientation,
    PartOrientation,
    PointBounds,
    PointFileInfo,
    PointReport,
    Spacing,
    StatusCounts,
    StoredNormals,
)
from mesh_normal.record import INDEX_LIST_LIMIT
from mesh_normal.tolerances import POINT_FAR_FROM_FLAT
from mesh_normal.types import BoolArray, FloatArray

__all__ = ["PointAnalysis", "analyse_points", "diagnose"]


@dataclass(frozen=True, slots=True, eq=False)
class PointAnalysis:
    """The cloud, its normals, and the report on them."""

    cloud: PointCloud
    normals: PointNormals
    report: PointReport


def analyse_points(
    cloud: PointCloud | ArrayLike | HeldCloud,
    *,
    k: int | None = None,
    radius: float | None = None,
    orient: OrientMode = "mst",
    viewpoint: ArrayLike | None = None,
    direction: ArrayLike | None = None,
    name: str | None = None,
    size: int = 0,
) -> PointAnalysis:
    """Estimate the normals of ``cloud`` and report on them.

    With ``orient="viewpoint"`` and no ``viewpoint``, a PCD file's VIEWPOINT origin is used;
    ``orient="file"`` orients along the file's normals. ``name`` and ``size`` describe the
    file the cloud came from. ``cloud`` is what :func:`~mesh_normal.points.read_points`
    returns, or a cloud in memory as :func:`~mesh_normal.points.point_normals` takes it (an
    array, an Open3D ``PointCloud`` with its normals, a ``trimesh.PointCloud``, a PyVista
    ``PolyData``, a mesh's vertices), whose report's format is ``"memory"``. Raises
    ValueError (one sentence) for bad arguments, TypeError for what is not a cloud.
    """
    if not isinstance(cloud, PointCloud):
        cloud = in_memory(cloud)
    from_file = False
    if orient == "viewpoint" and viewpoint is None:
        if cloud.viewpoint is None:
            raise ValueError('orient="viewpoint" needs a viewpoint: the file gives none.')
        viewpoint, from_file = cloud.viewpoint[0], True
    if orient == "file" and cloud.normals is None:
        raise ValueError('orient="file" needs normals stored in the file, and it has none.')
    stored = cloud.normals if orient == "file" else None
    normals = point_normals(
        cloud.points,
        k=k,
        radius=radius,
        orient=orient,
        viewpoint=viewpoint,
        direction=direction,
        stored=stored,
    )
    orientation = _orientation(normals, viewpoint, from_file, direction)
    finite = np.isfinite(cloud.points).all(axis=1)
    spacing = _spacing(cloud.points[finite])
    agreement = None if cloud.normals is None else _stored(cloud.normals, normals)
    counts = StatusCounts(**normals.counts())
    far_from_flat = int(np.count_nonzero(normals.valid & (normals.curvature > POINT_FAR_FROM_FLAT)))
    report = PointReport(
        file=_file_info(cloud, name, size),
        points=len(cloud.points),
        bounds=_bounds(cloud.points[finite]),
        spacing=spacing,
        neighbourhood=Neighbourhood(k=k, radius=radius),
        counts=counts,
        with_normal=int(normals.valid.sum()),
        far_from_flat=far_from_flat,
        orientation=orientation,
        stored_normals=agreement,
        diagnosis=diagnose(counts, orientation, spacing, agreement, k, radius, far_from_flat),
    )
    return PointAnalysis(cloud, normals, report)


def in_memory(held: ArrayLike | HeldCloud) -> PointCloud:
    """A cloud in memory as a :class:`PointCloud` of format ``"memory"``: its points checked
    as :func:`~mesh_normal.points.point_normals` checks them (non-finite rows are allowed),
    read-only views of them and of its normals."""
    points, normals = held_points(held)
    xyz = checked_points(points)
    return PointCloud(
        points=read_only(xyz),
        normals=None if normals is None else read_only(normals),
        colors=None,
        viewpoint=None,
        format="memory",
        source_kind="points",
        kept=np.arange(len(xyz), dtype=np.int64),
        file_points=len(xyz),
    )


def _vector(value: ArrayLike | None) -> list[float] | None:
    return None if value is None else [float(x) for x in np.asarray(value, dtype=np.float64)]


def _file_info(cloud: PointCloud, name: str | None, size: int) -> PointFileInfo:
    return PointFileInfo(
        name=name,
        format=cloud.format,
        source_kind=cloud.source_kind,
        bytes=size,
        file_points=cloud.file_points,
        left_out=cloud.file_points - len(cloud.points),
        has_normals=cloud.normals is not None,
        has_colors=cloud.colors is not None,
        viewpoint=None if cloud.viewpoint is None else _vector(cloud.viewpoint[0]),
        notes=list(cloud.notes),
    )


def _bounds(points: FloatArray) -> PointBounds | None:
    if not len(points):
        return None
    return PointBounds(min=points.min(axis=0).tolist(), max=points.max(axis=0).tolist())


def _spacing(points: FloatArray) -> Spacing | None:
    """Nearest other point's distance: 0 for points with a copy, else the nearest other
    place's, from one k = 2 query of the places (a pile of copies would make it quadratic)."""
    if len(points) < 2:
        return None
    from scipy.spatial import cKDTree  # type: ignore[import-untyped]  # on first use: 0.5 s

    first, group = coincident_groups(points)
    places = points[first]
    apart = np.full(len(places), np.inf)
    if len(places) > 1:
        apart = cKDTree(places).query(places, k=2, workers=-1)[0][:, 1]
    apart[np.bincount(group, minlength=len(places)) > 1] = 0.0
    nearest = apart[group]
    return Spacing(
        min=float(nearest.min()),
        median=float(np.median(nearest)),
        max=float(nearest.max()),
        coincident=int(np.count_nonzero(nearest == 0)),
    )


def _orientation(
    normals: PointNormals, viewpoint: ArrayLike | None, from_file: bool, direction: ArrayLike | None
) -> Orientation:
    parts = [
        PartOrientation(
            points=part.points,
            flipped=part.flipped,
            unoriented=part.unoriented,
            reason=part.reason,
            seed=part.seed,
        )
        for part in normals.components[:INDEX_LIST_LIMIT]
    ]
    mode = normals.orient
    return Orientation(
        mode=mode,
        viewpoint=_vector(viewpoint) if mode == "viewpoint" else None,
        viewpoint_from_file=from_file,
        direction=_vector(direction) if mode == "direction" else None,
        flipped=normals.flipped,
        unoriented=normals.unoriented,
        part_count=len(normals.components),
        parts=parts,
    )


def _stored(stored: FloatArray, normals: PointNormals) -> StoredNormals:
    """The angles between the stored and the estimated normal lines, where both exist."""
    with np.errstate(invalid="ignore", over="ignore"):
        lengths = np.sqrt(np.einsum("ij,ij->i", stored, stored))
    usable: BoolArray = np.isfinite(lengths) & (lengths > 0) & np.isfinite(stored).all(axis=1)
    compared = usable & normals.valid
    cosines = np.einsum("ij,ij->i", stored[compared], normals.normals[compared])
    cosines /= lengths[compared]
    angles = np.degrees(np.arccos(np.clip(np.abs(cosines), 0.0, 1.0)))
    oriented = normals.status[compared] == PointStatus.ok
    return StoredNormals(
        stored=len(stored),
        unusable=int(np.count_nonzero(~usable)),
        compared=int(compared.sum()),
        agreement_degrees=POINT_AGREEMENT_DEGREES,
        agreeing=int(np.count_nonzero(angles <= POINT_AGREEMENT_DEGREES)),
        median_angle_degrees=float(np.median(angles)) if len(angles) else None,
        max_angle_degrees=float(angles.max()) if len(angles) else None,
        same_side_fraction=float(np.mean(cosines[oriented] > 0)) if oriented.any() else None,
    )


def diagnose(
    counts: StatusCounts,
    orientation: Orientation,
    spacing: Spacing | None,
    stored: StoredNormals | None,
    k: int | None,
    radius: float | None,
    far_from_flat: int = 0,
) -> list[str]:
    """The report's findings as plain sentences, the ones that cost normals first."""
    found = [*_missing(counts, spacing, k, radius), *_unoriented(orientation)]
    if far_from_flat:
        size = f"k = {k}" if radius is None else "the neighbourhood"
        found.append(
            f"{_points(far_from_flat)} have neighbourhoods far from flat (surface variation "
            f"over {POINT_FAR_FROM_FLAT:g}): a thin wall or two sheets closer than {size} "
            "reaches, a sharp edge, or heavy noise. Their normals blend what the neighbourhood "
            "holds and their sides are unsure: use a smaller k or a radius, and "
            'orient="riemannian" for thin walls.'
        )
    if stored is not None:
        found.extend(_stored_findings(stored))
    if not found:
        found.append(ALL_CLEAR)
    return found


def _points(count: int) -> str:
    return f"{count:,} point" + ("" if count == 1 else "s")


def _missing(
    counts: StatusCounts, spacing: Spacing | None, k: int | None, radius: float | None
) -> list[str]:
    found = []
    if counts.not_finite:
        found.append(
            f"{_points(counts.not_finite)} have a coordinate that is not a finite number: "
            "they have no normal and are nobody's neighbour."
        )
    if spacing is not None and spacing.coincident:
        found.append(
            f"{_points(spacing.coincident)} sit exactly where another point is (duplicates); "
            "each gets the normal of its place, estimated once."
        )
    if counts.duplicates:
        found.append(
            f"{_points(counts.duplicates)} have neighbourhoods whose points all coincide "
            "(duplicated points), so no plane and no normal: remove the duplicates or use a "
            "larger k."
        )
    if counts.too_few_neighbours:
        within = f"within the radius {radius:g}" if radius is not None else "near them"
        found.append(
            f"{_points(counts.too_few_neighbours)} have fewer than 3 points {within} "
            "(isolated points), so no normal: use a larger radius, or k alone."
        )
    if counts.collinear:
        size = f"k = {k}" if k is not None else "the radius"
        found.append(
            f"{_points(counts.collinear)} have neighbourhoods that lie on a line (a scan line "
            f"or a thin edge), so no plane and no normal: a larger neighbourhood than {size} "
            "reaches points off the line."
        )
    if counts.ambiguous:
        found.append(
            f"{_points(counts.ambiguous)} have neighbourhoods with two equally flat directions "
            "(a symmetric corner), so no single normal."
        )
    return found


def _unoriented(orientation: Orientation) -> list[str]:
    if not orientation.unoriented:
        return []
    reasons = list(dict.fromkeys(part.reason for part in orientation.parts if part.reason))
    why = "; ".join(reasons[:3]) if reasons else "no reference decided their side"
    return [
        f"{_points(orientation.unoriented)} have a normal whose side could not be decided "
        f"({why}): their sign is arbitrary."
    ]


def _stored_findings(stored: StoredNormals) -> list[str]:
    found = []
    if stored.unusable:
        found.append(f"{_points(stored.unusable)} have a stored normal that is zero or not finite.")
    median = stored.median_angle_degrees
    if median is not None and median > POINT_AGREEMENT_DEGREES:
        found.append(
            f"The file's normals disagree with the estimated ones: a median angle of "
            f"{median:.1f} degrees between their lines (within {POINT_AGREEMENT_DEGREES:g} "
            f"degrees for {stored.agreeing:,} of {stored.compared:,})."
        )
    side = stored.same_side_fraction
    if side is not None and side < FLIPPED_FRACTION:
        found.append(
            f"The file's normals point to the other side from ours for "
            f"{math.floor(100 * (1 - side))}% of the points: they are flipped, or oriented "
            'another way (try orient="file" to keep their sides).'
        )
    return found
