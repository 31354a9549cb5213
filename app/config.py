"""The service's limits and settings, in one declarative table.

The constants are fixed by design; :class:`Settings` holds what an operator may change
through the environment (``MESH_UPLOAD_LIMIT_MB``, ``MESH_PUBLIC_URL``).
"""

from __future__ import annotations

from pydantic import Field, ValidationError
from pydantic_settings import BaseSettings, SettingsConfigDict

#: Most triangles one POST /api/normals request may carry.
BATCH_LIMIT = 100_000

#: Largest request body, in bytes, per path; other paths get DEFAULT_BODY_LIMIT.
#: One triangle needs far less than 64 KB; a full batch at full precision is about 20 MB.
BODY_LIMITS = {"/api/normals": 48 * 1024 * 1024}
DEFAULT_BODY_LIMIT = 64 * 1024

#: Paths that take a mesh file. Their bodies are streamed (never buffered whole by the
#: middleware) and counted against the upload limit as they arrive.
MESH_PATHS = frozenset({"/api/mesh", "/api/mesh/normals", "/api/mesh/fix", "/mesh"})

#: Most files one mesh request may carry as repeated multipart fields ``file`` (a .gltf, its
#: buffers and textures); each is spooled on its own, so the count is kept small: more go in
#: a .zip, which holds up to mesh_normal.files.archive.MAX_MEMBERS.
UPLOAD_FILES = 100

#: Environment variable that sets the upload limit, in megabytes (default 200).
UPLOAD_LIMIT_VARIABLE = "MESH_UPLOAD_LIMIT_MB"
DEFAULT_UPLOAD_LIMIT_MB = 200

#: Environment variable that sets the public address for absolute links (default: relative).
PUBLIC_URL_VARIABLE = "MESH_PUBLIC_URL"


class Settings(BaseSettings):
    """What the environment may set: ``MESH_UPLOAD_LIMIT_MB``, the mesh upload limit in MB,
    and ``MESH_PUBLIC_URL``, the server's public address."""

    model_config = SettingsConfigDict(
        env_prefix="MESH_", env_ignore_empty=True, extra="ignore", frozen=True
    )

    upload_limit_mb: float = Field(DEFAULT_UPLOAD_LIMIT_MB, gt=0, allow_inf_nan=False)
    #: ``MESH_PUBLIC_URL``: the address users reach the server at (``https://normals.example``),
    #: for the absolute links pasted elsewhere (the embed code, curl commands). Unset, the
    #: server writes relative links (the page's script completes them from its own address):
    #: the request's Host header, which anyone may forge, never goes into a link.
    public_url: str | None = Field(None, pattern=r"^https?://[^\s/?#@]+(/[^\s?#]*)?$")

    @property
    def upload_limit(self) -> int:
        """The largest mesh upload, in bytes."""
        return int(self.upload_limit_mb * 1024 * 1024)


def load_settings() -> Settings:
    """The settings from the environment; a bad value is one clear ``ValueError``."""
    try:
        return Settings()
    except ValidationError as error:
        first = error.errors()[0]
        given = first.get("input")
        if first.get("loc") == ("public_url",):
            raise ValueError(
                f"{PUBLIC_URL_VARIABLE} must be an http:// or https:// address without a query, "
                f"such as https://normals.example.org/, not {given!r}."
            ) from None
        raise ValueError(
            f"{UPLOAD_LIMIT_VARIABLE} must be a positive number of megabytes, not {given!r}."
        ) from None


def upload_limit() -> int:
    """The largest mesh upload in bytes: ``$MESH_UPLOAD_LIMIT_MB`` megabytes, default 200."""
    return load_settings().upload_limit
