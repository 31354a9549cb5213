"""Worked steps: how the calculator gets from the user's points to n, |n|, the plane and more.

Every number is the user's own, written as JavaScript's ``String(x)`` writes it. Values in
between (products, squares, u · v, d) are computed exactly with :class:`~fractions.Fraction`
from the doubles and rounded once, like the results; from the first number that rounding
changed, a chain reads "≈" instead of "=". For example, with A = (1, 0, 0), B = (0, 2, 0)
and C = (0, 0, 3)::

    n_x = u_y·v_z − u_z·v_y = (2)(3) − (0)(0) = 6 − 0 = 6
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from math import atan2, degrees, isfinite, isnan

from app.web.formatting import js_number
from mesh_normal.exact import ratio_sqrt
from mesh_normal.tolerances import LARGEST_DOUBLE_TEXT
from mesh_normal.triangle import AXES, MaybeVector, TriangleNormal, Vector

Exact3 = tuple[Fraction, Fraction, Fraction]

#: n_i = u_j v_k − u_k v_j, as (j, k) for i = x, y, z.
_CROSS = ((1, 2), (2, 0), (0, 1))


@dataclass(frozen=True, slots=True)
class Step:
    """One worked step: what it does in words, its math one line each, and special cases.

    ``key`` names the step for templates and tests: ``edges``, ``cross``, ``exact`` (only
    when naive floats disagree), ``magnitude``, ``area``, ``unit``, ``plane``, ``angle``,
    ``swap``. ``warn`` marks notes about a degenerate triangle or out-of-range values.
    """

    key: str
    title: str
    text: str
    lines: tuple[str, ...]
    notes: tuple[str, ...] = ()
    warn: bool = False


@dataclass(frozen=True, slots=True)
class _Shown:
    """A number as displayed: its double (None beyond the double range) and whether exact."""

    value: float | None
    exact: bool


@dataclass(frozen=True, slots=True)
class _Exact:
    """The triangle's exact values, with the points in the chosen order."""

    points: tuple[Vector, Vector, Vector]
    u: Exact3
    v: Exact3
    n: Exact3
    square: Fraction  # |n|²
    dot: Fraction  # u · v


# --- Numbers ----------------------------------------------------------------------------------


def _round(x: Fraction) -> float | None:
    """``x`` rounded once to the nearest double; None when it overflows or underflows to 0."""
    try:
        value = float(x)  # int / int: correctly rounded
    except OverflowError:
        return None
    return None if value == 0 and x != 0 else value


def _shown(x: Fraction) -> _Shown:
    return _matching(_round(x), x)


def _matching(value: float | None, x: Fraction) -> _Shown:
    """A value the core rounded from ``x``."""
    return _Shown(value, value is not None and Fraction(value) == x)


def _given(value: float) -> _Shown:
    return _Shown(value, True)


def _num(s: _Shown) -> str:
    return "out of range" if s.value is None else js_number(s.value)


def _term(s: _Shown) -> str:
    """A number in a sum or difference: negatives in parentheses."""
    text = _num(s)
    return f"({text})" if text.startswith("-") else text


def _factor(s: _Shown) -> str:
    return f"({_num(s)})"


def _base(s: _Shown) -> str:
    """A number to be squared: ``(-6)²`` and ``(1e-7)²``, but ``6²``."""
    text = _num(s)
    return f"({text})" if text.startswith("-") or "e" in text else text


def _vector(values: Iterable[_Shown]) -> str:
    return "(" + ", ".join(_num(s) for s in values) + ")"


def _float_text(x: float) -> str:
    """A plain float result, including JavaScript's words for the non-finite ones."""
    if isnan(x):
        return "NaN"
    if not isfinite(x):
        return "Infinity" if x > 0 else "-Infinity"
    return js_number(x)


def _float_term(x: float) -> str:
    text = _float_text(x)
    return f"({text})" if text.startswith("-") else text


# --- Chains of equalities ---------------------------------------------------------------------

Segment = tuple[str, tuple[_Shown, ...]]


def _seg(text: str, *values: _Shown) -> Segment:
    return text, values


