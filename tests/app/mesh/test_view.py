"""app/mesh/view.py: the mesh's 3D view, its decimation and its float32-safe coordinates."""

from __future__ import annotations

import json

import numpy as np

from app.mesh import view as mesh_view
from app.mesh.classes import BOUNDARY, COLORS, DEGENERATE, FLIPPED, OK
from app.mesh.view import build_view, problem_faces, view_space
from tests.meshes import CUBE_FACES, CUBE_VERTICES


def test_problem_faces_are_all_kept_or_the_worst_first() -> None:
    classes = np.full(100_000, OK, dtype=np.int8)
    problems = np.arange(5, 100_000, 97)
    classes[problems] = FLIPPED
    assert np.array_equal(problem_faces(classes), problems)
    classes[:8_000] = BOUNDARY
    classes[[1, 2]] = DEGENERATE
    kept = problem_faces(classes, limit=3_000)
    assert len(kept) == 3_000 and (np.diff(kept) > 0).all()
    # The two degenerate faces and every flipped one first, then boundary faces fill the cap.
    flipped = np.flatnonzero(classes == FLIPPED)
    assert np.isin([1, 2], kept).all() and np.isin(flipped, kept).all()
    assert np.count_nonzero(classes[kept] == BOUNDARY) == 3_000 - 2 - len(flipped)
    assert np.array_equal(kept, problem_faces(classes, limit=3_000))
    assert not len(problem_faces(np.full(10, OK, dtype=np.int8)))


def grid(size: int) -> tuple[np.ndarray, np.ndarray]:
    """A flat size x size grid of squares, two triangles each, wound counter-clockwise."""
    x, y = np.meshgrid(np.arange(size + 1.0), np.arange(size + 1.0))
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    corner = (np.arange(size)[:, None] * (size + 1) + np.arange(size)).ravel()
    faces = np.concatenate(
        [
            np.column_stack([corner, corner + 1, corner + size + 2]),
            np.column_stack([corner, corner + size + 2, corner + size + 1]),
        ]
    )
    return vertices, faces


def test_view_colours_faces_and_caps_a_large_mesh() -> None:
    vertices, faces = grid(120)  # 28,800 faces
    normals = np.tile([0.0, 0.0, 1.0], (len(faces), 1))
    classes = np.full(len(faces), OK, dtype=np.int8)
    classes[[3, 7]] = FLIPPED
    classes[11] = DEGENERATE
    view = build_view(
        vertices, faces, normals, classes, np.zeros((0, 2), int), np.zeros((0, 2), int)
    )
    assert view["total_faces"] == len(faces) and view["simplified"]
    assert abs(view["shown_faces"] - mesh_view.DISPLAY_FACES) < 0.1 * mesh_view.DISPLAY_FACES
    traces = {trace["name"]: trace for trace in view["figure"]["data"]}
    mesh = traces["faces"]
    assert len(mesh["i"]) == len(mesh["facecolor"]) == view["shown_faces"] - 1
    assert mesh["facecolor"].count(COLORS[FLIPPED]) == 2
    assert set(mesh["facecolor"]) == {COLORS[OK], COLORS[FLIPPED]}
    assert traces["degenerate"]["x"] and len(traces["degenerate"]["x"]) == 1
    assert view["arrows"] == mesh_view.ARROW_FACES
    flipped_heads = traces["flipped normals"]  # the cone trace comes after the shafts
    assert flipped_heads["type"] == "cone" and len(flipped_heads["u"]) == 2
    assert view["counts"] == {
        "degenerate": 1,
        "flipped": 2,
        "nonmanifold": 0,
        "boundary": 0,
        "ok": len(faces) - 3,
    }
    cones = [t for t in view["figure"]["data"] if t["type"] == "cone"]
    assert all(w > 0 for t in cones for w in t["w"]), "arrows point along the normals"
    json.dumps(view, allow_nan=False)  # plain JSON: no NaN, no NumPy types


def test_view_draws_huge_and_far_meshes_in_float32_range() -> None:
    for vertices in (
        np.array([[1e300, -1e300, 0], [-1e300, 1e300, 1e300], [0, 0, -1e300]]),
        np.array([[1e6, 1e6, 0], [1e6 + 1e-3, 1e6, 0], [1e6, 1e6 + 1e-3, 0]]),
    ):
        space = view_space(vertices)
        assert space.transformed
        assert np.abs(space.points).max() < 2.0**21
        assert len(np.unique(space.points.astype(np.float32), axis=0)) == 3, "shape kept"
        view = build_view(
            vertices,
            np.array([[0, 1, 2]]),
            np.array([[0.0, 0.0, 1.0]]),
            np.array([OK], dtype=np.int8),
            np.zeros((0, 2), int),
            np.zeros((0, 2), int),
        )
        assert view["note"] and "the file's" in view["note"]
        json.dumps(view, allow_nan=False)
    assert not view_space(np.eye(3)).transformed


def _one_face_view(vertices: np.ndarray) -> dict:  # type: ignore[type-arg]
    return build_view(
        vertices,
        np.array([[0, 1, 2]]),
        np.array([[0.0, 0.0, 1.0]]),
        np.array([OK], dtype=np.int8),
        np.zeros((0, 2), int),
        np.zeros((0, 2), int),
    )


