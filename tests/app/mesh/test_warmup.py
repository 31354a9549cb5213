"""app/mesh/warmup.py: a worker loads everything a job needs before its first job."""

from __future__ import annotations

import json
import subprocess
import sys

from app.mesh import warmup
from app.mesh.work import report
from tests.paths import ROOT

#: In a fresh process: the modules after the warm-up, then the ones that a job on every test
#: file (report, face, vertex and corner normals, the fix) imported besides. A module a job
#: imports first is memory the worker takes at its first such job, and keeps.
COVERAGE = """
import json, sys
from pathlib import Path
from app.mesh import warmup, work
from app.mesh.uploads import Upload
warmup.warm()
warmed = set(sys.modules)

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

jobs = 0
for upload in uploads():
    for job in (
        lambda: work.report(upload, None),
        lambda: work.normals(upload, "face", "angle", 30.0),
        lambda: work.normals(upload, "vertex", "angle", 30.0),
        lambda: work.normals(upload, "corner", "angle", 30.0),
        lambda: work.fix(upload, None, None),
    ):
        try:
            job()
        except Exception as error:  # a file the readers refuse: its modules ran as far as it got
            if type(error).__name__ != "ApiError":
                raise
        jobs += 1
print(json.dumps({"jobs": jobs, "imported": sorted(set(sys.modules) - warmed)}))
"""


def test_the_jobs_on_every_test_file_import_nothing_the_warm_up_left_out() -> None:
    result = subprocess.run(
        [sys.executable, "-c", COVERAGE],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    last = json.loads(result.stdout.strip().splitlines()[-1])
    assert last["jobs"] > 100 and last["imported"] == []


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
