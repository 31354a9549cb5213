"""app/web/plotly.py: the look both 3D views and both charts share."""

from __future__ import annotations

import json
import re

import numpy as np

from app.web.plotly import DARK, FONT, INK, cone_trace
from tests.paths import STATIC


def test_cone_trace_puts_each_tip_where_asked() -> None:
    tips = np.array([[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]])
    heads = np.array([[0.0, 0.0, 0.5], [0.1, 0.0, 0.0]])
    trace = cone_trace("normals", tips, heads, "#123456")
    assert trace["type"] == "cone" and trace["anchor"] == "tip" and trace["sizemode"] == "raw"
    assert (trace["x"], trace["y"], trace["z"]) == ([1.0, 0.0], [2.0, 0.0], [3.0, 0.0])
    assert (trace["u"], trace["v"], trace["w"]) == ([0.0, 0.1], [0.0, 0.0], [0.5, 0.0])
    assert trace["colorscale"] == [[0, "#123456"], [1, "#123456"]]
    json.dumps(trace, allow_nan=False)


def test_cone_trace_takes_lists_as_it_takes_arrays() -> None:
    """The calculator passes lists (it imports no NumPy); the mesh views pass arrays."""
    tips = [[1.0, 2.0, 3.0], [0.0, -0.0, 1e-300]]
    heads = [(0.0, 0.0, 0.5), (0.1, 0, 2)]
    from_lists = cone_trace("normals", tips, heads, "#123456")
    from_arrays = cone_trace("normals", np.array(tips), np.array(heads, dtype=float), "#123456")
    assert json.dumps(from_lists) == json.dumps(from_arrays)  # -0.0 and 2.0 (not 2) included
    assert cone_trace("none", [], [], "#123456")["x"] == []


def test_font_uses_the_ink_colour() -> None:
    assert FONT["color"] == INK


def test_the_dark_table_is_the_one_the_3d_script_uses() -> None:
    """static/js/view3d.js swaps colours with its own copy of DARK: the two stay equal."""
    script = (STATIC / "js" / "view3d.js").read_text()
    block = re.search(r"const DARK = \{(.*?)\};", script, re.DOTALL)
    assert block, "view3d.js has no DARK table"
    pairs = dict(re.findall(r'"(#[0-9a-f]{6})":\s*"(#[0-9a-f]{6})"', block.group(1)))
    assert pairs == DARK
