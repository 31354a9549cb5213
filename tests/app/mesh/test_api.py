"""POST /api/mesh, /api/mesh/normals and /api/mesh/fix: reports, normals, fixes and errors."""

from __future__ import annotations

import io
import json
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any, get_args

import numpy as np
import pytest
from fastapi.testclient import TestClient

from app import config
from app.main import create_app
from app.mesh.api import FixFormat
from app.mesh.page import FIX_FORMATS
from mesh_normal import face_normals, vertex_normals
from mesh_normal.files import FORMATS, WRITABLE, read_mesh
from tests.conftest import assert_error
from tests.meshes import (
    CUBE_OBJ,
    CUBE_OBJ_FACES,
    CUBE_OBJ_POINTS,
    CUBE_ONE_FLIPPED_OBJ,
    HUGE_TETRA_OBJ,
    OPEN_BOX_OBJ,
    TETRA_FACES,
    TETRA_OBJ,
    TETRA_OBJ_POINTS,
    TETRA_VERTICES,
    ascii_stl,
    obj_as_solids,
    obj_text,
)
from tests.paths import DATA

TETRA_CORNERS = TETRA_VERTICES[TETRA_FACES]


def upload(client: TestClient, path: str, text: str | bytes, name: str = "mesh.obj", **params: str):  # type: ignore[no-untyped-def]
    data = text.encode() if isinstance(text, str) else text
    return client.post(path, params=params, files={"file": (name, data)})


