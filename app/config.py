"""The service's limits and settings, in one declarative table.

The constants are fixed by design; :class:`Settings` holds what an operator may change
through the environment (``MESH_UPLOAD_LIMIT_MB``, ``MESH_PUBLIC_URL``, ``MESH_DOCS_URL`` and
the heavy-job settings; docs/operators.md lists them).
"""

from __future__ import annotations

import os
from typing import Any

from pydantic import Field, ValidationError
from pydantic_settings import BaseSettings, SettingsConfigDict

#: Most triangles one POST /api/normals request may carry.
BATCH_LIMIT = 100_000

#: Largest request body, in bytes, per path; other paths get DEFAULT_BODY_LIMIT.
#: One triangle needs far less than 64 KB; a full batch at full precision is about 20 MB.
BODY_LIMITS = {"/api/normals": 48 * 1024 * 1024}
DEFAULT_BODY_LIMIT = 64 * 1024

#: Paths that take a mesh or point-cloud file. Their bodies are streamed (never buffered
#: whole by the middleware) and counted against the upload limit as they arrive.
MESH_PATHS = frozenset(
    {
        "/api/mesh",
        "/api/mesh/normals",
        "/api/mesh/fix",
        "/api/mesh/export",
        "/mesh",
        "/api/points",
        "/api/points/normals",
        "/points",
    }
)

#: Most files one mesh request may carry as repeated multipart fields ``file`` (a .gltf, its
#: buffers and textures); each is spooled on its own, so the count is kept small: more go in
#: a .zip, which holds up to mesh_normal.files.archive.MAX_MEMBERS.
UPLOAD_FILES = 100

#: Environment variable that sets the upload limit, in megabytes (default 200).
UPLOAD_LIMIT_VARIABLE = "MESH_UPLOAD_LIMIT_MB"
DEFAULT_UPLOAD_LIMIT_MB = 200

#: Environment variable that sets the public address for absolute links (default: relative).
PUBLIC_URL_VARIABLE = "MESH_PUBLIC_URL"

#: An http(s) address without a query or fragment: ``MESH_PUBLIC_URL`` and ``MESH_DOCS_URL``.
ADDRESS_PATTERN = r"^https?://[^\s/?#@]+(/[^\s?#]*)?$"

#: An example of each address setting, for the sentence naming a bad one.
_ADDRESS_EXAMPLES = {
    "public_url": "https://normals.example.org/",
    "docs_url": "https://docs.normals.example.org/",
}


#: Seconds a client is asked to wait (``Retry-After``) when the heavy-job slots are full.
RETRY_AFTER_SECONDS = 5


def machine_memory() -> int:
    """Bytes of memory this process may use: the machine's, or its container's limit (cgroup v2)."""
    total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    try:
        with open("/sys/fs/cgroup/memory.max") as limit:
            text = limit.read().strip()
    except OSError:
        return total
    return min(total, int(text)) if text.isdigit() else total


def default_memory_budget_mb() -> float:
    """Half of the memory the server may use: the rest for the server itself and the system."""
    return machine_memory() / 2 / (1024 * 1024)


