"""The JSON answer for one triangle of doubles, without Fractions: the common case, fast.

:func:`app.calculator.calculation.calculation_payload` of :func:`from_doubles` builds every
exact value as a :class:`~fractions.Fraction` (a gcd at each step) and spends most of a
request on it. Here the same exact values are held as Python integers over powers of two
(every double is ``X * 2**-k``; see :mod:`mesh_normal.exact`), each output is rounded once
from them by the same functions, and the edges u and v come from float subtraction, which
IEEE 754 rounds correctly (the exact difference rounded once, as the exact path does).

The fast path answers only where it is certain to write the same bytes as the exact path:
a triangle with some area, every value within the double range, and exact forms that are
certainly left out as too long (the usual case for JSON decimals such as 0.1). Everywhere
else (a degenerate triangle, a value beyond the doubles, exact forms that may fit) it
returns ``None`` and the caller takes the exact path. ``tests/app/calculator/test_fast.py``
compares the two on random and adversarial triangles.
"""

from __future__ import annotations

from math import atan2, degrees, gcd, isfinite
from typing import Any

from app.calculator.calculation import DOUBLES_HINT
from app.calculator.exact_forms import MAX_DIGITS, TOO_LONG, equation_text
from app.web.formatting import js_number
from mesh_normal.exact import OutOfRange, ratio_sqrt, sqrt_scaled

Point = list[float]

_LIMIT: int = 10**MAX_DIGITS
#: The largest power of two below ``_LIMIT``: a reduced denominator 2**e fits when e <= this.
_MAX_DENOMINATOR_BITS = _LIMIT.bit_length() - 1
_REASON = TOO_LONG + DOUBLES_HINT


def fast_payload(a: Point, b: Point, c: Point, swap_winding: bool) -> dict[str, Any] | None:
    """The same dict as the exact path for ABC (ACB with ``swap_winding``), or ``None``.

    ``None`` where the fast path cannot be sure of the same answer (see the module docstring).
    """
    given = (*a, *b, *c)
    if len(given) != 9 or not all(type(x) is float and isfinite(x) for x in given):
        return None
    p, q, r = (a, c, b) if swap_winding else (a, b, c)
    # u and v: one correctly rounded subtraction each (+ 0.0 writes the exact zero as 0.0).
    u = [q[0] - p[0] + 0.0, q[1] - p[1] + 0.0, q[2] - p[2] + 0.0]
    v = [r[0] - p[0] + 0.0, r[1] - p[1] + 0.0, r[2] - p[2] + 0.0]
    if not all(isfinite(x) for x in (*u, *v)):
        return None

    # Every coordinate as an integer over one scale 2**-k (mesh_normal.exact.to_fixed).
    ratios = [x.as_integer_ratio() for x in (*p, *q, *r)]
    shifts = [den.bit_length() - 1 for _, den in ratios]
    k = max(shifts)
    px, py, pz, qx, qy, qz, rx, ry, rz = (
        num << (k - shift) for (num, _), shift in zip(ratios, shifts, strict=True)
    )
    ux, uy, uz = qx - px, qy - py, qz - pz
    vx, vy, vz = rx - px, ry - py, rz - pz
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx  # over 2**(2k)
    square = nx * nx + ny * ny + nz * nz  # |n|**2 over 2**(4k)
    if square == 0:
        return None  # degenerate: the exact path writes its message

    d = nx * px + ny * py + nz * pz  # the plane's n . A, over 2**(3k)
    if _forms_may_fit(ratios, k, (ux, uy, uz, vx, vy, vz), (nx, ny, nz), d, square):
        return None
    try:
        den2 = 1 << (2 * k)
        normal = [_divided(nx, den2), _divided(ny, den2), _divided(nz, den2)]
        magnitude = sqrt_scaled(square, 2 * k)
        area = sqrt_scaled(square, 2 * k + 1)
    except OutOfRange:
        return None  # the exact path names the values beyond the double range
    unit = [_unit(nx, square), _unit(ny, square), _unit(nz, square)]
    return {
        "a": list(a),
        "b": list(b),
        "c": list(c),
        "order": "ACB" if swap_winding else "ABC",
        "u": u,
        "v": v,
        "normal": normal,
        "magnitude": magnitude,
        "unit_normal": unit,
        "area": area,
        "degenerate": False,
        "plane": _plane(normal, d, 3 * k),
        "plane_reason": None,
        "angle": _angle(square, ux * vx + uy * vy + uz * vz),
        "angle_reason": None,
        "exact": None,
        "exact_reason": _REASON,
    }


