"""Normals and areas of the faces of a triangle mesh, in float64.

A mesh is ``vertices``, an (n, 3) array of points, and ``faces``, an (m, 3) array of indices
into it. Face ``[a, b, c]`` has the normal n = (B - A) x (C - A) of
:func:`mesh_normal.triangle.normal.triangle_normal`: it points to the side from which A, B, C run
counter-clockwise, |n| is twice the face's area, and reversing the face negates it.

Precision. The cross product is a float64 product of edges (each a correctly rounded
difference), so it is within about 6 eps |p| |q| of the exact one, where p and q are the two
edges it was taken from and eps = 2**-53. It is first taken at corner A; where the sine of
that angle is small (``MESH_RECOMPUTE_SINE``) it is taken again at the face's largest
corner, between its two shortest edges, where that error is smallest. A needle (one tiny
angle) therefore keeps an accurate normal, and only a flat sliver loses it.

Degenerate faces. A face is degenerate when the sine of its largest corner angle is at most
``MESH_DEGENERATE_SINE`` (2**-37): its normal is then rounding noise. This covers repeated
indices, coincident points and collinear points. The test is relative (|n| against |p| |q|),
so it gives the same verdict in any unit, unlike an absolute threshold on |n|. Degenerate
faces get a zero normal, a zero area and ``True`` in the ``degenerate`` mask. Arrays are
always full length, in input order, and never NaN.

The vertices are first scaled by a power of two (exact) so that the largest |coordinate| is
about 1: only edges shorter than about 1e-71 times that coordinate then underflow (such faces
count as degenerate), and only areas beyond the double range (coordinates beyond about 1e154)
are infinite; nothing else overflows.

One pass. :func:`face_geometry` computes the cross products of a mesh once, in one compiled
loop on every core (``mesh_normal._core``, ``cpp/faces.cpp``), into a :class:`FaceGeometry`;
the face, vertex and corner normals and :func:`mesh_normal.mesh.orientation.orient` all take one
instead of recomputing them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TypeAlias

import numpy as np
from numpy.typing import ArrayLike

import mesh_normal._core as _core
from mesh_normal.mesh.checks import (
    CheckedMesh,
    HeldMesh,
    checked_mesh,
    read_only,
    refuse_faces,
)
from mesh_normal.types import BoolArray, FloatArray, IndexArray


@dataclass(frozen=True, slots=True, eq=False)
class FaceGeometry:
    """The cross product of every face of a checked mesh, computed once, and what follows.

    Lengths are of the vertices scaled by ``2**-mesh.scale`` (exact), so that nothing
    over- or underflows; directions are unaffected.

    Attributes
    ----------
    mesh : CheckedMesh
        The mesh they were computed from.
    crosses : (m, 3) float64
        (B - A) x (C - A), scaled, from the corner where it is most accurate; zero where
        degenerate.
    normals : (m, 3) float64
        Unit normals, ``crosses / lengths``; zero rows where degenerate.
    lengths : (m,) float64
        |crosses|, twice the (scaled) area.
    degenerate : (m,) bool
        The face has no usable normal (see the module docstring).
    recomputed : (m,) bool
        The product was not kept from corner A (taken again at the largest corner, or
        degenerate): there ``crosses`` differs from (B - A) x (C - A) taken at A.
    """

    mesh: CheckedMesh
    crosses: FloatArray
    lengths: FloatArray
    degenerate: BoolArray
    recomputed: BoolArray
    _cache: dict[str, FloatArray] = field(default_factory=dict, repr=False)

    def __len__(self) -> int:
        return len(self.lengths)

    @property
    def normals(self) -> FloatArray:
        """(m, 3) float64 unit normals, ``crosses / lengths``, taken on first use and kept.

        Not taken with the products: the topology and orientation do not need them, and a
        server's peak memory is lower for 24 bytes a face fewer while they run.
        """
        found = self._cache.get("normals")
        if found is None:
            found = self.unit_normals()
            self._cache["normals"] = found
        return found

    def unit_normals(
        self, rows: slice | IndexArray = slice(None), out: FloatArray | None = None
    ) -> FloatArray:
        """(k, 3) float64: the unit normals of a slice (or a list) of the faces, not kept
        (a writer taking them a block at a time); into ``out`` if given (``crosses`` itself,
        by a caller that needs nothing more of this geometry and not 24 bytes a face more)."""
        if isinstance(rows, slice) and rows == slice(None):  # one compiled pass on every core
            found = np.empty(self.crosses.shape) if out is None else out
            _core.unit_normals(self.crosses, self.lengths, self.degenerate, found)
            return found
        divisor = np.where(self.degenerate[rows], 1.0, self.lengths[rows])
        found = np.divide(self.crosses[rows], divisor[:, None], out=out)
        found += 0.0  # -0.0 becomes 0.0
        return found


#: What the core's functions take: raw ``vertices`` (with ``faces``), or without ``faces`` a
#: mesh as :func:`~mesh_normal.mesh.checks.checked_mesh` takes it (a checked mesh, a
#: ``(vertices, faces)`` tuple, what ``read_mesh`` returns, a trimesh, Open3D or PyVista mesh)
#: or the face geometry of one.
MeshInput: TypeAlias = "ArrayLike | HeldMesh | FaceGeometry"


@dataclass(frozen=True, slots=True)
class FaceNormals:
    """Full-length results for ``m`` faces, in input order.

    Attributes
    ----------
    normals : (m, 3) float64
        Unit normals; zero rows where ``degenerate``.
    areas : (m,) float64
        Areas, |(B - A) x (C - A)| / 2; zero where ``degenerate``.
    degenerate : (m,) bool
        The face has no usable normal (see the module docstring).
    """

    normals: FloatArray
    areas: FloatArray
    degenerate: BoolArray

    def __len__(self) -> int:
        return len(self.areas)


def face_geometry(vertices: MeshInput, faces: ArrayLike | None = None) -> FaceGeometry:
    """Compute the cross products of a mesh once (``vertices`` itself if it is a geometry).

    Parameters
    ----------
    vertices : (n, 3) float64, a mesh or FaceGeometry
        Finite coordinates; or a mesh as :func:`~mesh_normal.mesh.checks.checked_mesh` takes
        it (read_mesh's, a ``(vertices, faces)`` tuple, trimesh, Open3D, PyVista), then
        without ``faces``.
    faces : (m, 3) int, optional
        Indices into ``vertices``.

    Returns
    -------
    FaceGeometry
        In face order.
    """
    mesh = checked_input(vertices, faces)
    if isinstance(mesh, FaceGeometry):
        return mesh
    count = len(mesh.faces)
    crosses = np.empty((count, 3))
    lengths, degenerate = np.empty(count), np.empty(count, dtype=bool)
    recomputed = np.empty(count, dtype=bool)
    if not _core.face_geometry(
        mesh.points, mesh.factor, mesh.faces, crosses, lengths, degenerate, recomputed
    ):
        refuse_faces(mesh.faces, len(mesh.points))
    return FaceGeometry(mesh, crosses, lengths, degenerate, recomputed)


def checked_input(vertices: MeshInput, faces: ArrayLike | None) -> CheckedMesh | FaceGeometry:
    """A checked mesh or geometry as given, or raw arrays checked (see :func:`checked_mesh`)."""
    if isinstance(vertices, FaceGeometry):
        if faces is not None:
            raise TypeError("a face geometry holds its faces: pass it without faces.")
        return vertices
    return checked_mesh(vertices, faces)


def kernel_ranged_input(vertices: MeshInput, faces: ArrayLike | None) -> CheckedMesh | FaceGeometry:
    """:func:`checked_input`, for a caller whose kernel checks each index of raw faces as it
    reads it and then calls ``refuse_faces`` for the error: raw intp faces are not checked
    against the vertices here (one pass over them fewer)."""
    if faces is not None and not isinstance(vertices, (CheckedMesh, FaceGeometry)):
        return checked_mesh(vertices, faces, ranged=False)
    return checked_input(vertices, faces)


def face_normals(
    vertices: MeshInput, faces: ArrayLike | None = None, *, out: FaceNormals | None = None
) -> FaceNormals:
    """Return the unit normal and the area of every face.

    Parameters
    ----------
    vertices : (n, 3) float64, a mesh or FaceGeometry
        Finite coordinates; or a mesh as :func:`~mesh_normal.mesh.checks.checked_mesh` takes
        it (read_mesh's, a ``(vertices, faces)`` tuple, trimesh, Open3D, PyVista) or its
        geometry, then without ``faces``.
    faces : (m, 3) int
        Indices into ``vertices``; face ``[a, b, c]`` has the normal (B - A) x (C - A).
    out : FaceNormals, optional
        Arrays to write the results into, e.g. the last call's for a mesh whose points move
        from frame to frame: writable, C-contiguous, of the returned shapes and dtypes, and
        sharing no memory with the input. Returned, written. New memory of hundreds of
        megabytes costs the system time to hand out (a quarter to a third of the call at 14
        million faces); these arrays are written in place. On an error their contents are
        unspecified.

    Returns
    -------
    FaceNormals
        ``normals`` (m, 3) float64, ``areas`` (m,) float64 and the ``degenerate`` (m,) bool
        mask, in input order; zero rows where degenerate. Given a geometry, ``normals`` and
        ``degenerate`` are read-only views of its own arrays, not copies (unless ``out`` is
        given).

    Examples
    --------
    >>> face_normals([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]).normals
    array([[0., 0., 1.]])
    """
    mesh = kernel_ranged_input(vertices, faces)
    count = len(mesh.mesh.faces if isinstance(mesh, FaceGeometry) else mesh.faces)
    if out is not None:
        _check_out(out, count, mesh)
    if isinstance(mesh, FaceGeometry):
        if out is None:  # read-only views: passed as ``out`` later, they are refused
            return FaceNormals(
                read_only(mesh.normals), geometry_areas(mesh), read_only(mesh.degenerate)
            )
        mesh.unit_normals(out=out.normals)
        np.copyto(out.areas, geometry_areas(mesh))
        np.copyto(out.degenerate, mesh.degenerate)
        return out
    # From the mesh, one pass (no cross products kept): the same bits, a third of the traffic.
    if out is None:
        into = FaceNormals(np.empty((count, 3)), np.empty(count), np.empty(count, bool))
    else:
        into = out
    if not run_face_kernel(mesh, into):
        refuse_faces(mesh.faces, len(mesh.points))
    return into


def run_face_kernel(mesh: CheckedMesh, into: FaceNormals) -> bool:
    """Write the unit normals, areas and degenerate flags of ``mesh``'s faces into the arrays
    of ``into``, in one compiled pass on every core; False if a face has an index out of
    range (then ``into`` holds no result)."""
    return _core.face_normals(
        mesh.points,
        mesh.factor,
        mesh.faces,
        2 * mesh.scale - 1,
        into.normals,
        into.areas,
        into.degenerate,
    )


def _check_out(out: FaceNormals, count: int, mesh: CheckedMesh | FaceGeometry) -> None:
    """Refuse ``out`` for :func:`face_normals` unless its arrays can take the results of
    ``count`` faces and share no memory with the input's (a geometry's too) or each other's:
    the one sentence names the first array that cannot."""
    if not isinstance(out, FaceNormals):
        raise TypeError(
            f"out must be a FaceNormals (e.g. an earlier result), not {type(out).__name__}."
        )
    wanted = (
        ("normals", (count, 3), np.dtype(np.float64)),
        ("areas", (count,), np.dtype(np.float64)),
        ("degenerate", (count,), np.dtype(bool)),
    )
    checked = mesh.mesh if isinstance(mesh, FaceGeometry) else mesh
    seen: list[np.ndarray] = [checked.points, checked.faces, checked.vertices]
    if isinstance(mesh, FaceGeometry):
        seen += [mesh.crosses, mesh.lengths, mesh.degenerate, mesh.recomputed]
        seen += list(mesh._cache.values())  # its normals, if taken
    for name, shape, dtype in wanted:
        array = getattr(out, name)
        if not (
            isinstance(array, np.ndarray)
            and array.shape == shape
            and array.dtype == dtype
            and array.flags.c_contiguous
            and array.flags.aligned
            and array.flags.writeable
        ):
            raise ValueError(
                f"out.{name} must be a writable C-contiguous {dtype} array of shape {shape} "
                f"(for the {count:,} faces), not "
                + (
                    f"{'read-only ' if not array.flags.writeable else ''}"
                    f"{'' if array.flags.c_contiguous else 'strided '}{array.dtype} of shape "
                    f"{array.shape}."
                    if isinstance(array, np.ndarray)
                    else f"{type(array).__name__}."
                )
            )
        if any(np.may_share_memory(array, other) for other in seen):
            raise ValueError(f"out.{name} shares memory with the input or another of out's arrays.")
        seen.append(array)


def geometry_areas(geometry: FaceGeometry) -> FloatArray:
    """(m,) float64: the areas of a geometry's faces, without taking its unit normals."""
    with np.errstate(over="ignore"):
        return np.ldexp(geometry.lengths, 2 * geometry.mesh.scale - 1)


def face_areas(vertices: MeshInput, faces: ArrayLike | None = None) -> FloatArray:
    """Return the area of every face.

    Parameters
    ----------
    vertices : (n, 3) float64, a mesh or FaceGeometry
        Finite coordinates; or a mesh as :func:`~mesh_normal.mesh.checks.checked_mesh` takes
        it (read_mesh's, a ``(vertices, faces)`` tuple, trimesh, Open3D, PyVista) or its
        geometry, then without ``faces``.
    faces : (m, 3) int
        Indices into ``vertices``.

    Returns
    -------
    (m,) float64
        |(B - A) x (C - A)| / 2, in input order; zero for degenerate faces.
    """
    return geometry_areas(face_geometry(vertices, faces))
