"""What each worker process runs once as it starts, apart from the app: a worker is handed
:func:`warm_workers` by reference and imports this module for it, not :mod:`app.main`, which
would build a whole app it never serves."""

from __future__ import annotations


def warm_workers() -> None:
    """Every mesh job, then every point job, on small files."""
    from app.mesh import warmup
    from app.points import work as points_work

    warmup.warm()
    points_work.warm()
