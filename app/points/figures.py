"""The point-cloud page's figures: a 3D view of an even sample and a histogram, as plain dicts.

The view shows at most :data:`VIEW_POINTS` points, one per cell of a voxel grid sized so that
the sample spreads over the whole cloud (a dense patch does not crowd out the rest), shaded by
their normal under a fixed light (:func:`shading`), and the normals of at most
:data:`VIEW_NORMALS` of them, spread the same way, as short strokes. The points carry two
colourings (the light, one for each up axis, or curvature); the page's script swaps them, and
the camera for each up axis, framed on the cloud (:mod:`app.web.camera`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from app.web.camera import CAMERAS, Scene, cameras, up_axis, vector
from app.web.plotly import ACCENT, DEEP_ACCENT, FONT, MUTED, TRANSPARENT, Trace, histogram_layout
from mesh_normal.points.analysis import PointAnalysis
from mesh_normal.points.estimate import PointStatus
from mesh_normal.types import BoolArray, FloatArray, IndexArray

#: The most points the 3D view draws, and of those the most with a normal stroke: a few hundred
#: strokes show which way the normals point; thousands hide the cloud behind them.
VIEW_POINTS = 20_000
VIEW_NORMALS = 300
#: A stroke is this fraction of the cloud's bounding-box diagonal long.
STROKE_FRACTION = 0.03
#: The view's box reaches this fraction of the cloud's diagonal beyond the drawing.
BOX_MARGIN = 0.01
#: The light's share that reaches every point: the side turned away stays a colour, not black.
AMBIENT = 0.3
#: How far above the camera the light stands: its direction is the camera's, raised by this
#: much of the up axis (a key light over the viewer's shoulder, as the mesh view's).
LIGHT_RISE = 0.6
#: The shading's codes, the marker's colour numbers (cmin 0, cmax 300): 0 to 100 the brightness
#: of a normal whose side is known (or not asked for), 150 a point without a normal, 200 to 300
#: the brightness of a normal whose side could not be decided. One colour scale draws all three.
NO_NORMAL = 150
UNDECIDED = 200
SHADE_MAX = 300
#: One hue from dark to light for the normals, grey for none, amber (the page's warning) for
#: the undecided; the 1-wide steps between the ranges hold no code, so no colour bleeds.
SHADING_SCALE = [
    [0.0, "#10144a"],
    [100 / SHADE_MAX, "#aab1ff"],
    [101 / SHADE_MAX, "#9a9a9a"],
    [199 / SHADE_MAX, "#9a9a9a"],
    [200 / SHADE_MAX, "#3a2200"],
    [1.0, "#ffb84d"],
]
UNDECIDED_STROKE = "#c2410c"
#: The histogram's bins; curvature (surface variation) lies in [0, 1/3].
BINS = 40
GRID = "rgba(138,147,168,0.25)"


def voxel_sample(points: FloatArray, limit: int = VIEW_POINTS) -> IndexArray:
    """The indices (ascending) of at most ``limit`` finite points, the first in each occupied
    cell of a cubic grid, its cells halved in count until at most ``limit`` are occupied.

    Parameters
    ----------
    points : (n, 3) float64
    """
    finite = np.flatnonzero(np.isfinite(points).all(axis=1))
    if len(finite) <= limit:
        return finite
    chosen = points[finite]
    low, high = chosen.min(axis=0), chosen.max(axis=0)
    extent = float(np.max(high - low)) or 1.0
    # Start near limit cells over the longest side's cube, then coarsen until they fit.
    cells = max(1, math.ceil(limit ** (1 / 3)) * 2)
    while True:
        size = extent / cells
        keys = np.floor((chosen - low) / size).astype(np.int64)
        keys = np.minimum(keys, cells - 1)
        flat = (keys[:, 0] * (cells + 1) + keys[:, 1]) * (cells + 1) + keys[:, 2]
        _, first = np.unique(flat, return_index=True)
        if len(first) <= limit or cells == 1:
            return finite[np.sort(first)][:limit]
        cells = max(1, int(cells / math.sqrt(len(first) / limit) / 1.05))


def _rounded(values: FloatArray, scale: float) -> list[Any]:
    """Six significant digits of the cloud's size: the JSON stays small, the view exact."""
    digits = max(0, 6 - math.floor(math.log10(scale))) if scale > 0 else 6
    return np.round(values, min(digits, 15)).tolist()  # type: ignore[no-any-return]


def scene_box(drawn: FloatArray, scale: float) -> tuple[FloatArray, FloatArray]:
    """The view's box: the drawn coordinates' bounds, widened on each side by :data:`BOX_MARGIN`
    of ``scale`` (the cloud's diagonal), so that no axis is flat and no point, rounded for
    the page, falls outside it."""
    if not len(drawn):
        return np.full(3, -BOX_MARGIN * scale), np.full(3, BOX_MARGIN * scale)
    pad = BOX_MARGIN * scale
    return drawn.min(axis=0) - pad, drawn.max(axis=0) + pad


