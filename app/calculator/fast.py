"""The JSON answer for one triangle of doubles, without Fractions: the common case, fast.

:func:`app.calculator.calculation.calculation_payload` of :func:`from_doubles` builds every
exact value as a :class:`~fractions.Fraction` (a gcd at each step) and spends most of a
request on it. Here the same exact values are held as Python integers over powers of two
(every double is ``X * 2**-k``; see :mod:`mesh_normal.triangle.exact`), each output is rounded once
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

from math import atan2, degrees, frexp, gcd, isfinite, isqrt, ldexp
from typing import Any

from app.calculator.calculation import DOUBLES_HINT
from app.calculator.exact_forms import MAX_DIGITS, TOO_LONG
from app.web.formatting import js_number
from mesh_normal.triangle.exact import _GUARD_BITS, OutOfRange, ratio_sqrt

Point = list[float]

_LIMIT: int = 10**MAX_DIGITS
#: The largest power of two below ``_LIMIT``: a reduced denominator 2**e fits when e <= this.
_MAX_DENOMINATOR_BITS = _LIMIT.bit_length() - 1
_REASON = TOO_LONG + DOUBLES_HINT


def fast_payload(a: Point, b: Point, c: Point, swap_winding: bool) -> dict[str, Any] | None:
    """The same dict as the exact path for ABC (ACB with ``swap_winding``), or ``None``.

    ``None`` where the fast path cannot be sure of the same answer (see the module docstring).
    Written out long hand: every call and comprehension here costs a request's time.
    """
    if len(a) != 3 or len(b) != 3 or len(c) != 3:
        return None
    p, q, r = (a, c, b) if swap_winding else (a, b, c)
    px, py, pz = p
    qx, qy, qz = q
    rx, ry, rz = r
    for x in (px, py, pz, qx, qy, qz, rx, ry, rz):
        if type(x) is not float:
            return None
    # A sum that is not finite: some value is not, or the sum overflows (then the exact path).
    if not isfinite(px + py + pz + qx + qy + qz + rx + ry + rz):
        return None
    # u and v: one correctly rounded subtraction each (+ 0.0 writes the exact zero as 0.0).
    u = [qx - px + 0.0, qy - py + 0.0, qz - pz + 0.0]
    v = [rx - px + 0.0, ry - py + 0.0, rz - pz + 0.0]
    if not isfinite(abs(u[0]) + abs(u[1]) + abs(u[2]) + abs(v[0]) + abs(v[1]) + abs(v[2])):
        return None

    # Every coordinate as an integer over one scale 1 / D, D = 2**k
    # (mesh_normal.triangle.exact.to_fixed).
    pxn, pxd = px.as_integer_ratio()
    pyn, pyd = py.as_integer_ratio()
    pzn, pzd = pz.as_integer_ratio()
    qxn, qxd = qx.as_integer_ratio()
    qyn, qyd = qy.as_integer_ratio()
    qzn, qzd = qz.as_integer_ratio()
    rxn, rxd = rx.as_integer_ratio()
    ryn, ryd = ry.as_integer_ratio()
    rzn, rzd = rz.as_integer_ratio()
    scale = max(pxd, pyd, pzd, qxd, qyd, qzd, rxd, ryd, rzd)
    k = scale.bit_length() - 1
    px_, py_, pz_ = pxn * (scale // pxd), pyn * (scale // pyd), pzn * (scale // pzd)
    ux = qxn * (scale // qxd) - px_
    uy = qyn * (scale // qyd) - py_
    uz = qzn * (scale // qzd) - pz_
    vx = rxn * (scale // rxd) - px_
    vy = ryn * (scale // ryd) - py_
    vz = rzn * (scale // rzd) - pz_
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx  # over 2**(2k)
    square = nx * nx + ny * ny + nz * nz  # |n|**2 over 2**(4k)
    if square == 0:
        return None  # degenerate: the exact path writes its message
    d = nx * px_ + ny * py_ + nz * pz_  # the plane's n . A, over 2**(3k)
    if _forms_may_fit(k, (ux, uy, uz, vx, vy, vz, nx, ny, nz, d, square), (*p, *q, *r)):
        return None

    den2 = scale * scale
    try:
        normal = [nx / den2, ny / den2, nz / den2]  # int / int: rounded once
    except OverflowError:
        return None
    if (normal[0] == 0.0 and nx) or (normal[1] == 0.0 and ny) or (normal[2] == 0.0 and nz):
        return None  # nonzero below the doubles: the exact path says so
    magnitude = _root_scaled(square, 2 * k)
    if magnitude is None or magnitude < _HALVES_EXACTLY:
        return None
    area = magnitude * 0.5  # the exact half rounded once, as the magnitude is a normal double
    return {
        "a": list(a),
        "b": list(b),
        "c": list(c),
        "order": "ACB" if swap_winding else "ABC",
        "u": u,
        "v": v,
        "normal": normal,
        "magnitude": magnitude,
        "unit_normal": [
            _unit(nx, square, normal[0], magnitude),
            _unit(ny, square, normal[1], magnitude),
            _unit(nz, square, normal[2], magnitude),
        ],
        "area": area,
        "degenerate": False,
        "plane": _plane(normal, d, 3 * k),
        "plane_reason": None,
        "angle": _angle(square, ux * vx + uy * vy + uz * vz, den2, magnitude),
        "angle_reason": None,
        "exact": None,
        "exact_reason": _REASON,
    }


#: From here up, halving a double is exact and is the correctly rounded half of its exact value.
_HALVES_EXACTLY = 2.0**-1020


def _root_scaled(square: int, exponent: int) -> float | None:
    """:func:`mesh_normal.triangle.exact.sqrt_scaled`, step for step; ``None`` for out of range."""
    shift = max(0, 53 + _GUARD_BITS - square.bit_length() // 2)
    quotient = square << (2 * shift)
    root = isqrt(quotient)
    sticky = (root << 1) | (root * root != quotient)
    try:
        value = sticky / (1 << (exponent + shift + 1))
    except OverflowError:
        return None
    return value or None  # zero: nonzero below the doubles


def _unit(ni: int, square: int, normal: float, magnitude: float) -> float:
    """``ni / sqrt(square)`` rounded once, certified from the float ``normal / magnitude``."""
    if ni == 0:
        return 0.0
    value = _certified_root(ni * ni, square, abs(normal) / magnitude)
    if value is None:
        value = _exact_unit(ni * ni, square)
    return -value if ni < 0 else value


def _exact_unit(part: int, square: int) -> float:
    """:func:`mesh_normal.triangle.exact.ratio_sqrt`, step for step."""
    shift = 53 + _GUARD_BITS + max(0, square.bit_length() - part.bit_length()) // 2 + 1
    quotient, remainder = divmod(part << (2 * shift), square)
    root = isqrt(quotient)
    sticky = (root << 1) | (remainder != 0 or root * root != quotient)
    return sticky / (1 << (shift + 1))  # below the doubles: 0.0, as ratio_sqrt has it


#: Below this a guess is not certified (the grid of subnormals is coarser).
_SMALLEST_CERTIFIED = 2.0**-1000
#: The most steps of one ulp a guess is moved while certifying it.
_CERTIFY_STEPS = 3


def _certified_root(part: int, whole: int, guess: float) -> float | None:
    """``sqrt(part / whole)`` rounded to the nearest double, for ``0 < part <= whole``, or
    ``None`` when it cannot be certified near ``guess`` (a few ulps away at most).

    A double ``y = Y * 2**E`` (``2**52 < Y < 2**53``) is the nearest to ``t = sqrt(part /
    whole)`` exactly when ``t`` is strictly inside ``(y - h, y + h)``, ``h = 2**(E - 1)`` half
    an ulp: ``(2Y - 1)**2 * whole < part * 2**(2 - 2E) < (2Y + 1)**2 * whole``, in integers.
    A power of two (its lower neighbour is nearer), a tie and a tiny ``y`` are left to the
    exact path, which rounds the same value once (so both give the same double).
    """
    if not _SMALLEST_CERTIFIED <= guess < 1.0:
        return None
    mantissa, exponent = frexp(guess)
    top = int(mantissa * 9007199254740992.0)  # Y, 53 bits
    scaled = part << (108 - 2 * exponent)  # part * 2**(2 - 2E), E = exponent - 53
    for _ in range(_CERTIFY_STEPS):
        if top == 4503599627370496 or top >= 9007199254740992:  # 2**52 (a power of two), 2**53
            return None
        low = 2 * top - 1
        if scaled <= low * low * whole:
            top -= 1  # t is at or below the lower midpoint
            continue
        high = 2 * top + 1
        if scaled >= high * high * whole:
            top += 1
            continue
        return ldexp(float(top), exponent - 53)
    return None


def _divided(value: int, denominator: int) -> float:
    """``value / denominator`` rounded once (int / int is correctly rounded in Python)."""
    try:
        result = value / denominator
    except OverflowError:
        raise OutOfRange("overflow") from None
    if result == 0.0 and value != 0:
        raise OutOfRange("underflow")
    return result


def _plane(normal: list[float], d_scaled: int, d_bits: int) -> dict[str, Any]:
    """:func:`app.calculator.plane_angle.plane_payload` without the exact forms."""
    try:
        d: float | None = _divided(d_scaled, 1 << d_bits)
    except OutOfRange:
        d = None
    return {
        "a": normal[0],
        "b": normal[1],
        "c": normal[2],
        "d": d,
        "equation": None if d is None else _equation(normal, d),
        "exact": None,
    }


def _equation(normal: list[float], d: float) -> str:
    """:func:`app.calculator.exact_forms.equation_text` of the numbers' texts, which are
    never ``-0`` and hold no ``/``: ``35.275x - 2.28y + 26.425z = 60.685``."""
    text = ""
    for value, axis in zip(normal, "xyz", strict=True):
        if value == 0:
            continue
        size = _number_text(-value if value < 0 else value)
        term = axis if size == "1" else size + axis
        if text:
            text += (" - " if value < 0 else " + ") + term
        else:
            text = "-" + term if value < 0 else term
    return f"{text or '0'} = {_number_text(d)}"


def _number_text(x: float) -> str:
    """:func:`app.web.formatting.js_number`, quickly where ``repr`` has no exponent.

    Both write the shortest digits that round-trip; without an exponent (``1e-4 <= |x| < 1e16``)
    JavaScript writes them as ``repr`` does, less a trailing ``.0``.
    """
    text = repr(x)
    if x == 0 or "e" in text:
        return js_number(x)
    return text[:-2] if text.endswith(".0") else text


def _angle(square: int, dot: int, den2: int, magnitude: float) -> dict[str, float]:
    """:func:`app.calculator.plane_angle.angle_radians` on the same exact values.

    ``square`` is |u x v|**2 and ``dot`` is u . v, both over 2**(4k) once ``dot`` is squared
    (``den2`` is 2**(2k), ``magnitude`` the rounded |u x v|). Each square root of a ratio is
    certified from a float guess, else rounded as the Fraction there is, reduced.
    """
    dot_square = dot * dot
    try:
        dot_value = abs(dot / den2)
    except OverflowError:  # beyond the doubles: no guess, the exact roots then
        dot_value = 0.0
    if square <= dot_square:
        guess = magnitude / dot_value if dot_value else 0.0
        radians = atan2(_ratio_root(square, dot_square, guess), 1.0 if dot > 0 else -1.0)
    else:
        cosine_part = _ratio_root(dot_square, square, dot_value / magnitude)
        radians = atan2(1.0, cosine_part if dot >= 0 else -cosine_part)
    return {"degrees": degrees(radians), "radians": radians}


def _ratio_root(part: int, whole: int, guess: float) -> float:
    value = _certified_root(part, whole, guess)
    if value is not None:
        return value
    common = gcd(part, whole)
    return ratio_sqrt(part // common, whole // common)


def _dyadic_fits(value: int, bits: int) -> bool:
    """Whether ``value * 2**-bits``, reduced, has numerator and denominator below ``_LIMIT``."""
    if value == 0:
        return True
    zeros = min((value & -value).bit_length() - 1, bits)
    return bits - zeros <= _MAX_DENOMINATOR_BITS and abs(value >> zeros) < _LIMIT


def _forms_may_fit(k: int, values: tuple[int, ...], corners: tuple[float, ...]) -> bool:
    """False when :func:`app.calculator.exact_forms.exact_forms` certainly says ``TOO_LONG``.

    Its first two checks, on the same values: the corners, u, v, n and the plane's d, then
    |n|**2 (each reduced, as Fractions are). Beyond them (the surd of |n|) the exact path
    decides. ``values`` are u, v (over 2**k), n (2**2k), d (2**3k) and |n|**2 (2**4k).
    """
    ux, uy, uz, vx, vy, vz, nx, ny, nz, d, square = values
    # Any one value that does not fit is enough: the likeliest (the longest) first.
    if not (_dyadic_fits(d, 3 * k) and _dyadic_fits(square, 4 * k)):
        return False
    if not (_dyadic_fits(nx, 2 * k) and _dyadic_fits(ny, 2 * k) and _dyadic_fits(nz, 2 * k)):
        return False
    if not all(_dyadic_fits(x, k) for x in (ux, uy, uz, vx, vy, vz)):
        return False
    ratios = [x.as_integer_ratio() for x in corners]
    return all(abs(num) < _LIMIT and den < _LIMIT for num, den in ratios)
