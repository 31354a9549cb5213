"""REFERENCE ONLY: app/calculator/view3d.py as it was with NumPy, verbatim below this note.

tests/app/calculator/test_view3d.py compares the pure-Python module against it. Do not edit
the code below: it is the behaviour the rewrite keeps (it imports the app's plotly helpers,
which still take NumPy arrays).
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import numpy as np

from app.web.formatting import js_number
from app.web.plotly import ACCENT, DEEP_ACCENT, FONT, INK, MUTED, TRANSPARENT, Trace, cone_trace

FACE_COLOR = ACCENT
POINT_COLORS = ["#c2410c", "#15803d", "#1d4ed8"]  # the page's badges for A, B and C
EDGE_COLOR = INK
NORMAL_COLOR = "#e8590c"
TURN_COLOR = DEEP_ACCENT
TRIAD_COLOR = MUTED
#: Within these sizes (of the largest offset from the centroid) the view keeps true scale.
TRUE_SCALE = (Fraction(1, 2**20), Fraction(2**20))
ARROW = 0.6  # the normal arrow's length, times the longest edge
DEFAULT_EYE: np.ndarray = np.array([1.0, 1.0, 1.0]) / np.sqrt(3.0)
EYE_DISTANCE = 1.35


def view3d_figure(payload: dict[str, Any]) -> dict[str, Any]:
    """Return ``{"data": [...], "layout": {...}}`` for a result payload.

    Every coordinate is a finite float, at most a few million, whatever the input.
    """
    points, exponent = view_space([payload["a"], payload["b"], payload["c"]])
    winding = [0, 1, 2] if payload["order"] == "ABC" else [0, 2, 1]
    longest = max(float(np.linalg.norm(points[i] - points[i - 1])) for i in range(3)) or 1.0
    normal = None if payload["degenerate"] else np.array(payload["unit_normal"], dtype=float)
    eye = _eye(normal, points)
    traces = _edges(payload, points, winding, eye)
    if normal is not None:
        traces = [
            _face(points, winding, payload),
            *traces,
            *_normal_arrow(normal, longest, payload),
            *_turn_arrow(normal, points, longest),
        ]
    traces.append(_corners(payload, points, exponent, eye))
    radius = max(float(np.linalg.norm(point)) for trace in traces for point in _points(trace))
    traces.extend(_axes_triad(eye, radius or 1.0))  # three equal points: radius 0
    return {"data": traces, "layout": _layout(payload, traces, eye)}


def view_space(points: list[list[float]]) -> tuple[np.ndarray, int]:
    """The points minus their centroid, times ``2**-exponent``; returns ``(points, exponent)``.

    The arithmetic is exact until the one rounding to float, so nothing overflows (1e308
    minus -1e308 is fine) and a sliver far from the origin keeps its shape.
    """
    exact = [[Fraction(x) for x in point] for point in points]
    centroid = [sum(column, Fraction(0)) / 3 for column in zip(*exact, strict=True)]
    offsets = [[x - c for x, c in zip(point, centroid, strict=True)] for point in exact]
    extent = max(abs(x) for point in offsets for x in point)
    exponent = 0
    if extent and not TRUE_SCALE[0] <= extent <= TRUE_SCALE[1]:
        exponent = _floor_log2(extent)
    scale = Fraction(2) ** -exponent
    return np.array([[float(x * scale) for x in point] for point in offsets]), exponent


def _floor_log2(x: Fraction) -> int:
    exponent = x.numerator.bit_length() - x.denominator.bit_length()
    return exponent if Fraction(2) ** exponent <= x else exponent - 1


def _vector_text(values: list[float | None] | None) -> str:
    if values is None:
        return "none"
    return "(" + ", ".join("out of range" if x is None else js_number(x) for x in values) + ")"


def _line(points: np.ndarray, **style: Any) -> Trace:
    x, y, z = points.T.tolist()
    return {"type": "scatter3d", "x": x, "y": y, "z": z, **style}


def _cone(name: str, tip: np.ndarray, vector: np.ndarray, color: str, hover: str) -> Trace:
    """An arrowhead whose tip is at ``tip``; its length is the length of ``vector``."""
    return {
        **cone_trace(name, np.array([tip]), np.array([vector]), color),
        "hovertemplate": f"{hover}<extra></extra>",
    }


def _face(points: np.ndarray, winding: list[int], payload: dict[str, Any]) -> Trace:
    x, y, z = points[winding].T.tolist()
    area = "out of range" if payload["area"] is None else js_number(payload["area"])
    return {
        "type": "mesh3d",
        "name": "face",
        "x": x,
        "y": y,
        "z": z,
        "i": [0],
        "j": [1],
        "k": [2],
        "color": FACE_COLOR,
        "opacity": 0.45,
        "flatshading": True,
        "lighting": {"ambient": 1, "diffuse": 0, "specular": 0, "fresnel": 0},
        "hovertemplate": f"area {area}<extra></extra>",
    }


def _edges(
    payload: dict[str, Any], points: np.ndarray, winding: list[int], eye: np.ndarray
) -> list[Trace]:
    """u and v from A, labelled at their middles, and the third edge as a thin outline."""
    names = "ABC"
    traces = []
    for label, end in (("u", winding[1]), ("v", winding[2])):
        middle = (points[0] + points[end]) / 2
        hover = f"{label} = {names[end]} − A = {_vector_text(payload[label])}"
        edge = points[end] - points[0]
        # edge @ edge is 0 for a zero edge and for one of subnormal length (a sliver as long
        # as the double range, squeezed into view space).
        length_squared = float(edge @ edge)
        away = middle - (middle @ edge) / length_squared * edge if length_squared else middle
        if np.linalg.norm(away) <= 1e-9 * np.linalg.norm(edge):
            away = np.zeros(3)  # the edge runs through the centroid: three points on a line
        (side,) = _outward([away], eye, "bottom center")
        traces.append(
            _line(
                np.array([points[0], middle, points[end]]),
                name=label,
                mode="lines+text",
                text=["", label, ""],
                textposition=["middle center", side, "middle center"],
                textfont={"color": EDGE_COLOR, "size": 14},
                line={"color": EDGE_COLOR, "width": 5},
                hovertemplate=f"{hover}<extra></extra>",
            )
        )
    traces.append(
        _line(
            points[[1, 2]],
            name="edge",
            mode="lines",
            line={"color": FACE_COLOR, "width": 3},
            hoverinfo="skip",
        )
    )
    return traces


def _normal_arrow(normal: np.ndarray, longest: float, payload: dict[str, Any]) -> list[Trace]:
    """A shaft from the centroid and a cone at its tip, labelled "front"."""
    length = ARROW * longest
    head = 0.22 * length
    tip = normal * length
    hover = f"unit normal {_vector_text(payload['unit_normal'])}"
    shaft = _line(
        np.array([[0.0, 0.0, 0.0], normal * (length - head)]),
        name="normal",
        mode="lines",
        line={"color": NORMAL_COLOR, "width": 7},
        hovertemplate=f"{hover}<extra></extra>",
    )
    label = _line(
        np.array([normal * (length + 0.12 * longest)]),
        name="front",
        mode="text",
        text=["front"],
        textfont={"color": NORMAL_COLOR, "size": 13},
        hoverinfo="skip",
    )
    return [shaft, _cone("normal", tip, normal * head, NORMAL_COLOR, hover), label]


def _turn_arrow(normal: np.ndarray, points: np.ndarray, longest: float) -> list[Trace]:
    """Three quarters of a circle around the centroid, counter-clockwise seen from the front.

    Its radius fits inside a fat triangle; a sliver gets a minimum size so it stays visible.
    It floats a little above the face, on the front side.
    """
    first = _perpendicular(normal, points[0])
    second = np.cross(normal, first)
    perimeter = sum(float(np.linalg.norm(points[i] - points[i - 1])) for i in range(3))
    double_area = float(np.linalg.norm(np.cross(points[1] - points[0], points[2] - points[0])))
    radius = min(max(0.75 * double_area / perimeter, 0.1 * longest), 0.25 * longest)
    angles = np.linspace(0.35, 0.35 + 1.5 * np.pi, 40)
    lift = normal * 0.02 * longest
    arc = (np.outer(np.cos(angles), first) + np.outer(np.sin(angles), second)) * radius + lift
    end = angles[-1]
    tangent = -np.sin(end) * first + np.cos(end) * second
    head = 0.8 * radius
    return [
        _line(
            arc, name="turn", mode="lines", line={"color": TURN_COLOR, "width": 4}, hoverinfo="skip"
        ),
        _cone(
            "turn",
            arc[-1] + tangent * head,
            tangent * head,
            TURN_COLOR,
            "the corners turn this way",
        ),
    ]


def _perpendicular(normal: np.ndarray, hint: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to ``normal``, towards ``hint`` when it can be."""
    for candidate in (hint, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])):
        flat = candidate - np.dot(candidate, normal) * normal
        size = float(np.linalg.norm(flat))
        if size > 1e-6 * float(np.linalg.norm(candidate)):
            unit: np.ndarray = flat / size
            return unit
    raise AssertionError("unreachable: z and x cannot both be parallel to a unit vector")


