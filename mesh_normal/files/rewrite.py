"""A mesh file written again: its winding kept, fixed or flipped, its normals recomputed, and
everything else it holds kept where the chosen format can hold it, the rest named.

This is what ``mesh-normal fix`` and ``export``, ``POST /api/mesh/fix`` and
``POST /api/mesh/export`` write. Nothing is dropped without a sentence in
:attr:`MeshExport.dropped`: the callers print it or send it as the ``X-Dropped`` header.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import get_args

import numpy as np

from mesh_normal.choices import NormalsChoice as NormalsChoice
from mesh_normal.choices import Winding as Winding
from mesh_normal.files.formats import (
    HOLDS_COLORS,
    HOLDS_FACE_COLORS,
    HOLDS_GROUPS,
    HOLDS_NORMALS,
    WRITABLE,
)
from mesh_normal.files.loaded import LoadedMesh
from mesh_normal.files.normals import NormalsKind, compute_normals
from mesh_normal.files.write import unkept, write_mesh
from mesh_normal.mesh.orientation import Orientation, orient
from mesh_normal.mesh.vertices import Weighting
from mesh_normal.types import BoolArray

#: ``keep`` the faces as they are, ``fix`` them with :func:`~mesh_normal.orient`, ``flip``
#: every face.
WINDINGS: tuple[Winding, ...] = get_args(Winding)
#: The normals to write: a kind, ``none``, or ``auto``: the kind the file had (see
#: :func:`file_normals`), recomputed.
NORMALS_CHOICES: tuple[NormalsChoice, ...] = get_args(NormalsChoice)


@dataclass(frozen=True, slots=True)
class MeshExport:
    """A written mesh file and what went into it.

    Attributes
    ----------
    data : bytes
        The file.
    file_format : str
        Its format (a name of :data:`~mesh_normal.files.formats.WRITABLE`).
    flipped : (m,) bool
        Which faces were reversed (all for ``winding="flip"``, none for ``"keep"``).
    normals_kind : str or None
        The kind of normals written (``None``: none, or none the format holds).
    kept : tuple of str
        What besides the vertices and faces the file holds, in words.
    dropped : tuple of str
        What of the mesh the format could not hold (or the caller did not ask for), in words;
        empty when nothing was left out.
    orientation : Orientation or None
        The fix, for ``winding="fix"``: its verdict and components.
    """

    data: bytes
    file_format: str
    flipped: BoolArray
    normals_kind: NormalsKind | None
    kept: tuple[str, ...]
    dropped: tuple[str, ...]
    orientation: Orientation | None = None

    @property
    def faces_flipped(self) -> int:
        return int(np.count_nonzero(self.flipped))


def file_normals(mesh: LoadedMesh) -> NormalsKind | None:
    """The kind of normals the file stored: vertex (PLY, glTF, OBJ with one ``vn`` a vertex),
    corner (OBJ ``f v//vn`` otherwise), face (PLY face normals); ``None`` for STL, whose
    facet normals every STL file has (they are not a choice of its maker)."""
    if mesh.file_vertex_normals is not None:
        return "vertex"
    if mesh.file_corner_normals is not None:
        return "corner"
    if mesh.file_face_normals is not None and mesh.format != "stl":
        return "face"
    return None


def default_format(mesh: LoadedMesh) -> str:
    """The input's format where it can be written, else the first writable one (PLY)."""
    return mesh.format if mesh.format in WRITABLE else WRITABLE[0]


def export_mesh(
    mesh: LoadedMesh,
    file_format: str | None = None,
    *,
    normals: NormalsChoice = "auto",
    winding: Winding = "keep",
    weighting: Weighting = "angle",
    crease_angle: float = 30.0,
    weld: float | None = None,
) -> MeshExport:
    """``mesh`` as a file of ``file_format`` (default: :func:`default_format`).

    Normals are always computed by our kernels on the faces written (so they follow a fix or
    a flip), never copied from the file; ``weld`` is the fix's (see
    :func:`~mesh_normal.orient`).

    Examples
    --------
    >>> result = export_mesh(read_mesh("bunny.obj"), "glb", normals="corner", winding="fix")
    >>> result.faces_flipped, result.dropped
    """
    chosen = file_format or default_format(mesh)
    faces, flipped, orientation = _wound(mesh, winding, weld)
    wound = dataclasses.replace(mesh, faces=faces)
    had = file_normals(mesh)
    kind = had if normals == "auto" else None if normals == "none" else normals
    values = None
    if kind is not None and kind in HOLDS_NORMALS.get(chosen, ()):
        values, _ = compute_normals(wound, kind, weighting, crease_angle)
    objects = len(mesh.group_names or ())
    data = write_mesh(
        mesh.vertices,
        faces,
        chosen,
        vertex_colors=mesh.vertex_colors,
        face_colors=mesh.face_colors,
        normals=values,
        normals_kind=kind if values is not None else None,
        face_groups=mesh.face_groups,
        group_names=mesh.group_names,
    )
    dropped = unkept(
        chosen, mesh.vertex_colors, mesh.face_colors, objects=objects, normals_kind=kind
    )
    if had is not None and normals == "none":
        dropped.append(f"the file's {had} normals (no normals were asked for)")
    dropped.extend(mesh.unkept)
    return MeshExport(
        data=data,
        file_format=chosen,
        flipped=flipped,
        normals_kind=kind if values is not None else None,
        kept=tuple(_kept(mesh, chosen, kind if values is not None else None, objects)),
        dropped=tuple(dropped),
        orientation=orientation,
    )


def _wound(
    mesh: LoadedMesh, winding: Winding, weld: float | None
) -> tuple[np.ndarray, BoolArray, Orientation | None]:
    """The faces to write, which were reversed, and the fix (for ``winding="fix"``)."""
    if winding == "fix":
        fixed = orient(mesh.checked(), weld=weld)
        return fixed.faces, fixed.flipped, fixed
    if winding == "flip":
        return mesh.faces[:, [0, 2, 1]], np.ones(len(mesh.faces), dtype=bool), None
    if winding != "keep":
        raise ValueError(f"winding must be keep, fix or flip, not {winding!r}.")
    return mesh.faces, np.zeros(len(mesh.faces), dtype=bool), None


def _kept(mesh: LoadedMesh, chosen: str, kind: str | None, objects: int) -> list[str]:
    """What besides vertices and faces the file written holds, in words."""
    kept = []
    if kind is not None:
        kept.append(f"{kind} normals (recomputed)")
    if mesh.vertex_colors is not None and chosen in HOLDS_COLORS:
        kept.append("vertex colours")
    if mesh.face_colors is not None and chosen in HOLDS_FACE_COLORS:
        kept.append("face colours")
    if objects > 1 and chosen in HOLDS_GROUPS:
        kept.append(f"{objects:,} groups")
    return kept
