"""Exact forms of a result: n as rationals, |n| as a simplified surd, beside the rounded values.

The exact values come from the decimal text typed (``0.1`` is 1/10), or from the doubles'
own values when the input is JSON numbers. For A = (0, 0, 0), B = (1, 0, 1.5), C = (0, 3, 6.5)::

    n = (-9/2, -13/2, 3),  |n|² = 143/2,  |n| = √286 / 2,  n̂_x = -9√286 / 286,  area = √286 / 4

A unit-normal component n_i / (c √r) is written rationalised, (n_i / (c r)) √r. Forms whose
integers pass ``MAX_DIGITS`` digits are left out with a reason rather than printed.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from math import gcd, lcm
from typing import Any

from markupsafe import Markup

from app.calculator.mathml import (
    COMMA,
    EQUALS,
    Formula,
    chained,
    fenced,
    fraction,
    joined,
    math,
    op,
    plain_number,
    row,
    sqrt,
)
from mesh_normal.triangle.exact import root_over, square_root
from mesh_normal.triangle.normal import AXES, ExactTriangle

RationalPoint = tuple[Fraction, Fraction, Fraction]
Exact3 = tuple[Fraction, Fraction, Fraction]
IntPoint = tuple[int, int, int]

#: The most digits an integer of an exact form may have; beyond, the forms are left out.
MAX_DIGITS = 40
_LIMIT = 10**MAX_DIGITS


#: The largest decimal exponent read exactly: ``Fraction("1e-99999999")`` would never finish.
MAX_EXACT_EXPONENT = 30


@dataclass(slots=True)
class Exact:
    """A triangle's exact values, with the points in the chosen order (A, B, C or A, C, B).

    Held as integers over one denominator D (the corners' least common one): u and v over D,
    n over D², n · A over D³, |n|² over D⁴ and u · v over D². Integer arithmetic needs no gcd
    at each step, as Fractions do; the Fractions are made only where they are shown. Not
    frozen: a frozen dataclass is made field by field through ``object.__setattr__``, several
    times slower, and one is made for every request to ``POST /api/normal``.
    """

    #: The corners in the chosen order, over D.
    scaled_points: tuple[IntPoint, IntPoint, IntPoint]
    #: Whether the order is A, C, B.
    swapped: bool
    denominator: int
    scaled_u: tuple[int, int, int]
    scaled_v: tuple[int, int, int]
    scaled_n: tuple[int, int, int]
    #: n · A, over D³.
    scaled_d: int
    #: |n|² = n · n, over D⁴.
    scaled_square: int
    #: u · v, over D².
    scaled_dot: int

    @property
    def points(self) -> tuple[RationalPoint, RationalPoint, RationalPoint]:
        """A, B, C in the chosen order."""
        p, q, r = self.scaled_points
        den = self.denominator
        return _over(p, den), _over(q, den), _over(r, den)

    @property
    def given(self) -> tuple[RationalPoint, RationalPoint, RationalPoint]:
        """A, B, C as given (not reordered)."""
        p, q, r = self.points
        return (p, r, q) if self.swapped else (p, q, r)

    @property
    def u(self) -> Exact3:
        return _over(self.scaled_u, self.denominator)

    @property
    def v(self) -> Exact3:
        return _over(self.scaled_v, self.denominator)

    @property
    def n(self) -> Exact3:
        return _over(self.scaled_n, self.denominator**2)

    @property
    def square(self) -> Fraction:
        """|n|² = n · n."""
        return Fraction(self.scaled_square, self.denominator**4)

    @property
    def dot(self) -> Fraction:
        """u · v."""
        return Fraction(self.scaled_dot, self.denominator**2)

    @property
    def plane_d(self) -> Fraction:
        """n · A: the plane through the triangle is n · (x, y, z) = n · A."""
        return Fraction(self.scaled_d, self.denominator**3)

    def integer_plane(self) -> list[int]:
        """a, b, c, d of n · (x, y, z) = n · A scaled by one positive factor to coprime
        integers (n must not be zero): all four over D³, divided by their gcd."""
        den = self.denominator
        nx, ny, nz = self.scaled_n
        values = (nx * den, ny * den, nz * den, self.scaled_d)
        common = gcd(*values)
        return [value // common for value in values]


def _over(values: tuple[int, int, int], denominator: int) -> Exact3:
    return (
        Fraction(values[0], denominator),
        Fraction(values[1], denominator),
        Fraction(values[2], denominator),
    )


def _dot(p: IntPoint, q: IntPoint) -> int:
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]


def _from_scaled(fixed: list[int], denominator: int, swap_winding: bool) -> Exact:
    """The exact values of corners ``fixed`` (A, B, C in the chosen order, 9 integers over D)."""
    p = (fixed[0], fixed[1], fixed[2])
    q = (fixed[3], fixed[4], fixed[5])
    r = (fixed[6], fixed[7], fixed[8])
    u = (q[0] - p[0], q[1] - p[1], q[2] - p[2])
    v = (r[0] - p[0], r[1] - p[1], r[2] - p[2])
    n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    return Exact((p, q, r), swap_winding, denominator, u, v, n, _dot(n, p), _dot(n, n), _dot(u, v))


def exact_values(
    a: RationalPoint, b: RationalPoint, c: RationalPoint, *, swap_winding: bool = False
) -> Exact:
    """The exact u, v and n of triangle ABC (ACB with ``swap_winding``)."""
    p, q, r = (a, c, b) if swap_winding else (a, b, c)
    values = [*p, *q, *r]
    denominator = lcm(*(x.denominator for x in values))
    fixed = [x.numerator * (denominator // x.denominator) for x in values]
    return _from_scaled(fixed, denominator, swap_winding)


def double_values(triangle: ExactTriangle) -> Exact:
    """:func:`exact_values` of a triangle of doubles, from the integers over ``2**scale`` that
    :func:`mesh_normal.triangle.normal.exact_triangle` found (B and C are A plus u and v)."""
    p, u, v, n = triangle.origin, triangle.u, triangle.v, triangle.n
    q = (p[0] + u[0], p[1] + u[1], p[2] + u[2])
    r = (p[0] + v[0], p[1] + v[1], p[2] + v[2])
    swapped = triangle.order == "ACB"
    return Exact(
        (p, q, r), swapped, 1 << triangle.scale, u, v, n, _dot(n, p), _dot(n, n), _dot(u, v)
    )


@dataclass(frozen=True, slots=True)
class Surd:
    """``coefficient * sqrt(radicand)``; ``radicand`` is 1 for a rational."""

    coefficient: Fraction
    radicand: int

    def rounded(self) -> float:
        """The value rounded once to the nearest double."""
        p, q = self.coefficient.numerator, self.coefficient.denominator
        value = root_over(p * p * self.radicand, q)
        return -value if p < 0 else value


@dataclass(frozen=True, slots=True)
class ExactForms:
    """Everything the result shows exactly (A, B, C as typed are ``exact.given``)."""

    exact: Exact
    magnitude: Surd
    unit: tuple[Surd, Surd, Surd] | None
    area: Surd


def _fits(*values: Fraction | int) -> bool:
    for value in values:
        if isinstance(value, Fraction):
            if abs(value.numerator) >= _LIMIT or value.denominator >= _LIMIT:
                return False
        elif abs(value) >= _LIMIT:
            return False
    return True


def _fits_over(denominator: int, *values: int) -> bool:
    """Whether each ``value / denominator``, reduced, fits as :func:`_fits` has it."""
    for value in values:
        common = gcd(value, denominator)
        if abs(value) // common >= _LIMIT or denominator // common >= _LIMIT:
            return False
    return True


TOO_LONG = f"The exact forms are left out: their integers would have more than {MAX_DIGITS} digits."


def exact_forms(exact: Exact) -> ExactForms | str:
    """The exact forms, or a sentence saying why they are left out (integers too long)."""
    x = exact
    den = x.denominator
    # The likeliest to be too long first (|n|² and d, of the highest powers of D).
    if not (
        _fits_over(den**4, x.scaled_square)
        and _fits_over(den**3, x.scaled_d)
        and _fits_over(den**2, *x.scaled_n)
        and _fits_over(den, *x.scaled_u, *x.scaled_v)
        and _fits_over(den, *x.scaled_points[0], *x.scaled_points[1], *x.scaled_points[2])
    ):
        return TOO_LONG
    square = x.square
    c, r = square_root(square)
    if not _fits(c, r):
        return TOO_LONG
    unit: tuple[Surd, Surd, Surd] | None = None
    if square:
        scale = c * r
        ux, uy, uz = (Surd(ni / scale, r) for ni in x.n)
        if not _fits(ux.coefficient, uy.coefficient, uz.coefficient):
            return TOO_LONG
        unit = (ux, uy, uz)
    return ExactForms(x, Surd(c, r), unit, Surd(c / 2, r))


# --- Text and JSON ----------------------------------------------------------------------------


def rational_text(x: Fraction) -> str:
    """``5/2``, ``-3``, ``0``."""
    return str(x.numerator) if x.denominator == 1 else f"{x.numerator}/{x.denominator}"


def surd_text(s: Surd) -> str:
    """``√286 / 2``, ``-9√286 / 286``, ``7`` (a rational when the radicand is 1)."""
    if s.radicand == 1 or s.coefficient == 0:
        return rational_text(s.coefficient)
    p, q = s.coefficient.numerator, s.coefficient.denominator
    sign = "-" if p < 0 else ""
    head = f"{sign}{'' if abs(p) == 1 else abs(p)}√{s.radicand}"
    return head if q == 1 else f"{head} / {q}"


def ratio_json(numerator: int, denominator: int) -> dict[str, str]:
    """The JSON of ``numerator / denominator`` (``denominator > 0``), reduced as a Fraction is,
    its text as :func:`rational_text` writes it: the exact values are held as integers over
    powers of D, and one gcd reduces each without making a Fraction only to print it."""
    common = gcd(numerator, denominator)
    top, bottom = str(numerator // common), str(denominator // common)
    return {
        "text": top if bottom == "1" else f"{top}/{bottom}",
        "numerator": top,
        "denominator": bottom,
    }


def surd_json(s: Surd) -> dict[str, str]:
    return {
        "text": surd_text(s),
        "coefficient": rational_text(s.coefficient),
        "radicand": str(s.radicand),
    }


def forms_json(forms: ExactForms) -> dict[str, Any]:
    """The JSON ``exact`` object (see :class:`app.calculator.schemas.ExactResult`)."""
    x = forms.exact
    den = x.denominator
    p, q, r = x.scaled_points
    given = (p, r, q) if x.swapped else (p, q, r)
    a, b, c = ([ratio_json(value, den) for value in point] for point in given)
    return {
        "a": a,
        "b": b,
        "c": c,
        "u": [ratio_json(value, den) for value in x.scaled_u],
        "v": [ratio_json(value, den) for value in x.scaled_v],
        "normal": [ratio_json(value, den * den) for value in x.scaled_n],
        "magnitude_squared": ratio_json(x.scaled_square, den**4),
        "magnitude": surd_json(forms.magnitude),
        "unit_normal": None if forms.unit is None else [surd_json(s) for s in forms.unit],
        "area": surd_json(forms.area),
    }


def equation_text(coefficients: list[str], d: str, minus: str = "-") -> str:
    """``6x + 3y + 2z = 6`` from the texts of a, b, c (zero terms left out) and d."""
    parts: list[str] = []
    for text, axis in zip(coefficients, AXES, strict=True):
        if text in ("0", "-0"):
            continue
        negative = text.startswith("-")
        size = text.lstrip("-")
        term = axis if size == "1" else f"{size}{axis}" if "/" not in size else f"({size}){axis}"
        if parts:
            parts.append(f" {minus} " if negative else " + ")
        elif negative:
            parts.append(minus)
        parts.append(term)
    return f"{''.join(parts) or '0'} = {d.replace('-', minus)}"


def rounded_exact(x: Fraction) -> float | None:
    """``x`` rounded once; ``None`` beyond the double range or nonzero and below it."""
    return rounded_over(x.numerator, x.denominator)


def rounded_over(value: int, denominator: int) -> float | None:
    """``value / denominator`` rounded once (``int / int`` is); ``None`` as in
    :func:`rounded_exact`."""
    try:
        rounded = value / denominator
    except OverflowError:
        return None
    return None if rounded == 0 and value != 0 else rounded


# --- MathML for the result card ---------------------------------------------------------------

_NEGATIVE = op("−", "−")


def _signed(negative: bool, body: Formula) -> Formula:
    return row(_NEGATIVE, body) if negative else body


def rational_formula(x: Fraction) -> Formula:
    """5/2 as a built-up fraction; the precision setting leaves exact numbers alone."""
    top = plain_number(str(abs(x.numerator)))
    body = top if x.denominator == 1 else fraction(top, plain_number(str(x.denominator)))
    return _signed(x < 0, body)


def surd_formula(s: Surd) -> Formula:
    """√286 / 2 as a fraction with a square root on top."""
    if s.radicand == 1 or s.coefficient == 0:
        return rational_formula(s.coefficient)
    p, q = abs(s.coefficient.numerator), s.coefficient.denominator
    root = sqrt(plain_number(str(s.radicand)))
    top = root if p == 1 else row(plain_number(str(p)), root)
    return _signed(s.coefficient < 0, top if q == 1 else fraction(top, plain_number(str(q))))


def _magnitude_formula(square: Fraction, magnitude: Surd) -> Formula:
    """``√(143/2) = √286 / 2``; just ``√286`` or ``7`` when there is nothing to simplify."""
    simplified = surd_formula(magnitude)
    if magnitude.radicand == 1 or (magnitude.coefficient == 1 and magnitude.radicand == square):
        return simplified
    return chained([sqrt(rational_formula(square)), EQUALS, simplified])


def _vector(formulas: list[Formula]) -> Formula:
    return fenced(joined(formulas, COMMA))


def _is_double(x: Fraction) -> bool:
    """Whether ``x`` is a double (the rounded value shown is then already exact)."""
    return rounded_exact(x) is not None and Fraction(rounded_exact(x) or 0) == x


def forms_math(forms: ExactForms) -> dict[str, Markup]:
    """The result card's exact values as MathML, by the payload key they stand beside.

    A value whose rounded double is already exact (integers, halves) gets no exact twin.
    """
    x = forms.exact
    out: dict[str, Markup] = {}
    for key, values in (("u", x.u), ("v", x.v), ("normal", x.n)):
        if not all(_is_double(value) for value in values):
            out[key] = math(_vector([rational_formula(value) for value in values]))
    for key, surd in (("magnitude", forms.magnitude), ("area", forms.area)):
        if surd.radicand != 1 or not _is_double(surd.coefficient):
            formula = _magnitude_formula(x.square, surd) if key == "magnitude" else None
            out[key] = math(formula or surd_formula(surd))
    unit = forms.unit
    if unit is not None and not all(s.radicand == 1 and _is_double(s.coefficient) for s in unit):
        out["unit_normal"] = math(_vector([surd_formula(s) for s in unit]))
    return out
