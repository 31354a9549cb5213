"""``python -m mesh_normal``: the ``mesh-normal`` command."""

from __future__ import annotations

import sys

from mesh_normal.cli import main

if __name__ == "__main__":
    sys.exit(main())
