"""The mesh page's figures as plain Plotly dicts: the 3D view and the histogram of face areas.

The 3D view colours each face by its worst problem (no area, flipped by the fix, on a
non-manifold edge, on a boundary edge) and draws unit normals as arrows on a sample of
faces. A large mesh is decimated for display: every problem face is kept (up to a cap) and
the rest of the budget goes to a deterministic sample of the others, so the same file always
draws the same way. Degenerate faces have no area to fill, so they are drawn as dots.

WebGL draws in 32-bit floats, so a mesh far from the origin is shifted to its centre, and a
very large or very small one is scaled by a power of two (exact), as in app/view3d.py; the
axes then lose their numbers and the page says so.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from app.calculator.view3d import FONT  # the calculator's 3D view: one look for both

if TYPE_CHECKING:
    from mesh_normal.report import MeshAnalysis

#: Most faces the 3D view draws; a larger mesh is decimated.
DISPLAY_FACES = 20_000
#: Of those, at most this many are problem faces (all of them when there are fewer).
PROBLEM_FACES = 12_000
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
#: Bins of the area histogram, and the span (max / min) beyond which they are log-spaced.
HISTOGRAM_BINS = 30
LOG_SPAN = 100.0
SEED = 20240607  # the sample is random but fixed: the same file draws the same faces

OK, BOUNDARY, NONMANIFOLD, FLIPPED, DEGENERATE = range(5)


@dataclass(frozen=True, slots=True)
class FaceClass:
    code: int
    key: str
    color: str
    label: str


#: What each colour means, worst first; the page's HTML legend is built from this.
CLASSES = (
    FaceClass(DEGENERATE, "degenerate", "#e03131", "No area (degenerate), drawn as dots"),
    FaceClass(FLIPPED, "flipped", "#f76707", "Wound against its neighbours: the fix flips it"),
    FaceClass(NONMANIFOLD, "nonmanifold", "#9c36b5", "On an edge shared by 3 or more faces"),
    FaceClass(BOUNDARY, "boundary", "#f2c94c", "On a boundary edge (a hole or border)"),
    FaceClass(OK, "ok", "#aab4cc", "No problem"),
)
COLORS = {item.code: item.color for item in CLASSES}
ARROW_COLOR = "#3a44b0"
BOUNDARY_LINE = "#c99a06"
NONMANIFOLD_LINE = "#862e9c"
AREA_COLOR = "#4f5bd5"
GRID = "rgba(138, 147, 168, 0.35)"

Trace = dict[str, Any]
IntArray = NDArray[np.intp]


def edge_keys(edges: NDArray[np.integer[Any]], vertex_count: int) -> NDArray[np.int64]:
    """One integer per undirected edge: ``min * n + max`` for (k, 2) vertex pairs."""
    pairs = np.sort(np.asarray(edges, dtype=np.int64).reshape(-1, 2), axis=1)
    return pairs[:, 0] * max(vertex_count, 1) + pairs[:, 1]


def faces_on_edges(
    faces: IntArray, vertex_count: int, edges: NDArray[np.integer[Any]]
) -> NDArray[np.bool_]:
    """For (m, 3) faces, whether each has one of the (k, 2) ``edges`` as a side."""
    if not len(edges) or not len(faces):
        return np.zeros(len(faces), dtype=bool)
    sides = np.stack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]], axis=1)
    keys = edge_keys(sides, vertex_count).reshape(-1, 3)
    return np.isin(keys, edge_keys(edges, vertex_count)).any(axis=1)


def face_classes(
    faces: IntArray,
    vertex_count: int,
    degenerate: NDArray[np.bool_],
    flipped: NDArray[np.bool_],
    boundary_edges: NDArray[np.integer[Any]],
    nonmanifold_edges: NDArray[np.integer[Any]],
) -> NDArray[np.int8]:
    """Each face's worst problem, as one of the codes OK .. DEGENERATE; shape (m,)."""
    classes = np.full(len(faces), OK, dtype=np.int8)
    classes[faces_on_edges(faces, vertex_count, boundary_edges)] = BOUNDARY
    classes[faces_on_edges(faces, vertex_count, nonmanifold_edges)] = NONMANIFOLD
    classes[np.asarray(flipped, dtype=bool)] = FLIPPED
    classes[np.asarray(degenerate, dtype=bool)] = DEGENERATE
    return classes


def _sample(indices: IntArray, count: int, rng: np.random.Generator) -> IntArray:
    if len(indices) <= count:
        return indices
    return np.sort(rng.choice(indices, size=count, replace=False))