def test_view_of_subnormal_coordinates_is_scaled_up_not_nan() -> None:
    # 5e-324 = 2**-1074: its half is 0, so the scale comes from the whole extent.
    tiny = 5e-324
    for vertices in (
        np.array([[0.0, 0, 0], [tiny, 0, 0], [0, tiny, 0]]),
        np.array([[tiny, tiny, 0], [2 * tiny, tiny, 0], [tiny, 2 * tiny, 0]]),
        np.array([[0.0, 0, 0], [1e-310, 0, 0], [0, 3e-320, 5e-324]]),
    ):
        space = view_space(vertices)
        assert space.transformed and space.exponent < -1000
        assert np.isfinite(space.points).all()
        assert 0.5 <= np.abs(space.points).max() < 2.0**21
        view = _one_face_view(vertices)
        json.dumps(view, allow_nan=False)
        assert view["note"] and "scaled by 2^" in view["note"]


def test_view_of_mixed_scales_keeps_the_largest_and_stays_finite() -> None:
    # One axis at 1e300, one at 1e-300, one subnormal: the largest extent sets the scale.
    vertices = np.array([[0.0, 0, 0], [1e300, 0, 0], [0, 1e-300, 5e-324]])
    space = view_space(vertices)
    assert space.exponent > 900
    assert np.isfinite(space.points).all() and np.abs(space.points).max() < 2.0
    json.dumps(_one_face_view(vertices), allow_nan=False)
    # Extents beyond the double range (high - low overflows) still get a finite scale.
    edge = np.array([[-1.7e308, -1.7e308, 0], [1.7e308, -1.7e308, 0], [0, 1.7e308, 0]])
    assert np.isfinite(view_space(edge).points).all()
    json.dumps(_one_face_view(edge), allow_nan=False)


def test_rounding_leaves_tiny_extents_alone() -> None:
    points = np.array([[0.0, 5e-324, 1e-300]])
    assert np.array_equal(mesh_view._rounded(points), points)
    assert np.array_equal(mesh_view._rounded(np.zeros((2, 3))), np.zeros((2, 3)))


def test_camera_looks_along_the_up_axis_from_far_enough() -> None:
    vertices, faces = grid(2)
    for up in "xyz":
        view = build_view(
            vertices, faces, np.tile([0.0, 0.0, 1.0], (len(faces), 1)),
            np.full(len(faces), OK, dtype=np.int8), np.zeros((0, 2), dtype=np.intp),
            np.zeros((0, 2), dtype=np.intp), up=up,
        )  # fmt: skip
        camera = view["figure"]["layout"]["scene"]["camera"]
        assert camera["up"][up] == 1 and sum(camera["up"].values()) == 1
        eye = np.array([camera["eye"][axis] for axis in "xyz"])
        scene = mesh_view.Scene.of(vertices)
        drawn = _on_screen(camera, (vertices - scene.middle) / scene.unit)
        assert np.abs(drawn).max() < 0.9  # the whole grid, with a margin
        assert eye["xyz".index(up)] < eye.max()  # looked at from the side, a little above
        assert view["up"] == up and set(view["cameras"]) == {"x", "y", "z"}


def test_the_surface_is_lit_from_the_front_and_smooth_only_when_simplified() -> None:
    for (vertices, faces), flat in ((grid(4), True), (grid(120), False)):
        view = build_view(
            vertices, faces, np.tile([0.0, 0.0, 1.0], (len(faces), 1)),
            np.full(len(faces), OK, dtype=np.int8), np.zeros((0, 2), dtype=np.intp),
            np.zeros((0, 2), dtype=np.intp),
        )  # fmt: skip
        surface = next(t for t in view["figure"]["data"] if t["type"] == "mesh3d")
        assert surface["flatshading"] is flat
        light = surface["lightposition"]  # in the camera's frame: z is towards the viewer
        assert light["z"] > light["y"] > 0 and light["z"] > abs(light["x"])
        assert surface["lighting"]["diffuse"] > surface["lighting"]["ambient"]


def test_the_view_sends_face_normals_and_corner_neighbourhoods_for_the_crease_slider() -> None:
    vertices, faces = CUBE_VERTICES.astype(float), CUBE_FACES
    no_edges = np.zeros((0, 2), dtype=np.intp)
    classes = np.full(len(faces), OK, dtype=np.int8)
    classes[3] = DEGENERATE  # not drawn as a face: the normals follow the trace's faces
    view = build_view(vertices, faces, np.zeros((len(faces), 3)), classes, no_edges, no_edges)
    surface = next(t for t in view["figure"]["data"] if t["type"] == "mesh3d")
    normals = np.array(view["face_normals"])
    assert normals.shape == (len(surface["i"]), 3) == (11, 3)
    points = vertices  # near the origin and of size 1: drawn as it is
    for n, *corners in zip(normals, surface["i"], surface["j"], surface["k"], strict=True):
        a, b, c = np.array([surface[axis] for axis in "xyz"]).T[corners]
        assert np.abs(n).sum() == 1.0 and np.abs(n).max() == 1.0  # a unit axis
        assert np.dot(np.cross(b - a, c - a), n) == 1.0  # along the winding (twice the area 1/2)
    assert {tuple(p) for p in points} == {tuple(p) for p in np.array([surface[a] for a in "xyz"]).T}
    corner = view["normals"]["corner"]
    for label, around in zip(corner["label"], corner["around"], strict=True):
        f, k = (int(word.strip(",")) for word in label.split()[1::2])
        v = faces[f, k]
        assert len(around) == np.count_nonzero((faces == v).any(axis=1))
        own = np.cross(*(points[faces[f, 1:]] - points[faces[f, 0]]))
        assert np.allclose(around[0], own)  # its own face first; every cube triangle has area 1/2
        assert np.allclose(np.linalg.norm(around, axis=1), 1.0)


