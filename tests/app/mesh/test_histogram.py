"""app/mesh/histogram.py: the bins of the face areas and their bar chart."""

from __future__ import annotations

import json

import numpy as np

from app.mesh.classes import COLORS, DEGENERATE
from app.mesh.histogram import area_histogram, histogram_figure


def test_histogram_bins_add_up_to_the_faces() -> None:
    rng = np.random.default_rng(1)
    areas = 10.0 ** rng.uniform(-6, 2, 5000)
    degenerate = np.zeros(5000, dtype=bool)
    degenerate[:17] = True
    areas[:17] = 0.0
    areas[17] = np.inf
    histogram = area_histogram(areas, degenerate)
    assert histogram["log"] is True
    assert histogram["zero_area"] == 17 and histogram["beyond_range"] == 1
    assert sum(histogram["counts"]) + 17 + 1 == 5000
    assert len(histogram["edges"]) == len(histogram["counts"]) + 1
    figure = histogram_figure(histogram)
    zero = figure["data"][1]
    assert zero["y"] == [17] and zero["marker"]["color"] == COLORS[DEGENERATE]
    assert figure["layout"]["xaxis"]["ticktext"][0] == "zero"
    json.dumps(figure, allow_nan=False)


def test_histogram_is_linear_for_a_narrow_range_and_handles_equal_areas() -> None:
    linear = area_histogram(np.linspace(1.0, 2.0, 400), np.zeros(400, dtype=bool))
    assert linear["log"] is False and sum(linear["counts"]) == 400
    equal = area_histogram(np.full(12, 0.5), np.zeros(12, dtype=bool))
    assert equal["counts"] == [12] and equal["edges"][0] < 0.5 < equal["edges"][1]
    empty = area_histogram(np.zeros(3), np.ones(3, dtype=bool))
    assert empty["counts"] == [] and empty["zero_area"] == 3