def _sub(text: str, *operands: _Shown) -> Segment | None:
    """A substitution, left out when one of its numbers is out of range."""
    return None if any(s.value is None for s in operands) else (text, operands)


def _chain(*segments: Segment | None) -> str:
    """``first = second = third``, with "≈" from the first segment holding a rounded number."""
    exact, parts = True, []
    for segment in segments:
        if segment is None:
            continue
        text, values = segment
        exact = exact and all(s.exact or s.value is None for s in values)
        parts.append(f"{'=' if exact else '≈'} {text}" if parts else text)
    return " ".join(parts)


def _listing(names: Sequence[str]) -> str:
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def _range_notes(named: Iterable[tuple[str, _Shown]]) -> tuple[str, ...]:
    names = [name for name, s in named if s.value is None]
    if not names:
        return ()
    one = len(names) == 1
    return (
        f"Beyond the range of doubles (above {LARGEST_DOUBLE_TEXT}, or nonzero but below "
        f"4.9e-324): {_listing(names)}. {'It shows' if one else 'They show'} as “out of "
        f"range”; the calculation keeps the exact {'value' if one else 'values'}.",
    )


# --- Exact values -----------------------------------------------------------------------------


def _ordered_points(result: TriangleNormal) -> tuple[Vector, Vector, Vector]:
    by_name = {"A": result.a, "B": result.b, "C": result.c}
    first, second, third = (by_name[name] for name in result.order)
    return first, second, third


def _fractions(values: Iterable[float]) -> Exact3:
    x, y, z = (Fraction(value) for value in values)
    return x, y, z


def _difference(p: Exact3, q: Exact3) -> Exact3:
    return p[0] - q[0], p[1] - q[1], p[2] - q[2]


def _cross(u: Exact3, v: Exact3) -> Exact3:
    x, y, z = (u[j] * v[k] - u[k] * v[j] for j, k in _CROSS)
    return x, y, z


def _dot(u: Sequence[Fraction], v: Sequence[Fraction]) -> Fraction:
    return sum((a * b for a, b in zip(u, v, strict=True)), Fraction(0))


def _exact(result: TriangleNormal) -> _Exact:
    points = _ordered_points(result)
    p, q, r = (_fractions(point) for point in points)
    u, v = _difference(q, p), _difference(r, p)
    n = _cross(u, v)
    return _Exact(points, u, v, n, _dot(n, n), _dot(u, v))


def _shown_vector(values: MaybeVector, exact: Exact3) -> tuple[_Shown, ...]:
    return tuple(_matching(value, x) for value, x in zip(values, exact, strict=True))


def _magnitude(result: TriangleNormal, x: _Exact) -> _Shown:
    value = result.magnitude
    return _Shown(value, value is not None and Fraction(value) ** 2 == x.square)


# --- 1. Edges ---------------------------------------------------------------------------------


def _edge_lines(
    name: str, end: str, end_point: Vector, start: Vector, values: tuple[_Shown, ...]
) -> list[str]:
    lines = [f"{name} = {end} − A"]
    for axis, e, s, value in zip(AXES, end_point, start, values, strict=True):
        lines.append(
            _chain(
                _seg(f"{name}_{axis}"),
                _seg(f"{end.lower()}_{axis} − a_{axis}"),
                _seg(f"{_term(_given(e))} − {_term(_given(s))}"),
                _seg(_num(value), value),
            )
        )
    return [*lines, f"{name} = {_vector(values)}"]


def _edges_step(result: TriangleNormal, x: _Exact) -> Step:
    _, second, third = result.order
    u, v = _shown_vector(result.u, x.u), _shown_vector(result.v, x.v)
    if result.order == "ABC":
        text = "Both edges start at A: u = B − A and v = C − A, one component at a time."
    else:
        text = (
            "In the order A, C, B both edges start at A and C comes first: u = C − A and "
            "v = B − A, one component at a time."
        )
    p, q, r = x.points
    lines = [*_edge_lines("u", second, q, p, u), *_edge_lines("v", third, r, p, v)]
    named = [
        *zip((f"u_{a}" for a in AXES), u, strict=True),
        *zip((f"v_{a}" for a in AXES), v, strict=True),
    ]
    notes = _range_notes(named)
    return Step("edges", "Edges from A", text, tuple(lines), notes, warn=bool(notes))


