"""Worked steps: how the calculator gets from the user's points to n, |n|, the plane and more.

Every number is the user's own, written as JavaScript's ``String(x)`` writes it (the
notation is :mod:`app.calculator.notation`). The exact u, v and n come from the core
(:func:`mesh_normal.triangle.exact_triangle`, the integers that :func:`triangle_normal`
rounds); values in between (products, squares, u · v, d) are computed exactly from them and
rounded once, like the results; from the first number that rounding changed, a chain reads
"≈" instead of "=". For example, with A = (1, 0, 0), B = (0, 2, 0) and C = (0, 0, 3)::

    n_x = u_y·v_z − u_z·v_y = (2)(3) − (0)(0) = 6 − 0 = 6
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from math import atan2, degrees, isfinite

from app.calculator.notation import (
    Shown,
    base,
    chain,
    factor,
    float_term,
    float_text,
    given,
    matching,
    num,
    range_notes,
    seg,
    shown,
    sub,
    term,
    vector,
)
from mesh_normal.exact import ratio_sqrt
from mesh_normal.triangle import (
    AXES,
    IntVector,
    MaybeVector,
    TriangleNormal,
    Vector,
    exact_triangle,
)

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
class _Exact:
    """The triangle's exact values, with the points in the chosen order."""

    points: tuple[Vector, Vector, Vector]
    u: Exact3
    v: Exact3
    n: Exact3
    square: Fraction  # |n|²
    dot: Fraction  # u · v


# --- Exact values -----------------------------------------------------------------------------


def _fractions(values: Iterable[float]) -> Exact3:
    x, y, z = (Fraction(value) for value in values)
    return x, y, z


def _scaled(values: IntVector, exponent: int) -> Exact3:
    scale = 1 << exponent
    x, y, z = (Fraction(value, scale) for value in values)
    return x, y, z


def _dot(u: Sequence[Fraction], v: Sequence[Fraction]) -> Fraction:
    return sum((a * b for a, b in zip(u, v, strict=True)), Fraction(0))


def _exact(result: TriangleNormal) -> _Exact:
    """The core's exact u, v and n (integers over a power of two), as fractions to show."""
    exact = exact_triangle(result.a, result.b, result.c, swap_winding=result.order == "ACB")
    k = exact.scale
    return _Exact(
        exact.points,
        _scaled(exact.u, k),
        _scaled(exact.v, k),
        _scaled(exact.n, 2 * k),
        Fraction(exact.square, 1 << (4 * k)),
        Fraction(exact.dot, 1 << (2 * k)),
    )


def _shown_vector(values: MaybeVector, exact: Exact3) -> tuple[Shown, ...]:
    return tuple(matching(value, x) for value, x in zip(values, exact, strict=True))


def _magnitude(result: TriangleNormal, x: _Exact) -> Shown:
    value = result.magnitude
    return Shown(value, value is not None and Fraction(value) ** 2 == x.square)


# --- 1. Edges ---------------------------------------------------------------------------------


def _edge_lines(
    name: str, end: str, end_point: Vector, start: Vector, values: tuple[Shown, ...]
) -> list[str]:
    lines = [f"{name} = {end} − A"]
    for axis, e, s, value in zip(AXES, end_point, start, values, strict=True):
        lines.append(
            chain(
                seg(f"{name}_{axis}"),
                seg(f"{end.lower()}_{axis} − a_{axis}"),
                seg(f"{term(given(e))} − {term(given(s))}"),
                seg(num(value), value),
            )
        )
    return [*lines, f"{name} = {vector(values)}"]


def _edges_step(result: TriangleNormal, x: _Exact) -> Step:
    second, third = result.order[1], result.order[2]
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
    notes = range_notes(named)
    return Step("edges", "Edges from A", text, tuple(lines), notes, warn=bool(notes))


# --- 2. Cross product -------------------------------------------------------------------------


def _cross_line(i: int, u: tuple[Shown, ...], v: tuple[Shown, ...], x: _Exact, value: Shown) -> str:
    j, k = _CROSS[i]
    a, b, c = AXES[i], AXES[j], AXES[k]
    first, second = shown(x.u[j] * x.v[k]), shown(x.u[k] * x.v[j])
    return chain(
        seg(f"n_{a}"),
        seg(f"u_{b}·v_{c} − u_{c}·v_{b}"),
        sub(
            f"{factor(u[j])}{factor(v[k])} − {factor(u[k])}{factor(v[j])}",
            u[j],
            v[k],
            u[k],
            v[j],
        ),
        sub(f"{term(first)} − {term(second)}", first, second),
        seg(num(value), value),
    )


