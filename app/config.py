"""The service's limits and settings, in one declarative table."""

from __future__ import annotations

#: Most triangles one POST /api/normals request may carry.
BATCH_LIMIT = 100_000

#: Largest request body, in bytes, per path; other paths get DEFAULT_BODY_LIMIT.
#: One triangle needs far less than 64 KB; a full batch at full precision is about 20 MB.
BODY_LIMITS = {"/api/normals": 48 * 1024 * 1024}
DEFAULT_BODY_LIMIT = 64 * 1024

#: The example the calculator opens with: a right triangle tilted out of every plane.
EXAMPLE = {"ax": "1", "ay": "0", "az": "0", "bx": "0", "by": "2", "bz": "0",
           "cx": "0", "cy": "0", "cz": "3"}

COORDINATE_FIELDS = ("ax", "ay", "az", "bx", "by", "bz", "cx", "cy", "cz")