# --- 2. Cross product -------------------------------------------------------------------------


def _cross_line(
    i: int, u: tuple[_Shown, ...], v: tuple[_Shown, ...], x: _Exact, value: _Shown
) -> str:
    j, k = _CROSS[i]
    a, b, c = AXES[i], AXES[j], AXES[k]
    first, second = _shown(x.u[j] * x.v[k]), _shown(x.u[k] * x.v[j])
    return _chain(
        _seg(f"n_{a}"),
        _seg(f"u_{b}·v_{c} − u_{c}·v_{b}"),
        _sub(
            f"{_factor(u[j])}{_factor(v[k])} − {_factor(u[k])}{_factor(v[j])}",
            u[j],
            v[k],
            u[k],
            v[j],
        ),
        _sub(f"{_term(first)} − {_term(second)}", first, second),
        _seg(_num(value), value),
    )


def _cross_step(result: TriangleNormal, x: _Exact) -> Step:
    u, v = _shown_vector(result.u, x.u), _shown_vector(result.v, x.v)
    n = _shown_vector(result.normal, x.n)
    lines = ["n = u × v", *(_cross_line(i, u, v, x, n[i]) for i in range(3)), f"n = {_vector(n)}"]
    notes = _range_notes(zip((f"n_{a}" for a in AXES), n, strict=True))
    if result.degenerate and result.message:
        notes = (result.message, *notes)
    text = (
        "Each component of n = u × v is a 2×2 determinant made of the other two "
        "components of u and v."
    )
    return Step("cross", "The cross product n = u × v", text, tuple(lines), notes, warn=bool(notes))


# --- The naive float cross product, when it disagrees -----------------------------------------


def _naive_products(result: TriangleNormal) -> list[tuple[float, float, float, float]]:
    """(u_j, v_k, u_k, v_j) in plain floats, for n_x, n_y, n_z."""
    p, q, r = _ordered_points(result)
    u = [b - a for a, b in zip(p, q, strict=True)]
    v = [c - a for a, c in zip(p, r, strict=True)]
    return [(u[j], v[k], u[k], v[j]) for j, k in _CROSS]


def _naive_line(axis: str, factors: tuple[float, float, float, float]) -> str:
    uj, vk, uk, vj = factors
    first, second = uj * vk, uk * vj
    fs = [f"({_float_text(f)})" for f in factors]
    return (
        f"n_{axis} in floats: {fs[0]}{fs[1]} − {fs[2]}{fs[3]} → {_float_term(first)} − "
        f"{_float_term(second)} → {_float_text(first - second)}"
    )


def _exact_step(result: TriangleNormal, x: _Exact) -> Step | None:
    factors = _naive_products(result)
    naive = [uj * vk - uk * vj for uj, vk, uk, vj in factors]
    differ = [
        i for i in range(3) if result.normal[i] is not None and naive[i] != result.normal[i]
    ]  # NaN differs too
    if not differ:
        return None
    shown = "(" + ", ".join(_float_text(value) for value in naive) + ")"
    exact = _vector(_shown_vector(result.normal, x.n))
    lines = [
        *(_naive_line(AXES[i], factors[i]) for i in differ),
        f"naive n = {shown}",
        f"exact n, rounded once = {exact}",
    ]
    note = (
        f"A naive float computation gives n = {shown} because the products round before "
        "they are subtracted; this calculator works with the exact values and rounds once."
    )
    if not all(isfinite(value) for value in naive):
        note += (
            " In floats a value beyond the largest double becomes Infinity, and "
            "Infinity − Infinity or 0 · Infinity gives NaN."
        )
    elif not any(naive) and not result.degenerate:
        note += " Plain floats would call this triangle flat."
    text = (
        "Plain floating point rounds each product to a double (→) before subtracting, so "
        "digits that the subtraction needs are already gone."
    )
    return Step("exact", "Why exact arithmetic matters here", text, tuple(lines), (note,))


