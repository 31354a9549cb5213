"""The service's limits and settings, in one declarative table."""

from __future__ import annotations

import os

#: Most triangles one POST /api/normals request may carry.
BATCH_LIMIT = 100_000

#: Largest request body, in bytes, per path; other paths get DEFAULT_BODY_LIMIT.
#: One triangle needs far less than 64 KB; a full batch at full precision is about 20 MB.
BODY_LIMITS = {"/api/normals": 48 * 1024 * 1024}
DEFAULT_BODY_LIMIT = 64 * 1024

#: Paths that take a mesh file. Their bodies are streamed (never buffered whole by the
#: middleware) and counted against the upload limit as they arrive.
MESH_PATHS = frozenset({"/api/mesh", "/api/mesh/normals", "/api/mesh/fix", "/mesh"})

#: Environment variable that sets the upload limit, in megabytes (default 200).
UPLOAD_LIMIT_VARIABLE = "MESH_UPLOAD_LIMIT_MB"
DEFAULT_UPLOAD_LIMIT_MB = 200


def upload_limit() -> int:
    """The largest mesh upload in bytes: ``$MESH_UPLOAD_LIMIT_MB`` megabytes, default 200."""
    text = os.environ.get(UPLOAD_LIMIT_VARIABLE, "").strip()
    megabytes = float(text) if text else DEFAULT_UPLOAD_LIMIT_MB
    if not megabytes > 0:
        raise ValueError(f"{UPLOAD_LIMIT_VARIABLE} must be a positive number of megabytes.")
    return int(megabytes * 1024 * 1024)


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