def test_cube_is_clean(client: TestClient) -> None:
    response = upload(client, "/api/mesh", CUBE_OBJ, "cube.obj")
    assert response.status_code == 200, response.text
    report = response.json()
    assert report["file"] == {"name": "cube.obj", "format": "obj", "bytes": len(CUBE_OBJ)}
    assert (report["vertices"], report["faces"], report["source_faces"]) == (8, 12, 12)
    assert report["area"] == 6.0
    assert report["volume"] == pytest.approx(1.0, rel=1e-15)
    assert report["watertight"] is True and report["winding_consistent"] is True
    assert report["orientation"] == "outward"
    assert (report["boundary_edges"], report["nonmanifold_edges"], report["components"]) == (
        0,
        0,
        1,
    )
    assert report["degenerate_faces"] == 0 and report["degenerate_face_indices"] == []
    assert report["fix"]["faces_flipped"] == 0
    assert report["problems"] == []
    assert report["bounds"] == {"min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]}


def test_tetrahedron_volume_and_area(client: TestClient) -> None:
    report = upload(client, "/api/mesh", TETRA_OBJ).json()
    assert report["volume"] == pytest.approx(1 / 6, rel=1e-15)
    assert report["area"] == pytest.approx(1.5 + math.sqrt(3) / 2, rel=1e-15)


def test_one_flipped_face_is_found_and_named(client: TestClient) -> None:
    report = upload(client, "/api/mesh", CUBE_ONE_FLIPPED_OBJ).json()
    assert report["winding_consistent"] is False
    assert report["orientation"] == "mixed"
    assert report["volume"] is None
    assert report["fix"]["faces_flipped"] == 1
    assert report["fix"]["flipped_face_indices"] == [0]
    codes = [item["code"] for item in report["problems"]]
    assert codes[0] == "winding"
    assert report["problems"][0]["severity"] == "error"


def test_inward_mesh(client: TestClient) -> None:
    inward = obj_text(CUBE_OBJ_POINTS, [face[::-1] for face in CUBE_OBJ_FACES])
    report = upload(client, "/api/mesh", inward).json()
    assert report["orientation"] == "inward"
    assert report["winding_consistent"] is True
    assert report["volume"] == pytest.approx(-1.0, rel=1e-15)
    assert report["fix"]["faces_flipped"] == 12
    assert [item["code"] for item in report["problems"]] == ["inward"]


def test_open_box(client: TestClient) -> None:
    report = upload(client, "/api/mesh", OPEN_BOX_OBJ).json()
    assert report["watertight"] is False
    assert report["boundary_edges"] == 4
    assert report["volume"] is None
    assert report["orientation"] == "outward"
    assert "open" in [item["code"] for item in report["problems"]]


def test_degenerate_faces_are_counted_in_file_order(client: TestClient) -> None:
    text = TETRA_OBJ + "f 1 1 2\nf 1 2 2\nv 2 0 0\nf 1 2 5\n"
    report = upload(client, "/api/mesh", text).json()
    assert report["degenerate_faces"] == 3
    assert report["degenerate_face_indices"] == [4, 5, 6]
    assert report["repeated_index_faces"] == 2
    assert report["problems"][0]["code"] in ("nonmanifold", "winding", "degenerate")
    assert "degenerate" in [item["code"] for item in report["problems"]]


def test_two_components_and_an_unused_vertex(client: TestClient) -> None:
    shifted = "".join(f"v {x + 5} {y} {z}\n" for x in (0, 1) for y in (0, 1) for z in (0, 1))
    faces = CUBE_OBJ_FACES + [tuple(i + 8 for i in face) for face in CUBE_OBJ_FACES]
    report = upload(
        client, "/api/mesh", obj_text(CUBE_OBJ_POINTS + shifted + "v 9 9 9\n", faces)
    ).json()
    assert report["components"] == 2
    assert report["unused_vertices"] == 1
    assert report["volume"] == pytest.approx(2.0)
    assert len(report["fix"]["components"]) == 2


def test_raw_body_with_a_filename(client: TestClient) -> None:
    response = client.post(
        "/api/mesh",
        params={"filename": "cube.obj"},
        content=CUBE_OBJ.encode(),
        headers={"content-type": "application/octet-stream"},
    )
    assert response.status_code == 200, response.text
    assert response.json()["file"]["name"] == "cube.obj"


def test_sample_ply_matches_trimesh(client: TestClient) -> None:
    trimesh = pytest.importorskip("trimesh")
    path = DATA / "ant.ply"
    report = upload(client, "/api/mesh", path.read_bytes(), "ant.ply").json()
    theirs = trimesh.load(path, process=False)
    assert report["faces"] == len(theirs.faces)
    assert report["vertices"] == len(theirs.vertices)
    assert report["area"] == pytest.approx(theirs.area, rel=1e-12)
    assert report["watertight"] == theirs.is_watertight
    if report["volume"] is not None:
        assert report["volume"] == pytest.approx(theirs.volume, rel=1e-9)


def test_stored_face_normals_are_compared(client: TestClient) -> None:
    from mesh_normal.files import write_mesh

    mesh = read_mesh(CUBE_OBJ.encode(), "cube.obj")
    stl = write_mesh(mesh.vertices, mesh.faces, "stl")
    report = upload(client, "/api/mesh", stl, "cube.stl").json()
    stored = report["file_normals"]
    assert stored["kind"] == "face"
    assert stored["compared"] == 12 and stored["agreeing"] == 12 and stored["opposite"] == 0
    assert report["vertices"] == 8  # STL corners are welded


@pytest.mark.parametrize(
    ("kind", "shape"), [("face", (12, 3)), ("vertex", (8, 3)), ("corner", (12, 3, 3))]
)
def test_normals_as_npy(client: TestClient, kind: str, shape: tuple[int, ...]) -> None:
    response = upload(client, "/api/mesh/normals", CUBE_OBJ, "cube.obj", kind=kind, format="npy")
    assert response.status_code == 200, response.text
    assert 'filename="cube-' + kind + '-normals.npy"' in response.headers["content-disposition"]
    array = np.load(io.BytesIO(response.content), allow_pickle=False)
    assert array.dtype == np.float64 and array.shape == shape
    mesh = read_mesh(CUBE_OBJ.encode(), "cube.obj")
    if kind == "face":
        np.testing.assert_array_equal(array, face_normals(mesh.vertices, mesh.faces).normals)
    if kind == "vertex":
        np.testing.assert_array_equal(array, vertex_normals(mesh.vertices, mesh.faces).normals)
    if kind == "corner":  # a cube's edges are 90° creases: every corner is its face's normal
        faces = face_normals(mesh.vertices, mesh.faces).normals
        np.testing.assert_allclose(array, np.repeat(faces[:, None], 3, axis=1), atol=1e-15)


def test_normals_as_json_and_csv(client: TestClient) -> None:
    body = upload(client, "/api/mesh/normals", TETRA_OBJ, kind="vertex", weighting="area").json()
    assert body["kind"] == "vertex" and body["weighting"] == "area"
    assert body["shape"] == [4, 3] and body["missing"] == 0
    expected = vertex_normals(
        read_mesh(TETRA_OBJ.encode(), "t.obj").vertices,
        read_mesh(TETRA_OBJ.encode(), "t.obj").faces,
        "area",
    ).normals
    assert body["normals"] == expected.tolist()
    csv = upload(client, "/api/mesh/normals", TETRA_OBJ, kind="face", format="csv")
    assert csv.headers["content-type"].startswith("text/csv")
    lines = csv.text.strip().splitlines()
    assert lines[0] == "face,nx,ny,nz" and len(lines) == 5
    assert [float(x) for x in lines[1].split(",")[1:]] == [0.0, 0.0, -1.0]


def test_normals_query_errors(client: TestClient) -> None:
    assert_error(upload(client, "/api/mesh/normals", TETRA_OBJ, kind="edge"), 422, "kind")
    assert_error(upload(client, "/api/mesh/normals", TETRA_OBJ, weighting="mean"), 422, "weighting")
    assert_error(
        upload(client, "/api/mesh/normals", TETRA_OBJ, crease_angle="200"),
        422,
        "crease_angle",
        "at most 180",
    )
    assert_error(
        upload(client, "/api/mesh/normals", TETRA_OBJ, crease_angle="nan"), 422, "crease_angle"
    )
    assert_error(upload(client, "/api/mesh/normals", TETRA_OBJ, format="xml"), 422, "format")


def test_fix_flips_the_one_face_and_keeps_the_vertices(client: TestClient) -> None:
    response = upload(client, "/api/mesh/fix", CUBE_ONE_FLIPPED_OBJ, "box.obj")
    assert response.status_code == 200, response.text
    assert response.headers["x-faces-flipped"] == "1"
    assert response.headers["x-component-faces-flipped"] == "0:1"
    assert response.headers["x-orientation-before"] == "mixed"
    assert 'filename="box-fixed.obj"' in response.headers["content-disposition"]
    fixed = read_mesh(response.content, "fixed.obj")
    original = read_mesh(CUBE_ONE_FLIPPED_OBJ.encode(), "box.obj")
    np.testing.assert_array_equal(fixed.vertices, original.vertices)
    report = upload(client, "/api/mesh", response.content, "fixed.obj").json()
    assert report["orientation"] == "outward" and report["winding_consistent"] is True


@pytest.mark.parametrize("fmt", ["ply", "stl", "obj"])
def test_fix_writes_each_format(client: TestClient, fmt: str) -> None:
    response = upload(client, "/api/mesh/fix", OPEN_BOX_OBJ, "box.obj", format=fmt)
    assert response.status_code == 200, response.text
    again = upload(client, "/api/mesh", response.content, f"fixed.{fmt}").json()
    assert again["faces"] == 10 and again["boundary_edges"] == 4


@pytest.mark.parametrize("fmt", ["ply", "stl", "obj"])
def test_fix_of_stl_solids_names_the_objects_it_leaves_out(client: TestClient, fmt: str) -> None:
    """Every file the fix writes is one mesh (binary STL holds one): X-Dropped says the
    division into solids is gone; the triangles are all there, the turned cube turned back."""
    from tests.mesh_normal.mesh.report.test_objects import two_cubes

    data = obj_as_solids(two_cubes([face[::-1] for face in CUBE_OBJ_FACES], "turned"))
    response = upload(client, "/api/mesh/fix", data, "two.stl", format=fmt)
    assert response.status_code == 200, response.text
    title = FORMATS[fmt].title
    # OBJ keeps them, as o statements.
    assert response.headers.get("x-dropped") == (
        None if fmt == "obj" else f"the division into 2 objects (the {title} written is one mesh)"
    )
    assert response.headers["x-faces-flipped"] == "12"
    again = upload(client, "/api/mesh", response.content, f"fixed.{fmt}").json()
    assert again["faces"] == 24 and again["orientation"] == "outward"


def test_fix_of_one_object_drops_nothing(client: TestClient) -> None:
    for data, name in (
        (ascii_stl(TETRA_CORNERS, np.zeros((4, 3))), "t.stl"),
        ("o only\n" + TETRA_OBJ, "t.obj"),
    ):
        response = upload(client, "/api/mesh/fix", data, name)
        assert response.status_code == 200, response.text
        assert "x-dropped" not in response.headers


def test_the_fix_formats_are_the_librarys_writable_formats() -> None:
    # FixFormat stays a Literal for FastAPI and mypy: this keeps it in step with the table.
    assert get_args(FixFormat) == WRITABLE
    assert FIX_FORMATS == WRITABLE


@pytest.mark.parametrize("fmt", WRITABLE)
def test_fix_answers_with_the_tables_media_type(client: TestClient, fmt: str) -> None:
    response = upload(client, "/api/mesh/fix", TETRA_OBJ, format=fmt)
    assert response.status_code == 200, response.text
    assert response.headers["content-type"] == FORMATS[fmt].media_type
    default = upload(client, "/api/mesh/fix", response.content, f"fixed.{fmt}")
    assert default.headers["content-type"] == FORMATS[fmt].media_type  # the upload's format


def test_fix_documents_the_writable_formats(client: TestClient) -> None:
    fix = client.get("/openapi.json").json()["paths"]["/api/mesh/fix"]["post"]
    (parameter,) = [p for p in fix["parameters"] if p["name"] == "format"]
    assert parameter["description"].startswith("ply, stl, obj, off or glb; default: ")
    # PLY and OFF share application/octet-stream: each media type once.
    media = list(dict.fromkeys(FORMATS[n].media_type for n in WRITABLE))
    assert list(fix["responses"]["200"]["content"]) == media


def test_missing_and_empty_file(client: TestClient) -> None:
    assert_error(
        client.post("/api/mesh", files={"other": ("a.obj", b"v 0 0 0")}), 422, "file", "multipart"
    )
    assert_error(client.post("/api/mesh", data={"file": "v 0 0 0"}), 422, "file")
    assert_error(upload(client, "/api/mesh", b"", "empty.obj"), 422, "file", "empty")
    assert_error(
        client.post("/api/mesh", content=b"", headers={"content-type": "application/octet-stream"}),
        422,
        "file",
        "empty",
    )


@pytest.mark.parametrize(
    ("name", "data", "status"),
    [
        ("mesh.xyz", b"1 2 3\n", 415),
        ("mesh.stl", b"\0" * 80 + (1000).to_bytes(4, "little") + b"\0" * 50, 400),
        ("mesh.obj", TETRA_OBJ_POINTS + "f 1 2 9\n", 400),
        ("mesh.obj", TETRA_OBJ_POINTS + "f 1 2 -9\n", 400),
        ("mesh.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 400),
        ("mesh.obj", TETRA_OBJ_POINTS, 400),
        ("mesh.ply", b"ply\nformat ascii 1.0\nelement vertex 3\n", 400),
    ],
)
def test_broken_files_are_4xx_naming_the_problem(
    client: TestClient, name: str, data: str | bytes, status: int
) -> None:
    for path in ("/api/mesh", "/api/mesh/normals", "/api/mesh/fix"):
        assert_error(upload(client, path, data, name), status, "file")


@pytest.fixture(scope="module")
def small_limit() -> Iterator[TestClient]:
    with TestClient(create_app(upload_limit=2000), raise_server_exceptions=False) as client:
        yield client


def test_upload_limit_declared(small_limit: TestClient) -> None:
    big = CUBE_OBJ + "# padding\n" * 400
    body = assert_error(upload(small_limit, "/api/mesh", big), 413, None, "larger than")
    assert "1.953 KB" in body["error"]
    assert upload(small_limit, "/api/mesh", CUBE_OBJ).status_code == 200
    assert "up to 1.953 KB" in small_limit.get("/mesh").text  # the page states the app's limit


def test_upload_limit_streamed(small_limit: TestClient) -> None:
    def chunks() -> Iterator[bytes]:
        for _ in range(10):
            yield b"# padding\n" * 50

    response = small_limit.post(
        "/api/mesh", content=chunks(), headers={"content-type": "application/octet-stream"}
    )
    assert_error(response, 413, None, "larger than")


def test_upload_limit_from_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    from app.config import upload_limit

    monkeypatch.setenv("MESH_UPLOAD_LIMIT_MB", "0.5")
    assert upload_limit() == 512 * 1024
    monkeypatch.delenv("MESH_UPLOAD_LIMIT_MB")
    assert upload_limit() == 200 * 1024 * 1024


def test_report_is_strict_json(client: TestClient) -> None:
    text = upload(client, "/api/mesh", CUBE_ONE_FLIPPED_OBJ).text
    json.loads(text, parse_constant=lambda name: pytest.fail(f"{name} in the report"))


def test_coordinates_near_1e200_give_a_null_area_never_nan(client: TestClient) -> None:
    for text in (
        upload(client, "/api/mesh", HUGE_TETRA_OBJ).text,
        upload(client, "/api/mesh", HUGE_TETRA_OBJ + "v 5 5 5\n").text,  # and an unused vertex
    ):
        report = json.loads(text, parse_constant=lambda name: pytest.fail(f"{name} in the report"))
        assert report["area"] is None and report["volume"] is None
        assert report["bounds"]["max"] == [1e200, 1e200, 1e200]


# --- the response model: /openapi.json documents every key of POST /api/mesh ---------------


def resolve(spec: dict[str, Any], node: dict[str, Any]) -> dict[str, Any]:
    """``node`` with its ``$ref`` followed, into #/components/schemas."""
    while "$ref" in node:
        node = spec["components"]["schemas"][node["$ref"].rsplit("/", 1)[-1]]
    return node


def undocumented(spec: dict[str, Any], node: dict[str, Any], value: Any, where: str) -> list[str]:
    """Where ``value`` (parsed JSON) has a key that the schema ``node`` does not document, or
    the schema lists a property or a required key that ``value`` lacks."""
    node = resolve(spec, node)
    if "anyOf" in node:  # an optional part: the branch that is not null
        if value is None:
            assert {"type": "null"} in node["anyOf"], where
            return []
        [node] = [resolve(spec, item) for item in node["anyOf"] if item != {"type": "null"}]
    if isinstance(value, dict):
        properties = node.get("properties", {})
        found = [f"{where}.{key}: not in the schema" for key in set(value) - set(properties)]
        found += [f"{where}.{key}: not in the report" for key in set(properties) - set(value)]
        found += [f"{where}.{key}: not required" for key in set(value) - set(node["required"])]
        for key in set(value) & set(properties):
            assert properties[key].get("description"), f"{where}.{key} has no description"
            found += undocumented(spec, properties[key], value[key], f"{where}.{key}")
        return found
    if isinstance(value, list):
        return [
            problem
            for index, item in enumerate(value)
            for problem in undocumented(spec, node["items"], item, f"{where}[{index}]")
        ]
    return []


def test_openapi_documents_every_key_of_the_report(client: TestClient) -> None:
    """A report with every optional part filled: bounds, file normals, components, problems."""
    from mesh_normal.files import write_mesh

    mesh = read_mesh(CUBE_ONE_FLIPPED_OBJ.encode(), "flipped.obj")
    stl = write_mesh(mesh.vertices, mesh.faces, "stl")
    report = upload(client, "/api/mesh", stl, "flipped.stl").json()
    assert report["bounds"] and report["file_normals"] and report["problems"]
    assert report["fix"]["components"] and report["notes"]
    spec = client.get("/openapi.json").json()
    response = spec["paths"]["/api/mesh"]["post"]["responses"]["200"]
    schema = response["content"]["application/json"]["schema"]
    assert resolve(spec, schema)["title"] == "MeshReport"
    assert undocumented(spec, schema, report, "report") == []
    # The schema's enumerations are the values the report holds.
    report_schema = resolve(spec, schema)["properties"]
    assert report["orientation"] in report_schema["orientation"]["enum"]
    file_info = resolve(spec, report_schema["file"])["properties"]
    # "memory" is the library's, for a mesh handed over as arrays (never an upload).
    formats = {"stl", "obj", "ply", "off", "glb", "gltf", "3mf", "memory"}
    assert set(file_info["format"]["enum"]) == formats


def test_openapi_documents_every_key_of_the_objects(client: TestClient) -> None:
    """The objects of a file with OBJ groups are documented and required key by key."""
    report = upload(client, "/api/mesh", (DATA / "two_objects.obj").read_bytes()).json()
    assert report["object_count"] == 2 and len(report["objects"]) == 2
    spec = client.get("/openapi.json").json()
    schema = {"$ref": "#/components/schemas/MeshReport"}
    assert undocumented(spec, schema, report, "report") == []
    item = resolve(spec, resolve(spec, schema)["properties"]["objects"]["items"])
    assert set(item["properties"]["orientation"]["enum"]) == {
        "outward",
        "inward",
        "mixed",
        "undetermined",
    }


def test_stl_solids_are_objects_like_obj_objects(client: TestClient) -> None:
    """The same two cubes (the second turned inside out) as two OBJ objects and as two ASCII
    STL solids: the same objects, with the same counts and verdicts."""
    from tests.mesh_normal.mesh.report.test_objects import two_cubes

    text = two_cubes([face[::-1] for face in CUBE_OBJ_FACES], "turned")
    obj = upload(client, "/api/mesh", text, "two.obj").json()
    stl = upload(client, "/api/mesh", obj_as_solids(text), "two.stl").json()
    assert stl["file"]["format"] == "stl"
    assert stl["object_count"] == obj["object_count"] == 2
    assert [item["name"] for item in stl["objects"]] == ["left", "turned"]
    assert stl["objects"] == obj["objects"]
    assert [item["orientation"] for item in stl["objects"]] == ["outward", "inward"]


def test_the_trimesh_multibody_stl_lists_both_bodies(client: TestClient) -> None:
    report = upload(client, "/api/mesh", (DATA / "multibody.stl").read_bytes(), "m.stl").json()
    assert report["object_count"] == 2
    assert [(item["name"], item["faces"]) for item in report["objects"]] == [
        ("bodyB", 12),
        ("bodyA", 20),
    ]
    assert all(item["closed"] for item in report["objects"])
    assert report["winding_consistent"] is False  # as trimesh finds for each body
    assert any("Joined 2 ASCII STL solids" in note for note in report["notes"])


def test_a_wrong_key_is_found_by_the_schema_check(client: TestClient) -> None:
    """The check above can fail: a renamed or missing key is reported."""
    spec = client.get("/openapi.json").json()
    schema = {"$ref": "#/components/schemas/MeshReport"}
    report = upload(client, "/api/mesh", CUBE_OBJ).json()
    report["fix"]["flipped"] = report["fix"].pop("faces_flipped")
    assert sorted(undocumented(spec, schema, report, "report")) == [
        "report.fix.faces_flipped: not in the report",
        "report.fix.flipped: not in the schema",
        "report.fix.flipped: not required",
    ]


def test_mesh_work_runs_off_the_event_loop(monkeypatch: pytest.MonkeyPatch) -> None:
    """While one upload is being analysed, the server answers other requests."""
    import asyncio
    import threading

    import httpx

    import app.mesh.work as work
    from app.config import Settings
    from tests.conftest import EXAMPLE_QUERY

    started, release = threading.Event(), threading.Event()
    real = work.analyse_mesh

    def slow(*args, **kwargs):  # type: ignore[no-untyped-def]
        started.set()
        release.wait(10)
        return real(*args, **kwargs)

    monkeypatch.setattr(work, "analyse_mesh", slow)  # in a thread: the server's own process

    async def scenario() -> None:
        transport = httpx.ASGITransport(app=create_app(settings=Settings(in_process=True)))
        async with httpx.AsyncClient(transport=transport, base_url="http://test") as client:
            pending = asyncio.create_task(
                client.post("/api/mesh", files={"file": ("cube.obj", CUBE_OBJ.encode())})
            )
            assert await asyncio.to_thread(started.wait, 10)
            quick = await client.get("/api/normal", params=EXAMPLE_QUERY)
            assert quick.status_code == 200
            assert not pending.done()
            release.set()
            assert (await pending).json()["faces"] == 12

    # In a thread of its own: Playwright's sync API may hold an event loop in this one.
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(1) as pool:
        pool.submit(lambda: asyncio.run(scenario())).result(timeout=60)


@pytest.mark.skipif(not Path("/proc/self/fd").exists(), reason="needs /proc")
def test_no_upload_outlives_its_request(client: TestClient) -> None:
    """A large upload leaves no file open afterwards (none is made: it is kept in memory)."""
    import os

    big = CUBE_OBJ + "# padding to pass the 1 MB spooling threshold\n" * 40_000
    assert len(big) > 1024 * 1024
    upload(client, "/api/mesh", CUBE_OBJ)  # warm up: whatever the first request opens for good
    before = set(os.listdir("/proc/self/fd"))
    for path in ("/api/mesh", "/mesh"):
        assert upload(client, path, big).status_code == 200
    assert set(os.listdir("/proc/self/fd")) <= before


# --- regressions found in review ---------------------------------------------------------------


def test_stored_normals_that_are_not_finite_are_unusable_not_nan(client: TestClient) -> None:
    import struct

    from mesh_normal.files import write_mesh

    mesh = read_mesh(TETRA_OBJ.encode(), "t.obj")
    stl = bytearray(write_mesh(mesh.vertices, mesh.faces, "stl"))
    stl[84:88] = struct.pack("<f", float("inf"))  # the first facet normal's x
    response = upload(client, "/api/mesh", bytes(stl), "t.stl")
    json.loads(response.text, parse_constant=lambda name: pytest.fail(f"{name} in the report"))
    stored = response.json()["file_normals"]
    assert (stored["stored"], stored["compared"], stored["unusable"]) == (4, 3, 1)
    assert stored["agreeing"] == 3


def test_areas_near_the_double_maximum_keep_the_page_data_finite(client: TestClient) -> None:
    huge = "v 0 0 0\nv 1.8e154 0 0\nv 0 1.8e154 0\nf 1 2 3\n"
    response = upload(client, "/mesh", huge, part="report")
    assert response.status_code == 200
    assert "Infinity" not in response.text and "NaN" not in response.text


def test_stl_cannot_hold_coordinates_beyond_float32(client: TestClient) -> None:
    big = "v 0 0 0\nv 1e300 0 0\nv 0 1e300 0\nf 1 2 3\n"
    assert_error(upload(client, "/api/mesh/fix", big, format="stl"), 422, "format", "PLY or OBJ")
    assert upload(client, "/api/mesh/fix", big, format="ply").status_code == 200


def test_a_byte_order_mark_is_not_part_of_the_first_line(client: TestClient) -> None:
    text = "\ufeffv 9 9 9\n" + TETRA_OBJ_POINTS + "f -3 -2 -1\n"
    report = upload(client, "/api/mesh", text.encode("utf-8")).json()
    assert (report["vertices"], report["unused_vertices"]) == (5, 2)


def test_an_ascii_stl_may_name_its_solid_with_keywords(client: TestClient) -> None:
    text = (
        "solid part with vertex colors and facet data\nfacet normal 0 0 1\nouter loop\n"
        "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
        "endsolid part with vertex colors and facet data\n"
    )
    assert upload(client, "/api/mesh", text, "a.stl").json()["faces"] == 1


def test_ascii_ply_face_indices_must_be_whole_numbers(client: TestClient) -> None:
    ply = (
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
        "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 1.9\n"
    )
    assert_error(upload(client, "/api/mesh", ply, "p.ply"), 400, "file", "whole number")


def test_other_multipart_fields_do_not_get_in_the_way(client: TestClient) -> None:
    response = client.post(
        "/api/mesh", files=[("file", ("t.obj", TETRA_OBJ.encode())), ("other", ("b.txt", b"x"))]
    )
    assert response.status_code == 200 and response.json()["faces"] == 4


def test_a_malformed_multipart_body_is_one_sentence(client: TestClient) -> None:
    response = client.post(
        "/api/mesh",
        content=b"--x\r\nnot a part",
        headers={"content-type": "multipart/form-data; boundary=x"},
    )
    assert response.status_code in (400, 422)
    assert_error(response, response.status_code, "file")


def test_a_one_sided_part_is_not_offered_a_winding_fix(client: TestClient) -> None:
    strip = 12
    points, faces = [], []
    for i in range(strip):
        t = 2 * math.pi * i / strip
        for s in (-0.3, 0.3):
            radius = 1 + s * math.cos(t / 2)
            points.append(f"v {radius * math.cos(t)} {radius * math.sin(t)} {s * math.sin(t / 2)}")
    for i in range(strip):
        a, b = 2 * i, 2 * i + 1
        c, d = (2 * i + 2, 2 * i + 3) if i < strip - 1 else (1, 0)  # the half twist
        faces += [(a, b, d), (a, d, c)]
    report = upload(client, "/api/mesh", obj_text("\n".join(points) + "\n", faces)).json()
    codes = [item["code"] for item in report["problems"]]
    assert "nonorientable" in codes and "winding" not in codes


@pytest.mark.parametrize(
    ("size", "area", "title"),
    [
        ("1e120", True, "The total volume is beyond the double range"),
        ("1e200", False, "The total area and volume are beyond the double range"),
    ],
)
def test_values_beyond_the_double_range_are_null_and_explained(
    client: TestClient, size: str, area: bool, title: str
) -> None:
    points = f"v 0 0 0\nv {size} 0 0\nv 0 {size} 0\nv 0 0 {size}\n"
    report = upload(client, "/api/mesh", points + TETRA_OBJ[len(TETRA_OBJ_POINTS) :]).json()
    assert report["volume"] is None and (report["area"] is not None) == area
    assert report["watertight"] and report["orientation"] == "outward"
    assert [(item["code"], item["title"]) for item in report["problems"]] == [("overflow", title)]


def test_the_page_refuses_a_large_upload_with_its_own_html(small_limit: TestClient) -> None:
    big = CUBE_OBJ + "# padding\n" * 400
    response = upload(small_limit, "/mesh", big)
    assert response.status_code == 413
    assert response.headers["content-type"].startswith("text/html")
    assert "larger than 1.953 KB" in response.text


def test_a_trailing_slash_gets_the_upload_limit_too(client: TestClient) -> None:
    padded = CUBE_OBJ + "# padding past the 64 KB limit of other addresses\n" * 2000
    assert len(padded) > 64 * 1024
    response = upload(client, "/api/mesh/", padded)
    assert response.status_code == 200, response.text  # redirected to /api/mesh, not a 413
    assert response.json()["faces"] == 12


def test_stored_corner_and_vertex_normals_are_compared(client: TestClient) -> None:
    from mesh_normal import face_normals
    from mesh_normal.files.ply import ply_bytes

    mesh = read_mesh(CUBE_OBJ.encode(), "cube.obj")
    flat = face_normals(mesh.vertices, mesh.faces).normals  # a cube's corners: its faces'
    vn = "".join(f"vn {x!r} {y!r} {z!r}\n" for x, y, z in flat.tolist())
    faces = "".join(
        f"f {a + 1}//{k + 1} {b + 1}//{k + 1} {c + 1}//{k + 1}\n"
        for k, (a, b, c) in enumerate(mesh.faces.tolist())
    )
    corner = upload(client, "/api/mesh", CUBE_OBJ_POINTS + vn + faces).json()["file_normals"]
    assert corner["kind"] == "corner" and corner["compared"] == 36
    assert corner["agreeing"] == 36 and corner["opposite"] == 0

    smooth = vertex_normals(mesh.vertices, mesh.faces, "angle").normals
    ply = ply_bytes(mesh.vertices, mesh.faces, vertex_normals=-smooth)  # stored inside out
    vertex = upload(client, "/api/mesh", ply, "cube.ply").json()
    assert vertex["file_normals"]["kind"] == "vertex"
    assert vertex["file_normals"]["opposite"] == 8 and vertex["file_normals"]["agreeing"] == 0
    assert "file_normals" in [item["code"] for item in vertex["problems"]]


# --- the weld tolerance -----------------------------------------------------------------------


@pytest.fixture
def stepped() -> bytes:
    """The cube of six sides a float32 step apart, wound inward, as a float64 PLY."""
    from mesh_normal.files import write_mesh
    from tests.meshes import stepped_sides_cube

    vertices, faces = stepped_sides_cube()
    return write_mesh(vertices, faces[:, ::-1], "ply")


def test_the_weld_field_joins_the_sides(client: TestClient, stepped: bytes) -> None:
    plain = upload(client, "/api/mesh", stepped, "s.ply").json()
    assert plain["weld"] is None and plain["components"] == 6 and not plain["watertight"]
    response = client.post("/api/mesh", files={"file": ("s.ply", stepped)}, data={"weld": "1e-6"})
    report = response.json()
    assert (report["components"], report["watertight"], report["orientation"]) == (
        1,
        True,
        "inward",
    )
    assert report["weld"]["tolerance"] == 1e-6 and report["weld"]["joined_vertices"] == 40
    # A raw body takes it as a query parameter; an empty form field is off.
    raw = client.post("/api/mesh", content=stepped, params={"filename": "s.ply", "weld": "1e-6"})
    assert raw.json() == report
    empty = client.post("/api/mesh", files={"file": ("s.ply", stepped)}, data={"weld": " "})
    assert empty.json() == plain


def test_the_fix_uses_the_same_weld(client: TestClient, stepped: bytes) -> None:
    response = client.post(
        "/api/mesh/fix", files={"file": ("s.ply", stepped)}, data={"weld": "1e-6"}
    )
    assert response.status_code == 200, response.text
    assert response.headers["x-faces-flipped"] == "108" and response.headers["x-weld"] == "1e-06"
    assert response.headers["x-orientation-before"] == "inward"
    fixed, before = read_mesh(response.content, "f.ply"), read_mesh(stepped, "s.ply")
    np.testing.assert_array_equal(fixed.vertices, before.vertices)
    np.testing.assert_array_equal(fixed.faces, before.faces[:, [0, 2, 1]])
    again = client.post(
        "/api/mesh", files={"file": ("f.ply", response.content)}, data={"weld": "1e-6"}
    )
    assert again.json()["orientation"] == "outward" and again.json()["problems"] == []
    # Without the weld: six open sides, each seen from outside to face inward, turned too.
    plain = upload(client, "/api/mesh/fix", stepped, "s.ply")
    assert plain.headers["x-faces-flipped"] == "108" and "x-weld" not in plain.headers
    assert plain.headers["x-orientation-before"] == "inward"


@pytest.mark.parametrize("path", ["/api/mesh", "/api/mesh/fix"])
@pytest.mark.parametrize("value", ["-1e-6", "0.02", "nan", "inf", "abc", "1e400"])
def test_a_bad_weld_field_is_a_422_naming_it(client: TestClient, path: str, value: str) -> None:
    response = client.post(path, files={"file": ("c.obj", CUBE_OBJ.encode())}, data={"weld": value})
    assert_error(response, 422, "weld", "weld must be a number from 0 to 0.01", repr(value))


@pytest.mark.parametrize("path", ["/api/mesh", "/api/mesh/fix"])
@pytest.mark.parametrize("value", ["-1e-6", "0.02", "nan", "abc"])
def test_a_bad_weld_query_is_a_422_naming_it(client: TestClient, path: str, value: str) -> None:
    response = client.post(path, content=CUBE_OBJ.encode(), params={"weld": value})
    assert_error(response, 422, "weld", "weld")


def test_a_weld_given_twice_or_as_a_file_is_a_422(client: TestClient) -> None:
    twice = client.post(
        "/api/mesh",
        files={"file": ("c.obj", CUBE_OBJ.encode())},
        data={"weld": "1e-6"},
        params={"weld": "1e-6"},
    )
    assert_error(twice, 422, "weld", "given twice")
    as_file = client.post(
        "/api/mesh", files={"file": ("c.obj", CUBE_OBJ.encode()), "weld": ("w.txt", b"1e-6")}
    )
    assert_error(as_file, 422, "weld", "not a file")


def test_openapi_documents_the_weld(client: TestClient, stepped: bytes) -> None:
    spec = client.get("/openapi.json").json()
    for path in ("/api/mesh", "/api/mesh/fix"):
        operation = spec["paths"][path]["post"]
        form = operation["requestBody"]["content"]["multipart/form-data"]["schema"]
        assert form["properties"]["weld"]["maximum"] == 0.01
        assert "weld" in [item["name"] for item in operation["parameters"]]
    normals = spec["paths"]["/api/mesh/normals"]["post"]["requestBody"]["content"]
    assert "weld" not in normals["multipart/form-data"]["schema"]["properties"]
    report = client.post("/api/mesh", files={"file": ("s.ply", stepped)}, data={"weld": "1e-6"})
    schema = {"$ref": "#/components/schemas/MeshReport"}
    assert undocumented(spec, schema, report.json(), "report") == []


def test_every_address_that_takes_a_file_gets_the_upload_limit(client: TestClient) -> None:
    # Each multipart endpoint in the schema streams its body against the upload limit; one
    # left out would answer 413 for any file over 64 KB.
    paths = client.get("/openapi.json").json()["paths"]
    takes_files = {
        path
        for path, methods in paths.items()
        for operation in methods.values()
        if "multipart/form-data" in operation.get("requestBody", {}).get("content", {})
    }
    assert {"/api/mesh", "/api/mesh/export", "/api/points"} <= takes_files
    assert takes_files <= config.MESH_PATHS
    padded = CUBE_OBJ + "# padding past the 64 KB limit of other addresses\n" * 2000
    response = upload(client, "/api/mesh/export?format=ply", padded)
    assert response.status_code == 200, response.text