# --- 3. and 4. Length and area ----------------------------------------------------------------


def _magnitude_step(result: TriangleNormal, x: _Exact) -> Step:
    n = _shown_vector(result.normal, x.n)
    squares = tuple(_shown(ni * ni) for ni in x.n)
    total, magnitude = _shown(x.square), _magnitude(result, x)
    line = _chain(
        _seg("|n|"),
        _seg("sqrt(n_x² + n_y² + n_z²)"),
        _sub(f"sqrt({_base(n[0])}² + {_base(n[1])}² + {_base(n[2])}²)", *n),
        _sub(f"sqrt({' + '.join(_num(s) for s in squares)})", *squares),
        _sub(f"sqrt({_num(total)})", total),
        _seg(_num(magnitude), magnitude),
    )
    named = [
        *zip((f"n_{a}²" for a in AXES), squares, strict=True),
        ("the sum of squares", total),
        ("|n|", magnitude),
    ]
    notes = _range_notes(named)
    if total.value is None and magnitude.value is not None:
        notes = (
            *notes,
            "The sum of squares does not fit a double, but its square root does: "
            "|n| is the square root of the exact sum, rounded once.",
        )
    text = "The length of n, by Pythagoras in three dimensions."
    return Step("magnitude", "The length |n|", text, (line,), notes, warn=bool(notes))


def _area_step(result: TriangleNormal, x: _Exact) -> Step:
    magnitude = _magnitude(result, x)
    area = result.area
    shown = _Shown(area, area is not None and 4 * Fraction(area) ** 2 == x.square)
    line = _chain(
        _seg("area"),
        _seg("|n| / 2"),
        _sub(f"{_num(magnitude)} / 2", magnitude),
        _seg(_num(shown), shown),
    )
    notes = _range_notes([("the area", shown)])
    if magnitude.value is None and shown.value is not None:
        notes = (
            "|n| is beyond the largest double, but half of it is not: the area comes from "
            "the exact |n|, rounded once.",
        )
    text = "|n| is the area of the parallelogram spanned by u and v; the triangle is half of it."
    return Step("area", "The area", text, (line,), notes, warn=bool(notes))


# --- 5. Unit normal ---------------------------------------------------------------------------


def _unit_step(result: TriangleNormal, x: _Exact) -> Step:
    title = "The unit normal n̂ = n / |n|"
    if result.unit_normal is None:
        note = (
            "There is no unit normal: n = (0, 0, 0) has no direction, and dividing by "
            "|n| = 0 is undefined."
        )
        return Step(
            "unit", title, "n divided by its length.", ("n̂ = n / |n| = n / 0",), (note,), warn=True
        )
    n, magnitude = _shown_vector(result.normal, x.n), _magnitude(result, x)
    unit = tuple(
        _Shown(e, Fraction(e) ** 2 * x.square == ni * ni)
        for e, ni in zip(result.unit_normal, x.n, strict=True)
    )
    lines = [
        _chain(
            _seg(f"n̂_{a}"),
            _seg(f"n_{a} / |n|"),
            _sub(f"{_term(ni)} / {_num(magnitude)}", ni, magnitude),
            _seg(_num(e), e),
        )
        for a, ni, e in zip(AXES, n, unit, strict=True)
    ]
    notes: tuple[str, ...] = ()
    if magnitude.value is None or any(s.value is None for s in n):
        notes = (
            "n or |n| is beyond the range of doubles, but their ratio is not: the unit "
            "normal comes from the exact values, rounded once, and is shown all the same.",
        )
    text = "n divided by its length: the same direction, length 1."
    return Step("unit", title, text, (*lines, f"n̂ = {_vector(unit)}"), notes, warn=bool(notes))


# --- 6. Plane ---------------------------------------------------------------------------------


