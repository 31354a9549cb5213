"""Links that leave the page (the embed code, curl commands): never built from the Host header.

The request's ``Host`` header is whatever the client sent, so a link built from it
(``request.base_url``) can point anywhere. These links start from ``MESH_PUBLIC_URL`` when the
operator set it, and are relative otherwise: the page's own script then puts the address the
browser is at in front of them.
"""

from __future__ import annotations

from app import config


def public_url(path: str = "/") -> str:
    """``path`` (starting with ``/``) on the configured public address, or ``path`` alone."""
    base = config.load_settings().public_url
    if base is None:
        return path
    return base.rstrip("/") + path
