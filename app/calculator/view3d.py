"""The calculator's 3D view as a plain Plotly figure dict (drawn by the gl3d bundle of Plotly.js).

The triangle, its edges u and v, and its unit normal as an arrow from the centroid, with a
curved arrow in the face that turns the way the corners run: counter-clockwise seen from the
front, which is the side the normal points to.

WebGL draws in 32-bit floats, so coordinates like 1e200 (or a sliver far from the origin)
cannot be drawn as given. The view is therefore centred on the centroid, computed exactly,
and scaled by a power of two when the triangle is very large or very small. The axes are
hidden (their numbers would be the view's, not the input's); a small x, y, z triad shows
the directions, and the hover text gives the true coordinates.

Each trace has a ``name`` saying what it draws: face, u, v, edge, normal, front, turn,
corners, axes.

The arithmetic is plain Python on 3-tuples of floats (a dozen vectors: importing NumPy for
them would cost the server's start-up more than all the figures it draws). It rounds as the
former NumPy version did, step for step, so the figure is the same to the bit (where NumPy's
BLAS uses FMA, as on x86-64 today): products and sums element by element, cross products as
``np.cross``, and dot products (lengths too) as NumPy's: each product added to the running
sum with one rounding, a fused multiply-add. Only hypot and atan2, which merely choose
between branches (a label's side, a camera nudge), may differ from NumPy's in a last bit.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from fractions import Fraction
from typing import Any

from app.web.formatting import js_number
from app.web.plotly import ACCENT, DEEP_ACCENT, FONT, INK, MUTED, TRANSPARENT, Trace, cone_trace

Vector = tuple[float, float, float]

FACE_COLOR = ACCENT
POINT_COLORS = ["#c2410c", "#15803d", "#1d4ed8"]  # the page's badges for A, B and C
EDGE_COLOR = INK
NORMAL_COLOR = "#e8590c"
TURN_COLOR = DEEP_ACCENT
TRIAD_COLOR = MUTED
#: Within these sizes (of the largest offset from the centroid) the view keeps true scale.
TRUE_SCALE = (Fraction(1, 2**20), Fraction(2**20))
ARROW = 0.6  # the normal arrow's length, times the longest edge
DEFAULT_EYE: Vector = (1.0 / math.sqrt(3.0), 1.0 / math.sqrt(3.0), 1.0 / math.sqrt(3.0))
EYE_DISTANCE = 1.35
#: Added to an eye near the z axis: half the default eye, flattened (``* [1, 1, 0]``).
TURNTABLE_NUDGE: Vector = (0.5 * DEFAULT_EYE[0] * 1.0, 0.5 * DEFAULT_EYE[1] * 1.0, 0.0)
UP: Vector = (0.0, 0.0, 1.0)
ZERO: Vector = (0.0, 0.0, 0.0)
AXES: tuple[Vector, Vector, Vector] = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def _turn_angles(start: float, stop: float, num: int) -> list[float]:
    """``np.linspace(start, stop, num)``, to the bit: ``i * step + start``, and ``stop`` last."""
    step = (stop - start) / (num - 1)
    return [i * step + start for i in range(num - 1)] + [stop]


#: The turn arrow's angles, three quarters of a circle, and their cosines and sines.
TURN_ANGLES = _turn_angles(0.35, 0.35 + 1.5 * math.pi, 40)
TURN_COS = [math.cos(angle) for angle in TURN_ANGLES]
TURN_SIN = [math.sin(angle) for angle in TURN_ANGLES]


def view3d_figure(payload: dict[str, Any]) -> dict[str, Any]:
    """Return ``{"data": [...], "layout": {...}}`` for a result payload.

    Every coordinate is a finite float, at most a few million, whatever the input.
    """
    points, exponent = view_space([payload["a"], payload["b"], payload["c"]])
    winding = [0, 1, 2] if payload["order"] == "ABC" else [0, 2, 1]
    longest = max(_norm(_sub(points[i], points[i - 1])) for i in range(3)) or 1.0
    normal = None if payload["degenerate"] else _vector(payload["unit_normal"])
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
    radius = _reach(traces)
    triad = _axes_triad(eye, radius or 1.0)  # three equal points: radius 0
    reach = max(radius, _reach(triad))
    traces.extend(triad)
    return {"data": traces, "layout": _layout(payload, reach, eye)}


def view_space(points: list[list[float]]) -> tuple[list[Vector], int]:
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
    return [_vector([float(x * scale) for x in point]) for point in offsets], exponent


def _floor_log2(x: Fraction) -> int:
    exponent = x.numerator.bit_length() - x.denominator.bit_length()
    return exponent if Fraction(2) ** exponent <= x else exponent - 1


# --- Vector arithmetic, rounded as NumPy rounds it -----------------------------------------


def _vector(values: Sequence[float]) -> Vector:
    x, y, z = values
    return (float(x), float(y), float(z))


def _add(a: Vector, b: Vector) -> Vector:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _sub(a: Vector, b: Vector) -> Vector:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _scale(a: Vector, s: float) -> Vector:
    return (a[0] * s, a[1] * s, a[2] * s)


def _neg(a: Vector) -> Vector:
    return (-a[0], -a[1], -a[2])


def _cross(a: Vector, b: Vector) -> Vector:
    """``np.cross(a, b)``: each component a product minus a product, rounded after each."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _any(a: Vector) -> bool:
    return a[0] != 0 or a[1] != 0 or a[2] != 0