def select_faces(
    classes: NDArray[np.int8], limit: int = DISPLAY_FACES, problem_limit: int = PROBLEM_FACES
) -> IntArray:
    """The faces to draw, in file order: all when they fit, else problems first, then a sample.

    Deterministic: the same classes give the same selection.
    """
    everything = np.arange(len(classes), dtype=np.intp)
    if len(classes) <= limit:
        return everything
    rng = np.random.default_rng(SEED)
    problems = _sample(everything[classes != OK], min(problem_limit, limit), rng)
    others = _sample(everything[classes == OK], limit - len(problems), rng)
    return np.sort(np.concatenate([problems, others]))


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

    Halving before adding keeps the centre and extent finite even at ±1.8e308.
    """
    if not len(vertices):
        return ViewSpace(np.zeros((0, 3)), 0, np.zeros(3), False)
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    centre = low / 2 + high / 2
    half = float((high / 2 - low / 2).max())
    exponent = 0
    if half and not TRUE_SCALE[0] <= half <= TRUE_SCALE[1]:
        exponent = int(np.frexp(half)[1])
    shifted = exponent != 0 or float(np.abs(centre).max()) > FAR_AWAY * max(half, 1e-300)
    if not shifted:
        return ViewSpace(vertices, 0, np.zeros(3), False)
    if exponent > 0:  # large: scale first, so the difference cannot overflow
        points = np.ldexp(vertices, -exponent) - np.ldexp(centre, -exponent)
    else:  # small: subtract first, so the scaling cannot overflow
        points = np.ldexp(vertices - centre, -exponent)
    return ViewSpace(points, exponent, centre, True)


def _rounded(points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Points rounded to a millionth of their extent: all a 32-bit view shows, in short JSON."""
    extent = float(np.abs(points).max(initial=0.0))
    if not extent:
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
    x, y, z = _segments(points[edges[:, 0]], points[edges[:, 1]])
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


def _arrow_faces(shown: IntArray, classes: NDArray[np.int8]) -> IntArray:
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
    indices: IntArray,
    length: float,
    color: str,
) -> list[Trace]:
    """Shafts as one line trace and heads as one cone trace, from each face's centroid."""
    if not len(indices):
        return []
    head = 0.3 * length
    tips = _rounded(centroids + normals * length)
    x, y, z = _segments(centroids, _rounded(tips - normals * head))
    hover = [
        f"face {i}: normal ({n[0]:.4g}, {n[1]:.4g}, {n[2]:.4g})"
        for i, n in zip(indices.tolist(), normals.tolist(), strict=True)
    ]
    heads = _rounded(normals * head)
    return [
        {
            "type": "scatter3d",
            "mode": "lines",
            "name": name,
            "x": x,
            "y": y,
            "z": z,
            "line": {"color": color, "width": 3},
            "hoverinfo": "skip",
        },
        {
            "type": "cone",
            "name": name,
            "x": tips[:, 0].tolist(),
            "y": tips[:, 1].tolist(),
            "z": tips[:, 2].tolist(),
            "u": heads[:, 0].tolist(),
            "v": heads[:, 1].tolist(),
            "w": heads[:, 2].tolist(),
            "anchor": "tip",
            "sizemode": "raw",
            "sizeref": 1,
            "colorscale": [[0, color], [1, color]],
            "showscale": False,
            "lighting": {"ambient": 0.9, "diffuse": 0.3, "specular": 0.1},
            "hovertext": hover,
            "hovertemplate": "%{hovertext}<extra></extra>",
        },
    ]


