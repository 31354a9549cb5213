"""The table's schema: documented column by column, and what failed rows hold."""

from __future__ import annotations

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from mesh_normal.datasets.schema import (
    COLUMNS,
    NAMES,
    SCHEMA,
    STATUSES,
    failed_row,
    rows_table,
)
from mesh_normal.datasets.tasks import FileTask
from tests.paths import ROOT


def test_every_column_has_a_description() -> None:
    assert SCHEMA.names == list(NAMES)
    for field in SCHEMA:
        description = field.metadata[b"description"].decode()
        assert len(description) > 10, field.name


def test_the_types_are_the_documented_ones() -> None:
    assert SCHEMA.field("path").type == pa.string()
    assert not SCHEMA.field("path").nullable
    assert SCHEMA.field("size").type == pa.int64()
    assert SCHEMA.field("area").type == pa.float64()
    assert SCHEMA.field("watertight").type == pa.bool_()
    assert SCHEMA.field("problems_found").type == pa.list_(pa.string())
    assert SCHEMA.field("outputs").type == pa.list_(pa.string())
    assert STATUSES == ("ok", "problems", "unreadable", "too_large", "timed_out")


def test_a_failed_row_fills_every_column() -> None:
    row = failed_row(FileTask("/d/a.stl", "d/a.stl", 7), "timed_out", "It took too long.")
    assert set(row) == set(NAMES)
    assert row["status"] == "timed_out"
    assert row["error"] == "It took too long."
    assert row["size"] == 7
    assert row["faces"] is None
    assert row["problems_found"] == []


def test_rows_read_back_with_pyarrow(tmp_path: pytest.TempPathFactory) -> None:
    rows = [
        failed_row(FileTask("b", "b.stl", 2), "unreadable", "It is empty."),
        failed_row(FileTask("a", "a.stl", 1), "too_large", "It is large."),
    ]
    path = f"{tmp_path}/t.parquet"
    pq.write_table(rows_table(rows), path)
    table = pq.read_table(path)
    assert table.schema.equals(SCHEMA, check_metadata=False)
    assert table.column("path").to_pylist() == ["a.stl", "b.stl"]  # sorted by path
    description = table.schema.field("status").metadata[b"description"]
    assert b"timed_out" in description


def test_the_datasets_page_lists_every_column() -> None:
    section = (ROOT / "docs" / "datasets.md").read_text(encoding="utf-8")
    for name, *_ in COLUMNS:
        assert f"`{name}`" in section, name