def _corners(payload: dict[str, Any], points: np.ndarray, exponent: int, eye: np.ndarray) -> Trace:
    note = (
        ""
        if exponent == 0
        else f"<br>view centred on the centroid and scaled by 2<sup>{-exponent}</sup>"
    )
    hover = [f"{name} = {_vector_text(payload[name.lower()])}{note}" for name in "ABC"]
    return _line(
        points,
        name="corners",
        mode="markers+text",
        text=["A", "B", "C"],
        textposition=_outward(points, eye),
        textfont={"color": POINT_COLORS, "size": 15},
        marker={"color": POINT_COLORS, "size": 6},
        hovertext=hover,
        hovertemplate="%{hovertext}<extra></extra>",
    )


def _eye(normal: np.ndarray | None, points: np.ndarray) -> np.ndarray:
    """The camera's direction: the front, 45 degrees from the normal, so the arrow shows.

    It leans across the longest edge, towards the opposite corner unless that looks up from
    far below: the arrow then falls between two corners on the screen, and a sliver shows
    its full length. A degenerate triangle is seen from the side of its line.
    """
    up = np.array([0.0, 0.0, 1.0])
    start, end = _longest_edge(points)
    line = points[end] - points[start]
    if normal is not None:
        across = _perpendicular(normal, np.cross(normal, line) if line.any() else DEFAULT_EYE)
        toward = points[3 - start - end] - points[start]
        lean = across if across @ toward >= 0 else -across
        if (normal + lean)[2] < min(-0.9, (normal - lean)[2]):
            lean = -lean  # about 40 degrees from below or more, and the other way is higher
        eye = normal + lean
        if np.hypot(eye[0], eye[1]) < 0.25 * np.linalg.norm(eye):
            eye = eye + 0.5 * DEFAULT_EYE * [1, 1, 0]  # turntable needs an eye off the z axis
        return _unit(eye)
    if not line.any():
        return DEFAULT_EYE
    line = _unit(line)
    side = _perpendicular(line, np.cross(line, up)) if abs(line[2]) < 0.99 else up[[2, 0, 1]]
    side = side if side @ DEFAULT_EYE >= 0 else -side
    return _unit(side + 0.5 * _perpendicular(line, up))


