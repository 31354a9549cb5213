"""The ASGI app: ``uvicorn app.main:app``."""

from __future__ import annotations

from fastapi import FastAPI

from app import errors, mesh_page, pages
from app.api import mesh, normals
from app.middleware import BodyLimit, PageCompression, SecurityHeaders
from app.static import STATIC_DIR, CompressedStaticFiles

DESCRIPTION = """
Surface normals of triangles, exact to the last bit.

For points A, B, C: u = B - A, v = C - A, the normal n = u x v, |n| is twice the area and
n / |n| the unit normal. Every value is the exact result rounded once to the nearest double;
a value outside the double range is `null` with a `message`. Errors are
`{"error": "<one sentence>", "field": "<input name or null>"}`.
"""


def create_app(upload_limit: int | None = None) -> FastAPI:
    """The app; ``upload_limit`` (bytes) overrides ``$MESH_UPLOAD_LIMIT_MB`` for mesh files."""
    app = FastAPI(
        title="Mesh Normal Calculator",
        version="0.1.0",
        description=DESCRIPTION,
        docs_url=None,
        redoc_url=None,
    )
    errors.install(app)
    app.include_router(normals.router)
    app.include_router(mesh.router)
    app.include_router(pages.router)
    app.include_router(mesh_page.router)
    app.mount("/static", CompressedStaticFiles(directory=STATIC_DIR), name="static")
    app.add_middleware(PageCompression)
    app.add_middleware(BodyLimit, upload_limit=upload_limit)
    app.add_middleware(SecurityHeaders)
    return app


app = create_app()