class Settings(BaseSettings):
    """What the environment may set (``MESH_`` and the name in capitals).

    ``upload_limit_mb``: the mesh upload limit in MB. ``public_url``: the server's public
    address (``MESH_PUBLIC_URL``). ``docs_url``: the documentation site's address
    (``MESH_DOCS_URL``), for the pages' links to the guide. ``workers``: worker processes for the
    heavy mesh work, which is also the most heavy jobs at once. ``memory_budget_mb``: the
    memory the jobs running at once may use together, by their estimates (default half of the
    machine's or container's memory). ``queue_seconds``: how long a job waits for a slot
    before the answer is a 503. ``queue_length``: the most jobs waiting at once. ``in_process``:
    run the jobs in threads of the server process instead (tests, debugging: no abort or
    cancellation protection). ``worker_memory_mb``: each worker's memory cap in all
    (``RLIMIT_DATA``); unset, a worker may take the whole ``memory_budget_mb`` beyond what it
    holds once warm. ``expansion_limit_mb``: the most memory one upload may expand into.
    ``job_seconds``: how long one heavy job may run.
    """

    model_config = SettingsConfigDict(
        env_prefix="MESH_", env_ignore_empty=True, extra="ignore", frozen=True
    )

    upload_limit_mb: float = Field(DEFAULT_UPLOAD_LIMIT_MB, gt=0, allow_inf_nan=False)
    #: ``MESH_PUBLIC_URL``: the address users reach the server at (``https://normals.example``),
    #: for the absolute links pasted elsewhere (the embed code, curl commands). Unset, the
    #: server writes relative links (the page's script completes them from its own address):
    #: the request's Host header, which anyone may forge, never goes into a link.
    public_url: str | None = Field(None, pattern=ADDRESS_PATTERN)
    #: ``MESH_DOCS_URL``: where the documentation site (``make docs``, published by the
    #: operator; the app does not serve it) is (``https://docs.normals.example/``). Set, the
    #: pages link to its guide where it explains what they show; unset, they show no link.
    docs_url: str | None = Field(None, pattern=ADDRESS_PATTERN)
    workers: int = Field(2, ge=1, le=64)
    memory_budget_mb: float = Field(
        default_factory=default_memory_budget_mb, gt=0, allow_inf_nan=False
    )
    queue_seconds: float = Field(5.0, ge=0, le=600, allow_inf_nan=False)
    queue_length: int = Field(8, ge=0, le=10_000)
    in_process: bool = False
    worker_memory_mb: float | None = Field(None, gt=0, allow_inf_nan=False)
    #: The most memory one upload may expand into (unpacked archives, instances, decompressed
    #: points; mesh_normal.files.expansion), whatever its size.
    expansion_limit_mb: float = Field(4096, gt=0, allow_inf_nan=False)
    #: Seconds one heavy job may run before it is stopped.
    job_seconds: float = Field(60.0, gt=0, le=3600, allow_inf_nan=False)

    @property
    def upload_limit(self) -> int:
        """The largest mesh upload, in bytes."""
        return int(self.upload_limit_mb * 1024 * 1024)

    @property
    def expansion_limit(self) -> int:
        """The most memory one upload may expand into, in bytes."""
        return int(self.expansion_limit_mb * 1024 * 1024)

    @property
    def memory_budget(self) -> int:
        """The heavy jobs' memory budget, in bytes."""
        return int(self.memory_budget_mb * 1024 * 1024)


#: What each setting must be, for the one sentence naming a bad environment variable.
_EXPECTED = {
    "upload_limit_mb": "a positive number of megabytes",
    "workers": "a whole number from 1 to 64",
    "memory_budget_mb": "a positive number of megabytes",
    "queue_seconds": "a number of seconds from 0 to 600",
    "queue_length": "a whole number from 0 to 10000",
    "in_process": "true or false",
    "worker_memory_mb": "a positive number of megabytes",
    "expansion_limit_mb": "a positive number of megabytes",
    "job_seconds": "a number of seconds above 0, at most 3600",
}


def load_settings(**given: Any) -> Settings:
    """The settings from the environment (``given`` ones win); a bad value is one clear
    ``ValueError``."""
    try:
        return Settings(**given)
    except ValidationError as error:
        first = error.errors()[0]
        name = str(first["loc"][0]) if first.get("loc") else "upload_limit_mb"
        if name in _ADDRESS_EXAMPLES:
            raise ValueError(
                f"MESH_{name.upper()} must be an http:// or https:// address without a query, "
                f"such as {_ADDRESS_EXAMPLES[name]}, not {first.get('input')!r}."
            ) from None
        raise ValueError(
            f"MESH_{name.upper()} must be {_EXPECTED.get(name, 'valid')}, "
            f"not {first.get('input')!r}."
        ) from None


def upload_limit() -> int:
    """The largest mesh upload in bytes: ``$MESH_UPLOAD_LIMIT_MB`` megabytes, default 200."""
    return load_settings().upload_limit
