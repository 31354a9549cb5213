"""A worker's warm-up: everything a job can need, loaded before the first job.

A worker that loads something on its first glTF, its first 3MF or its first page keeps it for
good (a module, a cache), so that its resident memory grows during its first jobs and the
growth looks like a leak. :func:`warm` loads it all as the worker starts instead: it runs every
job of :mod:`app.mesh.work` on a small mesh in each kind of file, so that each reader's imports
(trimesh's glTF loader, DracoPy, the 3MF XML parser, zip archives, earcut for polygons), the
page's figures and the writers are part of the worker's baseline.
"""

from __future__ import annotations

import io
import json
import struct
import zipfile
from typing import get_args

import numpy as np

from app.mesh.uploads import Upload
from app.mesh.work import FIX_FORMATS, fix, normals, page, report
from mesh_normal.files import write_mesh
from mesh_normal.files.normals import KINDS
from mesh_normal.mesh.vertices import Weighting

#: A closed tetrahedron, wound outward.
VERTICES = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])

#: An open box of two quads and a triangle (polygons; an open part, decided by visibility).
POLYGONS_OBJ = (
    b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nf 1 4 3 2\nf 1 2 6 5\nf 2 3 6\n"
)
POLYGONS_OFF = (
    b"OFF\n6 3 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n4 0 3 2 1\n4 0 1 5 4\n3 1 2 5\n"
)
ASCII_PLY = (
    b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    b"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
)
ASCII_STL = (
    b"solid warm\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
    b"endloop\nendfacet\nendsolid warm\n"
)
#: A 3MF package's model part: one triangle.
MODEL_3MF = (
    b'<?xml version="1.0" encoding="UTF-8"?>\n'
    b'<model unit="millimeter" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">'
    b'<resources><object id="1" type="model"><mesh><vertices><vertex x="0" y="0" z="0"/>'
    b'<vertex x="1" y="0" z="0"/><vertex x="0" y="1" z="0"/></vertices><triangles>'
    b'<triangle v1="0" v2="1" v3="2"/></triangles></mesh></object></resources>'
    b'<build><item objectid="1"/></build></model>'
)


def warm() -> None:
    """Run each job once on each of the small files (milliseconds)."""
    import DracoPy  # noqa: F401 (the glTF reader imports it only for a Draco-compressed file)

    for upload in uploads():
        page(upload, "warm", "http://127.0.0.1/")  # the report, and the page's figures
    tetrahedron = uploads()[0]
    report(tetrahedron, 1e-6)
    for file_format in FIX_FORMATS:
        fix(tetrahedron, file_format, None)
    for kind in KINDS:
        for weighting in get_args(Weighting):
            normals(tetrahedron, kind, weighting, 30.0)


def uploads() -> list[Upload]:
    """A small mesh in each kind of file that the readers take apart."""
    written = [
        Upload(write_mesh(VERTICES, FACES, name), f"warm.{name}") for name in ("stl", "ply", "obj")
    ]
    return [
        *written,
        Upload(ASCII_STL, "ascii.stl"),
        Upload(ASCII_PLY, "ascii.ply"),
        Upload(POLYGONS_OBJ, "polygons.obj"),
        Upload(POLYGONS_OFF, "polygons.off"),
        Upload(glb(), "warm.glb"),
        Upload(zipped({"3D/3dmodel.model": MODEL_3MF}), "warm.3mf"),
        Upload(zipped({"polygons.obj": POLYGONS_OBJ}), "warm.zip"),
        Upload.several((("warm.gltf", gltf_json("warm.bin")), ("warm.bin", gltf_buffer())), None),
    ]


def gltf_buffer() -> bytes:
    """The tetrahedron's float32 positions, then its uint32 indices (both 4-byte aligned)."""
    return VERTICES.astype("<f4").tobytes() + FACES.astype("<u4").tobytes()


def gltf_json(uri: str | None) -> bytes:
    """The glTF JSON of the tetrahedron in :func:`gltf_buffer`, that buffer at ``uri`` (or, for
    None, the GLB's own binary chunk)."""
    positions = VERTICES.astype("<f4").nbytes
    buffer: dict[str, object] = {"byteLength": len(gltf_buffer())}
    if uri is not None:
        buffer["uri"] = uri
    document = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,  # float32
                "count": len(VERTICES),
                "type": "VEC3",
                "min": VERTICES.min(axis=0).tolist(),
                "max": VERTICES.max(axis=0).tolist(),
            },
            {"bufferView": 1, "componentType": 5125, "count": FACES.size, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": positions},
            {"buffer": 0, "byteOffset": positions, "byteLength": FACES.size * 4},
        ],
        "buffers": [buffer],
    }
    return json.dumps(document).encode()


def glb() -> bytes:
    """The tetrahedron as a GLB: a 12-byte header, then a JSON and a binary chunk."""
    text, binary = gltf_json(None), gltf_buffer()
    text += b" " * (-len(text) % 4)  # chunks are 4-byte aligned: JSON padded with spaces
    chunks = struct.pack("<I4s", len(text), b"JSON") + text
    chunks += struct.pack("<I4s", len(binary), b"BIN\0") + binary
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def zipped(members: dict[str, bytes]) -> bytes:
    archive = io.BytesIO()
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as package:
        for name, data in members.items():
            package.writestr(name, data)
    return archive.getvalue()
