"""The dataset folder, written once for the session (the tests only read it)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.mesh_normal.datasets.dataset import make_dataset


@pytest.fixture(scope="session")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, dict[str, Any]]]:
    """The folder of 52 meshes (and 2 other files), and each mesh's expected figures."""
    root = tmp_path_factory.mktemp("datasets") / "dataset"
    return root, make_dataset(root)
