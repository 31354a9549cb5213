"""GET /api/chart: a Plotly figure {"data": [...], "layout": {...}} that Plotly itself accepts."""

from __future__ import annotations

import json

import plotly.graph_objects as go
import pytest

from app.calculator.chart import bar_figure
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
    twin = client.get("/api/normal", params=query).json()
    expected = [*twin["normal"], twin["magnitude"], twin["area"]]
    # A second trace marks the values beyond the double range, and only then.
    assert len(figure.data) == (2 if None in expected else 1)
    assert all(trace.type == "bar" and trace.orientation == "h" for trace in figure.data)

    bars = body["data"][0]
    assert bars["x"] == expected
    assert list(figure.data[0].x) == expected
    assert len(bars["y"]) == 5 and len(bars["text"]) == 5
    assert twin["order"] in json.dumps(body["layout"])


def test_bar_values_and_labels_for_the_example(client) -> None:  # type: ignore[no-untyped-def]
    bars = client.get("/api/chart", params=EXAMPLE_QUERY).json()["data"][0]
    assert bars["x"] == [6.0, 3.0, 2.0, 7.0, 3.5]
    assert bars["text"] == ["6", "3", "2", "7", "3.5"]  # JavaScript's String(x)
    assert bars["customdata"] == ["6", "3", "2", "7", "3.5"]  # the page relabels from these
    assert bars["textfont"]["size"] >= 12 and bars["constraintext"] == "none"  # never squeezed


def payload_of(client, query: dict[str, str]) -> dict[str, object]:  # type: ignore[no-untyped-def]
    return client.get("/api/normal", params=query).json()  # type: ignore[no-any-return]


def test_labels_follow_the_precision_with_the_real_minus_sign(client) -> None:  # type: ignore[no-untyped-def]
    payload = payload_of(client, {**EXAMPLE_QUERY, "swap": "on"})
    bars = bar_figure(payload, decimals=4)["data"][0]
    assert bars["text"] == ["−6.0000", "−3.0000", "−2.0000", "7.0000", "3.5000"]
    assert bars["customdata"] == ["-6", "-3", "-2", "7", "3.5"]  # machine text, every digit
    assert bar_figure(payload)["data"][0]["text"][:3] == ["−6", "−3", "−2"]
    thirds = payload_of(client, {**EXAMPLE_QUERY, "cz": "0.3333333333333333"})
    assert bar_figure(thirds, decimals=2)["data"][0]["text"][0] == "0.67"
    assert bar_figure(thirds)["data"][0]["text"][0] == "0.6666666666666666"


def test_out_of_range_values_are_marked_never_an_empty_chart(client) -> None:  # type: ignore[no-untyped-def]
    body = client.get("/api/chart", params=QUERIES[4]).json()
    bars, capped = body["data"]
    assert bars["x"] == [0.0, 0.0, None, None, None]
    assert bars["text"][:2] == ["0", "0"]
    # Hatched bars past the others, each labelled, and a note that says what hatching means.
    assert capped["x"][:2] == [None, None] and all(x > 0 for x in capped["x"][2:])
    assert capped["text"][2:] == ["beyond 1.8e308"] * 3
    assert capped["marker"]["pattern"]["shape"] == "/"
    (note,) = body["layout"]["annotations"]
    assert "beyond the double range" in note["text"]
    low, high = body["layout"]["xaxis"]["range"]
    assert low == 0 and high > max(capped["x"][2:])  # room for the labels


def test_a_negative_out_of_range_component_is_capped_below_zero(client) -> None:  # type: ignore[no-untyped-def]
    body = client.get("/api/chart", params={**QUERIES[4], "swap": "on"}).json()
    capped = body["data"][1]
    assert capped["x"][2] < 0 < capped["x"][3]
    assert capped["text"][2] == "beyond −1.8e308"
    assert body["layout"]["xaxis"]["range"][0] < capped["x"][2]


def test_swap_flips_the_component_bars(client) -> None:  # type: ignore[no-untyped-def]
    plain_bars = client.get("/api/chart", params=QUERIES[0]).json()["data"][0]["x"]
    swapped = client.get("/api/chart", params=QUERIES[1]).json()["data"][0]["x"]
    assert swapped[:3] == [-y for y in plain_bars[:3]]
    assert swapped[3:] == plain_bars[3:]
