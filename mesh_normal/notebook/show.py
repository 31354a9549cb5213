"""``mn.show(mesh_or_cloud)``: a Plotly figure of a mesh or a point cloud, like the web page's
3D view, for a notebook (``pip install mesh-normal[show]``).

A mesh's faces are coloured by their worst problem, as on the mesh page: no area (drawn as
dots), flipped by the fix (:func:`~mesh_normal.orient`), on a non-manifold edge, on a boundary
edge; a sample of face normals is drawn as strokes, the flipped ones in the flipped colour. A
cloud's points are coloured by their estimated normal (x, y, z as red, green, blue; grey
without one), with strokes along a sample of them. The up axis is the file's (glTF and OBJ are
Y-up, the rest Z-up) or ``up``; the axes are drawn with their names.

Every face is drawn up to :data:`SHOW_FACES`; a larger mesh keeps its problem faces and an even
share of the rest, and the title says how many are shown (the web page decimates instead, with
a library the package does not depend on).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from mesh_normal.mesh.checks import MESH_FORMS, POINT_FORMS, CheckedMesh, checked_mesh, held_points
from mesh_normal.mesh.faces import face_geometry
from mesh_normal.mesh.orientation import orient
from mesh_normal.mesh.topology import by_position
from mesh_normal.points.estimate import point_normals
from mesh_normal.types import BoolArray, FloatArray, IndexArray

if TYPE_CHECKING:
    from plotly.graph_objects import Figure

#: The most faces and points a figure draws, and the most normal strokes.
SHOW_FACES = 200_000
SHOW_POINTS = 50_000
STROKES = 300
#: A stroke's length, as a fraction of the bounding box's diagonal.
STROKE_LENGTH = 0.04

OK, BOUNDARY, NONMANIFOLD, FLIPPED, DEGENERATE = range(5)
#: Each face class's legend and colour (the mesh page's), worst first.
CLASSES = (
    (DEGENERATE, "no area (degenerate)", "#e03131"),
    (FLIPPED, "flipped by the fix", "#f76707"),
    (NONMANIFOLD, "on a non-manifold edge", "#9c36b5"),
    (BOUNDARY, "on a boundary edge", "#f2c94c"),
    (OK, "no problem", "#aab4cc"),
)
COLORS = {code: color for code, _, color in CLASSES}
STROKE_COLOR = "#364fc7"
NO_NORMAL = "rgb(150,150,150)"

#: The up axis each format implies (as the mesh page has it): glTF by its specification and
#: most OBJ exporters are Y-up; STL, PLY, OFF and 3MF come mostly from CAD, which is Z-up.
FORMAT_UP = {"gltf": "y", "glb": "y", "obj": "y"}
#: A three-quarter view from the front for each up axis, far enough (about 2.4 units of the
#: ``aspectmode: data`` box from its centre) that a cube's nearest corner is not clipped.
CAMERAS: dict[str, dict[str, dict[str, float]]] = {
    "x": {"up": {"x": 1, "y": 0, "z": 0}, "eye": {"x": 1.2, "y": 1.6, "z": 1.6}},
    "y": {"up": {"x": 0, "y": 1, "z": 0}, "eye": {"x": 1.6, "y": 1.2, "z": 1.6}},
    "z": {"up": {"x": 0, "y": 0, "z": 1}, "eye": {"x": 1.6, "y": -1.6, "z": 1.2}},
}
#: Enough ambient light that the sides turned from the light keep their colour.
LIGHTING = {"ambient": 0.6, "diffuse": 0.55, "specular": 0.2, "roughness": 0.5}


def show(value: object, *, up: str | None = None) -> Figure:
    """A Plotly figure of a mesh or a point cloud: ``mn.show(mesh)`` in a notebook draws it.

    Parameters
    ----------
    value : a mesh or a point cloud
        Any mesh the mesh functions take alone (what ``read_mesh`` returns, a
        ``(vertices, faces)`` tuple, a trimesh, Open3D or PyVista mesh), or any cloud the
        point functions take (what ``read_points`` returns, an (n, 3) array, an Open3D or
        trimesh point cloud). A mesh's faces are coloured by their problems; a cloud's
        normals are estimated (:func:`~mesh_normal.point_normals`, its defaults) and colour it.
    up : {"x", "y", "z"}, optional
        The axis drawn upward; by default the file's (Y for glTF and OBJ), else Z.

    Returns
    -------
    plotly.graph_objects.Figure
        Shown by a notebook as it is; ``figure.write_html(path)`` saves it.

    Raises
    ------
    ImportError
        Without Plotly: ``pip install mesh-normal[show]``.
    """
    go = _plotly()
    if up is not None and up not in CAMERAS:
        raise ValueError(f'up must be "x", "y" or "z", not {up!r}.')
    file_format = getattr(value, "format", None)
    axis = up or FORMAT_UP.get(file_format if isinstance(file_format, str) else "", "z")
    try:
        # Anything: the TypeError of what is not a mesh sends it to the clouds.
        mesh: CheckedMesh | None = checked_mesh(value)  # type: ignore[arg-type]
    except TypeError:
        mesh = None
    if mesh is not None and len(mesh.faces):
        data, title = _mesh_traces(mesh)
    else:
        try:
            points, _ = held_points(mesh if mesh is not None else value)
        except TypeError:
            raise TypeError(
                f"show takes a mesh ({MESH_FORMS}) or a point cloud ({POINT_FORMS}), "
                f"not {type(value).__name__}."
            ) from None
        data, title = _cloud_traces(np.asarray(points))
    return go.Figure(data=data, layout=_layout(axis, title))


def _plotly() -> Any:
    try:
        import plotly.graph_objects as go
    except ImportError:
        raise ImportError(
            "mn.show draws with Plotly, which is not installed: pip install mesh-normal[show]"
        ) from None
    return go


def face_classes(
    faces: IndexArray,
    degenerate: BoolArray,
    flipped: BoolArray,
    boundary_edges: IndexArray,
    nonmanifold_edges: IndexArray,
) -> np.ndarray:
    """Each face's worst problem, one of OK .. DEGENERATE; ``faces`` by position, as the
    topology's edges name them."""
    classes = np.full(len(faces), OK, dtype=np.int8)
    classes[_on_edges(faces, boundary_edges)] = BOUNDARY
    classes[_on_edges(faces, nonmanifold_edges)] = NONMANIFOLD
    classes[flipped] = FLIPPED
    classes[degenerate] = DEGENERATE
    return classes