def _cross_step(result: TriangleNormal, x: _Exact) -> Step:
    u, v = _shown_vector(result.u, x.u), _shown_vector(result.v, x.v)
    n = _shown_vector(result.normal, x.n)
    lines = ["n = u × v", *(_cross_line(i, u, v, x, n[i]) for i in range(3)), f"n = {vector(n)}"]
    notes = range_notes(zip((f"n_{a}" for a in AXES), n, strict=True))
    if result.degenerate and result.message:
        notes = (result.message, *notes)
    text = (
        "Each component of n = u × v is a 2×2 determinant made of the other two "
        "components of u and v."
    )
    return Step("cross", "The cross product n = u × v", text, tuple(lines), notes, warn=bool(notes))


# --- The naive float cross product, when it disagrees -----------------------------------------


def _naive_products(x: _Exact) -> list[tuple[float, float, float, float]]:
    """(u_j, v_k, u_k, v_j) in plain floats, for n_x, n_y, n_z."""
    p, q, r = x.points
    u = [b - a for a, b in zip(p, q, strict=True)]
    v = [c - a for a, c in zip(p, r, strict=True)]
    return [(u[j], v[k], u[k], v[j]) for j, k in _CROSS]


def _naive_line(axis: str, factors: tuple[float, float, float, float]) -> str:
    uj, vk, uk, vj = factors
    first, second = uj * vk, uk * vj
    fs = [f"({float_text(f)})" for f in factors]
    return (
        f"n_{axis} in floats: {fs[0]}{fs[1]} − {fs[2]}{fs[3]} → {float_term(first)} − "
        f"{float_term(second)} → {float_text(first - second)}"
    )


