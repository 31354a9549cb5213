"""Worked steps: how the calculator gets from the user's points to n, |n|, the plane and more.

Every number is the user's own, written as JavaScript's ``String(x)`` writes it (the
notation is :mod:`app.calculator.notation`). The exact u, v and n are those of the decimals
typed (:mod:`app.calculator.calculation`: 0.1 is 1/10), or of the doubles
(:func:`mesh_normal.triangle.normal.exact_triangle`) when there is no typed text; values in between
(products, squares, u · v, d) are computed exactly from them and rounded once, like the
results; from the first number that rounding changed, a chain reads "≈" instead of "=". Each
line is a :class:`~app.calculator.mathml.Formula`: MathML for the page (vectors as columns,
determinants as matrices) and plain text beside it. For example, with A = (1, 0, 0),
B = (0, 2, 0) and C = (0, 0, 3)::

    n_x = |u_y u_z; v_y v_z| = |2 0; 0 3| = 2·3 − 0·0 = 6 − 0 = 6
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from math import degrees, isfinite

from markupsafe import Markup

from app.calculator.exact_forms import Exact
from app.calculator.mathml import (
    ARROW,
    COMMA,
    EQUALS,
    MINUS,
    PLUS,
    TIMES,
    Formula,
    determinant,
    fenced,
    fraction,
    hat,
    ident,
    indexed,
    joined,
    math,
    norm,
    number,
    op,
    row,
    sqrt,
    square,
    word,
)
from app.calculator.notation import (
    Shown,
    base,
    chain,
    float_number,
    float_term,
    float_text,
    given,
    matching,
    num,
    product,
    range_notes,
    seg,
    shown,
    sub,
    term,
    vector,
)
from app.calculator.plane_angle import angle_radians
from mesh_normal.triangle.normal import (
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

N, U, V, A = ident("n"), ident("u"), ident("v"), ident("A")


@dataclass(frozen=True, slots=True)
class Step:
    """One worked step: what it does in words, its math one formula a line, and special cases.

    ``key`` names the step for templates and tests: ``edges``, ``cross``, ``exact`` (only
    when naive floats disagree), ``magnitude``, ``area``, ``unit``, ``plane``, ``angle``,
    ``swap``. ``warn`` marks notes about a degenerate triangle or out-of-range values.
    """

    key: str
    title: str
    text: str
    formulas: tuple[Formula, ...]
    notes: tuple[str, ...] = ()
    warn: bool = False

    @property
    def lines(self) -> tuple[str, ...]:
        """The formulas as plain text (the MathML's ``alttext``)."""
        return tuple(f.text for f in self.formulas)

    @property
    def math(self) -> tuple[Markup, ...]:
        """The formulas as ``<math>`` elements for the page."""
        return tuple(math(f) for f in self.formulas)


@dataclass(frozen=True, slots=True)
class _Exact:
    """The triangle's exact values, with the points in the chosen order."""

    points: tuple[Vector, Vector, Vector]
    u: Exact3
    v: Exact3
    n: Exact3
    square: Fraction  # |n|²
    dot: Fraction  # u · v
    start: Exact3  # A


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


def _exact(result: TriangleNormal, typed: Exact | None) -> _Exact:
    """The exact u, v and n: of the typed decimals when given, else of the doubles."""
    if typed is not None:
        a, b, c = result.a, result.b, result.c
        return _Exact(
            (a, c, b) if result.order == "ACB" else (a, b, c),
            typed.u,
            typed.v,
            typed.n,
            typed.square,
            typed.dot,
            typed.points[0],
        )
    exact = exact_triangle(result.a, result.b, result.c, swap_winding=result.order == "ACB")
    k = exact.scale
    return _Exact(
        exact.points,
        _scaled(exact.u, k),
        _scaled(exact.v, k),
        _scaled(exact.n, 2 * k),
        Fraction(exact.square, 1 << (4 * k)),
        Fraction(exact.dot, 1 << (2 * k)),
        _fractions(exact.points[0]),
    )


def _shown_vector(values: MaybeVector, exact: Exact3) -> tuple[Shown, ...]:
    return tuple(matching(value, x) for value, x in zip(values, exact, strict=True))


def _magnitude(result: TriangleNormal, x: _Exact) -> Shown:
    value = result.magnitude
    return Shown(value, value is not None and Fraction(value) ** 2 == x.square)


# --- 1. Edges ---------------------------------------------------------------------------------


def _edge_lines(
    name: str, end: str, end_point: Vector, start: Vector, values: tuple[Shown, ...]
) -> list[Formula]:
    lines = [row(ident(name), EQUALS, ident(end), MINUS, A)]
    for axis, e, s, value in zip(AXES, end_point, start, values, strict=True):
        lines.append(
            chain(
                seg(indexed(name, axis)),
                seg(row(indexed(end.lower(), axis), MINUS, indexed("a", axis))),
                seg(row(term(given(e)), MINUS, term(given(s)))),
                seg(num(value), value),
            )
        )
    return [*lines, row(ident(name), EQUALS, vector(values))]


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


def _cross_line(
    i: int, u: tuple[Shown, ...], v: tuple[Shown, ...], x: _Exact, value: Shown
) -> Formula:
    """``n_x = |u_y u_z; v_y v_z| = |2 0; 0 3| = 2·3 − 0·0 = 6 − 0 = 6``."""
    j, k = _CROSS[i]
    a, b, c = AXES[i], AXES[j], AXES[k]
    first, second = shown(x.u[j] * x.v[k]), shown(x.u[k] * x.v[j])
    symbols = [[indexed("u", b), indexed("u", c)], [indexed("v", b), indexed("v", c)]]
    numbers = [[num(u[j]), num(u[k])], [num(v[j]), num(v[k])]]
    return chain(
        seg(indexed("n", a)),
        seg(determinant(symbols)),
        sub(determinant(numbers), u[j], v[k], u[k], v[j]),
        sub(row(product(u[j], v[k]), MINUS, product(u[k], v[j])), u[j], v[k], u[k], v[j]),
        sub(row(term(first), MINUS, term(second)), first, second),
        seg(num(value), value),
    )


def _cross_head(u: tuple[Shown, ...], v: tuple[Shown, ...]) -> Formula:
    """``n = u × v`` as the 3×3 determinant with the unit vectors on top."""
    units = [indexed("e", axis) for axis in AXES]
    symbols = [units, [indexed("u", a) for a in AXES], [indexed("v", a) for a in AXES]]
    numbers = [units, [num(s) for s in u], [num(s) for s in v]]
    return chain(
        seg(N),
        seg(row(U, TIMES, V)),
        seg(determinant(symbols)),
        sub(determinant(numbers), *u, *v),
    )


def _cross_step(result: TriangleNormal, x: _Exact) -> Step:
    u, v = _shown_vector(result.u, x.u), _shown_vector(result.v, x.v)
    n = _shown_vector(result.normal, x.n)
    lines = [
        _cross_head(u, v),
        *(_cross_line(i, u, v, x, n[i]) for i in range(3)),
        row(N, EQUALS, vector(n)),
    ]
    notes = range_notes(zip((f"n_{a}" for a in AXES), n, strict=True))
    if result.degenerate and result.message:
        notes = (result.message, *notes)
    text = (
        "n = u × v is the determinant with the unit vectors e_x, e_y, e_z on top; each "
        "component of n is the 2×2 determinant of the other two components of u and v."
    )
    return Step("cross", "The cross product n = u × v", text, tuple(lines), notes, warn=bool(notes))


# --- The naive float cross product, when it disagrees -----------------------------------------


def _naive_products(x: _Exact) -> list[tuple[float, float, float, float]]:
    """(u_j, v_k, u_k, v_j) in plain floats, for n_x, n_y, n_z."""
    p, q, r = x.points
    u = [b - a for a, b in zip(p, q, strict=True)]
    v = [c - a for a, c in zip(p, r, strict=True)]
    return [(u[j], v[k], u[k], v[j]) for j, k in _CROSS]


def _float_factor(x: float) -> Formula:
    return fenced(float_number(x)) if x < 0 or "e" in float_text(x) else float_number(x)


def _naive_line(axis: str, factors: tuple[float, float, float, float]) -> Formula:
    uj, vk, uk, vj = factors
    first, second = uj * vk, uk * vj
    dot = op("·")
    return row(
        indexed("n", axis),
        word(" in floats: "),
        _float_factor(uj),
        dot,
        _float_factor(vk),
        MINUS,
        _float_factor(uk),
        dot,
        _float_factor(vj),
        ARROW,
        float_term(first),
        MINUS,
        float_term(second),
        ARROW,
        float_number(first - second),
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
    naive_vector = fenced(joined((float_number(value) for value in naive), COMMA))
    lines = [
        *(_naive_line(AXES[i], factors[i]) for i in differ),
        row(word("naive "), N, EQUALS, naive_vector),
        row(word("exact "), N, word(", rounded once"), EQUALS, exact),
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
        seg(norm(N)),
        seg(sqrt(joined((square(indexed("n", a)) for a in AXES), PLUS))),
        sub(sqrt(joined((square(base(s)) for s in n), PLUS)), *n),
        sub(sqrt(joined((num(s) for s in squares), PLUS)), *squares),
        sub(sqrt(num(total)), total),
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
    two = number(2.0)
    line = chain(
        seg(ident("area")),
        seg(fraction(norm(N), two)),
        sub(fraction(num(magnitude), two), magnitude),
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
        line = row(hat(), EQUALS, fraction(N, norm(N)), EQUALS, fraction(N, number(0.0)))
        return Step("unit", title, "n divided by its length.", (line,), (note,), warn=True)
    n, magnitude = _shown_vector(result.normal, x.n), _magnitude(result, x)
    unit = tuple(
        Shown(e, Fraction(e) ** 2 * x.square == ni * ni)
        for e, ni in zip(result.unit_normal, x.n, strict=True)
    )
    lines = [
        chain(
            seg(hat(a)),
            seg(fraction(indexed("n", a), norm(N))),
            sub(fraction(num(ni), num(magnitude)), ni, magnitude),
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
    last = row(hat(), EQUALS, vector(unit))
    return Step("unit", title, text, (*lines, last), notes, warn=bool(notes))


# --- 6. Plane ---------------------------------------------------------------------------------


def _plane_equation(coefficients: Sequence[float], d: Shown) -> Formula:
    parts: list[Formula] = []
    for value, axis in zip(coefficients, AXES, strict=True):
        if value == 0:
            continue
        if parts:
            parts.append(MINUS if value < 0 else PLUS)
        elif value < 0:
            parts.append(op("−", "−"))
        if abs(value) != 1:
            parts.append(base(given(abs(value))))
        parts.append(ident(axis))
    return row(*parts, EQUALS, num(d))


def _plane_lines(unit: bool, normal: Sequence[Shown], a: Vector, d: Shown) -> list[Formula]:
    point = [given(value) for value in a]
    name = hat() if unit else N
    products = joined((product(ni, ai) for ni, ai in zip(normal, point, strict=True)), PLUS)
    dot = op("·")
    symbols = joined(
        (row(hat(axis) if unit else indexed("n", axis), dot, indexed("a", axis)) for axis in AXES),
        PLUS,
    )
    return [
        chain(
            seg(ident("d′" if unit else "d")),
            seg(row(name, op("·", " · "), A)),
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
    d = shown(_dot(x.n, x.start))
    if all(s.value is not None for s in n) and d.value is not None:
        text = (
            "A point (x, y, z) lies on the plane when n · (x, y, z) = d; A is on it, so d = n · A."
        )
        coefficients = [s.value for s in n if s.value is not None]
        lines = _plane_lines(False, n, a, d)
        return Step("plane", title, text, (*lines, _plane_equation(coefficients, d)))
    unit = result.unit_normal
    d_unit = shown(_dot(_fractions(unit), _fractions(a)))
    text = "A point (x, y, z) lies on the plane when n̂ · (x, y, z) = d′; A is on it, so d′ = n̂ · A."
    note = (
        "n or n · A is beyond the range of doubles, so the plane is written with the unit "
        "normal instead; d′ = n̂ · A is computed exactly from the doubles shown and "
        "rounded once."
    )
    lines = _plane_lines(True, [given(e) for e in unit], a, d_unit)
    return Step("plane", title, text, (*lines, _plane_equation(unit, d_unit)), (note,), warn=True)


# --- 7. Angle ---------------------------------------------------------------------------------


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
    dot_op, cdot = op("·", " · "), op("·")
    u_dot_v = row(U, dot_op, V)
    u_cross_v = norm(row(U, TIMES, V))
    factors = joined((product(a, b) for a, b in zip(u, v, strict=True)), PLUS)
    symbols = joined((row(indexed("u", a), cdot, indexed("v", a)) for a in AXES), PLUS)
    lines = [
        chain(
            seg(u_dot_v),
            seg(symbols),
            sub(factors, *u, *v),
            sub(joined((term(p) for p in products), PLUS), *products),
            seg(num(dot), dot),
        ),
        chain(seg(u_cross_v), seg(norm(N)), seg(num(magnitude), magnitude)),
    ]
    theta, atan2_name, degree = ident("θ"), ident("atan2"), op("°", "°")
    notes = _angle_notes(result, x)
    if x.square or x.dot:
        angle = given(degrees(angle_radians(x.square, x.dot)))
        exact = Shown(angle.value, not x.square or not x.dot)
        lines.append(
            chain(
                seg(theta),
                seg(row(atan2_name, fenced(row(u_cross_v, COMMA, u_dot_v)))),
                sub(row(atan2_name, fenced(row(num(magnitude), COMMA, num(dot)))), magnitude, dot),
                seg(row(num(exact), degree), exact),
            )
        )
    else:
        zeros = fenced(row(number(0.0), COMMA, number(0.0)))
        lines.append(row(theta, EQUALS, atan2_name, zeros, word(": undefined")))
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
    negated = op("−", "−")
    lines = (
        row(V, TIMES, U, EQUALS, negated, fenced(row(U, TIMES, V))),
        row(word(f"{other}: "), N, EQUALS, negated, vector(n), EQUALS, vector(flipped)),
        row(
            norm(N),
            EQUALS,
            num(magnitude),
            word(" and "),
            ident("area"),
            EQUALS,
            num(area),
            word(" either way"),
        ),
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


def worked_steps(result: TriangleNormal, exact: Exact | None = None) -> list[Step]:
    """The calculation of ``result`` step by step, with the user's own numbers.

    Edges, cross product (and, when plain floats would get it wrong, why), |n|, area, unit
    normal, plane, the angle between u and v, and why swapping the winding flips n. ``exact``
    holds the exact values of the typed decimals (0.1 is 1/10); without it the steps work
    with the doubles' exact values.
    """
    x = _exact(result, exact)
    why_exact = _exact_step(result, x)
    steps = [
        _edges_step(result, x),
        _cross_step(result, x),
        *([why_exact] if why_exact else []),
        _magnitude_step(result, x),
        _area_step(result, x),
        _unit_step(result, x),
        _plane_step(result, x),
        _angle_step(result, x),
        _swap_step(result, x),
    ]
    return _explain_rounding(steps)
