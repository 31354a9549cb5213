"""Which mesh jobs a server runs itself while its first worker starts: the report, the fix
and the face normals of a small file in a format read without trimesh
(:func:`app.web.workers.run_in_server_while_starting`; :mod:`app.mesh.work` names its jobs so
as it is imported). The jobs and the warm-up
(:mod:`app.mesh.warmup`, which tries each check) both import it."""

from __future__ import annotations

from app.mesh.uploads import Upload
from mesh_normal.files.formats import suffix_format
from mesh_normal.files.read import sniff

#: The largest file a job may read in the server while the workers start: its arrays stay
#: within the kernels' Python path (mesh_normal.kernels.PYTHON_ELEMENTS, 6,000 elements a
#: call: 4 KB are at most about 500 lines of OBJ or 80 triangles of binary STL).
SMALL_FILE_BYTES = 4096


def small_file(upload: Upload, *_args: object) -> bool:
    """Whether a job on ``upload`` may run in the server while the workers start: a small STL,
    or a small OBJ of triangles. Polygons (a triangulation kernel that always loads numba) and
    the other formats (PLY and OFF may hold polygons too; glTF and 3MF need trimesh) wait."""
    if not isinstance(upload, Upload) or upload.parts or len(upload.data) > SMALL_FILE_BYTES:
        return False
    found = sniff(upload.data) or suffix_format(upload.filename)
    return found == "stl" or (found == "obj" and _triangles_only(upload.data))


def _triangles_only(obj: bytes) -> bool:
    """Whether every face of an OBJ text has three corners."""
    for line in obj.splitlines():
        words = line.split()
        if words and words[0] == b"f" and len(words) != 4:
            return False
    return True


def small_face_normals(upload: Upload, kind: str, *_args: object) -> bool:
    """Face normals (no vertex sums, whose kernel loads numba) of a small file."""
    return kind == "face" and small_file(upload)
