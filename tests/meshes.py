"""The meshes the tests share: as arrays, as file texts and bytes, and the samples in tests/data.

A mesh that one test module needs stays in that module; this is for the ones several share.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

import numpy as np
import trimesh

from tests.paths import DATA

# --- as arrays ------------------------------------------------------------------------------

#: The unit corner tetrahedron: the origin and the three unit points.
TETRA_VERTICES = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
#: Its four faces, wound outward: -z, -y, -x, then the slanted one.
TETRA_FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])

#: The unit cube: corner (x, y, z) is vertex x + 2 y + 4 z.
CUBE_VERTICES = np.array(
    [[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=np.float64
)
#: Its sides (bottom, top, -y, +y, -x, +x), counter-clockwise seen from outside.
CUBE_QUADS = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
#: Each side cut into two triangles [a, b, c], [a, c, d]: 12 faces, wound outward.
CUBE_FACES = np.array([t for a, b, c, d in CUBE_QUADS for t in ((a, b, c), (a, c, d))])


def octahedron() -> tuple[np.ndarray, np.ndarray]:
    """The regular octahedron with corners at +-1 on each axis, its 8 faces wound outward."""
    vertices = np.array(
        [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64
    )
    faces = []
    for x in (0, 1):
        for y in (2, 3):
            for z in (4, 5):
                corner = [x, y, z]
                if np.linalg.det(vertices[corner]) < 0:  # outward: positive orientation
                    corner = [x, z, y]
                faces.append(corner)
    return vertices, np.array(faces)


# --- as OBJ texts ---------------------------------------------------------------------------


def obj_text(points: str, faces: Sequence[Sequence[int]]) -> str:
    """An OBJ file: the ``v`` lines in ``points``, then one ``f`` line a face (0-based rows)."""
    return points + "".join("f " + " ".join(str(i + 1) for i in face) + "\n" for face in faces)


#: The ``v`` lines of the tetrahedron above, written as integers.
TETRA_OBJ_POINTS = "".join(f"v {x:g} {y:g} {z:g}\n" for x, y, z in TETRA_VERTICES.tolist())
#: The tetrahedron above as an OBJ file, wound outward.
TETRA_OBJ = obj_text(TETRA_OBJ_POINTS, TETRA_FACES.tolist())
#: The tetrahedron with its corners at 1e200: finite, but its cross products overflow float64.
HUGE_TETRA_OBJ = obj_text("v 0 0 0\nv 1e200 0 0\nv 0 1e200 0\nv 0 0 1e200\n", TETRA_FACES.tolist())

#: The ``v`` lines of the unit cube as OBJ, numbered the other way round from CUBE_VERTICES:
#: vertex 4 x + 2 y + z (the API, page, CLI and report tests expect this file's numbering).
CUBE_OBJ_POINTS = "".join(f"v {x} {y} {z}\n" for x in (0, 1) for y in (0, 1) for z in (0, 1))
#: Its 12 triangles wound outward, in this numbering: sides -x, +x, -y, +y, -z, +z.
CUBE_OBJ_FACES = [
    (0, 1, 3),
    (0, 3, 2),
    (4, 6, 7),
    (4, 7, 5),
    (0, 4, 5),
    (0, 5, 1),
    (2, 3, 7),
    (2, 7, 6),
    (0, 2, 6),
    (0, 6, 4),
    (1, 5, 7),
    (1, 7, 3),
]
#: The unit cube as an OBJ file: closed and wound outward.
CUBE_OBJ = obj_text(CUBE_OBJ_POINTS, CUBE_OBJ_FACES)
#: The cube with its first face reversed: closed, winding mixed.
CUBE_ONE_FLIPPED_OBJ = obj_text(CUBE_OBJ_POINTS, [CUBE_OBJ_FACES[0][::-1], *CUBE_OBJ_FACES[1:]])
#: The cube without its top (z = 1): 10 faces, one hole of 4 boundary edges.
OPEN_BOX_OBJ = obj_text(
    CUBE_OBJ_POINTS, [face for face in CUBE_OBJ_FACES if face not in ((1, 5, 7), (1, 7, 3))]
)

# --- as STL bytes ---------------------------------------------------------------------------


def binary_stl(
    corners: np.ndarray,
    normals: np.ndarray | None = None,
    header: bytes = b"test",
    count: int | None = None,
) -> bytes:
    """A binary STL of (m, 3, 3) corners; ``count`` overrides the header's triangle count."""
    corners = np.asarray(corners, dtype="<f4").reshape(-1, 3, 3)
    normals = np.zeros((len(corners), 3)) if normals is None else normals
    body = b"".join(
        struct.pack("<12fH", *normal, *triangle.ravel(), 0)
        for normal, triangle in zip(normals, corners, strict=True)
    )
    stated = len(corners) if count is None else count
    return header.ljust(80, b" ") + struct.pack("<I", stated) + body


