"""Which format a file is in, and the one entry point that reads any of them."""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable

from mesh_normal.files.errors import MeshFileError, unsupported
from mesh_normal.files.gltf import read_glb, read_gltf
from mesh_normal.files.loaded import LoadedMesh
from mesh_normal.files.obj import read_obj
from mesh_normal.files.off import read_off
from mesh_normal.files.ply import read_ply
from mesh_normal.files.stl import is_binary, looks_ascii, read_stl

#: File extension (lower case, with the dot) to format.
SUFFIXES: dict[str, str] = {
    ".stl": "stl",
    ".obj": "obj",
    ".ply": "ply",
    ".off": "off",
    ".glb": "glb",
    ".gltf": "gltf",
}

NAMES = {"stl": "STL", "obj": "OBJ", "ply": "PLY", "off": "OFF", "glb": "GLB", "gltf": "glTF"}

READERS: dict[str, Callable[[bytes], LoadedMesh]] = {
    "stl": read_stl,
    "obj": read_obj,
    "ply": read_ply,
    "off": read_off,
    "glb": read_glb,
    "gltf": read_gltf,
}

_OFF = re.compile(rb"\s*(?:#[^\n]*\n\s*)*(?:ST)?C?N?4?n?OFF\b")
_OBJ = re.compile(rb"^[ \t]*(?:v|f)[ \t]", re.MULTILINE)


def read_mesh(data: bytes, filename: str | None = None) -> LoadedMesh:
    """Read a mesh file; the format comes from the bytes, else from the file name's extension.

    Raises
    ------
    MeshFileError
        With one sentence naming the problem: 400 for a broken file or bad content, 415 for
        a format that is unknown or not supported.
    """
    if not data:
        raise MeshFileError("The file is empty (0 bytes).")
    if data.startswith(b"\xef\xbb\xbf"):  # a UTF-8 byte order mark: text formats only
        data = data[3:]
    named = suffix_format(filename)
    found = sniff(data) or named
    if found is None:
        raise unknown_format(filename)
    try:
        mesh = READERS[found](data)
    except MeshFileError:
        raise
    except Exception as error:  # a library's own exception: never a 500
        reason = str(error).strip().rstrip(".") or type(error).__name__
        raise MeshFileError(
            f"The file could not be read as {NAMES[found]}: {reason[:200]}."
        ) from error
    if named is not None and named != found:
        note = (
            f"The file is named as {NAMES[named]} but holds {NAMES[found]}; it was read as "
            f"{NAMES[found]}."
        )
        mesh = dataclasses.replace(mesh, notes=(note, *mesh.notes))
    return mesh


def suffix_format(filename: str | None) -> str | None:
    """The format a file name's extension names, or ``None``."""
    if not filename or "." not in filename:
        return None
    return SUFFIXES.get("." + filename.rsplit(".", 1)[-1].lower())


def sniff(data: bytes) -> str | None:
    """The format the bytes themselves show, or ``None`` (OBJ only when it is plain)."""
    head = data[:4096]
    if head.startswith(b"glTF"):
        return "glb"
    if re.match(rb"ply\r?\n", head):
        return "ply"
    if is_binary(data) or looks_ascii(data):
        return "stl"
    if _OFF.match(head):
        return "off"
    if head.lstrip().startswith(b"{") and b'"asset"' in data:
        return "gltf"
    if b"\0" not in head and _OBJ.search(head):
        return "obj"
    return None


def unknown_format(filename: str | None) -> MeshFileError:
    formats = ", ".join(sorted(SUFFIXES))
    if filename and "." in filename:
        suffix = filename.rsplit(".", 1)[-1][:20]
        return unsupported(
            f"The format of this .{suffix} file is not supported; the formats are {formats}."
        )
    return unsupported(
        f"The file's format was not recognised from its content; the formats "
        f"are {formats} (a file name with its extension helps)."
    )
