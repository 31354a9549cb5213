"""The driver, mn.batch: the table, its file, resuming, memory:// datasets."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import fsspec
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest

import mesh_normal as mn
from mesh_normal.datasets.driver import BatchProgress, batch_options, run_batch
from mesh_normal.datasets.schema import SCHEMA
from tests.mesh_normal.datasets.dataset import CUBE_FORMATS, MESH_FILES, SKIPPED, cube

Dataset = tuple[Path, dict[str, dict[str, Any]]]


def without_time(table: pa.Table) -> list[dict[str, Any]]:
    return table.drop_columns(["wall_seconds"]).to_pylist()


@pytest.fixture(scope="module")
def finished(dataset: Dataset, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, pa.Table]:
    """One uninterrupted batch over the folder, with --fix."""
    root, _ = dataset
    out = tmp_path_factory.mktemp("finished")
    return out, mn.batch(str(root), out=out, fix=True, workers=2)


def test_the_table_has_one_row_a_file_sorted(dataset: Dataset, finished: Any) -> None:
    _, expected = dataset
    out, table = finished
    assert table.schema.equals(SCHEMA, check_metadata=False)
    assert table.column("path").to_pylist() == sorted(expected)
    stored = pq.read_table(out / "report.parquet")
    assert without_time(stored) == without_time(table)
    assert not (out / ".parts").exists()  # the parts are gone once the table is written
    statuses = pc.value_counts(table.column("status")).to_pylist()
    counts = {item["values"]: item["counts"] for item in statuses}
    # 40 cubes, and the real cube and sphere; 6 with problems; the 4 broken files.
    assert counts == {"ok": 42, "problems": 6, "unreadable": 4}


def test_the_readme_example(finished: Any) -> None:
    _, table = finished
    # every inside-out mesh bigger than 100 bytes (the README says 1 MB)
    mask = pc.and_(pc.equal(table["orientation"], "inward"), pc.greater(table["size"], 100))
    inside_out = table.filter(mask).column("path").to_pylist()
    assert [Path(path).name for path in inside_out] == ["inside_out.stl"]


def test_fix_writes_the_meshes_it_changes(finished: Any) -> None:
    out, table = finished
    written = [path for row in table.to_pylist() for path in row["outputs"]]
    # The inside-out cube and multibody.stl (its parts wound both ways) need the fix.
    flipped = {Path(row["path"]).name: row["faces_flipped"] for row in table.to_pylist()}
    assert {name: n for name, n in flipped.items() if n} == {"inside_out.stl": 12,
                                                            "multibody.stl": 26}  # fmt: skip
    assert [Path(path).name for path in written] == ["inside_out.stl", "multibody.stl"]
    for path in written:
        assert path.startswith(f"{out}/fixed/")
        assert mn.analyse(path).fix.faces_flipped == 0  # fixed


def test_a_second_run_reuses_every_row(dataset: Dataset, finished: Any) -> None:
    root, _ = dataset
    out, table = finished
    options = batch_options(out=str(out), fix=True)
    again = run_batch([str(root)], options, workers=2)
    assert again.reused == MESH_FILES
    assert again.skipped == SKIPPED
    assert again.table.equals(table)  # the same rows, wall times included: nothing ran


def test_a_changed_file_runs_again(tmp_path: Path) -> None:
    for side, fmt in enumerate(CUBE_FORMATS, start=1):
        (tmp_path / f"in/c{side}.{fmt}").parent.mkdir(exist_ok=True)
        (tmp_path / f"in/c{side}.{fmt}").write_bytes(cube(side, fmt))
    options = batch_options(out=str(tmp_path / "out"))
    first = run_batch([str(tmp_path / "in")], options, workers=1)
    assert first.reused == 0
    # Same size and name, other bytes: a cube of side 5 (and 5³ = 125) in place of side 1.
    (tmp_path / "in/c1.stl").write_bytes(cube(5, "stl"))
    second = run_batch([str(tmp_path / "in")], options, workers=1)
    assert second.reused == 3
    volumes = second.table.column("volume").to_pylist()
    assert volumes == [125.0, 8.0, 27.0, 64.0]
    # Other options (normals asked for): nothing is reused.
    third = run_batch([str(tmp_path / "in")], batch_options(out=str(tmp_path / "out"),
                      normals="face"), workers=1)  # fmt: skip
    assert third.reused == 0
    assert all(len(row["outputs"]) == 1 for row in third.table.to_pylist())


def test_an_interrupted_batch_keeps_its_rows_and_finishes(
    dataset: Dataset, finished: Any, tmp_path: Path
) -> None:
    root, _ = dataset
    _, table = finished
    seen: list[int] = []

    def stop_after_20(state: BatchProgress) -> None:
        seen.append(state.done)
        if state.done == 20:
            raise KeyboardInterrupt

    options = batch_options(out=str(tmp_path), fix=True)
    with pytest.raises(KeyboardInterrupt):
        run_batch([str(root)], options, workers=2, progress=stop_after_20, flush_rows=7)
    parts = pq.read_table(tmp_path / ".parts")
    assert parts.num_rows == 20  # 14 in two parts, the last 6 flushed on the way out
    assert not (tmp_path / "report.parquet").exists()
    resumed = run_batch([str(root)], options, workers=2)
    assert resumed.reused == 20
    mine = [{**row, "outputs": [p.replace(str(tmp_path), "OUT") for p in row["outputs"]]}
            for row in without_time(resumed.table)]  # fmt: skip
    out = str(finished[0])
    theirs = [{**row, "outputs": [p.replace(out, "OUT") for p in row["outputs"]]}
              for row in without_time(table)]  # fmt: skip
    assert mine == theirs


def test_a_memory_dataset() -> None:
    fs = fsspec.filesystem("memory")
    for side in (1, 2, 3):
        fs.pipe(f"/driver14/in/cube{side}.obj", cube(side, "obj"))
    fs.pipe("/driver14/in/broken.stl", b"solid x\nfacet normal 0 0 1\n")
    table = mn.batch("memory://driver14/in", out="memory://driver14/out", normals="face")
    assert table.column("status").to_pylist() == ["unreadable", "ok", "ok", "ok"]
    assert table.column("volume").to_pylist() == [None, 1.0, 8.0, 27.0]
    with fs.open("/driver14/out/report.parquet", "rb") as file:
        assert pq.read_table(file).num_rows == 4
    assert fs.exists("/driver14/out/normals/driver14/in/cube2.obj.face.npy")
    fs.rm("/driver14", recursive=True)


@pytest.mark.parametrize(
    ("given", "sentence"),
    [
        ({"normals": "edge"}, "normals must be face, vertex or corner"),
        ({"normals": "corner", "normals_format": "ply"}, "corner normals do not fit"),
        ({"timeout": 0}, "timeout must be a number above 0"),
        ({"weld": 1.0}, "weld must be a number from 0 to 0.01"),
    ],
)
def test_bad_options_are_one_sentence(given: dict[str, Any], sentence: str) -> None:
    with pytest.raises(ValueError, match=sentence):
        mn.batch("nowhere", out="out", **given)


def test_a_hung_and_a_large_file_do_not_stop_the_batch(tmp_path: Path) -> None:
    inputs = tmp_path / "in"
    inputs.mkdir()
    for side in (1, 2, 3):
        (inputs / f"cube{side}.ply").write_bytes(cube(side, "ply"))
    os.mkfifo(inputs / "hang.stl")  # blocks whoever reads it
    # A cube of side 5 with a comment of 2 MB.
    (inputs / "large.obj").write_bytes(cube(5, "obj") + b"# " + b"x" * 2_000_000 + b"\n")
    result = run_batch(
        [str(inputs)], batch_options(out=str(tmp_path / "out"), timeout=1.0, max_file_mb=1.0)
    )
    rows = {Path(row["path"]).name: row for row in result.table.to_pylist()}
    assert [rows[f"cube{side}.ply"]["volume"] for side in (1, 2, 3)] == [1.0, 8.0, 27.0]
    assert rows["hang.stl"]["status"] == "timed_out"
    assert rows["large.obj"]["status"] == "too_large"
    assert rows["large.obj"]["error"] == "It is 2.0 MB, over the limit of 1 MB (--max-file-mb)."
    # Run again under the same limits: every row is kept (the pipe is not opened again) ...
    assert run_batch([str(inputs)], batch_options(out=str(tmp_path / "out"), timeout=1.0,
                     max_file_mb=1.0)).reused == 5  # fmt: skip
    # ... and under others the two limited rows run again.
    (inputs / "hang.stl").unlink()
    (inputs / "hang.stl").write_bytes(cube(4, "stl"))
    again = run_batch([str(inputs)], batch_options(out=str(tmp_path / "out"), max_file_mb=5))
    assert again.reused == 3
    volumes = {Path(row["path"]).name: row["volume"] for row in again.table.to_pylist()}
    assert volumes == {"cube1.ply": 1.0, "cube2.ply": 8.0, "cube3.ply": 27.0, "hang.stl": 64.0,
                       "large.obj": 125.0}  # fmt: skip