def ascii_stl(corners: np.ndarray, normals: np.ndarray, name: str = "test") -> bytes:
    """An ASCII STL of (m, 3, 3) corners and (m, 3) stated normals, numbers as Python repr:
    one solid ``name``."""
    lines = [f"solid {name}".rstrip()]
    for normal, triangle in zip(
        np.asarray(normals).tolist(), np.asarray(corners).tolist(), strict=True
    ):
        lines += [f"  facet normal {normal[0]} {normal[1]} {normal[2]}", "    outer loop"]
        lines += [f"      vertex {x!r} {y!r} {z!r}" for x, y, z in triangle]
        lines += ["    endloop", "  endfacet"]
    lines.append(f"endsolid {name}".rstrip())
    return "\n".join(lines).encode()


def ascii_solids(*blocks: tuple[str, np.ndarray]) -> bytes:
    """ASCII STL with one ``solid NAME`` block for each (name, (m, 3, 3) corners); the facet
    normals all zero."""
    return b"\n".join(
        ascii_stl(corners, np.zeros((len(corners), 3)), name) for name, corners in blocks
    )


def obj_as_solids(text: str) -> bytes:
    """An OBJ file's groups as the solids of an ASCII STL, one for each group."""
    from mesh_normal.files import read_mesh

    mesh = read_mesh(text.encode(), "groups.obj")
    assert mesh.face_groups is not None and mesh.group_names is not None
    corners = mesh.vertices[mesh.faces]
    return ascii_solids(
        *((name, corners[mesh.face_groups == index]) for index, name in enumerate(mesh.group_names))
    )


# --- the sample files in tests/data ---------------------------------------------------------

#: The small sample files the differential tests compare with trimesh and libigl.
SAMPLES = ("sphere.ply", "nut.ply", "ant.ply", "cube.obj")


def load(name: str) -> tuple[np.ndarray, np.ndarray]:
    """A file of tests/data as read by trimesh (unprocessed): (n, 3) float64, (m, 3) int."""
    mesh = trimesh.load(DATA / name, process=False, force="mesh")
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces)


# --- generated hard cases for orientation: separate pieces, far away, open ---------------------