def _on_screen(camera: dict, corners: np.ndarray, aspect: float = 1.0) -> np.ndarray:
    """Where Plotly's camera (45 degrees of vertical field) draws scene points, in the screen's
    units: within -1 to 1 on both axes is in the picture."""
    eye, center, up = (
        np.array([camera[key][axis] for axis in "xyz"]) for key in ("eye", "center", "up")
    )
    forward = (center - eye) / np.linalg.norm(center - eye)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    upward = np.cross(right, forward)
    relative = corners - eye
    depth = relative @ forward
    focal = 1 / np.tan(np.pi / 8)
    return np.stack(
        [focal * (relative @ right) / depth / aspect, focal * (relative @ upward) / depth], axis=1
    )


def _scene_corners(points: np.ndarray) -> np.ndarray:
    """The corners of Plotly's scene box around ``points`` (aspectmode "data")."""
    ranges = points.max(axis=0) - points.min(axis=0)
    half = ranges / np.exp(np.log(ranges).mean()) / 2
    return np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half


def test_the_whole_mesh_is_framed_with_a_margin() -> None:
    """The inside-out cube sample's near bottom corner was cut off: the camera stood at 1.98
    scene units where the box's corners need 2.26 (the whole box in 45 degrees)."""
    for vertices in (CUBE_VERTICES, CUBE_VERTICES * [4.0, 1.0, 0.5], CUBE_VERTICES * [1, 1, 9]):
        classes = np.full(len(CUBE_FACES), FLIPPED, dtype=np.int8)
        normals = np.tile([0.0, 0.0, 1.0], (len(CUBE_FACES), 1))
        for up in "xyz":
            view = build_view(
                vertices, CUBE_FACES, normals, classes, np.zeros((0, 2), dtype=np.intp),
                np.zeros((0, 2), dtype=np.intp), up=up,
            )  # fmt: skip
            corners = _scene_corners(np.asarray(vertices, dtype=float))
            drawn = _on_screen(view["figure"]["layout"]["scene"]["camera"], corners)
            assert np.abs(drawn).max() < 0.95, (up, vertices.max(axis=0), drawn)
            assert view["cameras"][up] == view["figure"]["layout"]["scene"]["camera"]


def test_the_camera_turns_towards_the_problem_and_the_page_can_step_through_them() -> None:
    vertices, faces = grid(6)  # a flat grid in z = 0, one corner face flipped
    normals = np.tile([0.0, 0.0, 1.0], (len(faces), 1))
    classes = np.full(len(faces), OK, dtype=np.int8)
    corner = int(np.argmax(vertices[faces].mean(axis=1) @ [1.0, 1.0, 0.0]))
    classes[corner] = FLIPPED
    view = build_view(
        vertices, faces, normals, classes, np.zeros((0, 2), dtype=np.intp),
        np.zeros((0, 2), dtype=np.intp), up="z",
    )  # fmt: skip
    (spot,) = view["spots"]
    assert spot["face"] == corner
    assert spot["outward"] == {"x": 0.0, "y": 0.0, "z": -1.0}  # the side the fix turns it to
    centre = np.array([spot["center"][axis] for axis in "xyz"])
    assert centre[0] > 0.3 and centre[1] > 0.3  # the (+x, +y) corner of the scene
    eye = np.array([view["cameras"]["z"]["eye"][axis] for axis in "xyz"])
    default = np.array([1.25, -1.25, 0.9])
    # Turned towards the corner: nearer to it than the default three-quarter view is.
    assert eye @ centre / np.linalg.norm(eye) > default @ centre / np.linalg.norm(default)
    assert 0 < spot["distance"] < np.linalg.norm(eye)
    spread = build_view(
        vertices, faces, normals, np.full(len(faces), FLIPPED, dtype=np.int8),
        np.zeros((0, 2), dtype=np.intp), np.zeros((0, 2), dtype=np.intp), up="z",
    )  # fmt: skip
    assert len(spread["spots"]) == mesh_view.PROBLEM_SPOTS
    centres = np.array([[s["center"][axis] for axis in "xyz"] for s in spread["spots"]])
    assert np.ptp(centres[:, 0]) > 0.8 and np.ptp(centres[:, 1]) > 0.8  # spread over the grid
