"""The calculator's bar chart as a plain Plotly figure dict (drawn by Plotly.js).

The bars' ``y`` are the payload's values, so the figure's data is the API's. A value beyond
the double range is ``null`` there, and a second trace marks it: a hatched bar, taller than
every other, capped at the top (or bottom, for a negative n component) and labelled "beyond
1.8e308", so the chart is never empty. Labels are text for people; the page rewrites them for
its precision setting from ``customdata`` (static/js/chart.js).
"""

from __future__ import annotations

import sys
from typing import Any

from app.web.formatting import js_number, number_text
from app.web.plotly import FONT, MUTED, TRANSPARENT
from mesh_normal.triangle.normal import exact_triangle

LABELS = ["n<sub>x</sub>", "n<sub>y</sub>", "n<sub>z</sub>", "|n|", "area"]
COLORS = ["#e4572e", "#29a36a", "#2e86de", "#6c5ce7", "#f2a541"]

#: How much longer than the longest finite bar a capped one is, and the room for its label.
CAP_HEADROOM = 1.25
LABEL_ROOM = 2.2
BEYOND = "beyond {sign}1.8e308"
BEYOND_NOTE = "Hatched: beyond the double range"  # short enough for a phone


def _signs(payload: dict[str, Any]) -> list[int]:
    """The sign of each bar's exact value (n's from the exact cross product; |n| and area ≥ 0)."""
    order = payload["order"]
    exact = exact_triangle(payload["a"], payload["b"], payload["c"], swap_winding=order == "ACB")
    return [(n > 0) - (n < 0) for n in exact.n] + [1, 1]


def _cap(values: list[float | None]) -> float:
    """The capped bars' length; near the largest double it stays short of overflowing."""
    tallest = max((abs(v) for v in values if v is not None), default=0.0)
    limit = sys.float_info.max / (CAP_HEADROOM * LABEL_ROOM)
    return CAP_HEADROOM * min(tallest, limit) if tallest > 0 else 1.0


def _capped_trace(values: list[float | None], signs: list[int]) -> dict[str, Any]:
    """Hatched bars for the values beyond the double range, past every finite bar."""
    cap = _cap(values)
    heights = [
        None if v is not None else -cap if s < 0 else cap
        for v, s in zip(values, signs, strict=True)
    ]
    texts = ["" if h is None else BEYOND.format(sign="−" if h < 0 else "") for h in heights]
    return {
        "type": "bar",
        "name": "beyond the double range",
        "orientation": "h",
        "y": LABELS,
        "x": heights,
        "marker": {
            "color": COLORS,
            "opacity": 0.6,
            "pattern": {"shape": "/", "solidity": 0.4},
            "line": {"color": MUTED, "width": 1},
        },
        "text": texts,
        "textposition": "outside",
        "textfont": {"size": 13},
        "constraintext": "none",
        "hovertemplate": "%{y}: beyond the double range (kept exactly)<extra></extra>",
        "cliponaxis": False,
    }


def _range_with_room(values: list[float | None], signs: list[int]) -> list[float]:
    """The value axis with room beyond the capped bars for their labels."""
    cap, finite = _cap(values), [v for v in values if v is not None]
    negative = any(v is None and s < 0 for v, s in zip(values, signs, strict=True))
    positive = any(v is None and s >= 0 for v, s in zip(values, signs, strict=True))
    low = min([0.0, *finite, *([-cap * LABEL_ROOM] if negative else [])])
    high = max([0.0, *finite, *([cap * LABEL_ROOM] if positive else [])])
    return [low, high]


def bar_figure(payload: dict[str, Any], decimals: int | None = None) -> dict[str, Any]:
    """Return ``{"data": [...], "layout": {...}}`` for a result payload.

    ``decimals`` writes the bar labels with that many decimals (the page's precision
    setting); None writes each number in full, as JavaScript's ``String(x)`` does.
    """
    values: list[float | None] = [*payload["normal"], payload["magnitude"], payload["area"]]
    labels = ["" if v is None else number_text(v, decimals) for v in values]
    bars: dict[str, Any] = {
        "type": "bar",
        "name": "value",
        "orientation": "h",
        "y": LABELS,
        "x": values,
        "marker": {"color": COLORS},
        "text": labels,
        "customdata": [None if v is None else js_number(v) for v in values],
        "hovertext": ["" if v is None else number_text(v) for v in values],
        # Inside a bar long enough to hold the label, else beyond its end: never squeezed.
        # A zero has no bar to hold it.
        "textposition": ["outside" if not v else "auto" for v in values],
        "textfont": {"size": 13},
        "constraintext": "none",
        "hovertemplate": "%{y}: %{hovertext}<extra></extra>",
        "cliponaxis": False,
    }
    beyond = any(v is None for v in values)
    finite = [v for v in values if v is not None and v != 0]
    layout: dict[str, Any] = {
        "title": {"text": f"Normal of {payload['order']}", "x": 0.02, "xanchor": "left"},
        "margin": {"l": 48, "r": 16, "t": 64 if beyond else 44, "b": 36},
        "height": 320,
        "bargap": 0.3,
        "barmode": "overlay",
        "paper_bgcolor": TRANSPARENT,
        "plot_bgcolor": TRANSPARENT,
        "font": FONT,
        # Horizontal bars: a label of 17 digits has room along its bar.
        "xaxis": {
            "zeroline": True,
            "zerolinecolor": MUTED,
            "gridcolor": "#d9deea",
            "exponentformat": "e",
            # Only capped bars and zeros: a scale would mean nothing.
            "showticklabels": bool(finite) or not beyond,
        },
        "yaxis": {"fixedrange": True, "autorange": "reversed", "automargin": True},
        "showlegend": False,
    }
    data = [bars]
    if beyond:
        signs = _signs(payload)
        data.append(_capped_trace(values, signs))
        layout["xaxis"]["range"] = _range_with_room(values, signs)
        layout["annotations"] = [
            {
                "text": BEYOND_NOTE,
                "xref": "paper",
                "yref": "paper",
                "x": 0,
                "y": 1.0,
                "xanchor": "left",
                "yanchor": "bottom",
                "yshift": 4,
                "showarrow": False,
                "font": {"size": 12, "color": MUTED},
            }
        ]
    return {"data": data, "layout": layout}