def _fma_exact(a: float, b: float, c: float) -> float:
    """``a * b + c`` rounded once, in integers (int / int is correctly rounded in Python)."""
    try:
        an, ad = a.as_integer_ratio()
        bn, bd = b.as_integer_ratio()
        cn, cd = c.as_integer_ratio()
    except (OverflowError, ValueError):  # an infinity or a NaN: nothing to round
        if math.isinf(c) and math.isfinite(a) and math.isfinite(b):
            return c  # even if a * b alone would overflow
        return a * b + c
    denominator = ad * bd  # powers of two: one divides the other
    if denominator >= cd:
        numerator = an * bn + cn * (denominator // cd)
    else:
        numerator, denominator = an * bn * (cd // denominator) + cn, cd
    try:
        return numerator / denominator
    except OverflowError:
        return math.inf if numerator > 0 else -math.inf


_SPLIT = 134217729.0  # 2**27 + 1: Veltkamp's splitting constant for doubles
_SAFE = (2.0**-960, 2.0**960)  # products in here split into four exact partial products


def _fma_split(a: float, b: float, c: float) -> float:
    """``a * b + c`` rounded once: a and b split in halves, whose four products are exact."""
    product = abs(a * b)
    if _SAFE[0] < product < _SAFE[1] and abs(a) < _SAFE[1] and abs(b) < _SAFE[1]:
        t = _SPLIT * a
        a_high = t - (t - a)
        a_low = a - a_high
        t = _SPLIT * b
        b_high = t - (t - b)
        b_low = b - b_high
        parts = (a_high * b_high, a_high * b_low, a_low * b_high, a_low * b_low, c)
        return math.fsum(parts)  # the sum of exact values, rounded once
    if a == 0 or b == 0:
        return c + a * b  # the sign of a zero sum is the only question (IEEE 754 rules)
    return _fma_exact(a, b, c)  # products near the ends of the range, infinities, NaNs


#: ``a * b + c`` with one rounding (``math.fma`` from Python 3.13 on).
_fma: Callable[[float, float, float], float] = getattr(math, "fma", _fma_split)


def _dot(a: Vector, b: Vector) -> float:
    """``np.dot(a, b)`` of two 3-vectors, to the bit where NumPy's BLAS fuses.

    NumPy hands a dot product to OpenBLAS, whose kernels (on x86-64 with FMA) add each
    product to the running sum with one fused multiply-add, and the sum starts at +0.0.
    Without FMA, NumPy's would differ in the last bits; this one is the same everywhere.
    """
    # a[0] * b[0] rounds as the first fused step does, but for the sign of a zero: the
    # final + 0.0 makes every zero +0.0, as the kernel's sum does.
    return _fma(a[2], b[2], _fma(a[1], b[1], a[0] * b[0])) + 0.0


def _norm(a: Vector) -> float:
    """``np.linalg.norm(a)``: the square root of ``a @ a``."""
    return math.sqrt(_dot(a, a))


def _unit(vector: Vector) -> Vector:
    """``vector`` scaled to length 1; it must not be zero."""
    size = _norm(vector)
    return (vector[0] / size, vector[1] / size, vector[2] / size)


def _round4(x: float) -> float:
    """``np.round(x, 4)``: ``rint(x * 10**4) / 10**4``, the sign of a zero kept (not round())."""
    scaled = x * 10000.0
    return math.copysign(float(round(scaled)), scaled) / 10000.0


# --- Traces ---------------------------------------------------------------------------------


def _vector_text(values: list[float | None] | None) -> str:
    if values is None:
        return "none"
    return "(" + ", ".join("out of range" if x is None else js_number(x) for x in values) + ")"


def _line(points: Sequence[Vector], **style: Any) -> Trace:
    x = [point[0] for point in points]
    y = [point[1] for point in points]
    z = [point[2] for point in points]
    return {"type": "scatter3d", "x": x, "y": y, "z": z, **style}


def _cone(name: str, tip: Vector, vector: Vector, color: str, hover: str) -> Trace:
    """An arrowhead whose tip is at ``tip``; its length is the length of ``vector``."""
    return {
        **cone_trace(name, [tip], [vector], color),
        "hovertemplate": f"{hover}<extra></extra>",
    }


def _face(points: list[Vector], winding: list[int], payload: dict[str, Any]) -> Trace:
    corners = [points[i] for i in winding]
    area = "out of range" if payload["area"] is None else js_number(payload["area"])
    return {
        "type": "mesh3d",
        "name": "face",
        "x": [point[0] for point in corners],
        "y": [point[1] for point in corners],
        "z": [point[2] for point in corners],
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
    payload: dict[str, Any], points: list[Vector], winding: list[int], eye: Vector
) -> list[Trace]:
    """u and v from A, labelled at their middles, and the third edge as a thin outline."""
    names = "ABC"
    traces = []
    start = points[0]
    for label, end in (("u", winding[1]), ("v", winding[2])):
        stop = points[end]
        middle = ((start[0] + stop[0]) / 2, (start[1] + stop[1]) / 2, (start[2] + stop[2]) / 2)
        hover = f"{label} = {names[end]} − A = {_vector_text(payload[label])}"
        edge = _sub(stop, start)
        # edge @ edge is 0 for a zero edge and for one of subnormal length (a sliver as long
        # as the double range, squeezed into view space).
        length_squared = _dot(edge, edge)
        away = (
            _sub(middle, _scale(edge, _dot(middle, edge) / length_squared))
            if length_squared
            else middle
        )
        if _norm(away) <= 1e-9 * _norm(edge):
            away = ZERO  # the edge runs through the centroid: three points on a line
        (side,) = _outward([away], eye, "bottom center")
        traces.append(
            _line(
                [start, middle, stop],
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
            [points[1], points[2]],
            name="edge",
            mode="lines",
            line={"color": FACE_COLOR, "width": 3},
            hoverinfo="skip",
        )
    )
    return traces


def _normal_arrow(normal: Vector, longest: float, payload: dict[str, Any]) -> list[Trace]:
    """A shaft from the centroid and a cone at its tip, labelled "front"."""
    length = ARROW * longest
    head = 0.22 * length
    tip = _scale(normal, length)
    hover = f"unit normal {_vector_text(payload['unit_normal'])}"
    shaft = _line(
        [ZERO, _scale(normal, length - head)],
        name="normal",
        mode="lines",
        line={"color": NORMAL_COLOR, "width": 7},
        hovertemplate=f"{hover}<extra></extra>",
    )
    label = _line(
        [_scale(normal, length + 0.12 * longest)],
        name="front",
        mode="text",
        text=["front"],
        textfont={"color": NORMAL_COLOR, "size": 13},
        hoverinfo="skip",
    )
    return [shaft, _cone("normal", tip, _scale(normal, head), NORMAL_COLOR, hover), label]


def _turn_arrow(normal: Vector, points: list[Vector], longest: float) -> list[Trace]:
    """Three quarters of a circle around the centroid, counter-clockwise seen from the front.

    Its radius fits inside a fat triangle; a sliver gets a minimum size so it stays visible.
    It floats a little above the face, on the front side.
    """
    first = _perpendicular(normal, points[0])
    second = _cross(normal, first)
    perimeter = sum(_norm(_sub(points[i], points[i - 1])) for i in range(3))
    double_area = _norm(_cross(_sub(points[1], points[0]), _sub(points[2], points[0])))
    radius = min(max(0.75 * double_area / perimeter, 0.1 * longest), 0.25 * longest)
    lift = _scale(_scale(normal, 0.02), longest)
    (f0, f1, f2), (s0, s1, s2), (l0, l1, l2) = first, second, lift
    arc = [
        (
            (cos * f0 + sin * s0) * radius + l0,
            (cos * f1 + sin * s1) * radius + l1,
            (cos * f2 + sin * s2) * radius + l2,
        )
        for cos, sin in zip(TURN_COS, TURN_SIN, strict=True)
    ]
    tangent = _add(_scale(first, -TURN_SIN[-1]), _scale(second, TURN_COS[-1]))
    head = 0.8 * radius
    return [
        _line(
            arc, name="turn", mode="lines", line={"color": TURN_COLOR, "width": 4}, hoverinfo="skip"
        ),
        _cone(
            "turn",
            _add(arc[-1], _scale(tangent, head)),
            _scale(tangent, head),
            TURN_COLOR,
            "the corners turn this way",
        ),
    ]


def _perpendicular(normal: Vector, hint: Vector) -> Vector:
    """A unit vector perpendicular to ``normal``, towards ``hint`` when it can be."""
    for candidate in (hint, UP, AXES[0]):
        flat = _sub(candidate, _scale(normal, _dot(candidate, normal)))
        size = _norm(flat)
        if size > 1e-6 * _norm(candidate):
            return (flat[0] / size, flat[1] / size, flat[2] / size)
    raise AssertionError("unreachable: z and x cannot both be parallel to a unit vector")


def _corners(payload: dict[str, Any], points: list[Vector], exponent: int, eye: Vector) -> Trace:
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


def _eye(normal: Vector | None, points: list[Vector]) -> Vector:
    """The camera's direction: the front, 45 degrees from the normal, so the arrow shows.

    It leans across the longest edge, towards the opposite corner unless that looks up from
    far below: the arrow then falls between two corners on the screen, and a sliver shows
    its full length. A degenerate triangle is seen from the side of its line.
    """
    start, end = _longest_edge(points)
    line = _sub(points[end], points[start])
    if normal is not None:
        across = _perpendicular(normal, _cross(normal, line) if _any(line) else DEFAULT_EYE)
        toward = _sub(points[3 - start - end], points[start])
        lean = across if _dot(across, toward) >= 0 else _neg(across)
        if (normal[2] + lean[2]) < min(-0.9, normal[2] - lean[2]):
            lean = _neg(lean)  # about 40 degrees from below or more, and the other way is higher
        eye = _add(normal, lean)
        if math.hypot(eye[0], eye[1]) < 0.25 * _norm(eye):
            eye = _add(eye, TURNTABLE_NUDGE)  # turntable needs an eye off the z axis
        return _unit(eye)
    if not _any(line):
        return DEFAULT_EYE
    line = _unit(line)
    side = _perpendicular(line, _cross(line, UP)) if abs(line[2]) < 0.99 else AXES[0]
    side = side if _dot(side, DEFAULT_EYE) >= 0 else _neg(side)
    return _unit(_add(side, _scale(_perpendicular(line, UP), 0.5)))


def _longest_edge(points: list[Vector]) -> tuple[int, int]:
    edges = [(0, 1), (1, 2), (2, 0)]
    return max(edges, key=lambda edge: _norm(_sub(points[edge[1]], points[edge[0]])))


def _screen(eye: Vector) -> tuple[Vector, Vector]:
    """The directions that point right and up on the screen, for a camera at ``eye``."""
    back = _neg(eye)
    right = _cross(back, UP)
    size = _norm(right)
    right = (right[0] / size, right[1] / size, right[2] / size)
    return right, _cross(right, back)


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


def _outward(directions: Iterable[Vector], eye: Vector, centred: str = "top center") -> list[str]:
    """Text positions that put labels where the directions point to on the screen.

    Labels go away from the centroid: a corner's direction is its position, an edge's is
    across the edge. A direction that points nowhere on the screen (a corner at the
    centroid, the middle of three points on a line) gets ``centred``.
    """
    right, screen_up = _screen(eye)
    positions = []
    for direction in directions:
        across, up = _dot(direction, right), _dot(direction, screen_up)
        if not _any(direction) or math.hypot(across, up) <= 1e-9 * _norm(direction):
            positions.append(centred)
            continue
        sector = round(math.atan2(up, across) / (math.pi / 4)) % 8
        positions.append(POSITIONS[sector])
    return positions


def _axes_triad(eye: Vector, radius: float) -> list[Trace]:
    """Short x, y and z arrows in the view's lower left corner, for orientation."""
    right, screen_up = _screen(eye)
    origin = _scale(_sub(_scale(right, -0.95), _scale(screen_up, 0.75)), radius)
    arm = 0.3 * radius
    traces = []
    for direction, name in zip(AXES, "xyz", strict=True):
        end = _add(origin, _scale(direction, arm))
        traces.append(
            _line(
                [origin, end],
                name="axes",
                mode="lines",
                line={"color": TRIAD_COLOR, "width": 3},
                hoverinfo="skip",
            )
        )
        traces.append(
            _line(
                [_add(end, _scale(direction, 0.25 * arm))],
                name="axes",
                mode="text",
                text=[name],
                textfont={"color": TRIAD_COLOR, "size": 12},
                hoverinfo="skip",
            )
        )
    return traces


def _reach(traces: list[Trace]) -> float:
    """The largest distance of a trace's point from the centroid."""
    return max(
        _norm(point)
        for trace in traces
        for point in zip(trace["x"], trace["y"], trace["z"], strict=True)
    )


def _axis(reach: float) -> dict[str, Any]:
    return {"range": [-reach, reach], "autorange": False, "visible": False}


def _layout(payload: dict[str, Any], reach: float, eye: Vector) -> dict[str, Any]:
    camera = {
        "eye": dict(zip("xyz", [_round4(EYE_DISTANCE * x) for x in eye], strict=True)),
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