def build_view(
    vertices: NDArray[np.float64],
    faces: IntArray,
    normals: NDArray[np.float64],
    classes: NDArray[np.int8],
    boundary_edges: NDArray[np.integer[Any]],
    nonmanifold_edges: NDArray[np.integer[Any]],
) -> dict[str, Any]:
    """The 3D view: ``{"figure", "shown_faces", "total_faces", "arrows", "counts", "note"}``.

    ``counts`` holds the number of faces of each class in the whole mesh.
    """
    shown = select_faces(classes)
    used, local = np.unique(faces[shown], return_inverse=True)
    space = view_space(vertices[used])
    points = _rounded(space.points)
    local = local.reshape(-1, 3)
    corner_points = points[local] if len(local) else np.zeros((0, 3, 3))
    centroids = _rounded(corner_points.mean(axis=1))
    diagonal = (
        float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) if len(points) else 1.0
    )
    length = ARROW_LENGTH * (diagonal or 1.0)
    where = {int(face): row for row, face in enumerate(shown.tolist())}
    traces: list[Trace] = []
    solid = classes[shown] != DEGENERATE
    if solid.any():
        x, y, z = points.T.tolist()
        i, j, k = local[solid].T.tolist()
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
                "facecolor": [COLORS[int(code)] for code in classes[shown][solid]],
                "flatshading": True,
                "hoverinfo": "skip",
                "lighting": {
                    "ambient": 0.7,
                    "diffuse": 0.5,
                    "specular": 0.05,
                    "roughness": 0.9,
                    "fresnel": 0.05,
                },
                "lightposition": {"x": 1e5, "y": 2e5, "z": 3e5},
            }
        )
    traces.extend(_problem_edges(points, used, boundary_edges, nonmanifold_edges))
    dots = np.flatnonzero(~solid)[:EDGE_LINES]
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
                "hovertext": [f"face {int(shown[row])}: no area" for row in dots],
                "hovertemplate": "%{hovertext}<extra></extra>",
            }
        )
    arrow_faces = _arrow_faces(shown, classes)
    rows = np.array([where[int(face)] for face in arrow_faces], dtype=np.intp)
    for name, color, pick in (
        ("normals", ARROW_COLOR, classes[arrow_faces] != FLIPPED),
        ("flipped normals", COLORS[FLIPPED], classes[arrow_faces] == FLIPPED),
    ):
        traces.extend(
            _arrows(
                name,
                centroids[rows[pick]] if len(rows) else centroids[:0],
                normals[arrow_faces[pick]],
                arrow_faces[pick],
                length,
                color,
            )
        )
    return {
        "figure": {"data": traces, "layout": _layout()},
        "shown_faces": len(shown),
        "total_faces": len(faces),
        "arrows": len(arrow_faces),
        "counts": {item.key: int(np.count_nonzero(classes == item.code)) for item in CLASSES},
        "note": _note(space),
    }


def _problem_edges(
    points: NDArray[np.float64],
    used: IntArray,
    boundary_edges: NDArray[np.integer[Any]],
    nonmanifold_edges: NDArray[np.integer[Any]],
) -> list[Trace]:
    """Boundary and non-manifold edges whose both ends are drawn, in view coordinates."""
    traces = []
    for name, edges, color, width in (
        ("boundary edges", boundary_edges, BOUNDARY_LINE, 4),
        ("non-manifold edges", nonmanifold_edges, NONMANIFOLD_LINE, 6),
    ):
        edges = np.asarray(edges, dtype=np.intp).reshape(-1, 2)
        if not len(edges) or not len(used):
            continue
        at = np.searchsorted(used, edges).clip(0, len(used) - 1)
        drawn = (used[at] == edges).all(axis=1)
        local = at[drawn][:EDGE_LINES]
        if len(local):
            traces.append(_edge_trace(name, points, local, color, width))
    return traces


def _axis(title: str) -> dict[str, Any]:
    return {"visible": False, "title": {"text": title}}


