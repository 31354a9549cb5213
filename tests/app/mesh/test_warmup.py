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
