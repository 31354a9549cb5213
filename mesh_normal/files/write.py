"""Writing a mesh: binary PLY, binary STL or OBJ, with the vertices exactly as given.

PLY stores float64 coordinates and OBJ the shortest text that reads back as the same float64
(Python's ``repr``), so both round-trip bit for bit. STL can only hold float32 corners; its
facet normals are our face normals (:func:`mesh_normal.face_normals`), zero for degenerate faces.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mesh_normal.checks import check_mesh
from mesh_normal.files.errors import MeshFileError, unsupported
from mesh_normal.files.stl import HEADER, RECORD

#: The formats :func:`write_mesh` can write.
WRITABLE = ("ply", "stl", "obj")

_MAKER = "Mesh Normal Calculator"


def write_mesh(vertices: ArrayLike, faces: ArrayLike, file_format: str) -> bytes:
    """The bytes of a mesh file.

    Parameters
    ----------
    vertices : (n, 3) float
        Finite coordinates, written as given (as float32 in STL, which has nothing wider).
    faces : (m, 3) int
        Indices into ``vertices``.
    file_format : str
        ``"ply"`` (binary little endian, float64), ``"stl"`` (binary, with our facet normals)
        or ``"obj"`` (1-based indices, exact float64 text).

    Raises ``ValueError`` for a bad mesh (from :func:`mesh_normal.check_mesh`) and
    :class:`~mesh_normal.files.MeshFileError` (415) for another format.
    """
    points, triangles = check_mesh(vertices, faces)
    if file_format == "ply":
        return ply_bytes(points, triangles)
    if file_format == "stl":
        return _stl(points, triangles)
    if file_format == "obj":
        return _obj(points, triangles)
    raise unsupported(f"Cannot write {file_format!r} files; the formats are {', '.join(WRITABLE)}.")


def ply_bytes(
    points: NDArray[np.float64],
    triangles: NDArray[np.intp],
    vertex_normals: NDArray[np.float64] | None = None,
    face_normals: NDArray[np.float64] | None = None,
) -> bytes:
    """Binary little-endian PLY: float64 ``x y z`` and int32 triangles, and ``nx ny nz``
    (float64) of the vertices or of the faces where those normals are given.

    Parameters
    ----------
    points : (n, 3) float64
    triangles : (m, 3) intp
    vertex_normals : (n, 3) float64, optional
    face_normals : (m, 3) float64, optional
    """
    normal_fields = [("nx", "<f8"), ("ny", "<f8"), ("nz", "<f8")]
    normal_lines = "".join(f"property double {name}\n" for name, _ in normal_fields)
    vertices = np.empty(
        len(points),
        dtype=[("xyz", "<f8", (3,))] + (normal_fields if vertex_normals is not None else []),
    )
    faces = np.empty(
        len(triangles),
        dtype=[("count", "u1"), ("indices", "<i4", (3,))]
        + (normal_fields if face_normals is not None else []),
    )
    vertices["xyz"] = points
    faces["count"] = 3
    faces["indices"] = triangles
    for records, normals in ((vertices, vertex_normals), (faces, face_normals)):
        if normals is not None:
            for axis, (name, _) in enumerate(normal_fields):
                records[name] = normals[:, axis]
    header = (
        f"ply\nformat binary_little_endian 1.0\ncomment written by {_MAKER}\n"
        f"element vertex {len(points)}\nproperty double x\nproperty double y\n"
        f"property double z\n{normal_lines if vertex_normals is not None else ''}"
        f"element face {len(triangles)}\nproperty list uchar int vertex_indices\n"
        f"{normal_lines if face_normals is not None else ''}end_header\n"
    )
    return header.encode() + vertices.tobytes() + faces.tobytes()


def _stl(points: NDArray[np.float64], triangles: NDArray[np.intp]) -> bytes:
    from mesh_normal.faces import face_normals  # here: reading and writing need no numba

    largest = float(np.abs(points).max(initial=0.0))
    if largest > float(np.finfo(np.float32).max):
        raise MeshFileError(
            f"Coordinates up to {largest:.3g} do not fit in STL, which stores "
            "32-bit floats (up to about 3.4e38); choose PLY or OBJ.",
            422,
        )
    records = np.zeros(len(triangles), dtype=RECORD)
    records["normal"] = face_normals(points, triangles).normals
    records["corners"] = points[triangles]
    header = f"binary STL written by {_MAKER}".encode().ljust(HEADER - 4, b" ")
    return header + len(triangles).to_bytes(4, "little") + records.tobytes()


def _obj(points: NDArray[np.float64], triangles: NDArray[np.intp]) -> bytes:
    lines = [f"# written by {_MAKER}"]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in points.tolist()]
    lines += [f"f {a} {b} {c}" for a, b, c in (triangles + 1).tolist()]
    lines.append("")
    return "\n".join(lines).encode()
