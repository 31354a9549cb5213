"""The service's limits and settings, in one declarative table.

The constants are fixed by design; :class:`Settings` holds what an operator may change
through the environment (today only ``MESH_UPLOAD_LIMIT_MB``).
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


class Settings(BaseSettings):
    """What the environment may set: ``MESH_UPLOAD_LIMIT_MB``, the mesh upload limit in MB."""

    model_config = SettingsConfigDict(
        env_prefix="MESH_", env_ignore_empty=True, extra="ignore", frozen=True
    )

    upload_limit_mb: float = Field(DEFAULT_UPLOAD_LIMIT_MB, gt=0, allow_inf_nan=False)

    @property
    def upload_limit(self) -> int:
        """The largest mesh upload, in bytes."""
        return int(self.upload_limit_mb * 1024 * 1024)


def load_settings() -> Settings:
    """The settings from the environment; a bad value is one clear ``ValueError``."""
    try:
        return Settings()
    except ValidationError as error:
        given = error.errors()[0].get("input")
        raise ValueError(
            f"{UPLOAD_LIMIT_VARIABLE} must be a positive number of megabytes, not {given!r}."
        ) from None


def upload_limit() -> int:
    """The largest mesh upload in bytes: ``$MESH_UPLOAD_LIMIT_MB`` megabytes, default 200."""
    return load_settings().upload_limit
