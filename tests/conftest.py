"""Shared fixtures: the app under test and a client for it."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from app.main import create_app


@pytest.fixture(scope="session")
def client() -> Iterator[TestClient]:
    with TestClient(create_app(), raise_server_exceptions=False) as test_client:
        yield test_client


def assert_error(response, status: int, field: str | None, *words: str) -> None:  # type: ignore[no-untyped-def]
    """The one error shape: exactly {"error": one sentence, "field": name or null}."""
    assert response.status_code == status, response.text
    assert response.headers["content-type"].startswith("application/json")
    body = response.json()
    assert set(body) == {"error", "field"}
    assert body["field"] == field
    sentence = body["error"]
    assert sentence[0].isupper() or sentence.split()[0] == field or sentence[0] == field[0]
    assert sentence.endswith("."), sentence
    for word in words:
        assert word in sentence, (word, sentence)