def _unit(vector: np.ndarray) -> np.ndarray:
    """``vector`` scaled to length 1; it must not be zero."""
    return np.asarray(vector / np.linalg.norm(vector), dtype=np.float64)


def _longest_edge(points: np.ndarray) -> tuple[int, int]:
    edges = [(0, 1), (1, 2), (2, 0)]
    return max(edges, key=lambda edge: float(np.linalg.norm(points[edge[1]] - points[edge[0]])))


def _screen(eye: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The directions that point right and up on the screen, for a camera at ``eye``."""
    right = np.cross(-eye, [0.0, 0.0, 1.0])
    right = right / np.linalg.norm(right)
    return right, np.cross(right, -eye)


#: Text positions by the direction they lean to on the screen, counter-clockwise from right.
POSITIONS = [
    "middle right",
    "top right",
    "top center",
    "top left",
    "middle left",
    "bottom left",
    "bottom center",
    "bottom right",
]


def _outward(
    directions: np.ndarray | list[np.ndarray], eye: np.ndarray, centred: str = "top center"
) -> list[str]:
    """Text positions that put labels where the directions point to on the screen.

    Labels go away from the centroid: a corner's direction is its position, an edge's is
    across the edge. A direction that points nowhere on the screen (a corner at the
    centroid, the middle of three points on a line) gets ``centred``.
    """
    right, screen_up = _screen(eye)
    positions = []
    for direction in directions:
        across, up = float(direction @ right), float(direction @ screen_up)
        if not direction.any() or np.hypot(across, up) <= 1e-9 * np.linalg.norm(direction):
            positions.append(centred)
            continue
        sector = round(np.arctan2(up, across) / (np.pi / 4)) % 8
        positions.append(POSITIONS[sector])
    return positions


def _axes_triad(eye: np.ndarray, radius: float) -> list[Trace]:
    """Short x, y and z arrows in the view's lower left corner, for orientation."""
    right, screen_up = _screen(eye)
    origin = radius * (-0.95 * right - 0.75 * screen_up)
    arm = 0.3 * radius
    traces = []
    for index, name in enumerate("xyz"):
        direction = np.eye(3)[index]
        end = origin + arm * direction
        traces.append(
            _line(
                np.array([origin, end]),
                name="axes",
                mode="lines",
                line={"color": TRIAD_COLOR, "width": 3},
                hoverinfo="skip",
            )
        )
        traces.append(
            _line(
                np.array([end + 0.25 * arm * direction]),
                name="axes",
                mode="text",
                text=[name],
                textfont={"color": TRIAD_COLOR, "size": 12},
                hoverinfo="skip",
            )
        )
    return traces


def _points(trace: Trace) -> np.ndarray:
    return np.array([trace["x"], trace["y"], trace["z"]]).T


def _axis(reach: float) -> dict[str, Any]:
    return {"range": [-reach, reach], "autorange": False, "visible": False}


def _layout(payload: dict[str, Any], traces: list[Trace], eye: np.ndarray) -> dict[str, Any]:
    reach = max(float(np.linalg.norm(point)) for trace in traces for point in _points(trace))
    camera = {
        "eye": dict(zip("xyz", np.round(EYE_DISTANCE * eye, 4).tolist(), strict=True)),
        "up": {"x": 0, "y": 0, "z": 1},
        "center": {"x": 0, "y": 0, "z": 0},
    }
    order = " → ".join(payload["order"])
    title = (
        "degenerate: no normal" if payload["degenerate"] else f"Front: {order} counter-clockwise"
    )
    return {
        "title": {"text": title, "x": 0.02, "xanchor": "left", "font": {"size": 14}},
        "margin": {"l": 0, "r": 0, "t": 40, "b": 0},
        # Upright at the right edge, the toolbar stays clear of the title even on a phone.
        "modebar": {"orientation": "v"},
        "height": 360,
        "paper_bgcolor": TRANSPARENT,
        "font": FONT,
        "showlegend": False,
        "uirevision": "view3d",
        "scene": {
            "aspectmode": "cube",
            "camera": camera,
            "dragmode": "turntable",
            "bgcolor": TRANSPARENT,
            "xaxis": _axis(reach),
            "yaxis": _axis(reach),
            "zaxis": _axis(reach),
        },
    }
