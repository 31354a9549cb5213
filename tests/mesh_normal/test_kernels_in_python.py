"""Small calls run the kernels' Python source before numba is loaded: the same bits as compiled.

One fresh interpreter computes everything twice: first with numba never imported (every call
in Python, whatever its size), then after :func:`mesh_normal.kernels.load_numba` (every call
compiled). Each result is a fingerprint of every array's bytes and every float's repr: the
report of each test file, and the face geometry, orientation and topology of meshes made to
reach every branch (slivers retaken at the largest corner, degenerate faces, duplicated and
unused vertices, non-manifold edges, flipped faces, several shells, float32 coordinates, and
coordinates near the ends of the double range, which the kernels scale).
"""

from __future__ import annotations

import json
import subprocess
import sys

from mesh_normal.kernels import PYTHON_ELEMENTS
from tests.paths import ROOT

SCRIPT = r"""
import dataclasses, hashlib, json, sys
from pathlib import Path

import numpy as np

import mesh_normal as mn
from mesh_normal import kernels
from mesh_normal.analysis import analyse_mesh, build_report
from mesh_normal.orientation import orient
from mesh_normal.topology import mesh_topology

kernels.PYTHON_ELEMENTS = 10**9  # every call in Python until numba is loaded
for made in kernels._KERNELS:
    if made.python:  # the visibility kernels too, whatever their own limit
        made.python = 10**9
TRIANGLES = (
    "ant.ply", "colors_meshlab.ply", "cow.obj", "cube.obj", "multibody.stl", "nut.ply",
    "soup.stl", "sphere.ply", "two_objects.obj", "two_objects_mixed_case_names.stl",
)


def fingerprint(value):
    if isinstance(value, np.ndarray):
        data = np.ascontiguousarray(value)
        return f"{data.dtype}{data.shape}:" + hashlib.sha256(data.tobytes()).hexdigest()
    if dataclasses.is_dataclass(value):
        return {f.name: fingerprint(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if hasattr(value, "model_dump_json"):
        return value.model_dump_json()
    if isinstance(value, (list, tuple)):
        return [fingerprint(item) for item in value]
    if hasattr(value, "__len__") and hasattr(value, "__getitem__") and not isinstance(value, str):
        return [fingerprint(value[i]) for i in range(len(value))]
    return repr(value)


def meshes():
    rng = np.random.default_rng(13)
    for seed in range(12):
        count = int(rng.integers(4, 60))
        vertices = rng.standard_normal((count, 3))
        vertices[rng.integers(0, count, 3)] = vertices[0]  # duplicated points
        faces = rng.integers(0, count, (int(rng.integers(1, 120)), 3))
        if seed % 3 == 0:  # slivers: a third corner almost on the line of the first two
            t = rng.random(len(faces))[:, None]
            a, b = vertices[faces[:, 0]], vertices[faces[:, 1]]
            sliver = a + t * (b - a) + 1e-9 * rng.standard_normal((len(faces), 3))
            vertices = np.vstack([vertices, sliver])
            faces[:, 2] = count + np.arange(len(faces))
        scale = [1.0, 1e-300, 1e300, 2.0**-1070][seed % 4]
        yield f"random {seed}", vertices * scale, faces
    # Closed shells, some faces flipped, a shell inside another, float32 coordinates.
    tetra = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    sides = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    yield "nested", np.vstack([tetra, 0.1 + 0.2 * tetra]), np.vstack([sides, sides[:, ::-1] + 4])
    octa = np.array([[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
    octa_faces = np.array(
        [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    )
    flipped = octa_faces.copy()
    flipped[[1, 6]] = flipped[[1, 6], ::-1]
    yield "octahedron, two flipped", octa.astype(np.float32).astype(np.float64) * 0.3, flipped
    yield "open fan", tetra, sides[:3]
    pyramid = np.vstack([tetra, [[0.5, 0.5, -1]]])
    yield "a non-manifold edge", pyramid, np.vstack([sides, [[0, 1, 4]]])


def results():
    found = {}
    for path in sorted(Path("tests/data").glob("*")):
        if path.name in TRIANGLES:  # polygons are measured by kernels that load numba
            data = path.read_bytes()
            mesh = mn.read_mesh(data, path.name)
            report = build_report(analyse_mesh(mesh, path.name, len(data)))
            found[path.name] = report.model_dump_json()
    for name, vertices, faces in meshes():
        geometry = mn.face_geometry(vertices, faces)
        found[name] = {
            "geometry": fingerprint(geometry),
            "normals": fingerprint(mn.face_normals(geometry)),
            "mesh normals": fingerprint(mn.face_normals(vertices, faces)),  # the one-pass kernel
            "orient": fingerprint(orient(geometry)),
            "topology": fingerprint(mesh_topology(faces, len(vertices))),
        }
    return found


in_python = results()
assert "numba" not in sys.modules, "a kernel loaded numba"
kernels.load_numba()
compiled = results()
assert any(kernel.signatures for kernel in kernels._KERNELS), "nothing was compiled"
print(json.dumps({"python": in_python, "compiled": compiled}))
"""


def test_python_and_compiled_kernels_give_the_same_bits() -> None:
    completed = subprocess.run(
        [sys.executable, "-c", SCRIPT], cwd=ROOT, capture_output=True, text=True, check=False
    )
    assert completed.returncode == 0, completed.stderr[-3000:]
    found = json.loads(completed.stdout.splitlines()[-1])
    python, compiled = found["python"], found["compiled"]
    assert len(python) == 26 and python.keys() == compiled.keys()  # 10 files, 16 meshes
    for name in python:
        assert python[name] == compiled[name], name


def test_a_tiny_mesh_is_reported_without_numba_and_a_larger_one_loads_it() -> None:
    script = (
        "import sys\n"
        "import numpy as np\n"
        "import mesh_normal as mn\n"
        "tetra = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]\n"
        "print(mn.orient(tetra, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]).orientation)\n"
        "assert 'numba' not in sys.modules, 'numba was imported for 4 faces'\n"
        f"faces = np.zeros(({PYTHON_ELEMENTS} // 3 + 1, 3), dtype=np.intp)\n"
        "faces[:, 1:] = [1, 2]\n"
        "mn.orient(tetra, faces)\n"
        "assert 'numba' in sys.modules, 'numba was not loaded for a large call'\n"
    )
    completed = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, check=False
    )
    assert completed.returncode == 0, completed.stderr[-3000:]
    assert completed.stdout == "outward\n"


def test_compile_kernels_compiles_them_although_its_meshes_are_tiny() -> None:
    script = (
        "import sys\n"
        "from mesh_normal import kernels\n"
        "from mesh_normal.precompile import compile_kernels\n"
        "compile_kernels()\n"
        "assert 'numba' in sys.modules\n"
        "assert any(k.signatures for k in kernels._KERNELS), 'nothing compiled'\n"
    )
    completed = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, check=False
    )
    assert completed.returncode == 0, completed.stderr[-3000:]
