"""What every Plotly figure of the app shares: the font, the palette, arrowheads, the dark theme.

Figures are plain dicts (Plotly.js draws them; the server needs no plotly package). The page's
scripts swap each palette colour for its dark twin in :data:`DARK` when the reader prefers a
dark scheme (static/js/view3d.js holds the same table; a test keeps the two equal).
"""

from __future__ import annotations

from typing import Any

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
    name: str, tips: NDArray[np.float64], vectors: NDArray[np.float64], color: str
) -> Trace:
    """Arrowheads in one colour, each with its tip at ``tips[i]`` and as long as ``vectors[i]``.

    Parameters
    ----------
    tips, vectors : (k, 3) float64
        Where each head ends, and its direction and length (Plotly's ``sizemode="raw"``).
    """
    tips, vectors = np.asarray(tips, dtype=np.float64), np.asarray(vectors, dtype=np.float64)
    return {
        "type": "cone",
        "name": name,
        "x": tips[:, 0].tolist(),
        "y": tips[:, 1].tolist(),
        "z": tips[:, 2].tolist(),
        "u": vectors[:, 0].tolist(),
        "v": vectors[:, 1].tolist(),
        "w": vectors[:, 2].tolist(),
        "anchor": "tip",
        "sizemode": "raw",
        "sizeref": 1,
        "colorscale": [[0, color], [1, color]],
        "showscale": False,
        "lighting": CONE_LIGHTING,
    }


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