def _plane_equation(coefficients: Sequence[float], d: _Shown) -> str:
    text = ""
    for value, axis in zip(coefficients, AXES, strict=True):
        if value == 0:
            continue
        size = _base(_given(abs(value))) if abs(value) != 1 else ""
        sign = ("-" if value < 0 else "") if not text else (" − " if value < 0 else " + ")
        text += f"{sign}{size}{axis}"
    return f"{text} = {_num(d)}"


def _plane_lines(name: str, normal: Sequence[_Shown], a: Vector, d: _Shown) -> list[str]:
    point = [_given(value) for value in a]
    products = " + ".join(
        f"{_factor(ni)}{_factor(ai)}" for ni, ai in zip(normal, point, strict=True)
    )
    symbols = " + ".join(f"{name}_{axis}·a_{axis}" for axis in AXES)
    head = "d" if name == "n" else "d′"
    return [
        _chain(
            _seg(head),
            _seg(f"{name} · A"),
            _seg(symbols),
            _sub(products, *normal, *point),
            _seg(_num(d), d),
        )
    ]


def _plane_step(result: TriangleNormal, x: _Exact) -> Step:
    title = "The plane through the triangle"
    if result.unit_normal is None:
        note = (
            "There is no plane: points on one line (or repeated points) do not fix a "
            "single plane, since every plane through that line contains them."
        )
        return Step("plane", title, "A plane needs a normal direction.", (), (note,), warn=True)
    a = x.points[0]
    n = _shown_vector(result.normal, x.n)
    d = _shown(_dot(x.n, _fractions(a)))
    if all(s.value is not None for s in n) and d.value is not None:
        text = (
            "A point (x, y, z) lies on the plane when n · (x, y, z) = d; A is on it, so d = n · A."
        )
        coefficients = [s.value for s in n if s.value is not None]
        lines = _plane_lines("n", n, a, d)
        return Step("plane", title, text, (*lines, _plane_equation(coefficients, d)))
    unit = result.unit_normal
    d_unit = _shown(_dot(_fractions(unit), _fractions(a)))
    text = "A point (x, y, z) lies on the plane when n̂ · (x, y, z) = d′; A is on it, so d′ = n̂ · A."
    note = (
        "n or n · A is beyond the range of doubles, so the plane is written with the unit "
        "normal instead; d′ = n̂ · A is computed exactly from the doubles shown and "
        "rounded once."
    )
    lines = _plane_lines("n̂", [_given(e) for e in unit], a, d_unit)
    return Step("plane", title, text, (*lines, _plane_equation(unit, d_unit)), (note,), warn=True)


# --- 7. Angle ---------------------------------------------------------------------------------


def _sqrt_ratio(part: Fraction, whole: Fraction) -> float:
    """sqrt(part / whole) for 0 <= part <= whole, whole > 0, rounded once."""
    ratio = part / whole
    return ratio_sqrt(ratio.numerator, ratio.denominator)


def _angle_degrees(square: Fraction, dot: Fraction) -> float:
    """atan2(|u × v|, u · v) in degrees; only the ratio matters, so scale it into [0, 1].

    ``square`` is |u × v|², and not both it and ``dot`` are 0.
    """
    dot_square = dot * dot
    if square <= dot_square:
        return degrees(atan2(_sqrt_ratio(square, dot_square), 1.0 if dot > 0 else -1.0))
    cosine_part = _sqrt_ratio(dot_square, square)
    return degrees(atan2(1.0, cosine_part if dot >= 0 else -cosine_part))


def _angle_notes(result: TriangleNormal, x: _Exact) -> tuple[str, ...]:
    if not result.degenerate:
        return ()
    _first, second, third = result.order
    for name, edge, end in (("u", x.u, second), ("v", x.v, third)):
        if not any(edge):
            return (
                f"{name} has zero length (points A and {end} coincide), so the angle "
                "between u and v is undefined.",
            )
    way = "the same way (0°)" if x.dot > 0 else "opposite ways (180°)"
    return (f"The points lie on one line: u and v point {way}.",)


