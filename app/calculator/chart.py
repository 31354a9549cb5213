"""The calculator's bar chart as a plain Plotly figure dict (drawn by Plotly.js)."""

from __future__ import annotations

from typing import Any

from app.web.formatting import js_number
from app.web.plotly import FONT, MUTED, TRANSPARENT

LABELS = ["n<sub>x</sub>", "n<sub>y</sub>", "n<sub>z</sub>", "|n|", "area"]
COLORS = ["#e4572e", "#29a36a", "#2e86de", "#6c5ce7", "#f2a541"]


def bar_figure(payload: dict[str, Any]) -> dict[str, Any]:
    """Return ``{"data": [...], "layout": {...}}`` for a result payload.

    A value outside the double range is ``None`` and Plotly leaves its bar out; the hover
    text says so.
    """
    values = [*payload["normal"], payload["magnitude"], payload["area"]]
    hover = ["out of double range" if value is None else js_number(value) for value in values]
    return {
        "data": [
            {
                "type": "bar",
                "x": LABELS,
                "y": values,
                "marker": {"color": COLORS},
                "text": hover,
                "textposition": "outside",
                "hovertemplate": "%{x}: %{text}<extra></extra>",
                "cliponaxis": False,
            }
        ],
        "layout": {
            "title": {"text": f"Normal of {payload['order']}", "x": 0.02, "xanchor": "left"},
            "margin": {"l": 48, "r": 16, "t": 44, "b": 36},
            "height": 320,
            "bargap": 0.35,
            "paper_bgcolor": TRANSPARENT,
            "plot_bgcolor": TRANSPARENT,
            "font": FONT,
            "yaxis": {
                "zeroline": True,
                "zerolinecolor": MUTED,
                "gridcolor": "#d9deea",
                "exponentformat": "e",
            },
            "xaxis": {"fixedrange": True},
            "showlegend": False,
        },
    }
