"""Links that leave the page (the embed code, curl commands, the guide): never built from the
Host header.

The request's ``Host`` header is whatever the client sent, so a link built from it
(``request.base_url``) can point anywhere. These links start from ``MESH_PUBLIC_URL`` when the
operator set it, and are relative otherwise: the page's own script then puts the address the
browser is at in front of them. Links to the guide start from ``MESH_DOCS_URL``, the
documentation site the operator published (the app does not serve it); unset, there are none.
"""

from __future__ import annotations

from jinja2 import pass_context
from jinja2.runtime import Context

from app import config


def public_url(path: str = "/") -> str:
    """``path`` (starting with ``/``) on the configured public address, or ``path`` alone."""
    base = config.load_settings().public_url
    if base is None:
        return path
    return base.rstrip("/") + path


@pass_context
def guide_url(context: Context, page: str) -> str | None:
    """``page`` of the documentation site (``"meshes/#winding-and-orientation"``), or None
    when the app has no ``MESH_DOCS_URL``: the templates then show no link.

    The address is the app's (``create_app`` puts its settings' ``docs_url`` on its state), so
    a template calls ``guide_url("points/#orientation")`` with the request it is rendered for.
    """
    request = context.get("request")
    base = getattr(request.app.state, "docs_url", None) if request is not None else None
    return None if base is None else base.rstrip("/") + "/" + page
