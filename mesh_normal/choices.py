"""The names of the library's choices and verdicts, as ``Literal`` types, in a module that
imports nothing heavy: the report models (:mod:`mesh_normal.mesh.report.models`,
:mod:`mesh_normal.points.report`) and the web app's routes declare them without loading NumPy
and the kernels (the server answers its first page sooner). The modules that act on them
(:mod:`mesh_normal.mesh.orientation`, :mod:`mesh_normal.mesh.vertices`, ...) import them from
here, and their names there stay the same."""

from __future__ import annotations

from typing import Literal

#: How a part's orientation was decided (:mod:`mesh_normal.mesh.orientation`).
Verdict = Literal["outward", "inward", "mixed", "undetermined"]
Method = Literal["volume", "visibility", "none"]
#: How the faces around a vertex weigh in its normal (:mod:`mesh_normal.mesh.vertices`).
Weighting = Literal["uniform", "area", "angle", "max"]
#: Which normals (:mod:`mesh_normal.files.normals`).
NormalsKind = Literal["face", "vertex", "corner"]
#: A written mesh's winding, and the normals it holds (:mod:`mesh_normal.files.rewrite`).
Winding = Literal["keep", "fix", "flip"]
NormalsChoice = Literal["auto", "none", "face", "vertex", "corner"]
#: How point normals are oriented (:mod:`mesh_normal.points.orient`).
OrientMode = Literal["mst", "riemannian", "viewpoint", "direction", "file", "none"]
#: A mesh file's format, as a report names it (:mod:`mesh_normal.files.formats`).
MeshFormat = Literal["stl", "obj", "ply", "off", "glb", "gltf", "3mf"]
#: A report's format for a mesh or cloud handed over in memory (arrays or another library's
#: object), not read from a file.
InMemory = Literal["memory"]
#: A mesh report's format: the file's, or memory (one flat Literal: one enum in the schema).
ReportFormat = Literal[MeshFormat, InMemory]
#: What a point cloud was read from (:mod:`mesh_normal.points.io.cloud`).
SourceKind = Literal["points", "mesh vertices"]