def light(up: str) -> FloatArray:
    """The light's unit direction (towards it) for a view with ``up`` upward: from the side of
    that view's camera (:data:`app.web.camera.CAMERAS`), raised by :data:`LIGHT_RISE`."""
    camera = CAMERAS[up]
    eye = np.array([camera["eye"][axis] for axis in "xyz"], dtype=np.float64)
    upward = np.array([camera["up"][axis] for axis in "xyz"], dtype=np.float64)
    direction = eye / np.linalg.norm(eye) + LIGHT_RISE * upward
    return direction / np.linalg.norm(direction)


def shading(
    normals: FloatArray,
    valid: BoolArray,
    sided: BoolArray,
    undecided: BoolArray,
    toward: FloatArray,
) -> list[int]:
    """Each point's colour code (see :data:`SHADING_SCALE`): Lambert's brightness under the
    light ``toward``, ``AMBIENT + (1 - AMBIENT) * max(0, n . l)`` in hundredths, for a normal
    whose side is known (``sided``: one turned away is dark); ``|n . l|`` in place of the
    clamp where the side is arbitrary, as the light falls on a line, not a side;
    :data:`UNDECIDED` added where the side could not be decided; :data:`NO_NORMAL` without one.

    Parameters
    ----------
    normals : (n, 3) float64, unit rows where ``valid``
    valid, sided, undecided : (n,) bool
    toward : (3,) float64, a unit vector
    """
    cosine = normals @ toward
    lit = np.where(sided, np.maximum(cosine, 0.0), np.abs(cosine))
    level = np.round(100 * (AMBIENT + (1 - AMBIENT) * np.clip(lit, 0.0, 1.0))).astype(np.int64)
    codes = np.where(undecided, UNDECIDED + level, level)
    return np.where(valid, codes, NO_NORMAL).tolist()  # type: ignore[no-any-return]


def stroke_sample(shown: FloatArray, valid: BoolArray, limit: int = VIEW_NORMALS) -> IndexArray:
    """Which of the shown points get a stroke: at most ``limit`` of those with a normal, spread
    over the cloud as the sample is (:func:`voxel_sample`), ascending."""
    with_normal = np.flatnonzero(valid)
    return with_normal[voxel_sample(shown[with_normal], limit)]


def _segments(starts: FloatArray, ends: FloatArray, scale: float) -> dict[str, list[Any]]:
    """x, y, z lists for many separate segments in one trace (``None`` between them)."""
    gaps = np.full(len(starts), np.nan)
    return {
        axis: [
            None if math.isnan(v) else v
            for v in _rounded(np.stack([starts[:, i], ends[:, i], gaps], axis=1).ravel(), scale)
        ]
        for i, axis in enumerate("xyz")
    }


def _strokes(
    shown: FloatArray,
    normals: FloatArray,
    chosen: IndexArray,
    sided: BoolArray,
    undecided: BoolArray,
    scale: float,
) -> list[Trace]:
    """The normals of the chosen points as strokes: from the point outward where the side is
    known; where it is not, through the point both ways, since either end could be the
    normal's (amber where it could not be decided, as those points are)."""
    length = STROKE_FRACTION * scale
    traces: list[Trace] = []
    for name, pick, color in (
        ("normals", sided, DEEP_ACCENT),
        ("normals, side not asked", ~sided & ~undecided, DEEP_ACCENT),
        ("normals, side undecided", undecided, UNDECIDED_STROKE),
    ):
        where = chosen[pick[chosen]]
        if not len(where):
            continue
        points, along = shown[where], normals[where] * length
        starts = points if name == "normals" else points - along / 2
        traces.append(
            {
                "type": "scatter3d",
                "mode": "lines",
                "name": name,
                **_segments(starts, starts + along, scale),
                "line": {"color": color, "width": 2},
                "hoverinfo": "skip",
            }
        )
    return traces


