"""The app with the report replaced by :func:`tests.app.jobhooks.held`, for the tests that run
it under uvicorn with its worker processes: ``uvicorn tests.app.jobserver:app``."""

from __future__ import annotations

from app.main import create_app
from app.mesh import work
from tests.app import jobhooks

work.report = jobhooks.held  # the routes look it up when called; the workers import it by name
app = create_app()