def _divided(value: int, denominator: int) -> float:
    """``value / denominator`` rounded once (int / int is correctly rounded in Python)."""
    try:
        result = value / denominator
    except OverflowError:
        raise OutOfRange("overflow") from None
    if result == 0.0 and value != 0:
        raise OutOfRange("underflow")
    return result


def _unit(ni: int, square: int) -> float:
    value = ratio_sqrt(ni * ni, square)
    return -value if ni < 0 else value


def _plane(normal: list[float], d_scaled: int, d_bits: int) -> dict[str, Any]:
    """:func:`app.calculator.plane_angle.plane_payload` without the exact forms."""
    try:
        d: float | None = _divided(d_scaled, 1 << d_bits)
    except OutOfRange:
        d = None
    equation = None
    if d is not None:
        texts = [_number_text(value) for value in normal]
        equation = equation_text(texts, _number_text(d))
    return {
        "a": normal[0],
        "b": normal[1],
        "c": normal[2],
        "d": d,
        "equation": equation,
        "exact": None,
    }


def _number_text(x: float) -> str:
    """:func:`app.web.formatting.js_number`, quickly where ``repr`` has no exponent.

    Both write the shortest digits that round-trip; without an exponent (``1e-4 <= |x| < 1e16``)
    JavaScript writes them as ``repr`` does, less a trailing ``.0``.
    """
    text = repr(x)
    if x == 0 or "e" in text:
        return js_number(x)
    return text[:-2] if text.endswith(".0") else text


def _angle(square: int, dot: int) -> dict[str, float]:
    """:func:`app.calculator.plane_angle.angle_radians` on the same exact values.

    ``square`` is |u x v|**2 and ``dot`` is u . v, both over 2**(4k) once ``dot`` is squared;
    each ratio is reduced as the Fraction there is, so ``ratio_sqrt`` sees the same integers.
    """
    dot_square = dot * dot
    if square <= dot_square:
        radians = atan2(_ratio_root(square, dot_square), 1.0 if dot > 0 else -1.0)
    else:
        cosine_part = _ratio_root(dot_square, square)
        radians = atan2(1.0, cosine_part if dot >= 0 else -cosine_part)
    return {"degrees": degrees(radians), "radians": radians}


def _ratio_root(part: int, whole: int) -> float:
    common = gcd(part, whole)
    return ratio_sqrt(part // common, whole // common)


def _dyadic_fits(value: int, bits: int) -> bool:
    """Whether ``value * 2**-bits``, reduced, has numerator and denominator below ``_LIMIT``."""
    if value == 0:
        return True
    zeros = min((value & -value).bit_length() - 1, bits)
    return bits - zeros <= _MAX_DENOMINATOR_BITS and abs(value >> zeros) < _LIMIT


def _forms_may_fit(
    ratios: list[tuple[int, int]],
    k: int,
    edges: tuple[int, ...],
    n: tuple[int, int, int],
    d: int,
    square: int,
) -> bool:
    """False when :func:`app.calculator.exact_forms.exact_forms` certainly says ``TOO_LONG``.

    Its first two checks, on the same values: the corners, u, v, n and the plane's d, then
    |n|**2 (each reduced, as Fractions are). Beyond them (the surd of |n|) the exact path
    decides.
    """
    # Any one value that does not fit is enough: the likeliest (the longest) first.
    if not (_dyadic_fits(d, 3 * k) and _dyadic_fits(square, 4 * k)):
        return False
    if not all(_dyadic_fits(x, 2 * k) for x in n) or not all(_dyadic_fits(x, k) for x in edges):
        return False
    return all(abs(num) < _LIMIT and den < _LIMIT for num, den in ratios)
