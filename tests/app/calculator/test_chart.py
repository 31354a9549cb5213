"""GET /api/chart: a Plotly figure {"data": [...], "layout": {...}} that Plotly itself accepts."""

from __future__ import annotations

import json

import plotly.graph_objects as go
import pytest

from tests.conftest import EXAMPLE_QUERY

QUERIES = [
    EXAMPLE_QUERY,
    {**EXAMPLE_QUERY, "swap": "on"},
    {**EXAMPLE_QUERY, "ax": "-2.5e3", "cz": "0.125"},
    {
        "ax": "0",
        "ay": "0",
        "az": "0",
        "bx": "1",
        "by": "1",
        "bz": "1",
        "cx": "2",
        "cy": "2",
        "cz": "2",
    },  # degenerate
    {
        "ax": "0",
        "ay": "0",
        "az": "0",
        "bx": "1e200",
        "by": "0",
        "bz": "0",
        "cx": "0",
        "cy": "1e200",
        "cz": "0",
    },  # out of range: null bars
    {
        "ax": "0",
        "ay": "0",
        "az": "0",
        "bx": "1e-200",
        "by": "0",
        "bz": "0",
        "cx": "0",
        "cy": "1e-200",
        "cz": "0",
    },
]


def plain(value: object) -> bool:
    """Only JSON's own types: numbers are plain lists, not typed arrays or {"dtype", "bdata"}."""
    if isinstance(value, dict):
        return "bdata" not in value and all(plain(item) for item in value.values())
    if isinstance(value, list):
        return all(plain(item) for item in value)
    return value is None or isinstance(value, str | int | float | bool)


@pytest.mark.parametrize("query", QUERIES)
def test_chart_is_a_valid_plotly_figure(client, query: dict[str, str]) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/api/chart", params=query)
    assert response.status_code == 200, response.text
    assert response.headers["content-type"] == "application/json"
    assert "NaN" not in response.text and "Infinity" not in response.text
    body = response.json()
    assert set(body) == {"data", "layout"}
    assert plain(body)
    figure = go.Figure(body)  # raises on anything Plotly does not know
    assert len(figure.data) == 1
    assert figure.data[0].type == "bar"

    twin = client.get("/api/normal", params=query).json()
    expected = [*twin["normal"], twin["magnitude"], twin["area"]]
    bars = body["data"][0]
    assert bars["y"] == expected
    assert list(figure.data[0].y) == expected
    assert len(bars["x"]) == 5 and len(bars["text"]) == 5
    assert twin["order"] in json.dumps(body["layout"])


def test_bar_values_and_labels_for_the_example(client) -> None:  # type: ignore[no-untyped-def]
    bars = client.get("/api/chart", params=EXAMPLE_QUERY).json()["data"][0]
    assert bars["y"] == [6.0, 3.0, 2.0, 7.0, 3.5]
    assert bars["text"] == ["6", "3", "2", "7", "3.5"]  # JavaScript's String(x)


def test_out_of_range_bars_are_null_and_say_so(client) -> None:  # type: ignore[no-untyped-def]
    bars = client.get("/api/chart", params=QUERIES[4]).json()["data"][0]
    assert bars["y"] == [0.0, 0.0, None, None, None]
    assert bars["text"][2:] == ["out of double range"] * 3


def test_swap_flips_the_component_bars(client) -> None:  # type: ignore[no-untyped-def]
    plain_bars = client.get("/api/chart", params=QUERIES[0]).json()["data"][0]["y"]
    swapped = client.get("/api/chart", params=QUERIES[1]).json()["data"][0]["y"]
    assert swapped[:3] == [-y for y in plain_bars[:3]]
    assert swapped[3:] == plain_bars[3:]