def _angle_step(result: TriangleNormal, x: _Exact) -> Step:
    u, v = _shown_vector(result.u, x.u), _shown_vector(result.v, x.v)
    products = tuple(_shown(a * b) for a, b in zip(x.u, x.v, strict=True))
    dot, magnitude = _shown(x.dot), _magnitude(result, x)
    factors = " + ".join(f"{_factor(a)}{_factor(b)}" for a, b in zip(u, v, strict=True))
    lines = [
        _chain(
            _seg("u · v"),
            _seg("u_x·v_x + u_y·v_y + u_z·v_z"),
            _sub(factors, *u, *v),
            _sub(" + ".join(_term(p) for p in products), *products),
            _seg(_num(dot), dot),
        ),
        _chain(_seg("|u × v|"), _seg("|n|"), _seg(_num(magnitude), magnitude)),
    ]
    notes = _angle_notes(result, x)
    if x.square or x.dot:
        angle = _given(_angle_degrees(x.square, x.dot))
        exact = _Shown(angle.value, not x.square or not x.dot)
        lines.append(
            _chain(
                _seg("θ"),
                _seg("atan2(|u × v|, u · v)"),
                _sub(f"atan2({_num(magnitude)}, {_num(dot)})", magnitude, dot),
                _seg(f"{_num(exact)}°", exact),
            )
        )
    else:
        lines.append("θ = atan2(0, 0): undefined")
    notes += _range_notes([("u · v", dot)])
    text = (
        "|u × v| = |u||v| sin θ and u · v = |u||v| cos θ; atan2 uses both, so it stays "
        "accurate near 0° and 180°, where acos(u · v / (|u||v|)) loses digits."
    )
    return Step("angle", "The angle between u and v", text, tuple(lines), notes, warn=bool(notes))


# --- 8. Swapping the winding ------------------------------------------------------------------


def _swap_step(result: TriangleNormal, x: _Exact) -> Step:
    n = _shown_vector(result.normal, x.n)
    flipped = [_Shown(None if s.value is None else -s.value, s.exact) for s in n]
    other = "A, C, B" if result.order == "ABC" else "A, B, C"
    if result.order == "ABC":
        text = (
            "Listing the corners as A, C, B exchanges the roles of u and v (u = C − A, v = B − A)."
        )
    else:
        text = "You listed the corners as A, C, B: compared with A, B, C, u and v exchange roles."
    text += (
        " Since v × u = −(u × v), every component of n changes sign, while |n| and the "
        "area stay the same."
    )
    magnitude = _magnitude(result, x)
    area = _Shown(result.area, True)
    lines = (
        "v × u = −(u × v)",
        f"{other}: n = −{_vector(n)} = {_vector(flipped)}",
        f"|n| = {_num(magnitude)} and area = {_num(area)} either way",
    )
    notes = (
        ("n = (0, 0, 0) either way: a zero vector has no sign to flip.",)
        if result.degenerate
        else ()
    )
    return Step("swap", "Why swapping the winding flips the sign", text, lines, notes)


# --- All steps --------------------------------------------------------------------------------

_ROUNDED_NOTE = (
    "“≈” marks a number rounded to the nearest double for display; every step "
    "works with the exact values."
)


def _explain_rounding(steps: list[Step]) -> list[Step]:
    """Say what "≈" means, once, in the first step that uses it."""
    for index, step in enumerate(steps):
        if any("≈" in line for line in step.lines):
            steps[index] = replace(step, notes=(*step.notes, _ROUNDED_NOTE))
            break
    return steps


def worked_steps(result: TriangleNormal) -> list[Step]:
    """The calculation of ``result`` step by step, with the user's own numbers.

    Edges, cross product (and, when plain floats would get it wrong, why), |n|, area, unit
    normal, plane, the angle between u and v, and why swapping the winding flips n.
    """
    x = _exact(result)
    exact = _exact_step(result, x)
    steps = [
        _edges_step(result, x),
        _cross_step(result, x),
        *([exact] if exact else []),
        _magnitude_step(result, x),
        _area_step(result, x),
        _unit_step(result, x),
        _plane_step(result, x),
        _angle_step(result, x),
        _swap_step(result, x),
    ]
    return _explain_rounding(steps)
