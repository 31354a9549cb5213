"""The batch: find the files, run them on an engine, keep every row as it comes, write the table.

Rows are kept as they finish in Parquet parts under ``DIR/.parts/`` (each written under a
temporary name, then renamed), every :data:`FLUSH_ROWS` rows or :data:`FLUSH_SECONDS`; a run
that stops (Ctrl-C, a killed machine) loses at most the rows not yet flushed, and the next run
with the same options reads the parts (and any earlier ``report.parquet``) and runs only the
files without a row whose path, size and hash match. The table, ``DIR/report.parquet``, has
one row per file sorted by path, whatever the engine, the order of finishing or the number of
interruptions; once it is written the parts are removed.
"""

from __future__ import annotations

import hashlib
import os
import time
import uuid
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import astuple, dataclass, field, replace
from typing import TYPE_CHECKING, Any

from mesh_normal.datasets.inputs import discover, is_url
from mesh_normal.datasets.tasks import BatchOptions, FileTask, NormalsFormat, NormalsKind

if TYPE_CHECKING:
    import pyarrow as pa

#: The table's name under the output folder.
REPORT = "report.parquet"
#: The folder of parts (rows kept as they finish) under the output folder.
PARTS = ".parts"
#: A part is written after this many new rows, or this many seconds after the last one.
FLUSH_ROWS = 200
FLUSH_SECONDS = 5.0
#: The environment variable that names a Dask scheduler, as Dask's own tools read it.
SCHEDULER_VARIABLE = "DASK_SCHEDULER_ADDRESS"


@dataclass(frozen=True, slots=True)
class BatchProgress:
    """Where a batch is, after each file: handed to ``progress``."""

    done: int  # files with a row, those kept from an earlier run included
    total: int
    failures: int  # rows that are unreadable, too_large or timed_out
    reused: int  # rows kept from an earlier run
    elapsed: float  # seconds since this run started
    row: dict[str, Any] | None  # the row just made (None for the first call)


@dataclass(slots=True)
class BatchResult:
    """The table, and what the run did beside it."""

    table: pa.Table
    skipped: int  # files in the inputs' folders that are not meshes (or clouds)
    reused: int  # rows kept from an earlier run
    seconds: float  # this run's wall time
    report: str  # the table's URL
    engine: str  # "local", "in-process" or "dask"
    workers: int | None = None


def batch(
    paths: str | Sequence[str],
    *,
    out: str | os.PathLike[str],
    client: object | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    normals: NormalsKind | None = None,
    normals_format: NormalsFormat = "npy",
    fix: bool = False,
    points: bool = False,
    timeout: float | None = 60.0,
    max_file_mb: float | None = None,
    memory_mb: float | None = None,
    weld: float | None = None,
    crease_angle: float = 30.0,
    k: int = 30,
    progress: Callable[[BatchProgress], None] | None = None,
) -> pa.Table:
    """The report on every file of ``paths`` as a pyarrow Table, also written to
    ``out/report.parquet``: ``mn.batch("meshes/", out="checked/")``.

    ``paths`` are files, folders (recursive), glob patterns or fsspec URLs (``s3://``,
    ``memory://``); ``out`` is a folder or a folder URL. The files run on every core of this
    machine (``workers`` processes), or on a Dask cluster: ``client`` (a
    ``distributed.Client``), ``scheduler`` (``"tcp://host:8786"``) or the environment's
    ``DASK_SCHEDULER_ADDRESS``. ``normals`` (``"face"``, ``"vertex"`` or ``"corner"``) writes
    each file's normals to ``out/normals/`` as ``.npy`` or ``.ply`` (``normals_format``);
    ``fix`` writes the meshes the fix changes to ``out/fixed/``; ``points`` reads the files as
    point clouds. ``timeout`` (seconds), ``max_file_mb`` and ``memory_mb`` (a worker's memory
    beyond its start) bound one file: a file over them is a row saying so. A second call with
    the same arguments runs only the files without a row yet (see :mod:`.driver`).

    The columns are :data:`~mesh_normal.datasets.schema.SCHEMA`'s.

    Raises
    ------
    ValueError
        For a bad option, or an input that names nothing (one sentence).

    Examples
    --------
    Every inside-out mesh bigger than 1 MB, in pandas:

    >>> table = mn.batch("meshes/", out="checked/")
    >>> df = table.to_pandas()
    >>> df[(df.orientation == "inward") & (df["size"] > 1_000_000)].path
    """
    return run_batch(
        [paths] if isinstance(paths, str) else list(paths),
        batch_options(
            out=os.fspath(out),
            normals=normals,
            normals_format=normals_format,
            fix=fix,
            points=points,
            timeout=timeout,
            max_file_mb=max_file_mb,
            memory_mb=memory_mb,
            weld=weld,
            crease_angle=crease_angle,
            k=k,
        ),
        client=client,
        scheduler=scheduler,
        workers=workers,
        progress=progress,
    ).table


