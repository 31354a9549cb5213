"""The normal of one triangle, computed exactly and rounded once.

For points A, B, C the edges are u = B - A and v = C - A, the raw normal is n = u x v,
its length |n| is twice the triangle's area, and n / |n| is the unit normal. The normal
points to the side from which A, B, C run counter-clockwise (the right-hand rule);
swapping the winding to A, C, B negates it.

:func:`triangle_normal` works on the exact values of the given doubles: every output is
the exact result rounded once to the nearest double, so a sliver that a naive float cross
product reports as flat, or coordinates whose normal underflows, still get the right
direction. Values outside the double range come back as ``None`` with a message.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from decimal import Decimal, localcontext
from fractions import Fraction
from math import isfinite, lcm
from numbers import Real

from mesh_normal.tolerances import LARGEST_DOUBLE_TEXT
from mesh_normal.triangle.exact import (
    OutOfRange,
    bracketed,
    root_bracket,
    root_over,
    to_fixed,
    unit_vector,
)

Vector = tuple[float, float, float]  # not mesh_normal.types: this module needs no NumPy
MaybeVector = tuple[float | None, float | None, float | None]
IntVector = tuple[int, int, int]

AXES = ("x", "y", "z")

#: 2**-1021: a double from here up halves exactly, to a normal double.
_HALVES_EXACTLY = 2.0**-1021


@dataclass(frozen=True, slots=True)
class TriangleNormal:
    """The normal of one triangle and everything derived from it.

    ``None`` marks a value whose exact result is outside the double range; ``message``
    then says which and why. ``unit_normal`` is ``None`` only for a degenerate triangle.

    Attributes
    ----------
    a, b, c : (3,) float
        The corners as given, as floats.
    order : str
        ``"ABC"``, or ``"ACB"`` with ``swap_winding``.
    u, v : (3,) float or None
        The edges B - A and C - A (C - A and B - A for ``"ACB"``).
    normal : (3,) float or None
        The raw normal n = u x v.
    magnitude : float or None
        |n|, twice the area.
    unit_normal : (3,) float or None
        n / |n|; ``None`` for a degenerate triangle.
    area : float or None
        |n| / 2.
    degenerate : bool
        The exact n is zero (repeated or collinear points).
    message : str or None
        One sentence on a degenerate triangle or a value out of range; else ``None``.
    """

    a: Vector
    b: Vector
    c: Vector
    order: str
    u: MaybeVector
    v: MaybeVector
    normal: MaybeVector
    magnitude: float | None
    unit_normal: Vector | None
    area: float | None
    degenerate: bool
    message: str | None


@dataclass(slots=True)
class ExactTriangle:
    """The exact u, v and n of a triangle, as integers over one power-of-two scale.

    With the points in the chosen order (``points``: A, B, C or A, C, B), the exact edge
    ``u = B - A`` is ``u_i * 2**-scale`` (the same for ``v``), and the exact normal
    ``n = u x v`` is ``n_i * 2**(-2 * scale)``. Nothing here is rounded: :func:`triangle_normal`
    rounds these values once, and the calculator's worked steps show them. Not frozen: a frozen
    dataclass is made field by field through ``object.__setattr__``, several times slower, and
    the calculator's API makes one for every request.
    """

    points: tuple[Vector, Vector, Vector]
    order: str
    scale: int
    #: The first point, A, as integers over the scale (B is ``origin + u``, C ``origin + v``).
    origin: IntVector
    u: IntVector
    v: IntVector
    n: IntVector

    @property
    def square(self) -> int:
        """``|n|**2`` times ``2**(4 * scale)``: zero exactly when the triangle is degenerate."""
        x, y, z = self.n
        return x * x + y * y + z * z

    @property
    def dot(self) -> int:
        """``u . v`` times ``2**(2 * scale)``."""
        (ux, uy, uz), (vx, vy, vz) = self.u, self.v
        return ux * vx + uy * vy + uz * vz


def exact_triangle(
    a: Sequence[float],
    b: Sequence[float],
    c: Sequence[float],
    *,
    swap_winding: bool = False,
) -> ExactTriangle:
    """Return the exact u, v and n of triangle ABC (or ACB with ``swap_winding``).

    Parameters
    ----------
    a, b, c : (3,) float
        The corners, finite numbers (checked as :func:`triangle_normal` checks them).

    Examples
    --------
    >>> exact = exact_triangle((0, 0, 0), (0.5, 0, 0), (0, 0.5, 0))
    >>> exact.scale, exact.u, exact.n
    (1, (1, 0, 0), (0, 0, 1))
    """
    pa, pb, pc = _as_point("A", a), _as_point("B", b), _as_point("C", c)
    return _exact(pa, pb, pc, swap_winding)


def _exact(pa: Vector, pb: Vector, pc: Vector, swap_winding: bool) -> ExactTriangle:
    p, q, r = (pa, pc, pb) if swap_winding else (pa, pb, pc)
    (px, py, pz, qx, qy, qz, rx, ry, rz), k = to_fixed([*p, *q, *r])
    ux, uy, uz = qx - px, qy - py, qz - pz
    vx, vy, vz = rx - px, ry - py, rz - pz
    n = (uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx)
    order = "ACB" if swap_winding else "ABC"
    return ExactTriangle((p, q, r), order, k, (px, py, pz), (ux, uy, uz), (vx, vy, vz), n)


def _as_point(name: str, point: Sequence[float]) -> Vector:
    """Check one point up front, the way trimesh checks its inputs."""
    if type(point) in (list, tuple) and len(point) == 3:  # the common case, quickly
        x, y, z = point
        if (
            type(x) is float
            and type(y) is float
            and type(z) is float
            and isfinite(x)
            and isfinite(y)
            and isfinite(z)
        ):
            return (x, y, z)
    try:
        values = tuple(point)
    except TypeError:
        raise ValueError(f"Point {name} must be a sequence of 3 numbers.") from None
    if len(values) != 3:
        raise ValueError(f"Point {name} must have 3 coordinates, not {len(values)}.")
    floats: list[float] = []
    for axis, value in zip(AXES, values, strict=True):
        if isinstance(value, bool) or not isinstance(value, Real):
            raise ValueError(f"{name}.{axis} must be a number.")
        try:
            number = float(value)
        except OverflowError:
            number = float("inf")
        if not isfinite(number):
            raise ValueError(f"{name}.{axis} must be a finite number within the double range.")
        floats.append(number)
    return (floats[0], floats[1], floats[2])


def _approx(value: Decimal) -> str:
    return f"{value.normalize():.3g}"


class _Rounder:
    """Rounds exact fixed-point values, collecting the ones that do not fit a double."""

    def __init__(self) -> None:
        self.overflow: list[tuple[str, str]] = []
        self.underflow: list[tuple[str, str]] = []

    def value(self, name: str, value: int, denominator: int, *, root: bool = False) -> float | None:
        """``value / denominator`` (``sqrt(value) / denominator`` with ``root``), rounded once."""
        try:
            if root:
                return root_over(value, denominator)
            return _divided(value, denominator)
        except OutOfRange as error:
            with localcontext() as context:
                context.prec = 3
                exact = Decimal(value).sqrt() if root else Decimal(value)
                approx = _approx(exact / Decimal(denominator))
            target = self.overflow if error.kind == "overflow" else self.underflow
            target.append((name, approx))
            return None

    def vector(self, name: str, values: IntVector, denominator: int) -> MaybeVector:
        x, y, z = values
        try:  # the common case: one correctly rounded division each, all in range
            rx, ry, rz = x / denominator, y / denominator, z / denominator
            if (rx or not x) and (ry or not y) and (rz or not z):  # no underflow to 0
                return (rx, ry, rz)
        except OverflowError:
            pass
        # Some value is out of range: value() rounds each again and says which.
        out = [
            self.value(f"{name}_{axis}", value, denominator)
            for axis, value in zip(AXES, values, strict=True)
        ]
        return (out[0], out[1], out[2])

    def message(self, lead: str | None = None) -> str | None:
        """The sentences about out-of-range values, after ``lead`` when given."""
        sentences = [lead] if lead else []
        if self.overflow:
            sentences.append(
                f"{_listing(self.overflow)} {_verb(self.overflow)} beyond the largest double "
                f"({LARGEST_DOUBLE_TEXT}), so {_pronoun(self.overflow)} null."
            )
        if self.underflow:
            sentences.append(
                f"{_listing(self.underflow)} {_verb(self.underflow)} nonzero but smaller than "
                f"the smallest double (4.9e-324), so {_pronoun(self.underflow)} null."
            )
        if (self.overflow or self.underflow) and not lead:
            sentences.append("The unit normal is exact all the same.")
        return " ".join(sentences) or None


def _divided(value: int, denominator: int) -> float:
    """``value / denominator`` rounded once (int / int is correctly rounded in Python)."""
    if value == 0:
        return 0.0
    try:
        result = value / denominator
    except OverflowError:
        raise OutOfRange("overflow") from None
    if result == 0.0:
        raise OutOfRange("underflow")
    return result


def _listing(items: list[tuple[str, str]]) -> str:
    parts = [f"{name} (about {approx})" for name, approx in items]
    if len(parts) == 1:
        return parts[0]
    return ", ".join(parts[:-1]) + " and " + parts[-1]


def _verb(items: list[tuple[str, str]]) -> str:
    return "is" if len(items) == 1 else "are"


def _pronoun(items: list[tuple[str, str]]) -> str:
    return "it is" if len(items) == 1 else "they are"


def _degenerate_message(
    p: Sequence[object], q: Sequence[object], r: Sequence[object], order: str
) -> str:
    first, second, third = order[0], order[1], order[2]
    if p == q == r:
        return "All three points are the same, so the triangle has no area and no normal."
    for (x, y), (nx, ny) in (
        ((p, q), (first, second)),
        ((p, r), (first, third)),
        ((q, r), (second, third)),
    ):
        if x == y:
            return (
                f"Points {nx} and {ny} coincide, so the triangle has no area "
                "and no normal direction."
            )
    return "The three points lie on one line, so the triangle has no area and no normal direction."


def triangle_normal(
    a: Sequence[float],
    b: Sequence[float],
    c: Sequence[float],
    *,
    swap_winding: bool = False,
) -> TriangleNormal:
    """Return the normal of triangle ABC (or ACB with ``swap_winding``), rounded once.

    Parameters
    ----------
    a, b, c : (3,) float
        The corners, finite numbers.
    swap_winding : bool
        Use the order A, C, B, which negates the normal.

    Returns
    -------
    TriangleNormal
        u = B - A, v = C - A, n = u x v, |n|, n / |n| and the area |n| / 2, each the exact
        value rounded once to the nearest double. A degenerate triangle (the exact n is
        zero: repeated or collinear points) has n = (0, 0, 0), magnitude and area 0, no
        unit normal, and a message.

    Examples
    --------
    >>> triangle_normal((0, 0, 0), (1, 0, 0), (0, 1, 0)).unit_normal
    (0.0, 0.0, 1.0)
    """
    return rounded_normal(exact_triangle(a, b, c, swap_winding=swap_winding))


def rounded_normal(exact: ExactTriangle) -> TriangleNormal:
    """:func:`triangle_normal` of a triangle from :func:`exact_triangle`: its exact values,
    each rounded once (for a caller that uses the exact values as well)."""
    p, q, r = exact.points
    given = (p, r, q) if exact.order == "ACB" else exact.points
    return _rounded(given, exact.points, exact, 1 << exact.scale)


def _rounded(
    given: tuple[Vector, Vector, Vector],
    ordered: tuple[Sequence[object], Sequence[object], Sequence[object]],
    exact: ExactTriangle,
    denominator: int,
) -> TriangleNormal:
    """Round an exact triangle once; its u and v are integers over ``denominator``."""
    pa, pb, pc = given
    order, n, square = exact.order, exact.n, exact.square
    p, q, r = ordered
    rounder = _Rounder()
    u = rounder.vector("u", exact.u, denominator)
    v = rounder.vector("v", exact.v, denominator)
    if square == 0:
        return TriangleNormal(
            pa,
            pb,
            pc,
            order,
            u,
            v,
            (0.0, 0.0, 0.0),
            0.0,
            None,
            0.0,
            True,
            rounder.message(_degenerate_message(p, q, r, order)),
        )
    den2 = denominator * denominator
    normal = rounder.vector("n", n, den2)
    root, shift = root_bracket(square)
    magnitude = bracketed(root, den2 << shift)
    if magnitude is None:  # out of range, or a rounding boundary in the bracket
        magnitude = rounder.value("magnitude", square, den2, root=True)
    if magnitude is not None and magnitude >= _HALVES_EXACTLY:
        area: float | None = magnitude / 2  # rounding commutes with halving above the subnormals
    else:
        area = rounder.value("area", square, 2 * den2, root=True)
    unit = unit_vector(n, square, root, shift)
    return TriangleNormal(
        pa, pb, pc, order, u, v, normal, magnitude, unit, area, False, rounder.message()
    )


RationalPoint = tuple[Fraction, Fraction, Fraction]


def rational_exact(
    a: RationalPoint, b: RationalPoint, c: RationalPoint, *, swap_winding: bool = False
) -> tuple[ExactTriangle, int]:
    """The exact u, v and n of a triangle with rational corners, over one common denominator.

    Returns the triangle (its ``scale`` is 0 and unused) and the denominator ``D``: the exact
    ``u`` is ``exact.u / D`` and the exact ``n`` is ``exact.n / D**2``.
    """
    p, q, r = (a, c, b) if swap_winding else (a, b, c)
    values = [*p, *q, *r]
    denominator = lcm(*(x.denominator for x in values))
    fixed = [x.numerator * (denominator // x.denominator) for x in values]
    ux, uy, uz = (fixed[3 + i] - fixed[i] for i in range(3))
    vx, vy, vz = (fixed[6 + i] - fixed[i] for i in range(3))
    n = (uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx)
    points = tuple((float(x), float(y), float(z)) for x, y, z in (p, q, r))
    order = "ACB" if swap_winding else "ABC"
    origin = (fixed[0], fixed[1], fixed[2])
    exact = ExactTriangle(
        (points[0], points[1], points[2]), order, 0, origin, (ux, uy, uz), (vx, vy, vz), n
    )
    return exact, denominator


def rational_triangle_normal(
    a: RationalPoint, b: RationalPoint, c: RationalPoint, *, swap_winding: bool = False
) -> TriangleNormal:
    """:func:`triangle_normal` for exact rational corners (a typed ``1/3`` or ``0.1``).

    Every output is the exact result for the rationals, rounded once; the corners come back
    as their nearest doubles, which must be finite.

    Examples
    --------
    >>> o, t, w = Fraction(0), Fraction(1, 3), Fraction(1)
    >>> rational_triangle_normal((o, o, o), (t, w, o), (w, 3 * w, o)).degenerate
    True
    """
    exact, denominator = rational_exact(a, b, c, swap_winding=swap_winding)
    pa, pb, pc = (tuple(float(x) for x in point) for point in (a, b, c))
    given = ((pa[0], pa[1], pa[2]), (pb[0], pb[1], pb[2]), (pc[0], pc[1], pc[2]))
    p, q, r = (a, c, b) if swap_winding else (a, b, c)
    return _rounded(given, (p, q, r), exact, denominator)
