"""One calculation for the page and the API: the rounded result, its exact values and forms.

Typed decimal text is read exactly (``0.1`` is 1/10) and the result is that exact value
rounded once, so that the exact forms and the rounded values agree. When some coordinate
has no exact value (an exponent beyond ±30), the doubles are used and the exact forms are
left out, with the reason. JSON numbers are doubles: their exact values are the doubles'.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from markupsafe import Markup

from app.calculator.exact_forms import (
    MAX_EXACT_EXPONENT,
    Exact,
    ExactForms,
    RationalPoint,
    double_values,
    exact_forms,
    exact_values,
    forms_json,
    forms_math,
)
from app.calculator.params import TriangleInput
from app.calculator.payloads import normal_payload
from app.calculator.plane_angle import angle_math, angle_payload, plane_math, plane_payload
from app.calculator.presets import COORDINATE_FIELDS
from mesh_normal.triangle.normal import (
    TriangleNormal,
    exact_triangle,
    rational_triangle_normal,
    rounded_normal,
)

Points = tuple[RationalPoint, RationalPoint, RationalPoint]

#: Said after the reason when JSON numbers' exact forms are left out.
DOUBLES_HINT = (
    " JSON numbers are doubles, whose exact values are long (0.1 is "
    "3602879701896397/36028797018963968); GET /api/normal reads decimal text exactly."
)


@dataclass(slots=True)
class Calculation:
    """A result, the exact values it was rounded from, and the exact forms (or why not).

    Not frozen, as :class:`app.calculator.exact_forms.Exact` is not (the cost of making one).
    """

    result: TriangleNormal
    exact: Exact
    forms: ExactForms | None
    reason: str | None
    #: A, B, C as the exact decimals typed, when the result was computed from them.
    typed: Points | None = None


def _finish(result: TriangleNormal, exact: Exact, why: str | None, hint: str = "") -> Calculation:
    """The calculation with its exact forms, or ``why`` not (or why they are too long, then
    ``hint``)."""
    if why is None:
        forms = exact_forms(exact)
        if not isinstance(forms, str):
            return Calculation(result, exact, forms, None)
        why = forms + hint
    return Calculation(result, exact, None, why)


def from_doubles(
    a: list[float], b: list[float], c: list[float], *, swap_winding: bool = False
) -> Calculation:
    """The calculation for JSON numbers (the exact forms are the doubles' exact values)."""
    triangle = exact_triangle(a, b, c, swap_winding=swap_winding)
    return _finish(rounded_normal(triangle), double_values(triangle), None, DOUBLES_HINT)


def from_typed(parsed: TriangleInput) -> Calculation:
    """The calculation for what was typed; call only when ``parsed`` has no errors."""
    missing = [name for name in COORDINATE_FIELDS if name not in parsed.exact]
    if missing:
        # The fractions exactly, the decimals as their doubles (TriangleInput.normal).
        result = parsed.normal()
        why = (
            f"The exact forms are left out: {', '.join(missing)} "
            f"{'has' if len(missing) == 1 else 'have'} an exponent beyond ±{MAX_EXACT_EXPONENT}, "
            "so the doubles are used."
        )
        triangle = exact_triangle(result.a, result.b, result.c, swap_winding=parsed.swap)
        return _finish(result, double_values(triangle), why)
    x = [parsed.exact[name] for name in COORDINATE_FIELDS]
    points = ((x[0], x[1], x[2]), (x[3], x[4], x[5]), (x[6], x[7], x[8]))
    result = rational_triangle_normal(*points, swap_winding=parsed.swap)
    a, b, c = parsed.points()  # the corners as typed, -0 included
    exact = exact_values(*points, swap_winding=parsed.swap)
    return replace(_finish(replace(result, a=a, b=b, c=c), exact, None), typed=points)


def calculation_payload(calc: Calculation) -> dict[str, Any]:
    """The API's answer for one triangle: the rounded result, plane, angle and exact forms."""
    payload = normal_payload(calc.result)
    plane, plane_reason = plane_payload(
        calc.exact, calc.result.normal, with_exact=calc.forms is not None
    )
    angle, angle_reason = angle_payload(calc.exact, calc.result.order)
    payload.update(
        {
            "plane": plane,
            "plane_reason": plane_reason,
            "angle": angle,
            "angle_reason": angle_reason,
            "exact": None if calc.forms is None else forms_json(calc.forms),
            "exact_reason": calc.reason,
        }
    )
    return payload


def result_math(calc: Calculation, payload: dict[str, Any]) -> dict[str, Markup]:
    """The result card's formulas by key: exact values (when shown), the plane and the angle."""
    out = {} if calc.forms is None else forms_math(calc.forms)
    if payload["plane"] is not None:
        out.update(plane_math(payload["plane"], None if calc.forms is None else calc.exact))
    if payload["angle"] is not None:
        out["angle"] = angle_math(payload["angle"])
    return out