def _layout() -> dict[str, Any]:
    return {
        "margin": {"l": 0, "r": 0, "t": 0, "b": 0},
        "height": 460,
        "paper_bgcolor": "rgba(0,0,0,0)",
        "font": FONT,
        "showlegend": False,
        "scene": {
            "aspectmode": "data",
            "xaxis": _axis("x"),
            "yaxis": _axis("y"),
            "zaxis": _axis("z"),
            "camera": {"eye": {"x": 1.05, "y": -1.05, "z": 0.7}},
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


def area_histogram(
    areas: NDArray[np.float64], degenerate: NDArray[np.bool_], bins: int = HISTOGRAM_BINS
) -> dict[str, Any]:
    """Bins of the face areas: ``{"edges", "counts", "log", "zero_area", "beyond_range"}``.

    Degenerate (and zero) areas are counted apart as ``zero_area``, infinite ones (coordinates
    beyond about 1e154) as ``beyond_range``; the counts and those two add up to the faces.
    Bins are log-spaced when the areas span more than LOG_SPAN.
    """
    areas = np.asarray(areas, dtype=np.float64)
    zero = np.asarray(degenerate, dtype=bool) | (areas == 0)
    finite = np.isfinite(areas)
    values = areas[~zero & finite]
    result: dict[str, Any] = {
        "edges": [],
        "counts": [],
        "log": False,
        "zero_area": int(np.count_nonzero(zero)),
        "beyond_range": int(np.count_nonzero(~zero & ~finite)),
    }
    if not len(values):
        return result
    low, high = float(values.min()), float(values.max())
    log = high > LOG_SPAN * low
    count = max(1, min(bins, int(np.ceil(np.sqrt(len(values))))))
    if low == high:
        edges = np.array([low * (1 - 1 / 16), min(high * (1 + 1 / 16), np.finfo(float).max)])
    elif log:
        edges = np.geomspace(low, high, count + 1)
    else:
        edges = np.linspace(low, high, count + 1)
    edges[0], edges[-1] = min(edges[0], low), max(edges[-1], high)
    counts, _ = np.histogram(values, bins=edges)
    return {**result, "edges": edges.tolist(), "counts": counts.tolist(), "log": bool(log)}


def histogram_figure(histogram: dict[str, Any]) -> dict[str, Any]:
    """A bar chart of :func:`area_histogram`; log bins are drawn on a log10 axis."""
    edges = np.array(histogram["edges"], dtype=np.float64)
    log = histogram["log"]
    at = np.log10(edges) if log else edges
    # Halves first: near the double maximum a sum of two edges would overflow.
    centres, widths = at[:-1] / 2 + at[1:] / 2, np.diff(at)
    hover = [
        f"{a:.3g} to {b:.3g}: {n:,} faces"
        for a, b, n in zip(edges[:-1], edges[1:], histogram["counts"], strict=True)
    ]
    traces: list[Trace] = [
        {
            "type": "bar",
            "name": "faces",
            "x": centres.tolist(),
            "y": histogram["counts"],
            "width": (widths * 0.92).tolist(),
            "marker": {"color": AREA_COLOR},
            "hovertext": hover,
            "hovertemplate": "%{hovertext}<extra></extra>",
        }
    ]
    xaxis: dict[str, Any] = {
        "title": {"text": "face area" + (" (log scale)" if log else "")},
        "gridcolor": GRID,
        "zeroline": False,
        "exponentformat": "e",
    }
    zero = histogram["zero_area"]
    if zero and len(centres):
        step = float(widths.mean()) or 1.0
        spot = float(at[0]) - 1.5 * step
        traces.append(
            {
                "type": "bar",
                "name": "zero area",
                "x": [spot],
                "y": [zero],
                "width": [0.92 * step],
                "marker": {"color": COLORS[DEGENERATE]},
                "hovertext": [f"zero area (degenerate): {zero:,} faces"],
                "hovertemplate": "%{hovertext}<extra></extra>",
            }
        )
    if log and len(at):
        xaxis.update(_log_ticks(float(at[0]), float(at[-1])))
    if zero and len(centres):
        xaxis.setdefault("tickvals", []).insert(0, spot)
        xaxis.setdefault("ticktext", []).insert(0, "zero")
        if not log:
            xaxis["tickmode"] = "array"
            ticks = np.linspace(edges[0], edges[-1], 5)
            xaxis["tickvals"] += ticks.tolist()
            xaxis["ticktext"] += [f"{t:.3g}" for t in ticks]
    return {
        "data": traces,
        "layout": {
            "margin": {"l": 56, "r": 16, "t": 12, "b": 48},
            "height": 300,
            "bargap": 0,
            "paper_bgcolor": "rgba(0,0,0,0)",
            "plot_bgcolor": "rgba(0,0,0,0)",
            "font": FONT,
            "showlegend": False,
            "xaxis": xaxis,
            "yaxis": {"title": {"text": "faces"}, "gridcolor": GRID, "rangemode": "tozero"},
        },
    }


def _log_ticks(low: float, high: float) -> dict[str, Any]:
    """Ticks at powers of ten (every few when the span is wide), written as 1e-3."""
    first, last = int(np.floor(low)), int(np.ceil(high))
    step = max(1, (last - first) // 6)
    powers = list(range(first, last + 1, step))
    return {
        "tickmode": "array",
        "tickvals": [float(p) for p in powers],
        "ticktext": [f"1e{p}" for p in powers],
    }


def mesh_figures(analysis: MeshAnalysis) -> dict[str, Any]:
    """The page's figures for one analysed mesh: ``{"view", "histogram", "histogram_figure"}``."""
    mesh, topology = analysis.mesh, analysis.topology
    classes = face_classes(
        mesh.faces,
        len(mesh.vertices),
        analysis.faces.degenerate,
        analysis.orientation.flipped,
        topology.boundary_edge_list,
        topology.nonmanifold_edge_list,
    )
    view = build_view(
        mesh.vertices,
        mesh.faces,
        analysis.faces.normals,
        classes,
        topology.boundary_edge_list,
        topology.nonmanifold_edge_list,
    )
    histogram = area_histogram(analysis.faces.areas, analysis.faces.degenerate)
    return {
        "view": view,
        "histogram": histogram,
        "histogram_figure": histogram_figure(histogram) if histogram["counts"] else None,
    }
