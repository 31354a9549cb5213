"""The plane through the triangle and the angle between its edges u and v.

The plane through A with normal n is n · (x, y, z) = n · A, written ax + by + cz = d with
(a, b, c) = n and d = n · A, each the exact value rounded once. The angle is
atan2(|u × v|, u · v), computed from the exact |u × v|² and u · v so that it is accurate near 0°
and 180° and never NaN; it is undefined only when u or v is the zero vector.
"""

from __future__ import annotations

from fractions import Fraction
from math import atan2, degrees
from typing import Any

from markupsafe import Markup

from app.calculator.exact_forms import (
    Exact,
    equation_text,
    ratio_json,
    rounded_over,
)
from app.calculator.mathml import (
    EQUALS,
    MINUS,
    PLUS,
    Formula,
    ident,
    math,
    number,
    op,
    plain_number,
    row,
    word,
)
from app.web.formatting import js_number
from mesh_normal.triangle.exact import ratio_sqrt
from mesh_normal.triangle.normal import AXES, MaybeVector

NO_PLANE = (
    "There is no plane: points on one line (or repeated points) do not fix a single plane, "
    "since every plane through that line contains them."
)


def plane_payload(
    exact: Exact, normal: MaybeVector, *, with_exact: bool
) -> tuple[dict[str, Any] | None, str | None]:
    """The plane as rounded a, b, c, d and its equation (plus exact ones), or why there is none.

    ``normal`` is the result's rounded n, which (a, b, c) is."""
    if not exact.scaled_square:
        return None, NO_PLANE
    den2 = exact.denominator**2
    a, b, c = normal
    d = rounded_over(exact.scaled_d, den2 * exact.denominator)
    equation = None
    if a is not None and b is not None and c is not None and d is not None:
        equation = equation_text([js_number(a), js_number(b), js_number(c)], js_number(d))
    plane: dict[str, Any] = {"a": a, "b": b, "c": c, "d": d, "equation": equation, "exact": None}
    if with_exact:
        den = exact.denominator
        values = (*((value, den2) for value in exact.scaled_n), (exact.scaled_d, den2 * den))
        integers = [str(value) for value in exact.integer_plane()]
        plane["exact"] = {
            **{key: ratio_json(*value) for key, value in zip("abcd", values, strict=True)},
            "equation": equation_text(integers[:3], integers[3]),
        }
    return plane, None


def angle_radians(square: Fraction | int, dot: Fraction | int) -> float:
    """atan2(sqrt(square), dot): only the ratio matters, so it is scaled into [0, 1] first.

    ``square`` is |u × v|² and ``dot`` is u · v, exact (or integers, ``square`` over the
    square of ``dot``'s denominator); not both are 0. Scaling keeps the result finite whatever
    the size of u and v (their products may be far beyond doubles).
    """
    # square / dot² as one ratio of integers: part / whole.
    part = square.numerator * dot.denominator * dot.denominator
    whole = square.denominator * dot.numerator * dot.numerator
    if part <= whole:
        return atan2(ratio_sqrt(part, whole), 1.0 if dot > 0 else -1.0)
    cosine_part = ratio_sqrt(whole, part)
    return atan2(1.0, cosine_part if dot >= 0 else -cosine_part)


def undefined_angle(exact: Exact, order: str) -> str | None:
    """Why the angle between u and v is undefined (a zero edge), or ``None`` when it is not."""
    for name, edge, end in (("u", exact.scaled_u, order[1]), ("v", exact.scaled_v, order[2])):
        if not any(edge):
            return (
                f"{name} has zero length (points A and {end} coincide), so the angle "
                "between u and v is undefined."
            )
    return None


def angle_payload(exact: Exact, order: str) -> tuple[dict[str, float] | None, str | None]:
    """The angle between u and v in degrees and radians, or why it is undefined."""
    reason = undefined_angle(exact, order)
    if reason is not None:
        return None, reason
    radians = angle_radians(exact.scaled_square, exact.scaled_dot)
    return {"degrees": degrees(radians), "radians": radians}, None


# --- MathML for the result card ---------------------------------------------------------------


def plane_math(plane: dict[str, Any], exact: Exact | None) -> dict[str, Markup]:
    """The plane's equation, rounded (numbers the precision setting rewrites) and exact.

    ``exact`` is given when the exact forms are shown: the exact equation is scaled to
    coprime integers.
    """
    out: dict[str, Markup] = {}
    values = [plane[key] for key in "abcd"]
    if all(value is not None for value in values):
        terms = [(number(abs(v)), v < 0, abs(v) == 1) for v in values[:3] if v != 0]
        axes = [axis for axis, v in zip(AXES, values[:3], strict=True) if v != 0]
        out["plane"] = math(_axes_equation(terms, axes, number(values[3])))
    if exact is not None and exact.scaled_square:
        integers = exact.integer_plane()
        terms = [(plain_number(str(abs(v))), v < 0, abs(v) == 1) for v in integers[:3] if v != 0]
        axes = [axis for axis, v in zip(AXES, integers[:3], strict=True) if v != 0]
        d = integers[3]
        d_formula = row(op("−", "−"), plain_number(str(-d))) if d < 0 else plain_number(str(d))
        out["plane_exact"] = math(_axes_equation(terms, axes, d_formula))
    return out


def _axes_equation(terms: list[tuple[Formula, bool, bool]], axes: list[str], d: Formula) -> Formula:
    parts: list[Formula] = []
    for (size, negative, one), axis in zip(terms, axes, strict=True):
        if parts:
            parts.append(MINUS if negative else PLUS)
        elif negative:
            parts.append(op("−", "−"))
        parts.extend([ident(axis)] if one else [size, ident(axis)])
    return row(*(parts or [plain_number("0")]), EQUALS, d)


def angle_math(angle: dict[str, float]) -> Markup:
    """``40.9337…° = 0.7144… rad``."""
    return math(
        row(
            number(angle["degrees"]),
            op("°", "°"),
            EQUALS,
            number(angle["radians"]),
            word(" rad"),
        )
    )