def view_figure(analysis: PointAnalysis) -> dict[str, Any]:
    """The 3D view: the sample's points, shaded by their normal, and strokes along a few.

    Returns ``{"figure", "colors": {"light": {up: marker}, "curvature": marker}, "cameras",
    "up", "shown", "total", "strokes"}``: the figure's first trace is the points, whose
    ``marker`` the page swaps, and its camera the one for ``up`` (the format's up axis);
    ``cameras`` holds the camera for each up axis, framed on the sample.
    """
    points = analysis.cloud.points
    estimated = analysis.normals
    sample = voxel_sample(points)
    shown = points[sample]
    valid = estimated.valid[sample]
    normals = estimated.normals[sample]
    status = estimated.status[sample]
    undecided = status == PointStatus.unoriented
    # Without orientation (orient="none") every side is arbitrary, though none is undecided.
    sided = valid & ~undecided & (analysis.report.orientation.mode != "none")
    curvature = np.where(valid, estimated.curvature[sample], np.nan)
    diagonal = float(np.linalg.norm(shown.max(axis=0) - shown.min(axis=0))) if len(shown) else 0.0
    scale = diagonal or 1.0
    lit = {
        up: {
            "color": shading(normals, valid, sided, undecided, light(up)),
            "colorscale": SHADING_SCALE,
            "cmin": 0,
            "cmax": SHADE_MAX,
            "showscale": False,
            "size": 2.5,
        }
        for up in CAMERAS
    }
    up = up_axis(analysis.report.file.format)
    colors = {
        "light": lit,
        "curvature": {
            "color": [None if math.isnan(c) else round(c, 5) for c in curvature.tolist()],
            "colorscale": "Viridis",
            "cmin": 0,
            "cmax": float(np.nanmax(curvature)) if valid.any() else 1 / 3,
            "showscale": True,
            "colorbar": {"title": {"text": "curvature"}, "thickness": 12, "len": 0.6},
            "size": 2.5,
        },
    }
    traces: list[Trace] = [
        {
            "type": "scatter3d",
            "mode": "markers",
            "name": "points",
            "x": _rounded(shown[:, 0], scale),
            "y": _rounded(shown[:, 1], scale),
            "z": _rounded(shown[:, 2], scale),
            "marker": lit[up],
            "hoverinfo": "skip",
        }
    ]
    strokes = stroke_sample(shown, valid)
    traces.extend(_strokes(shown, normals, strokes, sided, undecided, scale))
    # The box is fixed, strokes included, so that the scene is the same with the strokes shown
    # or hidden, and a flat cloud is framed as it is drawn (Plotly would size a flat axis by
    # the strokes, or as 2 units without them).
    along = normals[strokes] * (STROKE_FRACTION * scale)
    drawn = np.concatenate([shown, shown[strokes] + along, shown[strokes] - along / 2])
    low, high = scene_box(drawn, scale)
    scene = Scene.of(np.stack([low, high]))
    views = cameras(scene, drawn)
    layout = {
        "margin": {"l": 0, "r": 0, "t": 0, "b": 0},
        "height": 460,
        "paper_bgcolor": TRANSPARENT,
        "font": FONT,
        "showlegend": False,
        "scene": {
            # What aspectmode "data" would choose for this box: each range over their
            # geometric mean (app.web.camera.Scene), which the cameras are framed in.
            "aspectmode": "manual",
            "aspectratio": vector((high - low) / scene.unit),
            **{
                f"{axis}axis": {
                    "visible": False,
                    "autorange": False,
                    "range": _rounded(np.array([low[i], high[i]]), scale),
                }
                for i, axis in enumerate("xyz")
            },
            "camera": views[up],
        },
    }
    return {
        "figure": {"data": traces, "layout": layout},
        "colors": colors,
        "cameras": views,
        "up": up,
        "shown": len(sample),
        "total": len(points),
        "strokes": len(strokes),
    }


def stored_angles(analysis: PointAnalysis) -> FloatArray | None:
    """Degrees between the file's normal lines and ours where both exist, or None."""
    stored = analysis.cloud.normals
    if stored is None:
        return None
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        lengths = np.linalg.norm(stored, axis=1)
        usable = np.isfinite(lengths) & (lengths > 0) & analysis.normals.valid
        cosines = np.einsum("ij,ij->i", stored[usable], analysis.normals.normals[usable])
        cosines /= lengths[usable]
    return np.degrees(np.arccos(np.clip(np.abs(cosines), 0.0, 1.0)))  # type: ignore[no-any-return]


def histogram_figure(analysis: PointAnalysis) -> dict[str, Any]:
    """A histogram of the angle to the stored normals when the file has them, else of the
    curvature. Returns ``{"figure" (None when there is nothing to count), "what", "count"}``."""
    angles = stored_angles(analysis)
    if angles is not None:
        values, what, low, high = angles, "angle to the stored normals (degrees)", 0.0, 90.0
    else:
        values = analysis.normals.curvature[analysis.normals.valid]
        what, low = "curvature (surface variation)", 0.0
        high = max(float(values.max()) if len(values) else 0.0, 1e-6)
    if not len(values):
        return {"figure": None, "what": what, "count": 0}
    counts, edges = np.histogram(values, bins=BINS, range=(low, high))
    centres = (edges[:-1] + edges[1:]) / 2
    trace: Trace = {
        "type": "bar",
        "name": "points",
        "x": centres.tolist(),
        "y": counts.tolist(),
        "width": (np.diff(edges) * 0.92).tolist(),
        "marker": {"color": ACCENT},
        "hovertemplate": "%{x:.3g}: %{y:,} points<extra></extra>",
    }
    figure = {
        "data": [trace],
        "layout": histogram_layout(
            {"title": {"text": what}, "gridcolor": GRID, "zerolinecolor": MUTED}, "points", GRID
        ),
    }
    return {"figure": figure, "what": what, "count": len(values)}