def _exact_step(result: TriangleNormal, x: _Exact) -> Step | None:
    factors = _naive_products(x)
    naive = [uj * vk - uk * vj for uj, vk, uk, vj in factors]
    differ = [
        i for i in range(3) if result.normal[i] is not None and naive[i] != result.normal[i]
    ]  # NaN differs too
    if not differ:
        return None
    naive_text = "(" + ", ".join(float_text(value) for value in naive) + ")"
    exact = vector(_shown_vector(result.normal, x.n))
    lines = [
        *(_naive_line(AXES[i], factors[i]) for i in differ),
        f"naive n = {naive_text}",
        f"exact n, rounded once = {exact}",
    ]
    note = (
        f"A naive float computation gives n = {naive_text} because the products round before "
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
    squares = tuple(shown(ni * ni) for ni in x.n)
    total, magnitude = shown(x.square), _magnitude(result, x)
    line = chain(
        seg("|n|"),
        seg("sqrt(n_x² + n_y² + n_z²)"),
        sub(f"sqrt({base(n[0])}² + {base(n[1])}² + {base(n[2])}²)", *n),
        sub(f"sqrt({' + '.join(num(s) for s in squares)})", *squares),
        sub(f"sqrt({num(total)})", total),
        seg(num(magnitude), magnitude),
    )
    named = [
        *zip((f"n_{a}²" for a in AXES), squares, strict=True),
        ("the sum of squares", total),
        ("|n|", magnitude),
    ]
    notes = range_notes(named)
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
    half = Shown(area, area is not None and 4 * Fraction(area) ** 2 == x.square)
    line = chain(
        seg("area"),
        seg("|n| / 2"),
        sub(f"{num(magnitude)} / 2", magnitude),
        seg(num(half), half),
    )
    notes = range_notes([("the area", half)])
    if magnitude.value is None and half.value is not None:
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
        Shown(e, Fraction(e) ** 2 * x.square == ni * ni)
        for e, ni in zip(result.unit_normal, x.n, strict=True)
    )
    lines = [
        chain(
            seg(f"n̂_{a}"),
            seg(f"n_{a} / |n|"),
            sub(f"{term(ni)} / {num(magnitude)}", ni, magnitude),
            seg(num(e), e),
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
    return Step("unit", title, text, (*lines, f"n̂ = {vector(unit)}"), notes, warn=bool(notes))


# --- 6. Plane ---------------------------------------------------------------------------------


def _plane_equation(coefficients: Sequence[float], d: Shown) -> str:
    text = ""
    for value, axis in zip(coefficients, AXES, strict=True):
        if value == 0:
            continue
        size = base(given(abs(value))) if abs(value) != 1 else ""
        sign = ("-" if value < 0 else "") if not text else (" − " if value < 0 else " + ")
        text += f"{sign}{size}{axis}"
    return f"{text} = {num(d)}"


def _plane_lines(name: str, normal: Sequence[Shown], a: Vector, d: Shown) -> list[str]:
    point = [given(value) for value in a]
    products = " + ".join(f"{factor(ni)}{factor(ai)}" for ni, ai in zip(normal, point, strict=True))
    symbols = " + ".join(f"{name}_{axis}·a_{axis}" for axis in AXES)
    head = "d" if name == "n" else "d′"
    return [
        chain(
            seg(head),
            seg(f"{name} · A"),
            seg(symbols),
            sub(products, *normal, *point),
            seg(num(d), d),
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
    d = shown(_dot(x.n, _fractions(a)))
    if all(s.value is not None for s in n) and d.value is not None:
        text = (
            "A point (x, y, z) lies on the plane when n · (x, y, z) = d; A is on it, so d = n · A."
        )
        coefficients = [s.value for s in n if s.value is not None]
        lines = _plane_lines("n", n, a, d)
        return Step("plane", title, text, (*lines, _plane_equation(coefficients, d)))
    unit = result.unit_normal
    d_unit = shown(_dot(_fractions(unit), _fractions(a)))
    text = "A point (x, y, z) lies on the plane when n̂ · (x, y, z) = d′; A is on it, so d′ = n̂ · A."
    note = (
        "n or n · A is beyond the range of doubles, so the plane is written with the unit "
        "normal instead; d′ = n̂ · A is computed exactly from the doubles shown and "
        "rounded once."
    )
    lines = _plane_lines("n̂", [given(e) for e in unit], a, d_unit)
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
    second, third = result.order[1], result.order[2]
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
    products = tuple(shown(a * b) for a, b in zip(x.u, x.v, strict=True))
    dot, magnitude = shown(x.dot), _magnitude(result, x)
    factors = " + ".join(f"{factor(a)}{factor(b)}" for a, b in zip(u, v, strict=True))
    lines = [
        chain(
            seg("u · v"),
            seg("u_x·v_x + u_y·v_y + u_z·v_z"),
            sub(factors, *u, *v),
            sub(" + ".join(term(p) for p in products), *products),
            seg(num(dot), dot),
        ),
        chain(seg("|u × v|"), seg("|n|"), seg(num(magnitude), magnitude)),
    ]
    notes = _angle_notes(result, x)
    if x.square or x.dot:
        angle = given(_angle_degrees(x.square, x.dot))
        exact = Shown(angle.value, not x.square or not x.dot)
        lines.append(
            chain(
                seg("θ"),
                seg("atan2(|u × v|, u · v)"),
                sub(f"atan2({num(magnitude)}, {num(dot)})", magnitude, dot),
                seg(f"{num(exact)}°", exact),
            )
        )
    else:
        lines.append("θ = atan2(0, 0): undefined")
    notes += range_notes([("u · v", dot)])
    text = (
        "|u × v| = |u||v| sin θ and u · v = |u||v| cos θ; atan2 uses both, so it stays "
        "accurate near 0° and 180°, where acos(u · v / (|u||v|)) loses digits."
    )
    return Step("angle", "The angle between u and v", text, tuple(lines), notes, warn=bool(notes))


# --- 8. Swapping the winding ------------------------------------------------------------------


def _swap_step(result: TriangleNormal, x: _Exact) -> Step:
    n = _shown_vector(result.normal, x.n)
    flipped = [Shown(None if s.value is None else -s.value, s.exact) for s in n]
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
    area = Shown(result.area, True)
    lines = (
        "v × u = −(u × v)",
        f"{other}: n = −{vector(n)} = {vector(flipped)}",
        f"|n| = {num(magnitude)} and area = {num(area)} either way",
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
