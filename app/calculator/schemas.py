"""Request and response models of the JSON API (pydantic, strict: a string is not a number)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from app.config import BATCH_LIMIT

Coordinate = Annotated[float, Field(allow_inf_nan=False, strict=True)]
Point = Annotated[list[Coordinate], Field(min_length=3, max_length=3, examples=[[0.0, 0.0, 0.0]])]
MaybeNumber = float | None
MaybeVector = Annotated[list[MaybeNumber], Field(min_length=3, max_length=3)]
Vector = Annotated[list[float], Field(min_length=3, max_length=3)]
Triangle = Annotated[list[Point], Field(min_length=3, max_length=3)]


class NormalRequest(BaseModel):
    """Three points of a triangle; ``swap_winding`` uses the order A, C, B."""

    model_config = ConfigDict(
        strict=True,
        extra="forbid",
        json_schema_extra={
            "examples": [{"a": [1, 0, 0], "b": [0, 2, 0], "c": [0, 0, 3], "swap_winding": False}]
        },
    )

    a: Point
    b: Point
    c: Point
    swap_winding: bool = False


class BatchRequest(BaseModel):
    """Up to 100,000 triangles, each ``[A, B, C]`` with ``A = [x, y, z]``."""

    model_config = ConfigDict(
        strict=True,
        extra="forbid",
        json_schema_extra={
            "examples": [
                {
                    "triangles": [
                        [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                        [[0, 0, 0], [1, 1, 1], [2, 2, 2]],
                    ],
                    "swap_winding": False,
                }
            ]
        },
    )

    triangles: Annotated[list[Triangle], Field(max_length=BATCH_LIMIT)]
    swap_winding: bool = False


Integer = Annotated[str, Field(pattern=r"^-?[0-9]+$", examples=["5"])]
RationalText = Annotated[str, Field(pattern=r"^-?[0-9]+(/[0-9]+)?$", examples=["1/2"])]


class ExactNumber(BaseModel):
    """An exact rational: ``text`` such as ``5/2`` or ``-3``, and its parts as integer strings."""

    text: str = Field(examples=["5/2"])
    numerator: Integer
    denominator: Annotated[str, Field(pattern=r"^[1-9][0-9]*$", examples=["2"])]


class ExactSurd(BaseModel):
    """``coefficient * sqrt(radicand)``, such as ``√286 / 2``; ``radicand`` 1 for a rational."""

    text: str = Field(examples=["√286 / 2"])
    coefficient: RationalText
    radicand: Annotated[str, Field(pattern=r"^[1-9][0-9]*$", examples=["286"])]


ExactVector = Annotated[list[ExactNumber], Field(min_length=3, max_length=3)]
SurdVector = Annotated[list[ExactSurd], Field(min_length=3, max_length=3)]


class ExactResult(BaseModel):
    """The exact values, from the decimal text typed (``0.1`` is 1/10) or the JSON doubles."""

    a: ExactVector
    b: ExactVector
    c: ExactVector
    u: ExactVector
    v: ExactVector
    normal: ExactVector = Field(description="n = u x v as exact rationals.")
    magnitude_squared: ExactNumber = Field(description="|n|² = n · n.")
    magnitude: ExactSurd = Field(description="|n| as a simplified surd.")
    unit_normal: SurdVector | None = Field(
        description="n / |n|, each a rational times the surd of |n|; null when degenerate."
    )
    area: ExactSurd = Field(description="|n| / 2.")


class ExactPlane(BaseModel):
    a: ExactNumber
    b: ExactNumber
    c: ExactNumber
    d: ExactNumber
    equation: str = Field(
        description="The plane scaled to coprime integers.", examples=["6x + 3y + 2z = 6"]
    )


class Plane(BaseModel):
    """The plane through A with normal n: ax + by + cz = d with (a, b, c) = n and d = n · A."""

    a: MaybeNumber
    b: MaybeNumber
    c: MaybeNumber
    d: MaybeNumber
    equation: str | None = Field(
        description="With the rounded values; null when one is out of range.",
        examples=["6x + 3y + 2z = 6"],
    )
    exact: ExactPlane | None = Field(description="Present with the exact forms.")


class Angle(BaseModel):
    """The angle between u and v, atan2(|u x v|, u · v)."""

    degrees: float = Field(ge=0, le=180)
    radians: float = Field(ge=0, le=3.1415926535897936)


class NormalResult(BaseModel):
    """One triangle's normal. ``null`` marks a value outside the double range (see ``message``)."""

    a: Vector
    b: Vector
    c: Vector
    order: Literal["ABC", "ACB"]
    u: MaybeVector = Field(description="B - A (C - A when the winding is swapped).")
    v: MaybeVector = Field(description="C - A (B - A when the winding is swapped).")
    normal: MaybeVector = Field(description="n = u x v, exact and rounded once.")
    magnitude: MaybeNumber = Field(description="|n|, twice the area.")
    unit_normal: Vector | None = Field(description="n / |n|; null for a degenerate triangle.")
    area: MaybeNumber
    degenerate: bool = Field(description="The exact n is zero: repeated or collinear points.")
    message: str | None = Field(None, description="Present when there is something to explain.")
    plane: Plane | None = Field(description="null for a degenerate triangle (see plane_reason).")
    plane_reason: str | None = Field(description="Why there is no plane; null when there is.")
    angle: Angle | None = Field(description="null when u or v is zero (see angle_reason).")
    angle_reason: str | None = Field(description="Why the angle is undefined; null when it is not.")
    exact: ExactResult | None = Field(
        description="Exact forms; null when an input has no exact value or they would be too long."
    )
    exact_reason: str | None = Field(description="Why the exact forms are left out, or null.")


class BatchItem(BaseModel):
    normal: MaybeVector
    unit_normal: Vector | None
    magnitude: MaybeNumber
    area: MaybeNumber
    degenerate: bool


class BatchResult(BaseModel):
    results: list[BatchItem]


class Figure(BaseModel):
    """A Plotly figure: pass ``data`` and ``layout`` to ``Plotly.newPlot``."""

    data: list[dict[str, object]]
    layout: dict[str, object]
