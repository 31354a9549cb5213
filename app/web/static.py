"""Static files with long-lived, content-hashed URLs and gzip done once per file."""

from __future__ import annotations

import gzip
import hashlib
import os
from functools import lru_cache
from os import PathLike
from pathlib import Path

from starlette.datastructures import Headers
from starlette.responses import FileResponse, Response
from starlette.staticfiles import StaticFiles
from starlette.types import Scope

STATIC_DIR = Path(__file__).resolve().parents[2] / "static"
COMPRESSIBLE = (".js", ".css", ".svg", ".json", ".map", ".html")


@lru_cache(maxsize=256)
def _digest(path: str, mtime: float) -> str:  # noqa: ARG001 (mtime: the cache key)
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:12]


def static_url(name: str) -> str:
    """``/static/<name>?v=<hash of the content>``, so browsers may cache it for a year."""
    path = STATIC_DIR / name
    return f"/static/{name}?v={_digest(str(path), path.stat().st_mtime)}"


@lru_cache(maxsize=64)
def _gzipped(path: str, mtime: float) -> bytes:  # noqa: ARG001 (mtime: the cache key)
    return gzip.compress(Path(path).read_bytes(), compresslevel=9, mtime=0)


class CompressedStaticFiles(StaticFiles):
    """StaticFiles that serves text assets gzipped (compressed once, kept in memory)."""

    def file_response(
        self,
        full_path: str | PathLike[str],
        stat_result: os.stat_result,
        scope: Scope,
        status_code: int = 200,
    ) -> Response:
        response = super().file_response(full_path, stat_result, scope, status_code)
        versioned = b"v=" in scope.get("query_string", b"")
        response.headers["cache-control"] = (
            "public, max-age=31536000, immutable" if versioned else "public, max-age=300"
        )
        accepts = Headers(scope=scope).get("accept-encoding", "")
        if (
            not isinstance(response, FileResponse)
            or "gzip" not in accepts
            or not str(full_path).endswith(COMPRESSIBLE)
        ):
            return response
        body = _gzipped(str(full_path), stat_result.st_mtime)
        headers = {
            key: value
            for key, value in response.headers.items()
            if key not in ("content-length", "content-encoding")
        }
        headers.update({"content-encoding": "gzip", "vary": "Accept-Encoding"})
        return Response(
            body, status_code=status_code, headers=headers, media_type=response.media_type
        )
