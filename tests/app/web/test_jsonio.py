"""app/web/jsonio.py: every JSON text the app writes is valid JSON, NaN and Infinity included."""

from __future__ import annotations

import json
import math
from typing import Any

import pytest
from fastapi import FastAPI
from fastapi.testclient import TestClient
from hypothesis import given
from hypothesis import strategies as st
from pydantic import BaseModel, ConfigDict

from app.main import create_app
from app.web.errors import ApiError
from app.web.jsonio import FastJSONResponse, json_bytes, parse_body, refuse_duplicate_keys
from app.web.templating import json_script


def strict(text: str | bytes) -> Any:
    """``json.loads`` that refuses NaN, Infinity and -Infinity, as browsers' JSON.parse does."""

    def refuse(word: str) -> None:
        raise ValueError(f"not JSON: {word}")

    return json.loads(text, parse_constant=refuse)


def test_the_strict_parser_refuses_bare_words() -> None:
    with pytest.raises(ValueError, match="NaN"):
        strict('{"x": NaN}')


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_non_finite_numbers_are_written_as_null(value: float) -> None:
    content = {"normal": [value, 1.0, -0.0], "nested": {"area": value}, "items": (value,)}
    expected = {"normal": [None, 1.0, -0.0], "nested": {"area": None}, "items": [None]}
    assert strict(json_bytes(content)) == expected
    assert strict(FastJSONResponse(content).body) == expected
    assert strict(json_script(content)) == expected


def test_finite_numbers_keep_every_bit() -> None:
    values = [5e-324, 1.7976931348623157e308, 0.1, -2.5e-7]
    assert strict(json_bytes(values)) == values


@pytest.fixture(scope="module")
def nan_client() -> TestClient:
    """The real app with one extra route whose payload holds NaN and Infinity."""
    app: FastAPI = create_app()

    @app.get("/api/test-non-finite")
    def non_finite() -> dict[str, float]:
        return {"nan": math.nan, "inf": math.inf, "one": 1.0}

    return TestClient(app, raise_server_exceptions=False)


def test_a_route_that_returns_nan_answers_valid_json(nan_client: TestClient) -> None:
    """FastAPI routes default to FastJSONResponse, so NaN becomes null, not a bare word."""
    response = nan_client.get("/api/test-non-finite")
    assert response.status_code == 200
    assert strict(response.text) == {"nan": None, "inf": None, "one": 1.0}


def test_errors_and_the_partials_twin_are_strict_json(client: TestClient) -> None:
    for response in (
        client.get("/api/nowhere"),
        client.get("/partials", params={"ax": "1e200", "by": "1e200", "cz": "1e-300"}),
        client.get("/api/normal", params={"ax": "1e308", "by": "1e308", "cz": "1e308"}),
    ):
        assert response.headers["content-type"].startswith("application/json")
        strict(response.text)


json_values = st.recursive(
    st.none() | st.booleans() | st.floats(allow_nan=False) | st.text(max_size=5),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=3), inner),
    max_leaves=12,
)


@given(json_values, st.booleans())
def test_duplicate_keys_are_found_in_any_json(value, spaced: bool) -> None:  # type: ignore[no-untyped-def]
    text = json.dumps(value, indent=1 if spaced else None)
    refuse_duplicate_keys(text.encode())  # json.dumps never repeats a key
    if isinstance(value, dict) and value:
        key = next(iter(value))
        doubled = text[:-1].rstrip() + f", {json.dumps(key)}: 1" + "}"
        with pytest.raises(ApiError) as raised:
            refuse_duplicate_keys(doubled.encode())
        assert raised.value.status_code == 422
        assert raised.value.field == key


def test_duplicate_keys_in_nested_objects_and_strings_that_look_like_keys() -> None:
    refuse_duplicate_keys(b'{"a": {"a": 1}, "b": [{"a": 1}, {"a": 2}], "c": "\\"a\\": 1"}')
    with pytest.raises(ApiError, match=r"^x is given twice"):
        refuse_duplicate_keys(b'{"a": [{"x": 1, "y": {"x": 2}, "x": 3}]}')


class _Fields(BaseModel):
    """A body of numbers and flags only, as the calculator's: its keys are its only strings."""

    model_config = ConfigDict(extra="forbid")
    a: list[float] = []
    b: bool = False
    note: str = ""


_FIELD_VALUES = {"a": "[1, 2.5]", "b": "true", "note": '"x"'}


@given(
    st.lists(st.sampled_from(sorted(_FIELD_VALUES)), min_size=1, max_size=5),
    st.booleans(),
    st.booleans(),
)
def test_parse_body_refuses_a_key_given_twice_however_written(
    keys: list[str], escaped: bool, spaced: bool
) -> None:
    """The count of quotes that lets a valid body skip the key scan never hides a repeat."""
    written = [
        f'"\\u{ord(key[0]):04x}{key[1:]}"' if escaped and i else f'"{key}"'
        for i, key in enumerate(keys)
    ]
    colon = " : " if spaced else ":"
    raw = (
        "{"
        + ", ".join(f"{w}{colon}{_FIELD_VALUES[k]}" for w, k in zip(written, keys, strict=True))
        + "}"
    ).encode()
    if len(set(keys)) == len(keys):
        assert parse_body(raw, _Fields).model_fields_set == set(keys)
    else:
        with pytest.raises(ApiError) as raised:
            parse_body(raw, _Fields)
        assert raised.value.status_code == 422
        assert "given twice" in raised.value.error
