"""MESH_EXPANSION_LIMIT_MB: the operator's most for what one upload may expand into."""

from __future__ import annotations

from fastapi.testclient import TestClient

from app.config import Settings
from app.main import create_app
from mesh_normal.files import expansion
from tests.conftest import assert_error
from tests.paths import ROOT

PLACEMENTS = ROOT / "tests" / "data" / "hostile" / "3mf_2500_placements.3mf"


def test_the_operators_most_is_the_limit_and_the_sentence_says_so() -> None:
    app = create_app(settings=Settings(in_process=True, expansion_limit_mb=100))
    with TestClient(app, raise_server_exceptions=False) as client:
        response = client.post("/api/mesh", files={"file": ("p.3mf", PLACEMENTS.read_bytes())})
    assert_error(response, 413, "file", "the 100 MB", "the most for one upload on this server")
    assert expansion.expansion_limit(2**40) == expansion.MAX_EXPANSION  # the test's own context
