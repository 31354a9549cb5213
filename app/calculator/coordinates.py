"""One typed coordinate: a decimal (``1.5``, ``-2e3``, ``2,5``) or an exact fraction (``1/3``).

Each has its exact value as typed (``0.1`` is 1/10, ``1/3`` is 1/3): the page and
``GET /api/normal`` compute the triangle on those exact rationals and round the result once
(:func:`app.calculator.calculation.from_typed`). A decimal whose exponent is beyond
:data:`MAX_EXACT_EXPONENT` has only its double.

Every exponent is checked on the text before a :class:`~fractions.Fraction` is built:
``Fraction("1e-99999999")`` would take forever, and ``1e999999`` fits in :data:`MAX_TEXT`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from fractions import Fraction
from math import isfinite

from app.web.errors import ApiError, clip

MAX_TEXT = 64
#: The largest decimal exponent read exactly: within it a Fraction is small and quick (the
#: text's 64 characters bound the digits); beyond it a decimal is only its double.
MAX_EXACT_EXPONENT = 30
#: Spaces a typed coordinate may carry around it (ASCII only, as the schema's pattern says).
SPACE = " \t\n\r\f\v"
SPACE_CLASS = r" \t\n\r\f\v"

#: A decimal, its point written ``.`` or (between digits) ``,``: ``1.5``, ``.5``, ``2,5``.
NUMBER = r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+|[0-9]+,[0-9]+)(?:[eE][+-]?[0-9]+)?"
#: A decimal, or a fraction of two decimals: ``1/3``, ``-2/7``, ``1.5 / 2``.
COORDINATE = rf"{NUMBER}(?:[{SPACE_CLASS}]*/[{SPACE_CLASS}]*{NUMBER})?"
#: The schema's pattern for a coordinate's text (the same rule as :func:`parse_coordinate`).
PATTERN = rf"^[{SPACE_CLASS}]*{COORDINATE}[{SPACE_CLASS}]*$"

_NUMBER = re.compile(
    r"(?P<sign>[+-]?)(?P<digits>[0-9]*(?P<point>[.,])?[0-9]*)(?:[eE](?P<exponent>[+-]?[0-9]+))?"
)
_COORDINATE = re.compile(COORDINATE)
#: ``1,000`` or ``12,500``: a thousands separator to some readers, a decimal comma to others.
_THOUSANDS = re.compile(r"[+-]?[1-9][0-9]{0,2},[0-9]{3}")

EXAMPLES = "1.5, -2e3 or 1/3"


@dataclass(frozen=True, slots=True)
class Coordinate:
    """What one field's text means.

    ``value`` is the double it denotes (for a fraction, the nearest double of its value);
    ``exact`` is its exact value (``0.1`` is 1/10), ``None`` for a decimal whose exponent is
    beyond ±:data:`MAX_EXACT_EXPONENT`; ``fraction`` says it was typed as one.
    """

    value: float
    exact: Fraction | None
    fraction: bool


def parse_coordinate(said: str, name: str, text: str) -> Coordinate:
    """Read one field's text; raise :class:`ApiError` for ``name`` (said as ``said``) if wrong.

    Call with non-blank text (blank is "missing", which the caller says).

    Examples
    --------
    >>> parse_coordinate("A.x", "ax", " 2,5 ")
    Coordinate(value=2.5, exact=Fraction(5, 2), fraction=False)
    >>> parse_coordinate("A.x", "ax", "-2/6")
    Coordinate(value=-0.3333333333333333, exact=Fraction(-1, 3), fraction=True)
    """
    stripped = text.strip(SPACE)
    if len(text) > MAX_TEXT:
        raise ApiError(
            422,
            f"{said} is longer than {MAX_TEXT} characters; "
            "shorten it or use an exponent, such as 1.5e-30.",
            name,
        )
    if not _COORDINATE.fullmatch(stripped):
        raise ApiError(
            422, f"{said} must be a number such as {EXAMPLES}, not {clip(stripped)!r}.", name
        )
    parts = [part.strip(SPACE) for part in stripped.split("/")]
    for part in parts:
        if _THOUSANDS.fullmatch(part):
            raise ApiError(
                422,
                f"{said} is {part!r}, which reads as a thousands separator or a decimal comma; "
                f"write {part.replace(',', '')} or {part.replace(',', '.')}.",
                name,
            )
    if len(parts) == 1:
        return _decimal(said, name, parts[0])
    return _fraction(said, name, parts[0], parts[1])


def _exponent(part: str) -> int:
    match = _NUMBER.fullmatch(part)
    assert match is not None  # the caller matched COORDINATE
    exponent = match["exponent"]
    return int(exponent) if exponent else 0


def _decimal(said: str, name: str, part: str) -> Coordinate:
    text = part.replace(",", ".")
    value = float(text)
    if not isfinite(value):
        raise ApiError(422, f"{said} is beyond the double range (about ±1.8e308).", name)
    exact = Fraction(text) if abs(_exponent(part)) <= MAX_EXACT_EXPONENT else None
    return Coordinate(value, exact, fraction=False)


def _fraction(said: str, name: str, top: str, bottom: str) -> Coordinate:
    if max(abs(_exponent(top)), abs(_exponent(bottom))) > MAX_EXACT_EXPONENT:
        raise ApiError(
            422,
            f"{said} is a fraction with an exponent beyond ±{MAX_EXACT_EXPONENT}, "
            "which is not read exactly; write its value as a decimal, such as 3.3e-40.",
            name,
        )
    numerator = Fraction(top.replace(",", "."))
    denominator = Fraction(bottom.replace(",", "."))
    if denominator == 0:
        raise ApiError(
            422, f"{said} divides by zero; a fraction's denominator must not be 0.", name
        )
    exact = numerator / denominator
    try:
        value = float(exact)
    except OverflowError:
        value = float("inf")
    if not isfinite(value):
        raise ApiError(422, f"{said} is beyond the double range (about ±1.8e308).", name)
    return Coordinate(value, exact, fraction=True)
