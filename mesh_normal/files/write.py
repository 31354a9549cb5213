"""Writing a mesh file: :func:`write_mesh` checks the mesh once and hands it to the format's
writer from :data:`~mesh_normal.files.formats.FORMATS` (the writers live beside their readers).

PLY stores float64 coordinates and OBJ the shortest text that reads back as the same float64
(Python's ``repr``), so both round-trip bit for bit. STL can only hold float32 corners; its
facet normals are our face normals (:func:`mesh_normal.face_normals`), zero for degenerate faces.

Vertex colours go where the format holds them: PLY in their own type (``uchar``, ``float``),
OBJ as ``v x y z r g b`` (floats 0-1, without alpha); STL holds none. Face colours (one per
triangle) go to PLY only, in their own type. Every file written is one mesh: the objects of the
file read (OBJ groups, ASCII STL solids...) are not kept. :func:`unkept` names what a format
leaves out, for callers that must say so.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mesh_normal.files.errors import unsupported
from mesh_normal.files.formats import (
    FORMATS,
    HOLDS_COLORS,
    HOLDS_FACE_COLORS,
    HOLDS_GROUPS,
    HOLDS_NORMALS,
    WRITABLE,
    MeshFormat,
    suffix_format,
)
from mesh_normal.mesh.checks import HeldMesh, checked_mesh

StrPath = str | os.PathLike[str]
NormalsKind = Literal["face", "vertex", "corner"]


@overload
def write_mesh(
    vertices: HeldMesh,
    file_format: str,
    /,
    *,
    vertex_colors: ArrayLike | None = None,
    face_colors: ArrayLike | None = None,
    normals: ArrayLike | None = None,
    normals_kind: NormalsKind | None = None,
    face_groups: ArrayLike | None = None,
    group_names: Sequence[str] | None = None,
) -> bytes: ...


@overload
def write_mesh(
    vertices: ArrayLike,
    faces: ArrayLike,
    file_format: str,
    *,
    vertex_colors: ArrayLike | None = None,
    face_colors: ArrayLike | None = None,
    normals: ArrayLike | None = None,
    normals_kind: NormalsKind | None = None,
    face_groups: ArrayLike | None = None,
    group_names: Sequence[str] | None = None,
) -> bytes: ...


@overload
def write_mesh(
    vertices: HeldMesh,
    faces: None = None,
    *,
    file_format: str,
    vertex_colors: ArrayLike | None = None,
    face_colors: ArrayLike | None = None,
    normals: ArrayLike | None = None,
    normals_kind: NormalsKind | None = None,
    face_groups: ArrayLike | None = None,
    group_names: Sequence[str] | None = None,
) -> bytes: ...


@overload
def write_mesh(
    vertices: ArrayLike | HeldMesh,
    faces: ArrayLike | None = None,
    file_format: str | None = None,
    *,
    path: StrPath,
    vertex_colors: ArrayLike | None = None,
    face_colors: ArrayLike | None = None,
    normals: ArrayLike | None = None,
    normals_kind: NormalsKind | None = None,
    face_groups: ArrayLike | None = None,
    group_names: Sequence[str] | None = None,
) -> None: ...


def write_mesh(
    vertices: ArrayLike | HeldMesh,
    faces: ArrayLike | None = None,
    file_format: str | None = None,
    *,
    path: StrPath | None = None,
    vertex_colors: ArrayLike | None = None,
    face_colors: ArrayLike | None = None,
    normals: ArrayLike | None = None,
    normals_kind: NormalsKind | None = None,
    face_groups: ArrayLike | None = None,
    group_names: Sequence[str] | None = None,
) -> bytes | None:
    """The bytes of a mesh file, or, given ``path``, that file written.

    Parameters
    ----------
    vertices : (n, 3) float, or a mesh
        Finite coordinates, written as given (as float32 in STL, which has nothing wider); or
        a mesh as :func:`~mesh_normal.mesh.checks.checked_mesh` takes it (read_mesh's, a
        ``(vertices, faces)`` tuple, trimesh, Open3D, PyVista), then without ``faces``:
        ``write_mesh(mesh, "ply")``. Only its vertices and faces are written; colours, normals
        and groups are passed as below.
    faces : (m, 3) int
        Indices into ``vertices``.
    file_format : str, optional
        ``"ply"`` (binary little endian, float64), ``"stl"`` (binary, with our facet normals),
        ``"obj"`` (1-based indices, exact float64 text), ``"glb"`` (binary glTF, float32) or
        ``"off"`` (ASCII, exact float64 text). Without it, the suffix of ``path`` names the
        format.
    path : str or os.PathLike, optional
        Where to write the file (replaced if it exists, through a temporary file and a rename,
        so a failed write leaves the old file whole); the function then returns ``None``.
    vertex_colors : (n, 3) or (n, 4), optional
        Vertex ``red green blue [alpha]`` (as ``LoadedMesh.vertex_colors`` holds them). PLY
        writes them in their own type (``uchar`` 0-255, ``float`` 0-1, ...), OBJ as
        ``v x y z r g b`` floats 0-1 (no alpha); STL holds none and writes none.
        :func:`unkept` names what is left out.
    face_colors : (m, 3) or (m, 4), optional
        The colour of each triangle (as ``LoadedMesh.face_colors`` holds them): PLY writes
        them on its faces in their own type, OFF after each face; STL, OBJ and GLB hold none.
    normals : (n, 3), (m, 3) or (m, 3, 3) float, optional
        Vertex, face or corner normals (from :func:`mesh_normal.vertex_normals` and the
        like), written as the format holds them
        (:data:`~mesh_normal.files.formats.HOLDS_NORMALS`): OBJ ``vn`` of any kind; PLY
        ``nx ny nz`` of vertices or faces; GLB ``NORMAL``, its vertices split where face or
        corner normals differ; OFF vertex normals (``NOFF``); STL the face normals as its
        facet normals. A kind the format cannot hold is left out: :func:`unkept` names it.
    normals_kind : "face", "vertex" or "corner", optional
        Which ``normals`` are; without it, told from their shape (``(m, 3, 3)`` corner,
        ``(n, 3)`` vertex, ``(m, 3)`` face), a ``ValueError`` when ``n == m`` leaves it open.
    face_groups : (m,) int, optional
        Each face's group, an index into ``group_names`` (as ``LoadedMesh.face_groups``);
        OBJ writes them as ``o``/``g`` runs, the other formats hold none.
    group_names : sequence of str, optional
        The groups' names (as ``LoadedMesh.group_names``); needed with ``face_groups``.

    Returns
    -------
    bytes or None
        The file's bytes; ``None`` when ``path`` was given and the file written.

    Raises
    ------
    ValueError
        For a bad mesh (from :func:`mesh_normal.mesh.checks.check_mesh`).
    TypeError
        For something that is not a mesh (the sentence says what can be passed).
    MeshFileError
        415 for a format that cannot be written (or a path whose suffix names none), 422 for
        coordinates STL cannot hold.
    OSError
        When ``path`` cannot be written, as Python raises it.

    Examples
    --------
    >>> data = write_mesh(vertices, faces, "ply")         # bytes
    >>> data = write_mesh(mn.read_mesh("bunny.obj"), "ply")  # a mesh alone
    >>> write_mesh(vertices, faces, path="fixed.obj")      # the format from the suffix
    >>> write_mesh(vertices, faces, "glb", normals=corners, normals_kind="corner")
    """
    if isinstance(faces, str) and file_format is None:  # write_mesh(mesh, "ply")
        faces, file_format = None, faces
    if file_format is None and path is None:
        raise TypeError("write_mesh needs a file_format or a path to take the format from.")
    entry = _writable(file_format, path)
    checked = checked_mesh(vertices, faces)
    points, triangles = checked.vertices, checked.faces
    kind, values = checked_normals(normals, normals_kind, len(points), len(triangles))
    groups = _checked_groups(face_groups, group_names, len(triangles))
    data = entry.write(
        points,
        triangles,
        _checked_colors(vertex_colors, len(points), "vertex_colors"),
        _checked_colors(face_colors, len(triangles), "face_colors"),
        normals=values,
        normals_kind=kind,
        face_groups=groups,
        group_names=None if groups is None or group_names is None else tuple(group_names),
    )
    if path is None:
        return data
    replace_file(path, data)
    return None


def unkept(
    file_format: str,
    vertex_colors: ArrayLike | None,
    face_colors: ArrayLike | None = None,
    *,
    objects: int = 0,
    normals_kind: str | None = None,
) -> list[str]:
    """What of the given colours and objects a format's file cannot hold, in words; empty
    when it holds all of them (or there are none).

    ``objects`` is how many the mesh has (:attr:`LoadedMesh.group_names
    <mesh_normal.files.LoadedMesh.group_names>`): every file written is one mesh, so two or
    more are named as left out (one object is the mesh itself).

    >>> unkept("stl", colors)
    ['vertex colours (STL holds none)']
    >>> unkept("stl", None, objects=2)
    ['the division into 2 objects (the STL written is one mesh)']
    >>> unkept("stl", None, normals_kind="corner")
    ['corner normals (STL holds face normals only)']
    """
    title = FORMATS[file_format].title if file_format in FORMATS else file_format
    dropped = []
    for colors, held, kind in (
        (vertex_colors, HOLDS_COLORS.get(file_format, ""), "vertex"),
        (face_colors, HOLDS_FACE_COLORS.get(file_format, ""), "face"),
    ):
        if colors is None:
            continue
        if not held:
            dropped.append(f"{kind} colours ({title} holds none)")
        elif np.shape(colors)[-1] > len(held):
            dropped.append(f"{kind} colour alpha ({title} holds red, green and blue only)")
    held_kinds = HOLDS_NORMALS.get(file_format, ())
    if normals_kind is not None and normals_kind not in held_kinds:
        holds = " and ".join(held_kinds) + " normals only" if held_kinds else "no normals"
        dropped.append(f"{normals_kind} normals ({title} holds {holds})")
    if objects > 1 and file_format not in HOLDS_GROUPS:
        dropped.append(f"the division into {objects:,} objects (the {title} written is one mesh)")
    return dropped


def checked_normals(
    normals: ArrayLike | None, kind: NormalsKind | None, vertices: int, faces: int
) -> tuple[NormalsKind | None, NDArray[np.float64] | None]:
    """The normals' kind (given, or told from their shape) and the normals as float64;
    ``ValueError`` for a shape that fits no kind, or fits two without ``kind`` to choose."""
    if normals is None:
        return None, None
    values = np.asarray(normals, dtype=np.float64)
    shapes: dict[NormalsKind, tuple[int, ...]] = {
        "face": (faces, 3),
        "vertex": (vertices, 3),
        "corner": (faces, 3, 3),
    }
    if kind is None:
        fits = [name for name, shape in shapes.items() if values.shape == shape]
        if len(fits) != 1:
            raise ValueError(
                f"normals of shape {values.shape} need normals_kind (face, vertex or corner)"
                if fits
                else f"normals must have shape ({vertices}, 3), ({faces}, 3) or "
                f"({faces}, 3, 3), not {values.shape}."
            )
        kind = fits[0]
    elif kind not in shapes:
        raise ValueError(f"normals_kind must be face, vertex or corner, not {kind!r}.")
    if values.shape != shapes[kind]:
        raise ValueError(f"{kind} normals must have shape {shapes[kind]}, not {values.shape}.")
    if not np.isfinite(values).all():
        raise ValueError("normals must be finite (zero rows for the missing ones).")
    return kind, values


def _checked_groups(
    groups: ArrayLike | None, names: Sequence[str] | None, count: int
) -> NDArray[np.intp] | None:
    if groups is None or names is None:
        return None
    result = np.asarray(groups, dtype=np.intp)
    if result.shape != (count,) or (count and not 0 <= result.min() <= result.max() < len(names)):
        raise ValueError(f"face_groups must be {count} indices into the {len(names)} group_names.")
    return result


def _checked_colors(colors: ArrayLike | None, count: int, name: str) -> NDArray[np.generic] | None:
    """Colours as an ``(count, 3)`` or ``(count, 4)`` array of numbers; ``ValueError``
    otherwise."""
    if colors is None:
        return None
    result = np.asarray(colors)
    if (
        result.ndim != 2
        or result.shape != (count, result.shape[1])
        or result.shape[1] not in (3, 4)
    ):
        raise ValueError(
            f"{name} must have shape ({count}, 3) or ({count}, 4), not {result.shape}."
        )
    if result.dtype.kind not in "uif":
        raise ValueError(f"{name} must be numbers, not {result.dtype}.")
    return result


def replace_file(path: StrPath, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file beside it, then rename it over
    ``path``: a failed write (a full disk, a size limit) leaves any old file as it was and no
    half-written one, and writing a mesh over its own input cannot lose it."""
    target = Path(path)
    temporary = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    try:
        temporary.write_bytes(data)
        os.replace(temporary, target)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def _writable(file_format: str | None, path: StrPath | None) -> MeshFormat:
    formats = ", ".join(WRITABLE)
    name = Path(os.fspath(path or "")).name
    named = suffix_format(name) if path is not None else None
    if file_format is not None and named is not None and named != file_format:
        raise unsupported(
            f"The path {name!r} names {FORMATS[named].title} but the file_format is "
            f"{file_format!r}; give one of them, or make them agree."
        )
    if file_format is None:
        file_format = named
        if file_format is None:
            raise unsupported(
                f"The format cannot be told from the name {name!r}; give a file_format "
                f"({formats}) or a path ending in one of them."
            )
    entry = FORMATS.get(file_format)
    if entry is None or not entry.writable:
        raise unsupported(f"Cannot write {file_format!r} files; the formats are {formats}.")
    return entry