def random_rotation(seed: int) -> np.ndarray:
    """A (3, 3) rotation drawn from ``seed``."""
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def separate_sides_cube(
    divisions: int = 3, wobble: bool = False, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """The unit cube, rotated, its six sides separate patches with their own float32 vertices.

    Each side is a grid of ``divisions`` squares a side, wound outward. Shared corners have
    identical coordinates (the same float32 numbers), unless ``wobble``: then every vertex of
    every side moves by one float32 step along each axis at random, so the sides wobble and
    miss each other by a step, as sides transformed one by one do.
    """
    rng = np.random.default_rng(seed)
    rotation = random_rotation(seed)
    steps = np.linspace(0.0, 1.0, divisions + 1)
    vertices, faces = [], []
    for axis in range(3):
        for high in (0.0, 1.0):
            s, t = np.meshgrid(steps, steps, indexing="ij")
            side = np.zeros((divisions + 1, divisions + 1, 3))
            u, v = (axis + 1) % 3, (axis + 2) % 3
            side[..., axis], side[..., u], side[..., v] = high, s, t
            points = (side.reshape(-1, 3) - 0.5) @ rotation.T
            points = points.astype(np.float32)
            if wobble:
                toward = np.where(rng.random(points.shape) < 0.5, -np.inf, np.inf)
                points = np.nextafter(points, toward.astype(np.float32))
            base = sum(len(p) for p in vertices)
            k = divisions + 1
            grid = []
            for i in range(divisions):
                for j in range(divisions):
                    a, b, c, d = i * k + j, (i + 1) * k + j, (i + 1) * k + j + 1, i * k + j + 1
                    grid += [(a, b, c), (a, c, d)]
            quads = np.array(grid) + base
            # (u, v, axis) is right-handed, so a, b, c winds towards +axis: out on the high side.
            faces.append(quads if high else quads[:, [0, 2, 1]])
            vertices.append(points.astype(np.float64))
    return np.concatenate(vertices), np.concatenate(faces)


def stepped_sides_cube() -> tuple[np.ndarray, np.ndarray]:
    """:func:`separate_sides_cube` (96 vertices, 56 positions) whose sides miss each other.

    The two sides across x keep their float32 coordinates, the two across y move one float32
    step up in every coordinate, the two across z one step down: every shared corner and edge
    point then has copies a step or two apart, none identical, so without a weld the cube is
    six open sides; a weld of 1e-6 joins the 96 vertices into the 56 points again.
    """
    vertices, faces = separate_sides_cube()
    points = vertices.astype(np.float32).reshape(6, -1, 3)
    points[2:4] = np.nextafter(points[2:4], np.float32(np.inf))
    points[4:6] = np.nextafter(points[4:6], np.float32(-np.inf))
    return points.reshape(-1, 3).astype(np.float64), faces


def icosphere(subdivisions: int = 2, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """trimesh's icosphere, wound outward."""
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces)


def combined(*pieces: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Several meshes as one, each keeping its own vertices."""
    vertices, faces, base = [], [], 0
    for points, triangles in pieces:
        vertices.append(points)
        faces.append(np.asarray(triangles) + base)
        base += len(points)
    return np.concatenate(vertices), np.concatenate(faces)


def head_with_eyes() -> tuple[np.ndarray, np.ndarray]:
    """A closed head (an icosphere) and two separate closed eyes sunk half into it."""
    head = icosphere(3)
    eyes = [icosphere(2, 0.2) for _ in range(2)]
    left = (eyes[0][0] + [0.6, 0.3, 0.75], eyes[0][1])
    right = (eyes[1][0] + [-0.6, 0.3, 0.75], eyes[1][1])
    return combined(head, left, right)


def open_hemisphere() -> tuple[np.ndarray, np.ndarray]:
    """The upper half of an icosphere: open, wound outward (convex side out)."""
    vertices, faces = icosphere(3)
    keep = vertices[faces].mean(axis=1)[:, 2] > 0
    return vertices, faces[keep]


def far_triangle(offset: float = 1e4) -> tuple[np.ndarray, np.ndarray]:
    """One small triangle near (offset, offset, offset)."""
    corners = np.array([[0.0, 0.0, 0.0], [0.3, 0.1, 0.0], [0.1, 0.2, 0.05]])
    return corners + offset, np.array([[0, 1, 2]])


def scan_fragments(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Open patches of a noisy sphere seen from six directions, each with its own vertices.

    Like range scans not yet merged: each faces its scanner (outward), and they neither
    share vertices nor close up.
    """
    rng = np.random.default_rng(seed)
    vertices, faces = icosphere(4)
    vertices = vertices * (1 + 0.003 * rng.standard_normal(len(vertices)))[:, None]
    centres = vertices[faces].mean(axis=1)
    centres /= np.linalg.norm(centres, axis=1)[:, None]
    pieces = []
    for direction in np.eye(3).tolist() + (-np.eye(3)).tolist():
        keep = faces[centres @ np.array(direction) > np.cos(np.radians(35))]
        used, inverse = np.unique(keep, return_inverse=True)
        pieces.append((vertices[used], inverse.reshape(-1, 3)))
    return combined(*pieces)


def open_box_of_sides() -> tuple[np.ndarray, np.ndarray]:
    """The separate-sides cube without its last side: five open, flat patches, wound outward."""
    vertices, faces = separate_sides_cube()
    return vertices, faces[: len(faces) * 5 // 6]


#: The generated hard cases: name -> (vertices, faces), every one wound outward.
HARD_CASES = {
    "open box of sides": open_box_of_sides,
    "separate sides cube": separate_sides_cube,
    "wobbling sides cube": lambda: separate_sides_cube(wobble=True),
    "head with eyes": head_with_eyes,
    "open hemisphere": open_hemisphere,
    "far triangle": far_triangle,
    "scan fragments": scan_fragments,
}


def hollow_ball() -> tuple[np.ndarray, np.ndarray]:
    """A ball with a spherical cavity: the outer shell wound outward, the inner one inward
    (its faces point into the cavity, away from the material), each with its own vertices."""
    outer = icosphere(3)
    inner_vertices, inner_faces = icosphere(2, 0.5)
    return combined(outer, (inner_vertices + np.array([0.1, 0.0, 0.05]), inner_faces[:, [0, 2, 1]]))


HARD_CASES["hollow ball"] = hollow_ball


# --- closed shells inside each other -------------------------------------------------------

Shell = tuple[np.ndarray, np.ndarray]


def ball(radius: float, centre: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Shell:
    vertices, faces = icosphere(2, radius)
    return vertices + np.array(centre), faces


def box(size: float, centre: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Shell:
    return (CUBE_VERTICES - 0.5) * size + np.array(centre), CUBE_FACES.copy()


def built(*shells: tuple[Shell, bool]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The shells as one mesh, each with its own vertices, wound outward or (True) inward;
    and each face's shell."""
    vertices, faces, labels, base = [], [], [], 0
    for number, ((points, triangles), inward) in enumerate(shells):
        vertices.append(points)
        faces.append((triangles[:, ::-1] if inward else triangles) + base)
        labels.append(np.full(len(triangles), number))
        base += len(points)
    return np.concatenate(vertices), np.concatenate(faces), np.concatenate(labels)


def turned(faces: np.ndarray, labels: np.ndarray, shells: list[int]) -> np.ndarray:
    """``faces`` with the given shells wound the other way (as orient() turns a row)."""
    rows = np.isin(labels, shells)
    result = faces.copy()
    result[rows] = faces[rows][:, [0, 2, 1]]
    return result


#: Closed shells inside each other, every one facing away from the material: (shells, the
#: depth of each).
NESTED_CASES = {
    "hollow ball": (((ball(1.0), False), (ball(0.5, (0.1, 0.0, 0.05)), True)), [0, 1]),
    "hollow box": (((box(2.0), False), (box(1.6, (0.05, 0.0, 0.0)), True)), [0, 1]),
    "ball in a hollow ball": (
        ((ball(1.0), False), (ball(0.7), True), (ball(0.3, (0.1, 0.1, 0.0)), False)),
        [0, 1, 2],
    ),
    "three levels of hollow balls": (
        (
            (ball(1.0), False),
            (ball(0.8), True),
            (ball(0.6), False),
            (ball(0.4), True),
            (ball(0.2), False),
            (ball(0.1), True),
        ),
        [0, 1, 2, 3, 4, 5],
    ),
    "two hollow boxes side by side": (
        (
            (box(2.0), False),
            (box(1.5), True),
            (box(2.0, (3.0, 0.0, 0.0)), False),
            (box(1.5, (3.0, 0.0, 0.0)), True),
        ),
        [0, 1, 0, 1],
    ),
    "two hollow boxes, one box each inside": (
        (
            (box(2.0), False),
            (box(1.5), True),
            (box(2.0, (0.0, 2.5, 0.0)), False),
            (box(1.5, (0.0, 2.5, 0.0)), True),
            (box(0.5, (0.0, 2.5, 0.0)), False),
            (box(0.5), False),
        ),
        [0, 1, 0, 1, 2, 2],
    ),
}
