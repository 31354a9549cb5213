"""Sample meshes for the mesh page's "Try a sample": small files made here, each showing one thing.

Each is a few hundred bytes of OBJ or ASCII PLY, written from the faces below when asked for;
``GET /mesh/sample/{name}`` reports on it exactly as an upload of the same file would be.
What the jobs make of a sample (its report, its page, its file written again) is the same every
time: each is computed once, by a heavy job, and then served from memory (:class:`Computed`),
so that a visitor who asks for the samples again and again costs no job slot.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable, Hashable, Sequence
from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING, Any, TypeVar

from starlette.requests import Request

from app.mesh.uploads import Upload
from app.web.errors import ApiError

if TYPE_CHECKING:  # NumPy is imported by the functions that make a file, not at start-up
    import numpy as np
    from numpy.typing import NDArray

    Points = NDArray[np.float64]

Faces = list[tuple[int, int, int]]
Value = TypeVar("Value")


@cache
def cube_points() -> Points:
    """The unit cube: corner (x, y, z) is vertex x + 2 y + 4 z."""
    import numpy as np

    points = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
    points.flags.writeable = False
    return points


#: Its sides (bottom, top, -y, +y, -x, +x), counter-clockwise seen from outside.
CUBE_QUADS = ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5))
#: Each side cut into two triangles: 12 faces, wound outward; the top is faces 2 and 3.
CUBE_FACES: Faces = [t for a, b, c, d in CUBE_QUADS for t in ((a, b, c), (a, c, d))]


def reversed_faces(faces: Sequence[tuple[int, int, int]]) -> Faces:
    """Every face wound the other way round: its normal points to the other side."""
    return [(a, c, b) for a, b, c in faces]


def icosphere() -> tuple[Points, Faces]:
    """The icosahedron split once (42 vertices, 80 faces) on the unit sphere, wound outward."""
    import numpy as np

    t = (1 + 5**0.5) / 2
    points = [
        *[(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0)],
        *[(0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t)],
        *[(t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)],
    ]
    faces: Faces = [
        *[(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11)],
        *[(1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8)],
        *[(3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9)],
        *[(4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)],
    ]
    middles: dict[tuple[int, int], int] = {}

    def middle(a: int, b: int) -> int:
        key = (min(a, b), max(a, b))
        if key not in middles:
            middles[key] = len(points)
            pa, pb = np.array(points[a], dtype=float), np.array(points[b], dtype=float)
            points.append(tuple((pa + pb) / 2))
        return middles[key]

    split: Faces = []
    for a, b, c in faces:
        ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
        split += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    array = np.array(points, dtype=float)
    return array / np.linalg.norm(array, axis=1, keepdims=True), split


def sliver_cube() -> tuple[Points, Faces]:
    """The cube with two faces of no area: each of two edges gets a point at its middle, the
    triangle beside it is cut in two there, and a flat triangle (the edge's ends and its
    middle) closes the gap, so that the mesh stays closed and consistently wound."""
    import numpy as np

    points = [*cube_points().tolist()]
    faces = list(CUBE_FACES)
    for index in (0, 4):  # bottom (0, 2, 3): edge 0-2; top (4, 5, 7): edge 4-5
        a, b, c = faces[index]
        m = len(points)
        points.append(((cube_points()[a] + cube_points()[b]) / 2).tolist())
        faces[index] = (a, m, c)
        faces += [(m, b, c), (b, m, a)]
    return np.array(points, dtype=float), faces


def obj_file(pieces: Sequence[tuple[str, Points, Faces]]) -> bytes:
    """An OBJ file: each piece an object (``o name``) with its own vertices and faces."""
    lines, offset = [], 1
    for name, points, faces in pieces:
        lines.append(f"o {name}")
        lines += [f"v {x:.6g} {y:.6g} {z:.6g}" for x, y, z in points.tolist()]
        lines += [f"f {a + offset} {b + offset} {c + offset}" for a, b, c in faces]
        offset += len(points)
    return ("\n".join(lines) + "\n").encode()


def ply_file(points: Points, faces: Faces) -> bytes:
    """An ASCII PLY file of the vertices and triangles."""
    head = [
        "ply",
        "format ascii 1.0",
        f"element vertex {len(points)}",
        *[f"property float {axis}" for axis in "xyz"],
        f"element face {len(faces)}",
        "property list uchar int vertex_indices",
        "end_header",
    ]
    body = [f"{x:.6g} {y:.6g} {z:.6g}" for x, y, z in points.tolist()]
    body += [f"3 {a} {b} {c}" for a, b, c in faces]
    return ("\n".join(head + body) + "\n").encode()


def _cube() -> bytes:
    return obj_file([("cube", cube_points(), CUBE_FACES)])


def _inside_out() -> bytes:
    return obj_file([("cube", cube_points(), reversed_faces(CUBE_FACES))])


def _some_flipped() -> bytes:
    points, faces = icosphere()
    for index in (0, 25, 50):  # three faces far apart, none touching another
        a, b, c = faces[index]
        faces[index] = (a, c, b)
    return ply_file(points, faces)


def _open() -> bytes:
    return obj_file([("box", cube_points(), CUBE_FACES[:2] + CUBE_FACES[4:])])


def _degenerate() -> bytes:
    return ply_file(*sliver_cube())


def _two_pieces() -> bytes:
    right = cube_points().copy()
    right[:, 0] += 2.0
    return obj_file(
        [
            ("left", cube_points(), CUBE_FACES),
            ("right", right, reversed_faces(CUBE_FACES)),
        ]
    )


@dataclass(frozen=True, slots=True)
class Sample:
    """One sample mesh: its name in the address, what it shows and how its file is made."""

    name: str
    title: str
    description: str
    format: str
    make: Callable[[], bytes]

    @property
    def filename(self) -> str:
        return f"{self.name}.{self.format}"

    def data(self) -> bytes:
        return _data(self.name)

    def upload(self) -> Upload:
        """The sample as the upload of its file would be."""
        return Upload(self.data(), self.filename)


#: The samples, in the order the page lists them.
SAMPLES: dict[str, Sample] = {
    sample.name: sample
    for sample in (
        Sample(
            "cube",
            "Clean cube",
            "A closed unit cube, every face wound outward: nothing to fix.",
            "obj",
            _cube,
        ),
        Sample(
            "inside-out",
            "Inside-out cube",
            "The same cube with every face reversed, so its normals point inward.",
            "obj",
            _inside_out,
        ),
        Sample(
            "some-flipped",
            "Sphere with flipped faces",
            "An 80-face sphere with 3 faces wound against their neighbours.",
            "ply",
            _some_flipped,
        ),
        Sample(
            "open-box",
            "Open box",
            "The cube without its top: a hole of 4 boundary edges, so no volume.",
            "obj",
            _open,
        ),
        Sample(
            "degenerate",
            "Cube with no-area faces",
            "A closed cube with 2 flat sliver faces that have no area and no normal.",
            "ply",
            _degenerate,
        ),
        Sample(
            "two-pieces",
            "Two cubes, one inside out",
            "Two separate cubes in one file: the left faces outward, the right inward.",
            "obj",
            _two_pieces,
        ),
    )
}


@cache
def _data(name: str) -> bytes:
    return SAMPLES[name].make()


def sample(name: str) -> Sample:
    """The sample of that name; another name is a 404 naming the samples there are."""
    found = SAMPLES.get(name)
    if found is None:
        raise ApiError(
            404,
            f"There is no sample mesh named {name[:40]!r}; the samples are "
            + ", ".join(SAMPLES)
            + ".",
            "name",
        )
    return found


#: The status of a job whose client hung up (:mod:`app.web.jobs`).
CLIENT_LEFT = 499


class Computed:
    """What the jobs made of the samples, by key: each computed once, by the first request
    that asks; the requests that ask meanwhile wait for that same computation."""

    def __init__(self) -> None:
        self.values: dict[Hashable, Any] = {}
        self._pending: dict[Hashable, asyncio.Task[Any]] = {}

    async def get(self, key: Hashable, compute: Callable[[], Awaitable[Value]]) -> Value:
        """The value for ``key``, from ``compute()`` (a job for the asking request) the first
        time. When the request that started it hangs up (its job stopped), the next one
        waiting starts again; any other failure is every waiting request's answer."""
        while True:
            if key in self.values:
                value: Value = self.values[key]
                return value
            task = self._pending.get(key)
            started = task is None or task.get_loop() is not asyncio.get_running_loop()
            if task is None or started:
                task = asyncio.ensure_future(compute())
                self._pending[key] = task
                task.add_done_callback(lambda done: self._done(key, done))
            try:
                # Shielded: a waiting request that is cancelled must not cancel the others' job.
                return await asyncio.shield(task)
            except ApiError as error:
                if started or error.status_code != CLIENT_LEFT:
                    raise

    def _done(self, key: Hashable, task: asyncio.Task[Any]) -> None:
        if self._pending.get(key) is task:
            del self._pending[key]
        if not task.cancelled() and task.exception() is None:
            self.values[key] = task.result()


def computed(request: Request) -> Computed:
    """The app's :class:`Computed`, made at its first use."""
    state = request.app.state
    found: Computed | None = getattr(state, "sample_values", None)
    if found is None:
        found = state.sample_values = Computed()
    return found
