"""The mesh page's 3D view as a plain Plotly figure dict.

The view colours each face by its worst problem (:mod:`app.mesh.classes`: no area, flipped by
the fix, on a non-manifold edge, on a boundary edge) and draws unit normals as arrows on a
sample of faces. A large mesh is drawn as a simplified surface of about DISPLAY_FACES faces
(:mod:`app.mesh.view_surface`): every problem face (up to a cap, worst first) exactly as it
is, the rest decimated, the same way for the same file. Degenerate faces have no area to
fill, so they are drawn as dots.

WebGL draws in 32-bit floats, so a mesh far from the origin is shifted to its centre, and a
very large or very small one is scaled by a power of two (exact), as in
app/calculator/view3d.py; the axes then lose their numbers and the page says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from app.mesh.classes import CLASSES, COLORS, DEGENERATE, FLIPPED, OK
from app.mesh.view_normals import normal_pools
from app.mesh.view_surface import display_surface, used_vertices
from app.web.camera import DEFAULT_UP, Scene, cameras, vector
from app.web.plotly import DEEP_ACCENT, FONT, TRANSPARENT, Trace, cone_trace
from mesh_normal.types import IndexArray

#: About the most faces the 3D view draws; a larger mesh is simplified.
DISPLAY_FACES = 20_000
#: At most this many problem faces are drawn exactly as they are, worst first; each keeps the
#: faces around it too (see app.mesh.view_surface), so the cap is well below DISPLAY_FACES.
PROBLEM_FACES = 6_000
#: Most faces that get a normal arrow, and the share of the drawn faces that get one.
ARROW_FACES = 300
ARROW_SHARE = 8
#: Most boundary and non-manifold edges drawn (each kind), and degenerate dots.
EDGE_LINES = 5_000
#: An arrow's length, as a fraction of the bounding box's diagonal.
ARROW_LENGTH = 0.04
#: Within these half-extents the view keeps the file's scale.
TRUE_SCALE = (2.0**-20, 2.0**20)
#: A mesh whose centre is this many half-extents from the origin is shifted to it.
FAR_AWAY = 1e3
#: Smallest extent that _rounded rounds (10**(6 - log10 of it) must stay a finite double).
MIN_ROUNDED = 1e-290
SEED = 20240607  # the sample is random but fixed: the same file draws the same faces

#: The most problem places the view's "Next problem" steps through, and how close it looks at
#: each (a fraction of the whole mesh's framing distance).
PROBLEM_SPOTS = 12
SPOT_DISTANCE = 0.7

#: The surface's light: a key light from above the camera's shoulder (LIGHT) with enough
#: diffuse and a little specular that curvature reads as a solid, and enough ambient that the
#: side turned away stays a colour, not black. A simplified surface is shaded smooth (its
#: facets are the decimation's, not the file's); a mesh drawn whole shows its own facets.
SURFACE_LIGHTING = {
    "ambient": 0.45,
    "diffuse": 0.7,
    "specular": 0.25,
    "roughness": 0.45,
    "fresnel": 0.15,
    "facenormalsepsilon": 0,
    "vertexnormalsepsilon": 0,
}
#: Where the light is. Plotly takes the surface's light in the camera's frame (x to the right
#: of the screen, y up it, z towards the viewer), so it follows the camera: this one is a key
#: light from in front, above and a little to the right, far enough to be directional.
LIGHT = {"x": 5e4, "y": 1e5, "z": 3e5}

ARROW_COLOR = DEEP_ACCENT
BOUNDARY_LINE = "#c99a06"
NONMANIFOLD_LINE = "#862e9c"


def _sample(indices: IndexArray, count: int, rng: np.random.Generator) -> IndexArray:
    if len(indices) <= count:
        return indices
    return np.sort(rng.choice(indices, size=count, replace=False))


def problem_faces(classes: NDArray[np.int8], limit: int = PROBLEM_FACES) -> IndexArray:
    """The problem faces to draw as they are, in file order: all of them, or the worst first.

    Within the class that reaches the cap, a fixed sample: the same classes give the same faces.
    """
    rng = np.random.default_rng(SEED)
    chosen: list[IndexArray] = []
    room = limit
    for item in CLASSES:  # worst first
        if item.code == OK or room <= 0:
            continue
        faces = _sample(np.flatnonzero(classes == item.code).astype(np.intp), room, rng)
        chosen.append(faces)
        room -= len(faces)
    return np.sort(np.concatenate(chosen)) if chosen else np.zeros(0, dtype=np.intp)


@dataclass(frozen=True, slots=True)
class ViewSpace:
    """Display coordinates: ``(p - centre) * 2**-exponent``, or ``p`` unchanged."""

    points: NDArray[np.float64]
    exponent: int
    centre: NDArray[np.float64]
    shifted: bool

    @property
    def transformed(self) -> bool:
        return self.shifted or self.exponent != 0


def view_space(vertices: NDArray[np.float64]) -> ViewSpace:
    """Coordinates a 32-bit WebGL view can draw, for finite float64 vertices of any size.

    Halving before adding keeps the centre finite even at ±1.8e308. The extent is taken
    whole where it is finite, so that a subnormal one (5e-324, whose half is 0) still sets
    the scale; only an extent beyond the double range is taken from the halves.
    """
    if not len(vertices):
        return ViewSpace(np.zeros((0, 3)), 0, np.zeros(3), False)
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    centre = low / 2 + high / 2
    with np.errstate(over="ignore"):
        span = float((high - low).max())
    if math.isfinite(span):
        half, power = span / 2, int(np.frexp(span)[1]) - 1  # 2**power: about the half-extent
    else:
        half = float((high / 2 - low / 2).max())
        power = int(np.frexp(half)[1])
    exponent = 0
    if span and not TRUE_SCALE[0] <= half <= TRUE_SCALE[1]:
        exponent = power
    shifted = exponent != 0 or float(np.abs(centre).max()) > FAR_AWAY * max(half, 1e-300)
    if not shifted:
        return ViewSpace(vertices, 0, np.zeros(3), False)
    if exponent > 0:  # large: scale first, so the difference cannot overflow
        points = np.ldexp(vertices, -exponent) - np.ldexp(centre, -exponent)
    else:  # small: subtract first, so the scaling cannot overflow
        points = np.ldexp(vertices - centre, -exponent)
    return ViewSpace(points, exponent, centre, True)


def _rounded(points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Points rounded to a millionth of their extent: all a 32-bit view shows, in short JSON.

    An extent below 1e-290 is left as it is: ``np.round`` multiplies by ``10**decimals``,
    which is infinite beyond 1e308 (and would turn every zero into NaN).
    """
    extent = float(np.abs(points).max(initial=0.0))
    if not (MIN_ROUNDED <= extent < math.inf):
        return points
    return np.round(points, 6 - int(np.ceil(np.log10(extent))))


