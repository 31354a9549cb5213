"""The calculator's query parameters (``ax`` ... ``cz``, ``swap``), read as typed text.

The page and its JSON twin read the same parameters in the same way, so a typing mistake
gets the same sentence in both, naming the field as the form does (``B.y``, not ``by``).
Each coordinate is read by :mod:`app.calculator.coordinates` (decimals and fractions).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Annotated, Any

from pydantic import BaseModel, Field, JsonValue

from app.calculator.coordinates import MAX_TEXT, PATTERN, SPACE, parse_coordinate
from app.calculator.presets import COORDINATE_FIELDS
from app.web.errors import ApiError
from mesh_normal.triangle.normal import TriangleNormal, rational_triangle_normal, triangle_normal

SWAP_ON = frozenset({"on", "true", "1"})
SWAP_OFF = frozenset({"", "off", "false", "0"})

#: What the OpenAPI schema says of a coordinate (documentation only: read_triangle checks).
Text = Annotated[
    str,
    Field(
        description=(
            "A number: a decimal such as 1.5 or -2e3 (a decimal comma works too: 2,5), "
            "or a fraction such as 1/3, -2/7 or 1.5/2. Each is read exactly (0.1 is 1/10), "
            "the triangle is computed on the exact values and rounded once. Exponents in a "
            "fraction stay within ±30."
        ),
        examples=["1.5", "1/3"],
        json_schema_extra={"pattern": PATTERN, "maxLength": MAX_TEXT},
    ),
]


class TriangleParams(BaseModel):
    """The page's query parameters, for the OpenAPI description of the GET routes.

    Documentation only (see :func:`query_parameters_spec`): FastAPI validating them would
    report a missing field before a wrong one, in words the page does not use.
    """

    ax: Text
    ay: Text
    az: Text
    bx: Text
    by: Text
    bz: Text
    cx: Text
    cy: Text
    cz: Text
    swap: str | None = Field(
        None,
        description="`on`, `true` or `1` uses the order A, C, B.",
        json_schema_extra={"enum": list[JsonValue](sorted(SWAP_ON | SWAP_OFF))},
    )


def query_parameters_spec() -> dict[str, Any]:
    """The OpenAPI ``parameters`` of a route that reads the triangle with :func:`read_triangle`."""
    schema = TriangleParams.model_json_schema()
    required = set(schema.get("required", ()))
    parameters = [
        {
            "name": name,
            "in": "query",
            "required": name in required,
            "schema": spec,
            "description": spec.get("description", ""),
        }
        for name, spec in schema["properties"].items()
    ]
    return {"parameters": parameters}


Point = tuple[float, float, float]


@dataclass
class TriangleInput:
    """What the user typed, what it means, and what stops it from being a triangle.

    ``errors`` holds a sentence for every value that was given and is wrong (and for the
    swap flag); ``missing`` lists the coordinates not given yet (absent or blank), which
    are said together in one calm line rather than as one error each.
    """

    typed: dict[str, str]
    swap: bool = False
    numbers: dict[str, float] = field(default_factory=dict)
    errors: dict[str, str] = field(default_factory=dict)
    missing: list[str] = field(default_factory=list)
    #: Each coordinate's exact value as typed (``0.1`` is 1/10, ``1/3`` is 1/3); absent for
    #: a decimal whose exponent is beyond ±30 (see app.calculator.coordinates).
    exact: dict[str, Fraction] = field(default_factory=dict)
    #: The coordinates typed as fractions: with any, the triangle is computed exactly.
    fractions: list[str] = field(default_factory=list)

    @property
    def valid(self) -> bool:
        return not self.errors and not self.missing

    def points(self) -> tuple[Point, Point, Point]:
        """The three points; call only when the input is valid."""
        x = [self.numbers[name] for name in COORDINATE_FIELDS]
        return (x[0], x[1], x[2]), (x[3], x[4], x[5]), (x[6], x[7], x[8])

    def normal(self) -> TriangleNormal:
        """The triangle's normal; call only when the input is valid.

        The fallback of :func:`app.calculator.calculation.from_typed` when some decimal has
        no exact value (an exponent beyond ±30): with a fraction among the coordinates, on
        exact rationals (each fraction as typed, each decimal as its double) rounded once;
        otherwise on the doubles.
        """
        if not self.fractions:
            return triangle_normal(*self.points(), swap_winding=self.swap)
        x = [
            self.exact[name] if name in self.fractions else Fraction(self.numbers[name])
            for name in COORDINATE_FIELDS
        ]
        a, b, c = (x[0], x[1], x[2]), (x[3], x[4], x[5]), (x[6], x[7], x[8])
        return rational_triangle_normal(a, b, c, swap_winding=self.swap)

    def missing_line(self) -> str:
        """The missing coordinates in one sentence, ``""`` when none is."""
        return missing_sentence(self.missing)

    def first_error(self) -> ApiError:
        """The one sentence for the API: a wrong value first, else what is missing."""
        if self.errors:
            name, sentence = next(iter(self.errors.items()))
            return ApiError(422, sentence, name)
        return ApiError(422, self.missing_line(), self.missing[0])


def missing_sentence(names: list[str]) -> str:
    """``B.x, B.y and C.z are missing.``; every one is said as "All nine ... are missing"."""
    said = [label(name) for name in names]
    if not said:
        return ""
    if len(said) == len(COORDINATE_FIELDS):
        return "All nine coordinates, A.x to C.z, are missing."
    if len(said) == 1:
        return f"{said[0]} is missing."
    return f"{', '.join(said[:-1])} and {said[-1]} are missing."


def label(name: str) -> str:
    """A coordinate as people say it: ``B.y`` for ``by`` (which reads as the English word)."""
    return f"{name[0].upper()}.{name[1:]}" if name in COORDINATE_FIELDS else name


def parse_swap(text: str | None) -> bool:
    if text is None or text in SWAP_OFF:
        return False
    if text in SWAP_ON:
        return True
    raise ApiError(422, "swap must be on, true or 1 (or left out for the order A, B, C).", "swap")


def read_triangle(query: Mapping[str, str]) -> TriangleInput:
    """Read all nine coordinates and the swap flag: every wrong value, then what is missing."""
    typed = {name: query.get(name, "") for name in COORDINATE_FIELDS}
    result = TriangleInput(typed=typed)
    for name in COORDINATE_FIELDS:
        if not typed[name].strip(SPACE):  # absent, or a field left blank: not yet given
            result.missing.append(name)
            continue
        try:
            coordinate = parse_coordinate(label(name), name, typed[name])
        except ApiError as error:
            result.errors[name] = error.error
            continue
        result.numbers[name] = coordinate.value
        if coordinate.exact is not None:
            result.exact[name] = coordinate.exact
        if coordinate.fraction:
            result.fractions.append(name)
    try:
        result.swap = parse_swap(query.get("swap"))
    except ApiError as error:
        result.errors["swap"] = error.error
    return result
