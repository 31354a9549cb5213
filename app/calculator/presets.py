"""The calculator's inputs: its coordinate fields, the example it opens with, and the presets."""

from __future__ import annotations

#: The example the calculator opens with: a right triangle tilted out of every plane.
EXAMPLE = {
    "ax": "1",
    "ay": "0",
    "az": "0",
    "bx": "0",
    "by": "2",
    "bz": "0",
    "cx": "0",
    "cy": "0",
    "cz": "3",
}

COORDINATE_FIELDS = ("ax", "ay", "az", "bx", "by", "bz", "cx", "cy", "cz")

#: One-click examples that teach something: (key, title, what it shows, query parameters).
PRESETS = [
    (
        "right",
        "Unit right triangle",
        "The normal of the xy-plane: (0, 0, 1).",
        {
            "ax": "0",
            "ay": "0",
            "az": "0",
            "bx": "1",
            "by": "0",
            "bz": "0",
            "cx": "0",
            "cy": "1",
            "cz": "0",
        },
    ),
    (
        "swapped",
        "Same, winding swapped",
        "A, C, B turns the other way: the normal flips.",
        {
            "ax": "0",
            "ay": "0",
            "az": "0",
            "bx": "1",
            "by": "0",
            "bz": "0",
            "cx": "0",
            "cy": "1",
            "cz": "0",
            "swap": "on",
        },
    ),
    (
        "collinear",
        "Collinear points",
        "Three points on a line: no area, no normal.",
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
        },
    ),
    (
        "sliver",
        "Sliver far from the origin",
        "A naive float cross product rounds n to zero; the exact one finds its direction.",
        {
            "ax": "1000000",
            "ay": "1000000",
            "az": "0",
            "bx": "1000003.0000000001",
            "by": "1000003",
            "bz": "0",
            "cx": "1000003",
            "cy": "1000002.9999999999",
            "cz": "0",
        },
    ),
    (
        "huge",
        "Huge coordinates",
        "|n| is beyond the double range; the unit normal is not.",
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
        },
    ),
]
