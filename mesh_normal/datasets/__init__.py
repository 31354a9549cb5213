"""Datasets: the report on every file of a folder, a glob or a bucket, as one Parquet table.

:func:`~mesh_normal.datasets.driver.batch` (``mn.batch``, ``mesh-normal batch``) finds the files
(:mod:`.inputs`), runs :func:`~mesh_normal.datasets.job.run_file` on each in persistent worker
processes (:mod:`.runner`, :mod:`.local`) or on a Dask cluster (:mod:`.cluster`), and writes one
row a file (:data:`~mesh_normal.datasets.schema.SCHEMA`) to ``DIR/report.parquet``.
"""
