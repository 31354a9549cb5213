"""app/mesh/estimates.py: a job's memory, estimated from its upload before the work starts."""

from __future__ import annotations

import io
import time
import zipfile

import numpy as np
import pytest

from app.mesh.estimates import (
    JOB_OVERHEAD,
    MEMORY_PER_BYTE,
    TASK_PER_BYTE,
    UNKNOWN_PER_BYTE,
    estimate,
)
from app.mesh.uploads import Upload
from app.web.errors import ApiError
from tests.hostile_archives import HOSTILE, directory_of
from tests.meshes import CUBE_OBJ, ascii_stl

OBJ = (CUBE_OBJ + "# padding\n" * 10_000).encode()


@pytest.mark.parametrize("task", list(TASK_PER_BYTE))
def test_the_content_decides_the_factor(task: str) -> None:
    """OBJ bytes count as OBJ whatever their name says; the task adds its own share."""
    for name in ("cube.obj", "cube.stl", None):
        expected = len(OBJ) * (MEMORY_PER_BYTE["obj"] + TASK_PER_BYTE[task]) + JOB_OVERHEAD  # type: ignore[index]
        assert estimate(Upload(OBJ, name), task) == int(expected)  # type: ignore[arg-type]


def test_each_format_has_its_factor_and_unknown_bytes_the_most() -> None:
    corners = np.tile(np.array([[[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]]), (2000, 1, 1))
    stl = ascii_stl(corners, np.tile([0.0, 0, 1], (2000, 1)))
    unknown = b"\x01\x02" * 50_000
    per_byte = {
        label: (estimate(Upload(data, "x"), "report") - JOB_OVERHEAD) / len(data)
        for label, data in (("stl", stl), ("obj", OBJ), ("unknown", unknown))
    }
    assert per_byte == pytest.approx({"stl": 6, "obj": 6, "unknown": 26}, rel=1e-6)
    assert UNKNOWN_PER_BYTE == max(MEMORY_PER_BYTE.values()) == 26


def test_a_zip_counts_its_members_unpacked() -> None:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("cube.obj", OBJ)
    data = buffer.getvalue()
    assert len(data) < len(OBJ) / 10  # the padding compresses well
    upload = Upload(data, "cube.zip")
    assert estimate(upload, "report") == int(len(OBJ) * UNKNOWN_PER_BYTE) + JOB_OVERHEAD


def test_several_files_add_up() -> None:
    parts = (("cube.obj", OBJ), ("cube.mtl", b"newmtl a\n" * 100))
    alone = [estimate(Upload(data, name), "fix") - JOB_OVERHEAD for name, data in parts]
    assert estimate(Upload.several(parts, None), "fix") == sum(alone) + JOB_OVERHEAD


@pytest.mark.parametrize("name", ["many.zip", "many.3mf", None])
def test_a_zip_listing_too_many_members_is_refused_at_once(name: str | None) -> None:
    """Its directory is counted from its end record, never parsed: a 413 naming the count,
    before any job is admitted."""
    for data, listed in (
        ((HOSTILE / "zip_many_entries.zip").read_bytes(), "400,001"),
        (directory_of(100_001, stated=1), "more than 1,000"),
    ):
        started = time.perf_counter()
        with pytest.raises(ApiError) as error:
            estimate(Upload(data, name), "report")
        assert time.perf_counter() - started < 1
        assert (error.value.status_code, error.value.field) == (413, "file")
        assert error.value.error == f"The .zip file lists {listed} members; at most 1,000."


def test_a_zip_that_cannot_be_opened_counts_as_its_size() -> None:
    data = b"PK\x03\x04" + b"\0" * 1000
    assert estimate(Upload(data, "x.zip"), "report") == len(data) * UNKNOWN_PER_BYTE + JOB_OVERHEAD
