"""The calculator's query parameters (``ax`` ... ``cz``, ``swap``), read as decimal text.

The page and its JSON twin read the same parameters in the same way, so a typing mistake
gets the same sentence in both, naming the field as the form does.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from math import isfinite
from typing import Annotated

from pydantic import BaseModel, Field, JsonValue

from app.calculator.exact_forms import exact_decimal
from app.calculator.presets import COORDINATE_FIELDS
from app.web.errors import ApiError, clip

DECIMAL = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
MAX_TEXT = 64
#: Spaces a typed coordinate may carry around it (ASCII only, as the schema's pattern says).
SPACE = " \t\n\r\f\v"
SPACE_CLASS = r" \t\n\r\f\v"
SWAP_ON = frozenset({"on", "true", "1"})
SWAP_OFF = frozenset({"", "off", "false", "0"})

#: What the OpenAPI schema says of a coordinate (documentation only: read_triangle checks).
Text = Annotated[
    str,
    Field(
        description="A decimal number, such as 1.5 or -2e3.",
        examples=["1.5"],
        json_schema_extra={
            "pattern": rf"^[{SPACE_CLASS}]*{DECIMAL.pattern}[{SPACE_CLASS}]*$",
            "maxLength": MAX_TEXT,
        },
    ),
]


class TriangleParams(BaseModel):
    """The page's query parameters, for the OpenAPI description of the GET routes."""

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


Point = tuple[float, float, float]


@dataclass
class TriangleInput:
    """What the user typed, what it means, and a sentence for every field that is wrong."""

    typed: dict[str, str]
    swap: bool = False
    numbers: dict[str, float] = field(default_factory=dict)
    errors: dict[str, str] = field(default_factory=dict)
    #: Each coordinate's exact value as typed (``0.1`` is 1/10); absent when it has none.
    exact: dict[str, Fraction] = field(default_factory=dict)

    def points(self) -> tuple[Point, Point, Point]:
        """The three points; call only when there are no errors."""
        x = [self.numbers[name] for name in COORDINATE_FIELDS]
        return (x[0], x[1], x[2]), (x[3], x[4], x[5]), (x[6], x[7], x[8])

    def first_error(self) -> ApiError:
        name, sentence = next(iter(self.errors.items()))
        return ApiError(422, sentence, name)


def parse_decimal(name: str, text: str) -> float:
    """Read one coordinate; raise :class:`ApiError` naming the field when it is not one."""
    stripped = text.strip(SPACE)
    if not stripped:
        raise ApiError(422, f"{name} is empty; enter a decimal number such as 1.5.", name)
    if len(text) > MAX_TEXT:
        raise ApiError(
            422,
            f"{name} is longer than {MAX_TEXT} characters; "
            "shorten it or use an exponent, such as 1.5e-30.",
            name,
        )
    if not DECIMAL.fullmatch(stripped):
        raise ApiError(
            422,
            f"{name} must be a decimal number such as 1.5 or -2e3, not {clip(stripped)!r}.",
            name,
        )
    value = float(stripped)
    if not isfinite(value):
        raise ApiError(422, f"{name} is beyond the double range (about ±1.8e308).", name)
    return value


def parse_swap(text: str | None) -> bool:
    if text is None or text in SWAP_OFF:
        return False
    if text in SWAP_ON:
        return True
    raise ApiError(422, "swap must be on, true or 1 (or left out for the order A, B, C).", "swap")


def read_triangle(query: Mapping[str, str]) -> TriangleInput:
    """Read all nine coordinates and the swap flag, collecting every error."""
    typed = {name: query.get(name, "") for name in COORDINATE_FIELDS}
    result = TriangleInput(typed=typed)
    for name in COORDINATE_FIELDS:
        if name not in query:
            result.errors[name] = f"{name} is missing."
            continue
        try:
            result.numbers[name] = parse_decimal(name, query[name])
            exact = exact_decimal(query[name])
            if exact is not None:
                result.exact[name] = exact
        except ApiError as error:
            result.errors[name] = error.error
    try:
        result.swap = parse_swap(query.get("swap"))
    except ApiError as error:
        result.errors["swap"] = error.error
    return result
