"""What every Plotly figure of the app shares: the font, the palette, arrowheads, the dark theme.

Figures are plain dicts (Plotly.js draws them; the server needs no plotly package). The page's
scripts swap each palette colour for its dark twin in :data:`DARK` when the reader prefers a
dark scheme (static/js/view3d.js holds the same table; a test keeps the two equal).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

Trace = dict[str, Any]

ACCENT = "#4f5bd5"  # the page's accent: the triangle's face, the mesh's area bars
DEEP_ACCENT = "#3a44b0"  # arrows: the turn of the corners, the mesh's normals
INK = "#56607a"  # text and edges
MUTED = "#8a93a8"  # axes and zero lines
TRANSPARENT = "rgba(0,0,0,0)"  # figures sit on the page's card, light or dark

FONT = {
    "family": "system-ui, -apple-system, Segoe UI, Roboto, sans-serif",
    "size": 13,
    "color": INK,
}

#: Each light colour's twin on the dark card (mirrored by static/js/view3d.js).
DARK = {
    INK: "#9aa3ba",
    ACCENT: "#8a94ff",
    DEEP_ACCENT: "#aab1ff",
    MUTED: "#69728a",
    "#c2410c": "#fb923c",
    "#15803d": "#4ade80",
    "#1d4ed8": "#7aa2ff",
}

#: Arrowheads are lit softly so that their colour reads as the shaft's.
CONE_LIGHTING = {"ambient": 0.9, "diffuse": 0.3, "specular": 0.1}


def cone_trace(
    name: str,
    tips: NDArray[np.float64] | Sequence[Sequence[float]],
    vectors: NDArray[np.float64] | Sequence[Sequence[float]],
    color: str,
) -> Trace:
    """Arrowheads in one colour, each with its tip at ``tips[i]`` and as long as ``vectors[i]``.

    Parameters
    ----------
    tips, vectors : (k, 3) float64, or lists of k points (x, y, z)
        Where each head ends, and its direction and length (Plotly's ``sizemode="raw"``).
        The mesh views pass arrays; the calculator's view passes lists, and this module
        imports NumPy only when it is given an array, so the calculator's page never does.
    """
    if isinstance(tips, list | tuple) and isinstance(vectors, list | tuple):
        x, y, z = _columns(tips)
        u, v, w = _columns(vectors)
    else:
        import numpy as np  # for arrays only (already imported by whoever made them)

        tips, vectors = np.asarray(tips, dtype=np.float64), np.asarray(vectors, dtype=np.float64)
        x, y, z = tips[:, 0].tolist(), tips[:, 1].tolist(), tips[:, 2].tolist()
        u, v, w = vectors[:, 0].tolist(), vectors[:, 1].tolist(), vectors[:, 2].tolist()
    return {
        "type": "cone",
        "name": name,
        "x": x,
        "y": y,
        "z": z,
        "u": u,
        "v": v,
        "w": w,
        "anchor": "tip",
        "sizemode": "raw",
        "sizeref": 1,
        "colorscale": [[0, color], [1, color]],
        "showscale": False,
        "lighting": CONE_LIGHTING,
    }


def _columns(points: Sequence[Sequence[float]]) -> tuple[list[float], list[float], list[float]]:
    """The x, y and z of each point as floats, as ``np.asarray(points, float)[:, i].tolist()``."""
    for point in points:
        if len(point) != 3:
            raise ValueError(f"a point has 3 coordinates, not {len(point)}")
    return (
        [float(point[0]) for point in points],
        [float(point[1]) for point in points],
        [float(point[2]) for point in points],
    )


def histogram_layout(xaxis: dict[str, Any], counted: str, grid: str) -> dict[str, Any]:
    """The layout of a page's histogram: bars edge to edge, ``counted`` up the side."""
    return {
        "margin": {"l": 56, "r": 16, "t": 12, "b": 48},
        "height": 300,
        "bargap": 0,
        "paper_bgcolor": TRANSPARENT,
        "plot_bgcolor": TRANSPARENT,
        "font": FONT,
        "showlegend": False,
        "xaxis": xaxis,
        "yaxis": {"title": {"text": counted}, "gridcolor": grid, "rangemode": "tozero"},
    }
