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


def test_ticks_are_round_numbers() -> None:
    # Areas 0.25 to 0.5 with zero-area faces: linear ticks at multiples of 0.05, not 0.312.
    areas = np.array([0.0, 0.25, 0.3, 0.5])
    figure = histogram_figure(area_histogram(areas, areas == 0))
    axis = figure["layout"]["xaxis"]
    assert axis["ticktext"] == ["zero", "0.25", "0.30", "0.35", "0.40", "0.45", "0.50"]
    assert axis["tickvals"][1:] == [0.25, 0.3, 0.35, 0.4, 0.45, 0.5]
    # Log ticks: powers of ten written in full from 0.001 to 1000, as 1e-6 beyond.
    wide = np.array([1e-6, 1e-4, 1e-2, 1.0])
    labels = histogram_figure(area_histogram(wide, wide == 0))["layout"]["xaxis"]["ticktext"]
    assert labels == ["1e-6", "1e-5", "1e-4", "0.001", "0.01", "0.1", "1"]
    # Whatever the range, no label carries rounding noise.
    rng = np.random.default_rng(3)
    for low, high in rng.uniform(0, 10, (20, 2)) * 10.0 ** rng.integers(-3, 4, (20, 1)):
        values = np.array([0.0, min(low, high) + 1e-9, max(low, high) + 2e-9])
        axis = histogram_figure(area_histogram(values, values == 0))["layout"]["xaxis"]
        assert 3 <= len(axis["ticktext"]) <= 7, axis["ticktext"]
        assert all(len(text) <= 8 for text in axis["ticktext"]), axis["ticktext"]
