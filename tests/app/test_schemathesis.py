"""Schemathesis 4.x over the app's own OpenAPI schema (/openapi.json): it finds nothing.

Every operation is exercised with schema-valid and schema-breaking data (Schemathesis' coverage
and fuzzing phases) and every default check runs on every response, with two exclusions, each
explained where it is made.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterator

import pytest
import schemathesis
from hypothesis import HealthCheck, settings

from app.config import Settings
from app.main import create_app

# The mesh jobs in threads: Schemathesis calls the app from a new event loop each time, and
# worker processes would start afresh for each (tests/app/mesh/test_work.py covers them).
schema = schemathesis.openapi.from_asgi(
    "/openapi.json", create_app(settings=Settings(in_process=True))
)

OPERATIONS = {
    "POST /api/normal",
    "GET /api/normal",
    "GET /api/normal.csv",
    "POST /api/normals",
    "GET /api/chart",
    "POST /api/mesh",
    "POST /api/mesh/normals",
    "POST /api/mesh/fix",
    "POST /api/mesh/export",
    "GET /api/mesh/sample/{name}",
    "POST /api/points",
    "POST /api/points/normals",
}

#: The query-string operations, whose coordinates are decimal *text*.
QUERY_OPERATIONS = {"GET /api/normal", "GET /api/normal.csv", "GET /api/chart"}

#: The operations that take a mesh or point-cloud file: any bytes fit their schema ("format:
#: binary").
MESH_OPERATIONS = {
    "POST /api/mesh",
    "POST /api/mesh/normals",
    "POST /api/mesh/fix",
    "POST /api/mesh/export",
    "POST /api/points",
    "POST /api/points/normals",
}

#: The smallest number of requests an operation must see for the run to count.
MIN_CALLS = 25


def test_the_schema_lists_every_api_operation() -> None:
    labels = {operation.ok().label for operation in schema.get_all_operations()}
    assert labels == OPERATIONS


def excluded_checks(label: str) -> list:
    excluded = []
    if label in QUERY_OPERATIONS:
        # The coordinates are documented with the decimal pattern, but "1e999" fits it and is
        # (rightly) refused as beyond the double range, which no pattern can express.
        excluded.append(schemathesis.checks.positive_data_acceptance)
    if label in MESH_OPERATIONS:
        # Whether bytes are a mesh file is not something a schema can say: random bytes fit
        # "format: binary" and are (rightly) refused as an unknown or broken file.
        excluded.append(schemathesis.checks.positive_data_acceptance)
    return excluded


@pytest.fixture
def statuses(request: pytest.FixtureRequest) -> Iterator[Counter[int]]:
    """The status codes one operation's run produced; it must have run, and both ways."""
    seen: Counter[int] = Counter()
    yield seen
    total = sum(seen.values())
    assert total >= MIN_CALLS, (request.node.name, seen)
    assert any(200 <= code < 300 for code in seen), ("no request was accepted", seen)
    assert any(400 <= code < 500 for code in seen), ("no request was refused", seen)
    assert not any(code >= 500 for code in seen), seen


@schema.parametrize()
@settings(
    max_examples=60,
    deadline=None,
    # The function-scoped `statuses` fixture deliberately spans all examples of one operation.
    suppress_health_check=[
        HealthCheck.function_scoped_fixture,
        HealthCheck.too_slow,
        HealthCheck.filter_too_much,
        HealthCheck.data_too_large,
    ],
)
def test_api(case, statuses: Counter[int]) -> None:  # type: ignore[no-untyped-def]
    label = case.operation.label
    assert label in OPERATIONS
    response = case.call_and_validate(excluded_checks=excluded_checks(label))
    statuses[response.status_code] += 1
    if response.status_code >= 400:
        body = response.json()
        assert set(body) == {"error", "field"}, body
