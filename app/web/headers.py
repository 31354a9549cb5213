"""The security headers every response carries: a CSP without inline scripts and framing rules.

Kept apart from the middleware so that the error handlers (which answer a crash outside every
middleware) and the middleware can both use them.
"""

from __future__ import annotations

CSP = (
    "default-src 'self'; script-src 'self'; style-src 'self' 'unsafe-inline'; "
    "img-src 'self' data: blob:; font-src 'self'; connect-src 'self'; object-src 'none'; "
    "base-uri 'none'; form-action 'self'; frame-ancestors {ancestors}"
)
#: Paths that any site may frame; every other page refuses framing.
FRAMEABLE = frozenset({"/embed"})

COMMON = [
    (b"x-content-type-options", b"nosniff"),
    (b"referrer-policy", b"strict-origin-when-cross-origin"),
    (b"cross-origin-opener-policy", b"same-origin"),
]
FRAMED = [*COMMON, (b"content-security-policy", CSP.format(ancestors="*").encode())]
UNFRAMED = [
    *COMMON,
    (b"content-security-policy", CSP.format(ancestors="'none'").encode()),
    (b"x-frame-options", b"DENY"),
]


def security_headers(path: str) -> dict[str, str]:
    """The headers SecurityHeaders adds for ``path``, as a dict."""
    chosen = FRAMED if path in FRAMEABLE else UNFRAMED
    return {key.decode(): value.decode() for key, value in chosen}
