"""The point-cloud page's figures: a 3D view of an even sample and a histogram, as plain dicts.

The view shows at most :data:`VIEW_POINTS` points, one per cell of a voxel grid sized so that
the sample spreads over the whole cloud (a dense patch does not crowd out the rest), and the
normals of at most :data:`VIEW_NORMALS` of them as short strokes. The points carry two colour
schemes (RGB from the normal, or curvature); the page's script swaps one for the other.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from app.web.plotly import ACCENT, DEEP_ACCENT, FONT, MUTED, TRANSPARENT, Trace, histogram_layout
from mesh_normal.points.analysis import PointAnalysis
from mesh_normal.types import BoolArray, FloatArray, IndexArray

#: The most points the 3D view draws, and of those the most with a normal stroke.
VIEW_POINTS = 20_000
VIEW_NORMALS = 2_000
#: A stroke is this fraction of the cloud's bounding-box diagonal long.
STROKE_FRACTION = 0.03
#: Points without a normal are drawn in this grey in the normal colouring.
NO_NORMAL = "rgb(150,150,150)"
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


def normal_colors(normals: FloatArray, valid: BoolArray) -> list[str]:
    """``rgb(r,g,b)`` from each unit normal's components mapped from [-1, 1] to [0, 255]."""
    rgb = np.clip(np.round((normals + 1.0) * 127.5), 0, 255).astype(np.int64)
    return [
        f"rgb({r},{g},{b})" if ok else NO_NORMAL
        for (r, g, b), ok in zip(rgb.tolist(), valid.tolist(), strict=True)
    ]


def view_figure(analysis: PointAnalysis) -> dict[str, Any]:
    """The 3D view: the sample's points, coloured by normal, and strokes along the normals.

    Returns ``{"figure", "colors": {"normal", "curvature"}, "shown", "total", "strokes"}``;
    the figure's first trace is the points, whose ``marker`` the page swaps.
    """
    points = analysis.cloud.points
    estimated = analysis.normals
    sample = voxel_sample(points)
    shown = points[sample]
    valid = estimated.valid[sample]
    normals = estimated.normals[sample]
    curvature = np.where(valid, estimated.curvature[sample], np.nan)
    diagonal = float(np.linalg.norm(shown.max(axis=0) - shown.min(axis=0))) if len(shown) else 0.0
    scale = diagonal or 1.0
    colors = {
        "normal": {"color": normal_colors(normals, valid), "size": 2.5},
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
            "marker": colors["normal"],
            "hoverinfo": "skip",
        }
    ]
    with_normal = np.flatnonzero(valid)
    step = max(1, math.ceil(len(with_normal) / VIEW_NORMALS))
    strokes = with_normal[::step][:VIEW_NORMALS]
    if len(strokes):
        starts = shown[strokes]
        ends = starts + normals[strokes] * (STROKE_FRACTION * scale)
        gaps = np.full(len(strokes), np.nan)
        line = {
            axis: [
                None if math.isnan(v) else v
                for v in _rounded(np.stack([starts[:, i], ends[:, i], gaps], axis=1).ravel(), scale)
            ]
            for i, axis in enumerate("xyz")
        }
        traces.append(
            {
                "type": "scatter3d",
                "mode": "lines",
                "name": "normals",
                **line,
                "line": {"color": DEEP_ACCENT, "width": 2},
                "hoverinfo": "skip",
            }
        )
    layout = {
        "margin": {"l": 0, "r": 0, "t": 0, "b": 0},
        "height": 460,
        "paper_bgcolor": TRANSPARENT,
        "font": FONT,
        "showlegend": False,
        "scene": {
            "aspectmode": "data",
            **{f"{axis}axis": {"visible": False} for axis in "xyz"},
            "camera": {"eye": {"x": 1.05, "y": -1.05, "z": 0.7}},
        },
    }
    return {
        "figure": {"data": traces, "layout": layout},
        "colors": colors,
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
