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
