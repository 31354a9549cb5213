"""app/mesh/warmup.py: a worker loads everything a job needs before its first job, and only
kernels that ``compile_kernels`` (the image build's call) compiles too."""

from __future__ import annotations

import subprocess
import sys

from app.mesh import warmup
from app.mesh.work import report
from tests.paths import ROOT

#: In a fresh process: the kernels' signatures after compile_kernels(), then the ones that the
#: warm-up and then a job on every test file (report, vertex and corner normals, the fix)
#: added. numba compiles a kernel for each new signature: with a read-only cache (a container)
#: that is a compile at run time, in every worker.
COVERAGE = """
import json
from pathlib import Path
from mesh_normal.kernels import _KERNELS
from mesh_normal.precompile import compile_kernels

def signatures():
    return {f"{k.py_func.__qualname__} {s}" for k in _KERNELS for s in k.signatures}

compile_kernels()
compiled = signatures()
from app.mesh import warmup, work
from app.mesh.uploads import Upload
warmup.warm()
warmed = signatures() - compiled

def uploads():
    data = Path("tests/data")
    for path in sorted(data.rglob("*")):
        if "hostile" in path.parts:  # refused before any kernel; tests/app/test_hostile_corpus.py
            continue
        if path.suffix in {".stl", ".obj", ".ply", ".off", ".glb", ".3mf"}:
            yield Upload(path.read_bytes(), path.name)
        elif path.suffix == ".gltf":
            uris = [b["uri"] for b in json.loads(path.read_text()).get("buffers", [])]
            parts = [(path.name, path.read_bytes())]
            parts += [(uri, (path.parent / uri).read_bytes()) for uri in uris]
            yield Upload.several(tuple(parts), None)

for upload in uploads():
    for job in (
        lambda: work.report(upload, None),
        lambda: work.normals(upload, "vertex", "angle", 30.0),
        lambda: work.normals(upload, "corner", "angle", 30.0),
        lambda: work.fix(upload, None, None),
    ):
        try:
            job()
        except Exception as error:  # a file the readers refuse: its kernels ran as far as it got
            if type(error).__name__ != "ApiError":
                raise
print(json.dumps({"warmed": sorted(warmed), "jobs": sorted(signatures() - compiled)}))
"""


def test_the_warm_up_and_the_jobs_need_no_kernel_that_compile_kernels_leaves_out() -> None:
    result = subprocess.run(
        [sys.executable, "-c", COVERAGE],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    assert result.stdout.strip().splitlines()[-1] == '{"warmed": [], "jobs": []}'


def test_each_small_file_is_read_as_its_format() -> None:
    formats = [(upload.filename, report(upload, None).file.format) for upload in warmup.uploads()]
    assert formats == [
        ("warm.stl", "stl"),
        ("warm.ply", "ply"),
        ("warm.obj", "obj"),
        ("ascii.stl", "stl"),
        ("ascii.ply", "ply"),
        ("polygons.obj", "obj"),
        ("polygons.off", "off"),
        ("warm.glb", "glb"),
        ("warm.3mf", "3mf"),
        ("warm.zip", "obj"),
        ("warm.gltf", "gltf"),
    ]


def test_polygons_are_triangulated_and_the_gltf_is_the_tetrahedron() -> None:
    by_name = {upload.filename: upload for upload in warmup.uploads()}
    polygons = report(by_name["polygons.obj"], None)
    assert (polygons.source_faces, polygons.faces) == (3, 5)  # two quads, two triangles each
    assert report(by_name["warm.glb"], None).faces == 4
    tetrahedron = report(by_name["warm.gltf"], None)
    assert (tetrahedron.faces, tetrahedron.watertight, tetrahedron.orientation) == (
        4,
        True,
        "outward",
    )


def test_the_warm_up_runs() -> None:
    warmup.warm()  # every job on every small file: none refuses its file


#: In a fresh process that imported the app, as a server has: the jobs that may run in the
#: server while the workers start, each on the small files they are let take. None may load
#: numba or trimesh (seconds, and their memory, in the server itself).
IN_SERVER = r"""
import sys
import app.main
from app.mesh import warmup, work
from app.web.workers import _STARTUP_JOBS
import mesh_normal.kernels as kernels

tetra = [u for u in warmup.uploads() if u.filename in ("warm.stl", "warm.obj")]
small = [*tetra, *(u for u in warmup.uploads() if u.filename == "ascii.stl")]
open_box = warmup.Upload(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\n", "open.obj")
from app.calculator import batch
assert set(_STARTUP_JOBS) == {work.report, work.fix, work.normals, batch.job}, _STARTUP_JOBS
assert batch.job(b'{"triangles": [[[0, 0, 0], [1, 0, 0], [0, 1, 0]]] }').startswith(b'{"results"')
for upload in [*small, open_box]:
    assert warmup.small_file(upload), upload.filename
    work.report(upload, None)
    work.report(upload, 1e-6)
    work.fix(upload, "obj", None)
    assert warmup.small_face_normals(upload, "face", "angle", 30.0)
    work.normals(upload, "face", "angle", 30.0)
assert not kernels._numba_loaded and "numba" not in sys.modules, "numba loaded"
assert "trimesh" not in sys.modules, "trimesh imported"
print("ok")
"""


def test_the_jobs_run_in_the_server_load_neither_numba_nor_trimesh() -> None:
    done = subprocess.run(
        [sys.executable, "-c", IN_SERVER], cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


def test_only_small_files_read_without_trimesh_run_in_the_server() -> None:
    tetra = warmup.uploads()[2]  # warm.obj
    assert tetra.filename == "warm.obj" and warmup.small_file(tetra, None)
    padded = warmup.Upload(tetra.data + b"#" * warmup.SMALL_FILE_BYTES, "warm.obj")
    assert not warmup.small_file(padded, None)
    by_name = {upload.filename: upload for upload in warmup.uploads()}
    assert not warmup.small_file(by_name["warm.glb"])  # trimesh's glTF reader
    assert not warmup.small_file(by_name["polygons.obj"])  # polygons: numba's triangulation
    assert not warmup.small_file(by_name["warm.ply"])  # PLY and OFF may hold polygons
    assert warmup.small_file(by_name["warm.stl"]) and warmup.small_file(by_name["ascii.stl"])
    assert not warmup.small_file(by_name["warm.3mf"])
    assert not warmup.small_file(by_name["warm.zip"])
    several = [upload for upload in warmup.uploads() if upload.parts]
    assert several and not warmup.small_file(several[0])
    assert not warmup.small_face_normals(tetra, "vertex", "angle", 30.0)  # loads numba
    assert warmup.small_face_normals(tetra, "face", "angle", 30.0)
