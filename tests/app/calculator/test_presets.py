"""app/calculator/presets.py: the example and the presets are valid inputs that teach."""

from __future__ import annotations

import pytest

from app.calculator.params import read_triangle
from app.calculator.presets import COORDINATE_FIELDS, EXAMPLE, PRESETS
from mesh_normal.triangle.normal import triangle_normal


def test_the_example_fills_every_field() -> None:
    assert tuple(EXAMPLE) == COORDINATE_FIELDS
    assert read_triangle(EXAMPLE).valid


@pytest.mark.parametrize(("key", "title", "lesson", "query"), PRESETS, ids=[p[0] for p in PRESETS])
def test_every_preset_reads_without_errors(key: str, title: str, lesson: str, query: dict) -> None:  # type: ignore[type-arg]
    assert key and title and lesson.endswith(".")
    parsed = read_triangle(query)
    assert parsed.valid, (parsed.errors, parsed.missing)
    assert set(COORDINATE_FIELDS) <= set(query)


def test_the_presets_show_what_they_say() -> None:
    results = {}
    for key, *_, query in PRESETS:
        parsed = read_triangle(query)
        results[key] = triangle_normal(*parsed.points(), swap_winding=parsed.swap)
    assert results["right"].unit_normal == (0.0, 0.0, 1.0)
    assert results["swapped"].unit_normal == (0.0, 0.0, -1.0)
    assert results["collinear"].degenerate
    assert results["huge"].magnitude is None and results["huge"].unit_normal == (0.0, 0.0, 1.0)
    assert not results["sliver"].degenerate
