"""``POST /api/normals``: a batch of triangles, parsed and computed in one step.

A large batch is a heavy job (:mod:`app.web.jobs`): parsing builds a Python object for every
number, and 12 batches of 100,000 triangles parsed at once in the server would take 1.3 GB
and stall its pages for seconds. So a body over :data:`INLINE_BYTES` runs in a worker process,
admitted against the memory budget with :func:`estimate`, and comes back as the JSON text of
the answer (bytes travel between processes in one piece; a dict of 100,000 rows would be
pickled and rebuilt object by object). A smaller body (a few triangles, a few hundred) is
answered in a thread of the server, at once.
"""

from __future__ import annotations

import re
from typing import Any

from app.calculator.payloads import batch_payload
from app.calculator.schemas import BatchRequest
from app.config import BATCH_LIMIT
from app.web.errors import ApiError
from app.web.jsonio import json_bytes, parse_body
from app.web.workers import run_in_server_while_starting
from mesh_normal.triangle.normal import triangle_normal

#: Bodies up to this size are answered in the server (a compact 16 KB body holds about 600
#: triangles, parsed and computed in about 4 ms); larger ones are a job in a worker.
INLINE_BYTES = 16 * 1024

#: Peak memory of a batch job per triangle (about 1,650 bytes for 100,000 triangles with
#: 17 significant digits, 1,900 for one-digit coordinates; the parsed lists dominate), and
#: per byte of the body (the body itself, in the server and in the worker).
BYTES_PER_TRIANGLE = 2048
BYTES_PER_BODY_BYTE = 2

#: While no worker is ready yet, bodies up to this size run in the server (tens of
#: milliseconds, tens of megabytes at most).
STARTING_BYTES = 256 * 1024


def estimate(raw: bytes) -> int:
    """The memory a batch job on ``raw`` may take, in bytes: its triangles counted by their
    opening brackets (``4 * n + 1`` in a valid body; at most the batch limit counts, as more
    are refused before parsing), and the body itself."""
    triangles = min(raw.count(b"[") // 4, BATCH_LIMIT)
    return BYTES_PER_TRIANGLE * triangles + BYTES_PER_BODY_BYTE * len(raw)


def refuse_beyond_budget(estimate: int, budget: int) -> None:
    """A 413 for a batch whose job would need more than the server's whole memory budget
    (the jobs' own sentence speaks of a file)."""
    if estimate > budget:
        raise ApiError(
            413,
            f"This batch would need about {estimate / 2**20:,.0f} MB of memory, more than this "
            f"server gives one request ({budget / 2**20:,.0f} MB); split it into several "
            "requests.",
            "triangles",
        )


def payload(raw: bytes) -> dict[str, Any]:
    """The answer to the batch in ``raw`` (an ApiError for a bad one)."""
    # Imported here, not at the top: NumPy is for batches only, and importing it would add
    # to every start-up of the server (the calculator page and /api/normal never need it).
    import numpy as np

    from mesh_normal.triangle.batch import triangle_normals

    refuse_oversized_batch(raw)
    body = parse_body(raw, BatchRequest)
    triangles = np.array(body.triangles, dtype=np.float64).reshape(-1, 3, 3)
    batch = triangle_normals(triangles, swap_winding=body.swap_winding)
    exact_rows = {
        int(row): triangle_normal(*triangles[row].tolist(), swap_winding=body.swap_winding)
        for row in np.flatnonzero(batch.out_of_range)
    }
    return batch_payload(batch, exact_rows)


def job(raw: bytes) -> bytes:
    """The JSON text of the answer to the batch in ``raw``: what a worker runs."""
    return json_bytes(payload(raw))


#: A JSON string, escapes included (linear: each character matches one way).
_STRING = re.compile(rb'"(?:[^"\\]|\\.)*"')


def refuse_oversized_batch(raw: bytes) -> None:
    """Refuse a batch of more than ``BATCH_LIMIT`` triangles before it is parsed.

    Parsing builds every number as an object (about 70 times the body's size for 1.9 million
    triangles); counting brackets reads the bytes once. A valid body holds exactly
    ``4 * n + 1`` of them for ``n`` triangles (keys are ``triangles`` and ``swap_winding``,
    with no bracket), so more than ``4 * BATCH_LIMIT + 1`` is over the limit or not a batch.
    """
    most = 4 * BATCH_LIMIT + 1
    brackets = raw.count(b"[")
    if brackets > most and b'"' in raw:  # brackets inside strings are no triangles
        brackets = _STRING.sub(b'""', raw).count(b"[")
    if brackets > most:
        raise ApiError(
            413,
            f"A batch holds at most {BATCH_LIMIT:,} triangles (about {(brackets - 1) // 4:,} "
            "were sent); split it into several requests.",
            "triangles",
        )


def _starting_job(raw: bytes) -> bool:
    return len(raw) <= STARTING_BYTES


run_in_server_while_starting(job, _starting_job)
