"""The mesh page's histogram of face areas: the bins, and their bar chart as a Plotly dict."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from app.mesh.classes import COLORS, DEGENERATE
from app.web.plotly import ACCENT, Trace, histogram_layout

#: Bins of the area histogram, and the span (max / min) beyond which they are log-spaced.
HISTOGRAM_BINS = 30
LOG_SPAN = 100.0
AREA_COLOR = ACCENT
GRID = "rgba(138, 147, 168, 0.35)"


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
            values, labels = _round_ticks(float(edges[0]), float(edges[-1]))
            xaxis["tickvals"] += values
            xaxis["ticktext"] += labels
    return {
        "data": traces,
        "layout": histogram_layout(xaxis, "faces", GRID),
    }


def _log_ticks(low: float, high: float) -> dict[str, Any]:
    """Ticks at powers of ten (every few when the span is wide): 0.01, 1, 100, 1e6."""
    first, last = int(np.floor(low)), int(np.ceil(high))
    step = max(1, (last - first) // 6)
    powers = list(range(first, last + 1, step))
    return {
        "tickmode": "array",
        "tickvals": [float(p) for p in powers],
        "ticktext": [_power(p) for p in powers],
    }


def _power(exponent: int) -> str:
    """10 to the power, as a reader writes it: 0.001 to 1000 in full, 1e-6 or 1e6 beyond."""
    return f"{10.0**exponent:g}" if -3 <= exponent <= 3 else f"1e{exponent}"


def _round_ticks(low: float, high: float, most: int = 6) -> tuple[list[float], list[str]]:
    """Ticks at round numbers (multiples of 1, 2 or 5 times a power of ten) from low to high,
    at most ``most`` of them, labelled without rounding noise: 0.3, 0.4, not 0.312, 0.438."""
    span = high - low
    if not (np.isfinite(span) and span > 0):
        return [low], [f"{low:.3g}"]
    for power in range(int(np.floor(np.log10(span / most))), 400):
        for digit in (1, 2, 5):
            step = digit * 10.0**power
            first, last = int(np.ceil(low / step)), int(np.floor(high / step))
            if last - first + 1 <= most:
                decimals = max(0, -power)
                values = [round(k * step, decimals) for k in range(first, last + 1)]
                if -4 <= power <= 5:  # as written: 0.0005 to 900000, all with one precision
                    return values, [f"{value:.{decimals}f}" for value in values]
                return values, [f"{value:.3g}" for value in values]
    return [low, high], [f"{low:.3g}", f"{high:.3g}"]
