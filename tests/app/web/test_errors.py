"""app.web.errors: naming inputs as the user wrote them; validation errors as one sentence."""

from __future__ import annotations

import pytest

from app.web.errors import ApiError, describe, field_name, from_validation


@pytest.mark.parametrize(
    ("location", "name"),
    [
        (("query", "ax"), "ax"),
        (("query", "swap"), "swap"),
        (("body", "a"), "a"),
        (("body", "a", 0), "a[0]"),
        (("a", 2), "a[2]"),  # pydantic's own locations, without FastAPI's "body"
        (("body", "swap_winding"), "swap_winding"),
        (("body", "triangles"), "triangles"),
        (("body", "triangles", 3), "triangles[3]"),
        (("body", "triangles", 3, 1), "triangles[3][1]"),
        (("body", "triangles", 3, 1, 2), "triangles[3][1][2]"),
        (("triangles", 99_999, 0, 0), "triangles[99999][0][0]"),
        (("body", "outer", "inner"), "outer.inner"),
        (("body", "outer", 0, "inner"), "outer[0].inner"),
        (("body",), None),
        (("query",), None),
        ((), None),
        (["body", "c", 1], "c[1]"),  # a list works as well as a tuple
    ],
)
def test_field_name(location, name: str | None) -> None:  # type: ignore[no-untyped-def]
    assert field_name(location) == name


@pytest.mark.parametrize(
    ("location", "name"),
    [
        (("body", "query"), "query"),
        (("body", "path"), "path"),
        (("body", "body"), "body"),
        (("body", "outer", "query"), "outer.query"),
    ],
)
def test_field_name_keeps_fields_named_like_locations(location, name: str) -> None:  # type: ignore[no-untyped-def]
    assert field_name(location) == name


@pytest.mark.parametrize(
    ("value", "words"),
    [
        (None, "null"),
        (True, "a boolean"),
        (False, "a boolean"),
        ("1", "the string '1'"),
        ([1, 2], "a list of 2"),
        ({"x": 1}, "an object"),
        (1.5, "1.5"),
    ],
)
def test_describe(value, words: str) -> None:  # type: ignore[no-untyped-def]
    assert describe(value) == words


def test_describe_does_not_echo_a_huge_value() -> None:
    text = describe("x" * 10_000)
    assert len(text) < 40 and text.endswith("...'")


def error(kind: str, loc: tuple, given: object = None, **ctx: object) -> dict:  # type: ignore[type-arg]
    return {"type": kind, "loc": loc, "input": given, "ctx": ctx or None, "msg": "ignored"}


@pytest.mark.parametrize(
    ("errors", "status", "field", "words"),
    [
        ([error("missing", ("body", "a"))], 422, "a", "a is missing."),
        ([error("float_type", ("body", "a", 0), "1")], 422, "a[0]", "JSON number"),
        ([error("finite_number", ("body", "c", 2), float("nan"))], 422, "c[2]", "finite"),
        ([error("too_short", ("body", "b"), [1], actual_length=1)], 422, "b", "3 numbers"),
        (
            [error("too_short", ("body", "triangles", 4), [], actual_length=0)],
            422,
            "triangles[4]",
            "3 points",
        ),
        (
            [error("too_long", ("body", "triangles"), [], actual_length=100_001)],
            413,
            "triangles",
            "100,001",
        ),
        ([error("extra_forbidden", ("body", "zz"), 1)], 422, "zz", "not a field"),
        ([error("json_invalid", ("body", 7), error="Expecting value")], 400, None, "character 7"),
        ([error("model_attributes_type", ("body",), [1, 2])], 422, None, "list of 2"),
        ([error("missing", ("body", "a")), error("missing", ("body", "b"))], 422, "a", "a is"),
    ],
)
def test_from_validation(errors, status: int, field: str | None, words: str) -> None:  # type: ignore[no-untyped-def]
    result = from_validation(errors)
    assert isinstance(result, ApiError)
    assert result.status_code == status
    assert result.field == field
    assert words in result.error
    assert result.error.endswith(".")
    assert result.body() == {"error": result.error, "field": field}