def batch_options(**given: Any) -> BatchOptions:
    """The options, checked: a ValueError names the one that is wrong."""
    options = BatchOptions(**given)
    if options.normals not in (None, "face", "vertex", "corner"):
        raise ValueError(f"normals must be face, vertex or corner, not {options.normals!r}.")
    if options.normals_format not in ("npy", "ply"):
        raise ValueError(f"the normals' format must be npy or ply, not {options.normals_format!r}.")
    if options.normals == "corner" and options.normals_format == "ply" and not options.points:
        raise ValueError("corner normals do not fit in a PLY file; write them as npy.")
    for name in ("timeout", "max_file_mb", "memory_mb"):
        value = getattr(options, name)
        if value is not None and not value > 0:
            raise ValueError(f"{name} must be a number above 0, not {value!r}.")
    if not options.k >= 3:
        raise ValueError(f"k must be at least 3, not {options.k!r}.")
    from mesh_normal.mesh.report.analysis import checked_weld

    return replace(options, weld=checked_weld(options.weld))


def fingerprint(options: BatchOptions) -> str:
    """What a report depends on (every option but where outputs go and the limits): a part
    made with other options is not reused."""
    unlimited = replace(options, out="", timeout=None, max_file_mb=None, memory_mb=None)
    return _digest(repr(astuple(unlimited)))


def limits_key(options: BatchOptions) -> str:
    """The limits: a timed_out or too_large row is reused only under the same ones."""
    return _digest(repr((options.timeout, options.max_file_mb, options.memory_mb)))


def _digest(text: str) -> str:
    return hashlib.blake2b(text.encode(), digest_size=8).hexdigest()


def run_batch(
    paths: Sequence[str],
    options: BatchOptions,
    *,
    client: object | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: Callable[[BatchProgress], None] | None = None,
    flush_rows: int = FLUSH_ROWS,
) -> BatchResult:
    """:func:`batch`, with what the run did beside the table; ``flush_rows`` new rows make a
    part (or :data:`FLUSH_SECONDS`)."""
    start = time.perf_counter()
    _needs_pyarrow()
    found = discover(paths, points=options.points, exclude=options.out)
    store = PartStore(options.out, fingerprint(options), limits_key(options), flush_rows)
    kept = store.reusable(found.tasks)
    todo = [task for task in found.tasks if task.path not in kept]
    engine, rows = _engine(todo, options, client, scheduler, workers)
    failures = sum(row["status"] in FAILED for row in kept.values())
    total, done = len(found.tasks), len(kept)
    if progress is not None:
        progress(BatchProgress(done, total, failures, len(kept), 0.0, None))
    made: dict[str, dict[str, Any]] = {}
    try:
        for row in rows:
            made[row["path"]] = row
            store.add(row)
            done, failures = done + 1, failures + (row["status"] in FAILED)
            if progress is not None:
                elapsed = time.perf_counter() - start
                progress(BatchProgress(done, total, failures, len(kept), elapsed, row))
    finally:
        close = getattr(rows, "close", None)
        if close is not None:
            close()
        store.flush()
    from mesh_normal.datasets.schema import rows_table

    table = rows_table([{**kept, **made}[task.path] for task in found.tasks])
    report = store.write_report(table)
    workers_used = None if engine != "local" else workers
    return BatchResult(
        table, found.skipped, len(kept), time.perf_counter() - start, report, engine, workers_used
    )


FAILED = frozenset({"unreadable", "too_large", "timed_out"})
#: The statuses a limit decides: such a row is run again under other limits.
LIMITED = frozenset({"too_large", "timed_out"})


def _needs_pyarrow() -> None:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise ValueError(
            "the batch writes a Parquet table and needs pyarrow: pip install 'mesh-normal[batch]'."
        ) from None


def _engine(
    tasks: list[FileTask],
    options: BatchOptions,
    client: object | None,
    scheduler: str | None,
    workers: int | None,
) -> tuple[str, Iterator[dict[str, Any]]]:
    """The engine's name and its rows (as files finish)."""
    address = client if client is not None else scheduler or os.environ.get(SCHEDULER_VARIABLE)
    if address:
        try:
            from mesh_normal.datasets.cluster import run_dask  # type: ignore[import-not-found,unused-ignore]
        except ImportError as error:
            raise ValueError(
                f"the Dask engine cannot be loaded ({error}); install it with "
                "pip install 'mesh-normal[dask]'."
            ) from None
        return "dask", iter(run_dask(tasks, options, address))
    from mesh_normal.datasets.local import in_process, run_local

    name = "in-process" if in_process(tasks, options) else "local"
    return name, run_local(tasks, options, workers)