def _on_edges(faces: IndexArray, edges: IndexArray) -> BoolArray:
    """Whether each face has one of the (k, 2) ``edges`` as a side."""
    if not len(edges) or not len(faces):
        return np.zeros(len(faces), dtype=bool)
    count = int(max(faces.max(), edges.max())) + 1
    sides = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 3, 2), axis=2).astype(np.int64)
    keys = sides[..., 0] * count + sides[..., 1]
    wanted = np.sort(np.asarray(edges, dtype=np.int64), axis=1)
    found = np.isin(keys, wanted[:, 0] * count + wanted[:, 1]).any(axis=1)
    return np.asarray(found, dtype=bool)


def _shown(classes: np.ndarray) -> IndexArray:
    """The faces to draw: all, or every problem face (up to ``SHOW_FACES``) and an even share
    of the rest."""
    limit = SHOW_FACES
    if len(classes) <= limit:
        return np.arange(len(classes), dtype=np.intp)
    problems = np.flatnonzero(classes != OK)[:limit]
    rest = np.flatnonzero(classes == OK)
    room = limit - len(problems)
    step = max(1, -(-len(rest) // max(room, 1)))
    return np.sort(np.concatenate([problems, rest[::step][:room]])).astype(np.intp)


def _mesh_traces(mesh: CheckedMesh) -> tuple[list[dict[str, Any]], str]:
    geometry = face_geometry(mesh)
    orientation = orient(geometry)
    topology = orientation.topology
    classes = face_classes(
        by_position(mesh),
        geometry.degenerate,
        orientation.flipped,
        topology.boundary_edge_list,
        topology.nonmanifold_edge_list,
    )
    shown = _shown(classes)
    vertices, faces = mesh.vertices, mesh.faces
    centroids = vertices[faces[shown]].mean(axis=1)
    traces: list[dict[str, Any]] = []
    for code, label, color in CLASSES:
        picked = shown[classes[shown] == code]
        if not len(picked):
            continue
        count = f"{label}: {int(np.count_nonzero(classes == code)):,}"
        if code == DEGENERATE:  # no area to fill: a dot at each
            x, y, z = vertices[faces[picked]].mean(axis=1).T.tolist()
            marker = {"color": color, "size": 4}
            traces.append(_scatter(count, x, y, z, mode="markers", marker=marker))
            continue
        used, local = np.unique(faces[picked], return_inverse=True)
        x, y, z = vertices[used].T.tolist()
        i, j, k = local.reshape(-1, 3).T.tolist()
        traces.append(
            {
                "type": "mesh3d",
                "name": count,
                "showlegend": True,
                "x": x,
                "y": y,
                "z": z,
                "i": i,
                "j": j,
                "k": k,
                "color": color,
                "flatshading": True,
                "lighting": LIGHTING,
                "hoverinfo": "skip",
            }
        )
    length = STROKE_LENGTH * _diagonal(vertices[faces[shown].ravel()])
    usable = np.flatnonzero(classes[shown] != DEGENERATE)
    flipped = usable[classes[shown][usable] == FLIPPED][: STROKES // 3]
    others = usable[classes[shown][usable] != FLIPPED]
    others = others[:: max(1, -(-len(others) // (STROKES - len(flipped))))]
    normals = geometry.normals[shown]
    for name, rows, color in (
        ("normals", others, STROKE_COLOR),
        ("flipped normals", flipped, COLORS[FLIPPED]),
    ):
        if len(rows):
            traces.append(_strokes(name, centroids[rows], normals[rows] * length, color))
    drawn = "" if len(shown) == len(faces) else f", {len(shown):,} shown"
    flips = int(np.count_nonzero(orientation.flipped))
    title = f"{len(faces):,} faces{drawn}; the fix flips {flips:,}"
    return traces, title


def _cloud_traces(points: np.ndarray) -> tuple[list[dict[str, Any]], str]:
    estimated = point_normals(points)
    finite = np.flatnonzero(
        np.isfinite(estimated.normals).all(axis=1) & np.isfinite(points).all(axis=1)
    )
    shown = finite[:: max(1, -(-len(finite) // SHOW_POINTS))]
    xyz = np.asarray(points, dtype=np.float64)[shown]
    normals, valid = estimated.normals[shown], estimated.valid[shown]
    rgb = np.clip(np.round((normals + 1.0) * 127.5), 0, 255).astype(int).tolist()
    colors = [
        f"rgb({r},{g},{b})" if ok else NO_NORMAL
        for (r, g, b), ok in zip(rgb, valid.tolist(), strict=True)
    ]
    x, y, z = xyz.T.tolist() if len(xyz) else ([], [], [])
    traces: list[dict[str, Any]] = [
        _scatter("points", x, y, z, mode="markers", marker={"color": colors, "size": 2.5})
    ]
    with_normal = np.flatnonzero(valid)
    rows = with_normal[:: max(1, -(-len(with_normal) // STROKES))]
    if len(rows):
        length = STROKE_LENGTH * _diagonal(xyz)
        traces.append(_strokes("normals", xyz[rows], normals[rows] * length, STROKE_COLOR))
    drawn = "" if len(shown) == len(points) else f", {len(shown):,} shown"
    title = (
        f"{len(points):,} points{drawn}; {int(np.count_nonzero(estimated.valid)):,} with a normal"
    )
    return traces, title


def _diagonal(points: FloatArray) -> float:
    if not len(points):
        return 1.0
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) or 1.0


def _scatter(name: str, x: list[Any], y: list[Any], z: list[Any], **style: Any) -> dict[str, Any]:
    return {"type": "scatter3d", "name": name, "x": x, "y": y, "z": z, "hoverinfo": "skip", **style}


def _strokes(name: str, starts: FloatArray, vectors: FloatArray, color: str) -> dict[str, Any]:
    """Segments from each start along its vector, as one line trace with gaps between."""
    gaps = np.full_like(starts, np.nan)
    stacked = np.stack([starts, starts + vectors, gaps], axis=1).reshape(-1, 3)
    x, y, z = ([None if v != v else v for v in column] for column in stacked.T.tolist())
    return _scatter(name, x, y, z, mode="lines", line={"color": color, "width": 3})


def _layout(up: str, title: str) -> dict[str, Any]:
    axes = {f"{axis}axis": {"title": {"text": axis}} for axis in "xyz"}
    return {
        "title": {"text": f"{title}; {up} up", "font": {"size": 14}},
        "height": 520,
        "margin": {"l": 0, "r": 0, "t": 40, "b": 0},
        "legend": {"itemsizing": "constant", "y": 0.95},
        "scene": {"aspectmode": "data", "camera": CAMERAS[up], **axes},
    }