def _segments(starts: NDArray[np.float64], ends: NDArray[np.float64]) -> tuple[list[Any], ...]:
    """x, y, z lists for many separate segments in one trace (``None`` between them)."""
    gaps = np.full_like(starts, np.nan)
    stacked = np.stack([starts, ends, gaps], axis=1).reshape(-1, 3)
    return tuple([None if np.isnan(x) else float(x) for x in column] for column in stacked.T)


def _edge_trace(
    name: str, points: NDArray[np.float64], edges: NDArray[np.integer[Any]], color: str, width: int
) -> Trace:
    return _line_trace(name, points[edges[:, 0]], points[edges[:, 1]], color, width)


def _line_trace(
    name: str, starts: NDArray[np.float64], ends: NDArray[np.float64], color: str, width: int
) -> Trace:
    """Segments from each start to its end as one line trace (gaps between them)."""
    x, y, z = _segments(starts, ends)
    return {
        "type": "scatter3d",
        "mode": "lines",
        "name": name,
        "x": x,
        "y": y,
        "z": z,
        "line": {"color": color, "width": width},
        "hoverinfo": "skip",
    }


def _arrow_faces(shown: IndexArray, classes: NDArray[np.int8]) -> IndexArray:
    """Faces that get an arrow: flipped ones first (up to a third), then a sample.

    One in ARROW_SHARE of the drawn faces, at least 24 and at most ARROW_FACES, so that a
    small mesh is not a hedgehog.
    """
    rng = np.random.default_rng(SEED + 1)
    usable = shown[classes[shown] != DEGENERATE]
    budget = min(ARROW_FACES, max(24, len(shown) // ARROW_SHARE))
    flipped = _sample(usable[classes[usable] == FLIPPED], budget // 3, rng)
    rest = _sample(np.setdiff1d(usable, flipped), budget - len(flipped), rng)
    return np.sort(np.concatenate([flipped, rest]))


def _arrows(
    name: str,
    centroids: NDArray[np.float64],
    normals: NDArray[np.float64],
    indices: IndexArray,
    length: float,
    color: str,
) -> list[Trace]:
    """Shafts as one line trace and heads as one cone trace, from each face's centroid."""
    if not len(indices):
        return []
    head = 0.3 * length
    tips = _rounded(centroids + normals * length)
    hover = [
        f"face {i}: normal ({n[0]:.4g}, {n[1]:.4g}, {n[2]:.4g})"
        for i, n in zip(indices.tolist(), normals.tolist(), strict=True)
    ]
    heads = _rounded(normals * head)
    return [
        _line_trace(name, centroids, _rounded(tips - normals * head), color, 3),
        {
            **cone_trace(name, tips, heads, color),
            "hovertext": hover,
            "hovertemplate": "%{hovertext}<extra></extra>",
        },
    ]


def build_view(
    vertices: NDArray[np.float64],
    faces: IndexArray,
    normals: NDArray[np.float64],
    classes: NDArray[np.int8],
    boundary_edges: NDArray[np.integer[Any]],
    nonmanifold_edges: NDArray[np.integer[Any]],
    up: str = DEFAULT_UP,
) -> dict[str, Any]:
    """The 3D view: ``{"figure", "shown_faces", "total_faces", "simplified", "arrows", "counts",
    "note", "up", "cameras", "spots", "normals", "face_normals"}``.

    ``counts`` holds the number of faces of each class in the whole mesh; ``up`` is the axis
    drawn upward ("x", "y" or "z") and ``cameras`` the camera for each, for the page's switch
    (the whole mesh framed); ``spots`` the problem places the page steps through
    (:func:`problem_spots`);
    ``normals`` the arrows the page may draw instead (:mod:`app.mesh.view_normals`);
    ``face_normals`` the unit normal of each face of the drawn surface (the "faces" trace's
    i/j/k, zero for none), for the page's crease slider, which splits the surface's vertices.
    """
    used, local = used_vertices(faces, len(vertices))
    space = view_space(vertices[used])
    surface = display_surface(space.points, local, problem_faces(classes), DISPLAY_FACES)
    points = _rounded(surface.points)
    face_class = np.full(len(surface.faces), OK, dtype=np.int8)
    copies = surface.source >= 0
    face_class[copies] = classes[surface.source[copies]]
    file_points = _rounded(space.points)
    centroids = _rounded(file_points[local].mean(axis=1)) if len(local) else np.zeros((0, 3))
    diagonal = (
        float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) if len(points) else 1.0
    )
    length = ARROW_LENGTH * (diagonal or 1.0)
    traces: list[Trace] = []
    solid = face_class != DEGENERATE
    face_normals = _unit_normals(points, surface.faces[solid])
    if solid.any():
        x, y, z = points.T.tolist()
        i, j, k = surface.faces[solid].T.tolist()
        traces.append(
            {
                "type": "mesh3d",
                "name": "faces",
                "x": x,
                "y": y,
                "z": z,
                "i": i,
                "j": j,
                "k": k,
                "facecolor": [COLORS[int(code)] for code in face_class[solid]],
                "flatshading": not surface.simplified,
                "hoverinfo": "skip",
                "lighting": SURFACE_LIGHTING,
                "lightposition": LIGHT,
            }
        )
    # The edges name the file's vertices: renumber them on the surface's points.
    on_surface = np.full(len(vertices), -1, dtype=np.intp)
    kept = surface.vertex_source >= 0
    on_surface[used[surface.vertex_source[kept]]] = np.flatnonzero(kept)
    traces.extend(_problem_edges(points, on_surface, boundary_edges, nonmanifold_edges))
    dots = surface.source[face_class == DEGENERATE][:EDGE_LINES]
    if len(dots):
        x, y, z = centroids[dots].T.tolist()
        traces.append(
            {
                "type": "scatter3d",
                "mode": "markers",
                "name": "degenerate",
                "x": x,
                "y": y,
                "z": z,
                "marker": {"color": COLORS[DEGENERATE], "size": 4},
                "hovertext": [f"face {int(face)}: no area" for face in dots],
                "hovertemplate": "%{hovertext}<extra></extra>",
            }
        )
    arrow_faces = _arrow_faces(np.arange(len(faces), dtype=np.intp), classes)
    for name, color, pick in (
        ("normals", ARROW_COLOR, classes[arrow_faces] != FLIPPED),
        ("flipped normals", COLORS[FLIPPED], classes[arrow_faces] == FLIPPED),
    ):
        traces.extend(
            _arrows(
                name,
                centroids[arrow_faces[pick]],
                normals[arrow_faces[pick]],
                arrow_faces[pick],
                length,
                color,
            )
        )
    scene = Scene.of(points)
    spots = problem_spots(scene, centroids, normals, classes)
    views = cameras(scene, points, _towards(scene, spots))
    layout = _layout()
    layout["scene"]["camera"] = views[up]
    return {
        "figure": {"data": traces, "layout": layout},
        "shown_faces": len(surface.faces),
        "total_faces": len(faces),
        "simplified": surface.simplified,
        "arrows": len(arrow_faces),
        "counts": {item.key: int(np.count_nonzero(classes == item.code)) for item in CLASSES},
        "note": _note(space),
        "up": up,
        "cameras": views,
        "spots": spots,
        "normals": normal_pools(
            file_points, local, normals, classes == FLIPPED, vertices[used], used
        ),
        "face_normals": face_normals,
    }


def problem_spots(
    scene: Scene,
    centroids: NDArray[np.float64],
    normals: NDArray[np.float64],
    classes: NDArray[np.int8],
) -> list[dict[str, Any]]:
    """Up to PROBLEM_SPOTS places of problem faces, spread over the mesh (each the farthest
    from those before it, from the first in file order): where the camera looks (``center``,
    in scene units), from which side (``outward``: the face's normal as the fix leaves it) and
    from how far (``distance``), with ``face``, the face's index in the file."""
    faces = np.flatnonzero(classes != OK)
    if not len(faces) or not len(centroids):
        return []
    where = centroids[faces]
    chosen = [0]
    nearest = np.linalg.norm(where - where[0], axis=1)
    while len(chosen) < min(PROBLEM_SPOTS, len(faces)) and nearest.max() > 0:
        chosen.append(int(np.argmax(nearest)))
        nearest = np.minimum(nearest, np.linalg.norm(where - where[chosen[-1]], axis=1))
    spots = []
    for index in chosen:
        face = int(faces[index])
        outward = -normals[face] if classes[face] == FLIPPED else normals[face]
        if not np.isfinite(outward).all() or not np.any(outward):  # no area: from the centre
            outward = where[index] - scene.middle
        length = float(np.linalg.norm(outward))
        direction = outward / length if length > 0 else np.array([1.0, 0.0, 0.0])
        spots.append(
            {
                "face": face,
                "center": scene.place(where[index]),
                "outward": vector(direction),
                "distance": round(SPOT_DISTANCE * scene.distance, 5),
            }
        )
    return spots


def _towards(scene: Scene, spots: list[dict[str, Any]]) -> NDArray[np.float64] | None:
    """Where the problem places lie from the centre (scene units), when they lie to one side:
    the camera turns that way. None when there are none or they are all around."""
    if not spots:
        return None
    centres = np.array([[spot["center"][axis] for axis in "xyz"] for spot in spots])
    towards = centres.mean(axis=0)
    if np.linalg.norm(towards) < 0.1 * scene.radius:  # all around: no side is better
        return None
    return towards  # type: ignore[no-any-return]


def _unit_normals(points: NDArray[np.float64], faces: IndexArray) -> list[list[float]]:
    """Unit normals of the faces, rounded to 5 decimals; zero rows for faces without area."""
    if not len(faces):
        return []
    p = points[faces]
    cross = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.linalg.norm(cross, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(length > 0, cross / length, 0.0)
    unit[~np.isfinite(unit).all(axis=1)] = 0.0
    return np.round(unit, 5).tolist()  # type: ignore[no-any-return]


def _problem_edges(
    points: NDArray[np.float64],
    on_surface: IndexArray,
    boundary_edges: NDArray[np.integer[Any]],
    nonmanifold_edges: NDArray[np.integer[Any]],
) -> list[Trace]:
    """Boundary and non-manifold edges whose both ends are drawn, in view coordinates.

    ``on_surface`` gives each vertex of the file its point on the surface, or -1.
    """
    traces = []
    for name, edges, color, width in (
        ("boundary edges", boundary_edges, BOUNDARY_LINE, 4),
        ("non-manifold edges", nonmanifold_edges, NONMANIFOLD_LINE, 6),
    ):
        edges = np.asarray(edges, dtype=np.intp).reshape(-1, 2)
        if not len(edges):
            continue
        local = on_surface[edges]
        local = local[(local >= 0).all(axis=1)][:EDGE_LINES]
        if len(local):
            traces.append(_edge_trace(name, points, local, color, width))
    return traces


def _axis(title: str) -> dict[str, Any]:
    return {"visible": False, "title": {"text": title}}


def _layout() -> dict[str, Any]:
    return {
        "margin": {"l": 0, "r": 0, "t": 0, "b": 0},
        "height": 460,
        "paper_bgcolor": TRANSPARENT,
        "font": FONT,
        "showlegend": False,
        "scene": {
            "aspectmode": "data",
            "xaxis": _axis("x"),
            "yaxis": _axis("y"),
            "zaxis": _axis("z"),
        },
    }


def _note(space: ViewSpace) -> str | None:
    if not space.transformed:
        return None
    centre = ", ".join(f"{x:.6g}" for x in space.centre.tolist())
    scale = f" and scaled by 2^{-space.exponent}" if space.exponent else ""
    return (
        f"Drawn centred on ({centre}){scale}, so that WebGL's 32-bit floats can show "
        "it; the report's numbers are the file's."
    )