# --- the rows kept --------------------------------------------------------------------------


@dataclass(slots=True)
class PartStore:
    """The rows of a batch under ``out``: the parts, and the table once written."""

    out: str
    options_key: str
    limits: str
    flush_rows: int = FLUSH_ROWS
    pending: list[dict[str, Any]] = field(default_factory=list)
    last_flush: float = field(default_factory=time.monotonic)

    def _fs(self) -> tuple[Any, str]:
        import fsspec

        fs, root = fsspec.core.url_to_fs(self.out)
        return fs, str(root)

    def previous(self) -> Iterable[dict[str, Any]]:
        """The rows of earlier runs with the same options: the table's, then the parts'."""
        import pyarrow.parquet as pq

        fs, root = self._fs()
        files = [f"{root}/{REPORT}"] if fs.exists(f"{root}/{REPORT}") else []
        if fs.isdir(f"{root}/{PARTS}"):
            parts = fs.ls(f"{root}/{PARTS}", detail=False)
            names = [(part.rsplit("/", 1)[-1], part) for part in parts]
            files += sorted(part for name, part in names if _is_part(name))
        for path in files:
            try:
                with fs.open(path, "rb") as file:
                    table = pq.read_table(file)
            except (OSError, ValueError):  # a part cut short: its rows are run again
                continue
            metadata = table.schema.metadata or {}
            if metadata.get(b"options") != self.options_key.encode():
                continue
            same_limits = metadata.get(b"limits") == self.limits.encode()
            for row in table.to_pylist():
                if same_limits or row["status"] not in LIMITED:
                    yield row

    def reusable(self, tasks: Sequence[FileTask]) -> dict[str, dict[str, Any]]:
        """The earlier rows that still hold: same path and size, and the same hash (a file
        read again to check it); rows without a hash (a file over a limit) by path and size."""
        earlier: dict[str, dict[str, Any]] = {}
        for row in self.previous():
            earlier[row["path"]] = row
        candidates = [
            (task, earlier[task.path])
            for task in tasks
            if task.path in earlier and earlier[task.path]["size"] == task.size
        ]
        with ThreadPoolExecutor(8) as pool:
            same = list(pool.map(lambda pair: _same_hash(*pair), candidates))
        return {task.path: row for (task, row), kept in zip(candidates, same, strict=True) if kept}

    def add(self, row: dict[str, Any]) -> None:
        self.pending.append(row)
        late = time.monotonic() - self.last_flush > FLUSH_SECONDS
        if len(self.pending) >= self.flush_rows or late:
            self.flush()

    def flush(self) -> None:
        """Write the pending rows as one more part (atomically)."""
        self.last_flush = time.monotonic()
        if not self.pending:
            return
        from mesh_normal.datasets.schema import rows_table

        table = self._marked(rows_table(self.pending))
        name = f"{PARTS}/part-{time.time_ns():020d}-{uuid.uuid4().hex[:8]}.parquet"
        self._write(name, table)
        self.pending = []

    def _marked(self, table: pa.Table) -> pa.Table:
        metadata = {
            **(table.schema.metadata or {}),
            b"options": self.options_key.encode(),
            b"limits": self.limits.encode(),
        }
        return table.replace_schema_metadata(metadata)

    def _write(self, name: str, table: pa.Table) -> str:
        import pyarrow.parquet as pq

        fs, root = self._fs()
        target = f"{root}/{name}"
        parent = target.rsplit("/", 1)[0]
        fs.makedirs(parent, exist_ok=True)
        temporary = f"{parent}/.{target.rsplit('/', 1)[-1]}.{uuid.uuid4().hex[:12]}.tmp"
        with fs.open(temporary, "wb") as file:
            pq.write_table(table, file)
        fs.mv(temporary, target)
        return target

    def write_report(self, table: pa.Table) -> str:
        """Write the table (atomically), then remove the parts it holds."""
        target = self._write(REPORT, self._marked(table))
        fs, root = self._fs()
        if fs.isdir(f"{root}/{PARTS}"):
            fs.rm(f"{root}/{PARTS}", recursive=True)
        return self.out.rstrip("/") + "/" + REPORT if is_url(self.out) else target


def _is_part(name: str) -> bool:
    """A finished part (not a temporary one, which starts with a dot)."""
    return name.startswith("part-") and name.endswith(".parquet")


def _same_hash(task: FileTask, row: dict[str, Any]) -> bool:
    if row["hash"] is None:
        return True
    import fsspec

    from mesh_normal.datasets.job import file_hash

    try:
        with fsspec.open(task.url, "rb") as file:
            return bool(file_hash(file.read()) == row["hash"])
    except OSError:
        return False
